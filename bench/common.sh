# What the bench scripts share (sourced, not run): their messages, apt-get installs, the
# repository's paths and cache, and bench_bed, built when missing.
#
# bench_paths BUILD: sets ROOT (and goes there), BUILD (absolute), BENCH_BED and CACHE, and
#   makes the cache, with a .gitignore of * so that nothing in it reaches git.
# bed_label N: how the cached beds' names write N (100000 -> 100k).
# apt_install PACKAGE...: installs with apt-get (through sudo when not root), or stops.
# ensure_bench_bed [REBUILD]: builds bench_bed if it is missing (or when REBUILD is 1), and warns
#   when the build folder is not a Release build.
# field LINE KEY: the value of KEY=VALUE among LINE's words.

BENCH_SCRIPT=${0##*/}
die() { echo "$BENCH_SCRIPT: error: $*" >&2; exit 1; }
note() { echo "$BENCH_SCRIPT: $*" >&2; }

bench_paths() {
  ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
  cd "$ROOT"
  BUILD=$1
  [[ "$BUILD" = /* ]] || BUILD="$ROOT/$BUILD"
  BENCH_BED="$BUILD/bench/bench_bed"
  CACHE="$ROOT/bench_cache"
  mkdir -p "$CACHE"
  [[ -f "$CACHE/.gitignore" ]] || printf '*\n' > "$CACHE/.gitignore"
}

bed_label() { if (( $1 % 1000 == 0 )); then echo "$(($1 / 1000))k"; else echo "$1"; fi; }

SUDO=()
if [[ $(id -u) -ne 0 ]] && command -v sudo >/dev/null 2>&1; then SUDO=(sudo); fi

apt_install() {
  command -v apt-get >/dev/null 2>&1 || die "apt-get not found: install $* by hand"
  if [[ $(id -u) -ne 0 && ${#SUDO[@]} -eq 0 ]]; then
    die "need root or sudo to install $* (or install it by hand: apt-get install $*)"
  fi
  note "installing $* with apt-get"
  "${SUDO[@]}" apt-get update -q >&2 || die "apt-get update failed"
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "$@" >&2 \
    || die "apt-get install $* failed"
}

ensure_bench_bed() {
  if [[ ! -x "$BENCH_BED" ]]; then
    note "building bench_bed in $BUILD"
    if [[ ! -f "$BUILD/CMakeCache.txt" ]]; then
      cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >&2 || die "cmake configure failed"
    fi
    cmake --build "$BUILD" -j2 --target bench_bed >&2 || die "building bench_bed failed"
  elif [[ "${1:-0}" -eq 1 ]]; then
    cmake --build "$BUILD" -j2 --target bench_bed >&2 || die "building bench_bed failed"
  fi
  [[ -x "$BENCH_BED" ]] || die "no executable $BENCH_BED after building"
  if [[ -f "$BUILD/CMakeCache.txt" ]]; then
    local btype
    btype=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
    case "$btype" in
      Release|RelWithDebInfo) ;;
      *) note "WARNING: $BUILD is a '${btype:-<none>}' build, not Release: sandflow's numbers will be low" ;;
    esac
  fi
}

field() { tr ' ' '\n' <<<"$1" | sed -n "s/^$2=//p" | head -n1; }
