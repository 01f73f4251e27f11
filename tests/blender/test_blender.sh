#!/usr/bin/env bash
# The Blender loader (tools/blender/sandflow_blender.py), headless, on a 40-frame run made here:
# every frame's grains and their radius, velocity, id and state checked against the PLY files
# (check_blender_load.py), loaded by the script and by the add-on, the same run written y up, then
# bad run folders, each refused with a message naming the file.
#   tests/blender/test_blender.sh SANDFLOW_BINARY SOURCE_DIR WORK_DIR
# Exits 77 (CTest's SKIP_RETURN_CODE) where Blender is not installed.
set -euo pipefail
if ! command -v blender > /dev/null; then
  echo "skipped: blender is not installed (./setup.sh test installs it: apt-get install blender)"
  exit 77
fi
sandflow=$1 src=$2 work=$3
loader=$src/tools/blender/sandflow_blender.py
rm -rf "$work" && mkdir -p "$work"
blender() { command blender -b --factory-startup --python-exit-code 1 "$@"; }

# 600 grains poured from 20 cm in 0.4 s, 40 frames (1.3 s, about 4 s of CPU): a small heap with
# ACTIVE and INTERFACE grains and a static layer. The angles are given, so no calibration runs.
"$sandflow" run "$src/scenes/floor.toml" --frames 40 --threads 1 --out "$work/run" \
  --set emitter.0.count=600 --set emitter.0.rate=1500 --set 'emitter.0.center=[0,0,0.2]' \
  --set surface.repose_angle=32 --set surface.max_angle=38 \
  --export ply,height,height_obj > "$work/sandflow.log" 2>&1 ||
  { cat "$work/sandflow.log"; exit 1; }

blender --python "$loader" --python "$src/tests/blender/check_blender_load.py" -- "$work/run"

# The add-on: registered, its File > Import operator run on the same folder
blender --python-expr "import sys; sys.path.insert(0, '$src/tools/blender')
import bpy, sandflow_blender
sandflow_blender.register()
assert bpy.ops.import_scene.sandflow_run(directory='$work/run') == {'FINISHED'}" \
  --python "$src/tests/blender/check_blender_load.py" -- "$work/run"

# The same run's first 5 frames written y up, the height field as OBJ only: loaded back z up,
# equal to the z-up files (the rotation and its inverse only swap and negate: exact)
"$sandflow" run "$src/scenes/floor.toml" --frames 5 --threads 1 --out "$work/run_y" \
  --set emitter.0.count=600 --set emitter.0.rate=1500 --set 'emitter.0.center=[0,0,0.2]' \
  --set surface.repose_angle=32 --set surface.max_angle=38 \
  --export ply,height_obj --up-axis y > "$work/sandflow_y.log" 2>&1 ||
  { cat "$work/sandflow_y.log"; exit 1; }
SANDFLOW_CHECK_AGAINST=$work/run \
  blender --python "$loader" --python "$src/tests/blender/check_blender_load.py" -- "$work/run_y"

# A bad run folder: exit status 2 and a message naming what is wrong, never a traceback.
refused() {  # refused WHAT EXPECTED_MESSAGE
  local status=0
  blender --python "$loader" -- "$1" > "$work/refused.log" 2>&1 || status=$?
  if [ "$status" != 2 ] || ! grep -qF -- "$2" "$work/refused.log" ||
     grep -q Traceback "$work/refused.log"; then
    cat "$work/refused.log"
    echo "FAIL: $1: expected exit status 2 and '$2', got status $status"
    exit 1
  fi
  echo "refused as expected: $(grep -F "sandflow_blender: error" "$work/refused.log")"
}
refused "$work/none" "$work/none: no such folder"
mkdir -p "$work/empty"
refused "$work/empty" "no frames/ folder"
cp -r "$work/run" "$work/truncated"
truncate -s -10 "$work/truncated/frames/0017.ply"
refused "$work/truncated" "0017.ply: byte"
cp -r "$work/run" "$work/no_radius"
sed -i 's/property float radius/property float radiux/' "$work/no_radius/frames/0003.ply"
refused "$work/no_radius" "0003.ply: the vertex element has no property 'radius'"
echo "blender test: ok"
