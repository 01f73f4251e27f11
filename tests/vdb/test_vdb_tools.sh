#!/usr/bin/env bash
# The `vdb` export read by other programs than sandflow's tests: OpenVDB's `vdb_print` lists both
# grids of every frame with their types, classes, voxel sizes and metadata; where Blender is
# installed, Blender imports a frame as a Volume object, finds the two grids, and its Volume to
# Mesh modifier turns the level set into a mesh that wraps the frame's grains.
#   tests/vdb/test_vdb_tools.sh SANDFLOW_BINARY SOURCE_DIR WORK_DIR
# Exits 77 (CTest's SKIP_RETURN_CODE) where vdb_print is not installed.
set -euo pipefail
if ! command -v vdb_print > /dev/null; then
  echo "skipped: vdb_print is not installed (./setup.sh test installs it: apt-get install libopenvdb-tools)"
  exit 77
fi
sandflow=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

# 300 grains dropped as a block onto the floor, in both modes: 5 frames, under a second
cat > "$work/drop.toml" <<'TOML'
[scene]
name = "drop"
[material]
diameter = 0.01
diameter_spread = 0.1
k_n = 1.0e4
[output]
fps = 30
[[geometry]]
type = "plane"
[[emitter]]
type = "block"
count = 300
center = [0.0, 0.0, 0.05]
size = [0.1, 0.1, 0.08]
TOML
for mode in surface dem; do
  "$sandflow" run "$work/drop.toml" --mode "$mode" --frames 5 --threads 1 --export vdb,ply \
    --out "$work/$mode" > "$work/$mode.log" 2>&1 || { cat "$work/$mode.log"; exit 1; }
done

# vdb_print: one line a grid (name, value type, ...), and with -l -m the details
for n in 1 2 3 4 5; do
  f=$work/surface/frames/000$n.vdb
  [ -f "$f" ] || fail "$f was not written"
  list=$(vdb_print "$f")
  grep -qE '^grains +ptdataidx32 ' <<< "$list" || fail "$f: no points grid 'grains' in: $list"
  grep -qE '^surface +float ' <<< "$list" || fail "$f: no float grid 'surface' in: $list"
done
long=$(vdb_print -l -m "$work/surface/frames/0005.vdb")
for want in "Name: grains" "Name: surface" "class: level set" "voxel size: 0.02" \
            "voxel size: 0.003" "frame: 5" "scene: drop" "units: m" "up_axis: z"; do
  grep -qF -- "$want" <<< "$long" || fail "vdb_print -l -m 0005.vdb has no '$want':
$long"
done
echo "vdb_print lists grains and surface in every frame:"
vdb_print "$work/surface/frames/0005.vdb"

if ! command -v blender > /dev/null; then
  echo "vdb tools test: ok (the Blender part skipped: blender is not installed)"
  exit 0
fi
# Blender: the DEM run's last frame as a Volume; the level set meshed by Volume to Mesh lies
# around the grains of the same frame's PLY: its box is the spheres' box within a voxel
blender -b --factory-startup --python-exit-code 1 --python-expr "
import sys
import bpy
sys.path.insert(0, '$src/tools/blender')
import sandflow_blender
frames = '$work/dem/frames/'
bpy.ops.object.volume_import(filepath=frames + '0005.vdb', directory=frames,
                             files=[{'name': '0005.vdb'}])
volume = bpy.context.active_object
assert volume.type == 'VOLUME', volume.type
assert volume.data.grids.load(), volume.data.grids.error_message
grids = {g.name: g.data_type for g in volume.data.grids}
assert grids == {'grains': 'POINTS', 'surface': 'FLOAT'}, grids
mesh = bpy.data.objects.new('sand', bpy.data.meshes.new('sand'))
bpy.context.scene.collection.objects.link(mesh)
modifier = mesh.modifiers.new('surface', 'VOLUME_TO_MESH')
modifier.object = volume
modifier.grid_name = 'surface'
modifier.threshold = 0.0
evaluated = mesh.evaluated_get(bpy.context.evaluated_depsgraph_get())
vertices = [v.co for v in evaluated.to_mesh().vertices]
assert len(vertices) > 1000, len(vertices)
grains = sandflow_blender.read_frame(frames + '0005.ply')
voxel = 0.0031
for axis in range(3):
    centres = grains.position[axis::3]
    lo = min(c - r for c, r in zip(centres, grains.radius))
    hi = max(c + r for c, r in zip(centres, grains.radius))
    got = (min(v[axis] for v in vertices), max(v[axis] for v in vertices))
    assert abs(got[0] - lo) < voxel and abs(got[1] - hi) < voxel, (axis, got, (lo, hi))
print('blender: a Volume with grids', sorted(grids), 'and a mesh of', len(vertices),
      'vertices around', grains.count, 'grains')
"
echo "vdb tools test: ok"
