#!/usr/bin/env bash
# Peak memory and time of `sandflow run FILE --check` on the worst inputs the limits allow (and a
# few they refuse): the table of docs/fuzzing.md, "Peak memory and time of run --check".
# Writes the inputs (about 260 MB, most of it one PLY, an STL and a GLB) into a temporary
# folder, measures each with GNU time on an otherwise idle machine, and prints one line per input.
#
# usage: bench/check_memory.sh [SANDFLOW]   (default build/sandflow)
# Needs /usr/bin/time (Debian package `time`) and /usr/bin/python3; takes about 4 minutes.
set -euo pipefail

sandflow=$(realpath "${1:-build/sandflow}")
[ -x "$sandflow" ] || { echo "no sandflow at $sandflow (build it: ./setup.sh build)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time: apt-get install time" >&2; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir"

/usr/bin/python3 - <<'PY'
import gzip, struct, zlib

head = '''[scene]
name = "worst"
[material]
diameter = 0.01
k_n = 1.0e4
[simulation]
mode = "{mode}"
[[geometry]]
type = "plane"
'''
block = '[[emitter]]\ntype = "block"\ncount = 10\ncenter = [0, 0, 1]\nsize = [0.1, 0.1, 0.1]\n'
pour = ('[[emitter]]\ntype = "pour"\nshape = "rect"\ncount = 100000\ncenter = [0, 0, 1]\n'
        'size = [40.0, 40.0, 0.1]\nrate = 1000\n')
field = '[surface]\ncell_size = 0.01\nextent = [-20.47, -20.47, 20.47, 20.47]\n'
def plane(k): return '[[geometry]]\ntype = "plane"\npoint = [0, 0, %d]\n' % (-k - 1)
def mesh(f, size): return '[[geometry]]\ntype = "mesh"\nfile = "%s"\nsize = %s\nposition = [0, 0, 0.001]\n' % (f, size)
png_map = '[[geometry]]\ntype = "heightmap"\nfile = "big.png"\nextent = [-2, -2, 2, 2]\n'
def write(name, text): open(name + '.toml', 'w').write(text)
dem, surface = head.format(mode='dem'), head.format(mode='surface')

# a 2 MB gzipped OBJ inflating to just under 1 GiB: 3 vertices, 19 million faces, comments
with gzip.open('bomb.obj.gz', 'wb', compresslevel=9) as f:
    f.write(b'v 0 0 0\nv 1 0 0\nv 0 1 0\n')
    faces = b'f 1 2 3\n' * (1 << 16)
    n = 0
    while n < 19_000_000:
        f.write(faces); n += 1 << 16
    pad = (b'#' * 1023 + b'\n') * 1024
    total = 24 + 8 * n
    while total + len(pad) < (1 << 30) - (1 << 20):
        f.write(pad); total += len(pad)
write('bomb', dem + mesh('bomb.obj.gz', 0.5) + block)
# a binary PLY of 6.6 million triangles (a bumpy grid)
N = 1820
with open('grid.ply', 'wb') as f:
    f.write(b'ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n'
            b'property float y\nproperty float z\nelement face %d\n'
            b'property list uchar int vertex_indices\nend_header\n' % (N * N, 2 * (N - 1) ** 2))
    for j in range(N):
        f.write(b''.join(struct.pack('<fff', i / (N - 1), j / (N - 1), ((i * 7 + j * 13) % 5) * 1e-4)
                         for i in range(N)))
    for j in range(N - 1):
        f.write(b''.join(struct.pack('<Biii', 3, a, a + 1, a + N + 1) + struct.pack('<Biii', 3, a, a + N + 1, a + N)
                         for a in range(j * N, j * N + N - 1)))
write('grid', dem + mesh('grid.ply', 0.5) + block)
# a binary STL and a GLB of just under 64 MiB, the limit of the formats read through assimp (which
# takes up to 18 times a file's size): the same bumpy grid
def grid_triangles(side):
    for j in range(side):
        for i in range(side):
            a, b, c, d = j * (side + 1) + i, j * (side + 1) + i + 1, (j + 1) * (side + 1) + i + 1, (j + 1) * (side + 1) + i
            yield a, b, c
            yield a, c, d
def grid_point(side, k):
    i, j = k % (side + 1), k // (side + 1)
    return i / side, j / side, ((i * 7 + j * 13) % 5) * 1e-4
limit = 64 << 20
n = (limit - 84) // 50
with open('limit.stl', 'wb') as f:
    f.write(b'binary STL at the limit'.ljust(80, b'\0') + struct.pack('<I', n))
    out, k = bytearray(), 0
    for t in grid_triangles(820):
        if k == n: break
        out += struct.pack('<3f', 0, 0, 1) + b''.join(struct.pack('<3f', *grid_point(820, v)) for v in t) + b'\0\0'
        k += 1
    f.write(out)
write('stl', dem + mesh('limit.stl', 0.5) + block)
# GLB: 12 bytes a vertex and 12 a triangle (32-bit indices), denser than glTF's JSON and base64
side = 1650
positions = b''.join(struct.pack('<3f', *grid_point(side, k)) for k in range((side + 1) ** 2))
indices = bytearray()
for t in grid_triangles(side):
    if len(positions) + len(indices) + 12 > limit - 2000: break
    indices += struct.pack('<3I', *t)
gltf = ('{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],'
        '"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],'
        '"buffers":[{"byteLength":%d}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":%d},'
        '{"buffer":0,"byteOffset":%d,"byteLength":%d}],"accessors":[{"bufferView":0,'
        '"componentType":5126,"count":%d,"type":"VEC3","min":[0,0,0],"max":[1,1,0.0004]},'
        '{"bufferView":1,"componentType":5125,"count":%d,"type":"SCALAR"}]}'
        % (len(positions) + len(indices), len(positions), len(positions), len(indices),
           (side + 1) ** 2, len(indices) // 4)).encode()
gltf += b' ' * (-len(gltf) % 4)
chunks = struct.pack('<I4s', len(gltf), b'JSON') + gltf
chunks += struct.pack('<I4s', len(positions) + len(indices), b'BIN\0') + positions + indices
open('limit.glb', 'wb').write(struct.pack('<4sII', b'glTF', 2, 12 + len(chunks)) + chunks)
write('glb', dem + mesh('limit.glb', 0.5) + block)
# a flat square sampled into just under 20 million points before merging
open('quad.obj', 'w').write('v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n')
write('square', dem + mesh('quad.obj', 7.89) + block)
write('pour', dem + pour)
# a 4096 x 4096 16-bit grey PNG
W = 4096
co = zlib.compressobj(6)
rows = [co.compress(b'\0' + b''.join(struct.pack('>H', (i + j) % 65536) for i in range(W))) for j in range(W)]
rows.append(co.flush())
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open('big.png', 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', W, W, 16, 0, 0, 0, 0))
                            + chunk(b'IDAT', b''.join(rows)) + chunk(b'IEND', b''))
write('png', surface + png_map + block)
write('field', surface + block + field)
write('field_64_planes', surface + ''.join(plane(k) for k in range(63)) + block + field)
write('planes_200k', dem + ''.join(plane(k) for k in range(200_000)) + block)
parts, size, k = [dem], len(dem), 0
while size < (32 << 20) - 200:
    parts.append(plane(k)); size += len(parts[-1]); k += 1
write('planes_32mib', ''.join(parts) + block)
n = ((32 << 20) - 400) // 2
write('toml_worst', dem + '[[geometry]]\ntype = "heightmap"\nextent = [-1, -1, 1, 1]\nheights = [['
      + '0,' * (n - 1) + '0]]\n' + block)
write('stacked_boxes', surface + ''.join(
    '[[geometry]]\ntype = "box"\ncenter = [0, 0, %d]\nsize = [41, 41, 0.5]\ncontainer = true\n'
    'rotation = [0, 0, 0.5]\n' % (-k - 1) for k in range(31)) + block + field)
write('every_limit', surface + mesh('grid.ply', 0.5) + png_map
      + pour + field)
PY

printf '%-16s %4s %12s %9s  %s\n' input exit "peak (MiB)" "time (s)" "last line"
for t in bomb grid stl glb square pour png field field_64_planes stacked_boxes planes_200k \
  planes_32mib toml_worst every_limit; do
  set +e
  /usr/bin/time -o time.txt -f "%e %M" timeout 300 "$sandflow" run "$t.toml" --check > out.txt 2>&1
  rc=$?
  set -e
  read -r seconds kb < <(tail -1 time.txt)
  printf '%-16s %4s %12.0f %9s  %s\n' "$t" "$rc" "$((kb / 1024))" "$seconds" \
    "$(grep -v '^Command' out.txt | tail -1 | cut -c1-100)"
done
