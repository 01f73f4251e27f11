#!/usr/bin/env bash
# Where the DEM sweep sits on this machine's roofline: the floating-point
# operations and the bytes one grain-step of the settled bed costs, beside the
# peak rates and bandwidths likwid-bench measures here, at 1 and 2 threads.
#
# The flops and bytes per grain-step are a count, not a measurement: this
# machine's VM gives no hardware counters. They are counted from the source of
# the sweep (src/dem/dem_solver.cpp, src/dem/contact.hpp), term by term below,
# with the pair counts bench_bed reports for the bed it timed. --instructions
# adds a measured figure beside them: the instructions one grain-step executes,
# counted by valgrind's lackey on a 10,000-grain bed (a few minutes).
#
# Prints a table; see bench/README.md.
set -euo pipefail

usage() {
  cat <<'EOF'
usage: bench/roofline.sh [--grains N] [--steps N] [--build DIR] [--instructions]

  --grains N      bed grains (default 100000; the bed cached by compare_lammps.sh,
                  bench_cache/bed<N>.bin, built and settled first if missing)
  --steps N       timed steps of each bench_bed run (default 1000)
  --build DIR     CMake build directory holding bench/bench_bed (default: build)
  --instructions  also count the instructions of a grain-step with valgrind's
                  lackey (10,000-grain bed, 20 and 60 steps: a few minutes)
  -h, --help      this help

Installs Debian's likwid (likwid-bench) and, with --instructions, valgrind with
apt-get if they are missing. Run it on an idle machine.
EOF
}

# die, note, bench_paths, bed_label, apt_install, ensure_bench_bed, field
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

GRAINS=100000
STEPS=1000
BUILD=build
INSTRUCTIONS=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --grains) [[ $# -ge 2 ]] || die "--grains needs a value"; GRAINS=$2; shift 2 ;;
    --steps) [[ $# -ge 2 ]] || die "--steps needs a value"; STEPS=$2; shift 2 ;;
    --build) [[ $# -ge 2 ]] || die "--build needs a value"; BUILD=$2; shift 2 ;;
    --instructions) INSTRUCTIONS=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) usage >&2; die "unknown argument: $1" ;;
  esac
done
[[ "$GRAINS" =~ ^[1-9][0-9]*$ ]] || die "--grains must be a positive integer, got '$GRAINS'"
[[ "$STEPS" =~ ^[1-9][0-9]*$ ]] || die "--steps must be a positive integer, got '$STEPS'"

bench_paths "$BUILD"

command -v likwid-bench >/dev/null 2>&1 || apt_install likwid
if (( INSTRUCTIONS )); then command -v valgrind >/dev/null 2>&1 || apt_install valgrind; fi

ensure_bench_bed

# ---------------------------------------------------------------- the kernel
# bench_bed THREADS: sets GSS (grain-steps/s), TOUCH, NEAR and LISTED (pairs per grain)
bench() {
  local log="$CACHE/roofline_t$1.log"
  OMP_NUM_THREADS=$1 "$BENCH_BED" --case bed --grains "$GRAINS" --threads "$1" --steps "$STEPS" \
    --bed "bench_cache/bed$(bed_label "$GRAINS").bin" >"$log" 2>&1 \
    || { tail -n 20 "$log" >&2; die "bench_bed failed, see $log"; }
  local line
  line=$(grep -E '^engine=' "$log" | tail -n1)
  GSS=$(field "$line" grain_steps_per_s)
  TOUCH=$(awk -v c="$(field "$line" contacts_per_grain)" 'BEGIN {print c / 2}')
  LISTED=$(sed -n 's/^listed pairs per grain \([0-9.]*\).*/\1/p' "$log")
  NEAR=$(sed -n 's/^listed pairs per grain .*, \([0-9.]*\) near$/\1/p' "$log")
  [[ -n "$GSS" && -n "$LISTED" && -n "$NEAR" ]] || die "bench_bed's output lacks its figures, see $log"
}
note "bench_bed, $GRAINS grains, $STEPS steps, 1 thread"
bench 1
GSS1=$GSS
note "bench_bed, 2 threads"
bench 2
GSS2=$GSS

# The count per grain-step, from the source (an add, a multiply, a division or
# a square root is one flop; comparisons, min and max are none):
#   a touching pair: 131 flops. Its geometry (pair_force: dx, |dx|^2, the sum of
#     radii and its square, sqrt, 1/|dx|^2 and |dx|/|dx|^2, n, delta, the overlap
#     check) 19; the law (contact_force: v_i - v_j, the surfaces' velocity
#     3 + 9 + 9 + 3, v_n 5, v_t 6, F_n 3, c_t 1, rotate_into_plane 24,
#     capped_spring 22, F 6, q 9) 100; the sums (the grain's own 6, the
#     partner's accumulator 6) 12.
#   a pair of the near list that does not touch: 10 (dx, |dx|^2, the radii, the
#     square). The sweep visits the near list only (DemSolver::build_near; the
#     list's own making, a few times in a hundred steps, is left out).
#   a grain: 54 (its accumulator 6, the torque 7, integrate: v 12, w 7, x 6,
#     the allowance and near-margin checks 16).
# Bytes: what the step must bring in and write back at least once (each array
# element once, whatever the order; write-backs counted):
#   a grain: 349. x, v, w read and written 144; r, 1/m, 1/I 24; state 1; the
#     position at the last rebuild 24 and the allowance 8, at the last near list
#     24 and the margin 8; the two accumulators
#     read and cleared 96; the pair, wall and boundary lists' offsets 12; the
#     split (written and read) 8.
#   a pair of the near list: 66. Its slot 4, the partner's 4, its touch flag
#     read and written 2,
#     the damping 8, the tangential history read and written 48 (in slot order;
#     a line shared with slots the near list skips is loaded all the same, so
#     this is the least the pairs can cost).
# Partners' x, v, w are counted with their own grain: the bed is sorted by
# cell, so a partner's data are still in cache (L2) when the sweep needs them.
model() {  # TOUCH NEAR -> FLOPS BYTES
  awk -v t="$1" -v l="$2" 'BEGIN { printf "%.0f %.0f\n", 131 * t + 10 * (l - t) + 54, 349 + 66 * l }'
}
read -r FLOPS BYTES < <(model "$TOUCH" "$NEAR")
WORKING_MB=$(awk -v b="$BYTES" -v n="$GRAINS" 'BEGIN { m = b * n / 1e6; printf "%d", (m < 1 ? 1 : m) }')

# ---------------------------------------------------------------- the roofs
lb() {  # TEST SIZE THREADS FIELD -> the value of likwid-bench's FIELD line
  local out
  out=$(likwid-bench -t "$1" -w "N:$2:$3" 2>&1) || { echo "$out" >&2; die "likwid-bench -t $1 failed"; }
  local v
  v=$(sed -n "s|^$4:[[:space:]]*||p" <<<"$out" | head -n1)
  [[ "$v" =~ ^[0-9.]+$ ]] || { echo "$out" >&2; die "likwid-bench -t $1 gave no $4"; }
  echo "$v"
}
VEC=
grep -qw avx512f /proc/cpuinfo && VEC=peakflops_avx512_fma
[[ -z "$VEC" ]] && grep -qw fma /proc/cpuinfo && VEC=peakflops_avx_fma
declare -A ROOF
for t in 1 2; do
  note "likwid-bench, $t thread(s)"
  ROOF[scalar$t]=$(lb peakflops 32kB "$t" MFlops/s)
  [[ -n "$VEC" ]] && ROOF[vector$t]=$(lb "$VEC" 32kB "$t" MFlops/s)
  ROOF[cache$t]=$(lb stream "${WORKING_MB}MB" "$t" MByte/s)
  ROOF[dram$t]=$(lb stream 2GB "$t" MByte/s)
done

# ----------------------------------------------------------------- instructions
INSTR=
if (( INSTRUCTIONS )); then
  note "valgrind lackey: the instructions of a grain-step (10,000-grain bed; minutes)"
  count() {
    valgrind --tool=lackey "$BENCH_BED" --case bed --grains 10000 --threads 1 --steps "$1" \
      --bed bench_cache/bed10k.bin 2>&1 | sed -n 's/.*guest instrs:[[:space:]]*\([0-9,]*\).*/\1/p' \
      | tr -d , | head -n1
  }
  i20=$(count 20); i60=$(count 60)
  [[ -n "$i20" && -n "$i60" ]] || die "valgrind gave no instruction count"
  INSTR=$(awk -v a="$i20" -v b="$i60" 'BEGIN { printf "%.0f", (b - a) / (40 * 10000) }')
fi

# ------------------------------------------------------------------- report
echo
echo "settled bed: $GRAINS grains, $STEPS steps; pairs per grain: $TOUCH touching, $NEAR near, $LISTED listed"
echo "count per grain-step: $FLOPS flops, $BYTES bytes (intensity $(awk -v f="$FLOPS" -v b="$BYTES" 'BEGIN {printf "%.2f", f / b}') flop/byte); working set ${WORKING_MB} MB"
[[ -n "$INSTR" ]] && echo "instructions per grain-step (valgrind lackey, 10,000-grain bed): $INSTR"
echo
printf '%-8s %14s %10s %10s %12s %12s %12s %12s %16s\n' threads grain-steps/s GFlop/s GB/s \
  scalar_peak vector_peak "stream(${WORKING_MB}MB)" stream_2GB memory_bound_gss
for t in 1 2; do
  g=$([[ $t == 1 ]] && echo "$GSS1" || echo "$GSS2")
  awk -v t="$t" -v g="$g" -v f="$FLOPS" -v b="$BYTES" -v s="${ROOF[scalar$t]}" \
      -v v="${ROOF[vector$t]:-0}" -v c="${ROOF[cache$t]}" -v d="${ROOF[dram$t]}" 'BEGIN {
    gf = g * f / 1e9; gb = g * b / 1e9
    printf "%-8s %14.4g %10.2f %10.2f %5.1f (%3.0f%%) %5.1f (%3.0f%%) %5.1f (%3.0f%%) %5.1f (%3.0f%%) %16.3g\n",
      t, g, gf, gb, s / 1e3, 100 * gf / (s / 1e3), v / 1e3, (v > 0 ? 100 * gf / (v / 1e3) : 0),
      c / 1e3, 100 * gb / (c / 1e3), d / 1e3, 100 * gb / (d / 1e3), d * 1e6 / b
  }'
done
echo
echo "peaks in GFlop/s (likwid-bench peakflops, ${VEC:-no vector test}), bandwidths in GB/s (stream triad);"
echo "(%): the kernel's share of each; memory_bound_gss: grain-steps/s if the 2 GB stream's bandwidth were the only limit"
