#!/usr/bin/env bash
# Fuzzes each reader of user files with libFuzzer (docs/fuzzing.md):
#   scripts/fuzz.sh [SECONDS] [TARGET...]   each target (default: all) for SECONDS (default 300),
#                                           one after the other
# Installs clang if missing (Debian 12 packages), builds the targets in build-fuzz/ (ASan + UBSan,
# the library instrumented for coverage), seeds each from the repository's good and malformed
# files, and prints per target the number of inputs tried and whether it found anything. What a
# target finds is left in build-fuzz/findings/TARGET/; what it learnt (its corpus) is kept in
# build-fuzz/corpus/TARGET/ for the next run. Exit status: 0 no finding, 1 a finding, 2 bad usage.
set -euo pipefail
cd "$(dirname "$0")/.."

# The targets, one per reader (each also named in fuzz/CMakeLists.txt, with a seeds_ function below)
all_targets=(scene mesh frame_ply png checkpoint)
usage="usage: scripts/fuzz.sh [SECONDS] [TARGET...]   (SECONDS per target, a whole number >= 1,
default 300; TARGET among: ${all_targets[*]}; default all)"

seconds=${1:-300}
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || ((seconds < 1)); then
  echo "$usage" >&2
  exit 2
fi
shift $(($# > 0 ? 1 : 0))
targets=("${@:-${all_targets[@]}}")
for t in "${targets[@]}"; do
  if ! [[ " ${all_targets[*]} " == *" $t "* ]]; then
    echo "scripts/fuzz.sh: unknown target '$t'" >&2
    echo "$usage" >&2
    exit 2
  fi
done

# 1. Debian packages (only the missing ones are installed), as setup.sh does
packages=(clang libclang-rt-14-dev libomp-dev cmake make pkg-config libtomlplusplus-dev
          libcli11-dev libfmt-dev nlohmann-json3-dev libpng-dev zlib1g-dev libassimp-dev
          libopenvdb-dev libboost-iostreams-dev)
scripts/install_packages.sh "${packages[@]}"

# 2. Build (clang, -fsanitize=fuzzer,address,undefined)
build=build-fuzz
echo "==> building the fuzz targets in $build"
mkdir -p "$build"
CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSANDFLOW_FUZZ=ON \
  -DSANDFLOW_TESTS=OFF -DSANDFLOW_BENCH=OFF > "$build/cmake.log" 2>&1 ||
  { cat "$build/cmake.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" --target "${targets[@]/#/fuzz_}"

# 3. Seeds: the repository's files, copied fresh each run (a seed of the mesh target starts with
#    the byte that picks its format: fuzz/fuzz_mesh.cpp)
seeds_scene() {
  cp scenes/*.toml tests/data/scenes/bad/*.toml "$1/"
  { cat scenes/floor.toml; printf '\n#--set\nmaterial.friction=0.5\nemitter.0.rate=4000\n'; } \
    > "$1/floor_with_overrides.toml"
}
seeds_mesh() {
  local f name prefix fitted
  for f in tests/data/meshes/*.* tests/data/meshes/bad/*; do
    name=$(basename "$f")
    case "$name" in
      *.obj | *.obj.gz) prefix=o fitted='\200' ;;
      *.ply | *.ply.gz) prefix=p fitted='\201' ;;
      *.off | *.off.gz) prefix=f fitted='\202' ;;
      *.stl | *.stl.gz) prefix=s fitted='\203' ;;
      *.gltf) prefix=g fitted='\204' ;;
      *.glb) prefix=b fitted='\205' ;;
      *) continue ;;
    esac
    { printf %s "$prefix"; cat "$f"; } > "$1/$name"
    { printf "$fitted"; cat "$f"; } > "$1/fitted_$name"
  done
}
seeds_frame_ply() { cp tests/data/frames/*.ply tests/data/frames/bad/*.ply "$1/"; }
seeds_png() { cp tests/data/png/*.png tests/data/png/bad/*.png "$1/"; }
# checkpoints of the target's own scene in the current format, written by the target itself
seeds_checkpoint() { SANDFLOW_FUZZ_WRITE_SEEDS="$1" "$build/fuzz/fuzz_checkpoint"; }

# The dictionaries: TOML syntax plus every key and word the scene loader reads
{
  cat fuzz/toml.dict
  grep -ohE '(read|table|array_of_tables|require|has|fail_at)\("[a-z_]+"' src/scene/*.cpp |
    sed -E 's/.*\("([a-z_]+)"/"\1"/'
  grep -ohE '\{"[a-z]+", [A-Za-z]+::' src/scene/*.cpp | sed -E 's/\{("[a-z]+").*/\1/'
} | sort -u > "$build/scene.dict"
cat fuzz/ply.dict fuzz/mesh.dict > "$build/mesh.dict"
cp fuzz/ply.dict "$build/frame_ply.dict"
cp fuzz/png.dict "$build/png.dict"
cp fuzz/checkpoint.dict "$build/checkpoint.dict"

# 4. Run each target in turn
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}
declare -A tried result
status=0
for t in "${targets[@]}"; do
  seeds="$build/seeds/$t" corpus="$build/corpus/$t" findings="$build/findings/$t"
  rm -rf "$seeds" && mkdir -p "$seeds" "$corpus" "$findings"
  "seeds_$t" "$seeds"
  log="$build/fuzz_$t.log"
  echo "==> fuzzing $t for $seconds s (log: $log)"
  # -timeout: an input that takes 10 s is a hang (and one of 10 s is reported as slow); -rss_limit_mb:
  # 2 GB of memory is a leak or an unbounded allocation (a single allocation beyond it too). The
  # scene and mesh targets build a World, which within the limits takes up to 3 GiB and a minute
  # in Release (docs/fuzzing.md); this build runs about 10 times slower (the terrain scene's World:
  # 1.5 s in Release, 19 s here), so there 300 s is a hang and 4 GB too much.
  limits=(-timeout=10 -rss_limit_mb=2048)
  case "$t" in
    scene | mesh) limits=(-timeout=300 -report_slow_units=300 -rss_limit_mb=4096) ;;
  esac
  # what this run finds is what is newer than this mark (earlier runs' findings stay in the folder)
  mark="$build/.fuzz_start_$t"
  touch "$mark"
  set +e
  "$build/fuzz/fuzz_$t" "$corpus" "$seeds" -dict="$build/$t.dict" -max_total_time="$seconds" \
    "${limits[@]}" -print_final_stats=1 -artifact_prefix="$findings/" > "$log" 2>&1
  rc=$?
  set -e
  # the scene and mesh targets' own files (libFuzzer ends a timed run without running atexit),
  # named sandflow_fuzz_PID (fuzz/fuzz_common.hpp); only those: scripts/fuzz_cli.py's folder,
  # sandflow_fuzz_cli_*, was removed under it when the two ran side by side
  rm -rf /dev/shm/sandflow_fuzz_[0-9]* "${TMPDIR:-/tmp}"/sandflow_fuzz_[0-9]*
  tried[$t]=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
  found=$(find "$findings" -type f -newer "$mark" | sort)
  earlier=$(find "$findings" -type f ! -newer "$mark" | wc -l)
  rm -f "$mark"
  if [ -n "$found" ] || [ "$rc" -ne 0 ]; then
    result[$t]="FOUND (exit $rc): ${found:-see $log}"
    status=1
  else
    result[$t]="nothing found"
  fi
  [ "$earlier" -eq 0 ] || result[$t]+=" ($earlier file(s) of earlier runs still in $findings)"
  echo "    $t: ${tried[$t]:-?} inputs tried, ${result[$t]}"
done

echo "==> summary ($seconds s per target)"
printf '%-10s %14s  %s\n' target "inputs tried" result
for t in "${targets[@]}"; do printf '%-10s %14s  %s\n' "$t" "${tried[$t]:-?}" "${result[$t]}"; done
exit $status
