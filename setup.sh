#!/usr/bin/env bash
# sandflow set-up: installs what is missing (Debian 12 packages), builds in Release, then
#   ./setup.sh demo   runs the default scene (floor, 20,000 grains), renders its last frame and
#                     writes its report (out/floor-demo/report.html)
#   ./setup.sh test   runs the whole test suite (and installs Blender for tests/blender)
# Options (environment): SANDFLOW_DEMO_GRAINS (default 20000; the full scene has 107687),
#   SANDFLOW_BUILD (build folder, default build), SANDFLOW_SANITIZE=1 (ASan + UBSan build, with
#   the assertions of src/core/assert.hpp), SANDFLOW_COMPILER=clang (clang++ and LLVM's OpenMP,
#   in build-clang: the same results, the bed's sweep 6-10 % faster than GCC's, docs/performance.md,
#   seventy-fifth entry, and about 2 % with rolling resistance, seventy-fourth;
#   the program then needs /dev/shm and a file-size limit of 1 KB or more, docs/known-issues.md).
set -euo pipefail
cd "$(dirname "$0")"

what=${1:-demo}
case "$what" in demo|test|build) ;; *) echo "usage: ./setup.sh demo|test|build" >&2; exit 2 ;; esac

# 1. Debian packages (only the missing ones are installed)
packages=(g++ cmake make pkg-config libtomlplusplus-dev libcli11-dev libfmt-dev nlohmann-json3-dev
          libgtest-dev libpng-dev zlib1g-dev libassimp-dev povray ffmpeg libopenvdb-dev
          libboost-iostreams-dev)
# (OpenVDB's find module asks for Boost's iostreams, which libopenvdb-dev does not pull in)
# Blender runs one test, the loader's (tests/blender); it is large (190 MB installed, with its data,
# and some 70 libraries), so only `test` installs it
# vdb_print (libopenvdb-tools, 23 MB) reads the `vdb` export back in tests/vdb
if [ "$what" = test ]; then packages+=(blender libopenvdb-tools); fi
compiler=${SANDFLOW_COMPILER:-gcc}
case "$compiler" in
  gcc) ;;
  clang) packages+=(clang libomp-dev) ;;
  *) echo "SANDFLOW_COMPILER=$compiler: expected gcc or clang" >&2; exit 2 ;;
esac
scripts/install_packages.sh "${packages[@]}"

# 2. Build (Release, or the sanitizer build; RelWithDebInfo and the sanitizers turn the assertions on)
build=${SANDFLOW_BUILD:-build}
flags=(-DCMAKE_BUILD_TYPE=Release -DSANDFLOW_WERROR="${SANDFLOW_WERROR:-OFF}")
if [ "${SANDFLOW_SANITIZE:-0}" = 1 ]; then
  build=${SANDFLOW_BUILD:-build-asan}
  flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DSANDFLOW_SANITIZE=ON -DSANDFLOW_BENCH=OFF
         -DSANDFLOW_WERROR="${SANDFLOW_WERROR:-OFF}")
fi
if [ "$compiler" = clang ]; then
  # (a folder of its own: CMake keeps the compiler a folder was first configured with)
  build=${SANDFLOW_BUILD:-$build-clang}
  # (and without precompiled headers: each file of src/ and apps/ then compiles from its own
  # includes, so a missing #include fails here rather than nowhere; the test files keep their
  # batches, tests/CMakeLists.txt)
  flags+=(-DCMAKE_CXX_COMPILER=clang++ -DSANDFLOW_PCH=OFF)
fi
echo "==> building in $build"
cmake -S . -B "$build" "${flags[@]}" > "$build.cmake.log" 2>&1 || { cat "$build.cmake.log"; exit 1; }
cmake --build "$build" -j "$(nproc)"

# 3. The sample meshes of the dragon and armadillo scenes (not committed; without them those
#    scenes run with a stand-in box and say so)
if ! scripts/fetch_meshes.sh; then
  echo "warning: the sample meshes could not all be fetched; scenes without theirs use a box" >&2
fi

# 4. The job
if [ "$what" = test ]; then
  echo "==> running the tests"
  ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
elif [ "$what" = demo ]; then
  out=out/floor-demo
  grains=${SANDFLOW_DEMO_GRAINS:-20000}
  echo "==> simulating scenes/floor.toml with $grains grains (surface flow: height field + DEM) -> $out"
  "./$build/sandflow" run scenes/floor.toml --grains "$grains" --out "$out" --force
  echo "==> rendering the last frame with POV-Ray"
  png=$("./$build/sandflow" render "$out" --width 1280 --height 720)
  echo "==> writing the report: summary, plots, and a contact sheet of frames rendered with POV-Ray"
  "./$build/sandflow" report "$out" > /dev/null
  echo "==> done: summary $out/summary.json, statistics $out/stats.csv"
  echo "picture  $png"
  echo "report   $out/report.html"
fi
