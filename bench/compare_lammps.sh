#!/usr/bin/env bash
# Times the same grains in sandflow (bench_bed) and in LAMMPS (pair_style
# gran/hooke/history), at 1 and at 2 threads / MPI processes: a settled bed
# (--case bed, the default) or a pour (--case pour: a column released onto the
# floor, timed while it lands and spreads). See bench/README.md for what is
# measured and why it is like for like.
#
# Last line of output: ratio_1=X ratio_2=Y scaling_sandflow=Z scaling_lammps=W
# (sandflow grain-steps/s over LAMMPS's at 1 and at 2 threads/processes; each
# engine's 2-thread/process speed over its 1-thread/process speed), each the
# median over the rounds (--rounds) of the ratio within a round.
# Exit status: 0 ok; 3 the two engines did not simulate the same grains (bed:
# contacts per grain more than 5% apart; pour: contacts per grain more than 10%
# or the grains' mean height more than 2% apart; the ratio line is still
# printed, but the comparison is not like for like); anything else: an error,
# explained on stderr.
set -euo pipefail

usage() {
  cat <<'EOF'
usage: bench/compare_lammps.sh [--case bed|pour] [--grains N] [--steps N] [--rounds R] [--build DIR] [--rebuild]

  --case C     bed (default): a settled bed, timed after a warm-up;
               pour: a column of grains released onto the floor, timed from
               the release while it lands and makes a heap
  --grains N   grains (default: bed 100000, pour 20000). Each bed N has its
               own cached bed, bench_cache/bed<N>.bin (100000 -> bed100k.bin);
               building and settling a new bed takes minutes, once. A pour's
               column is made in a moment and not cached.
  --steps N    timed steps (default: bed 2000, pour 100000, 1 s of the pour)
  --rounds R   rounds of the four runs (default: bed 3, about 2.5 minutes a
               round at 100,000 grains; pour 1, about 14 minutes). Each round
               runs sandflow and LAMMPS on 1, then on 2, back to back, so that
               a ratio compares runs minutes apart at most: a shared machine's
               speed drifts by a fifth within an hour. The ratios printed are
               the medians of the rounds' ratios.
  --build DIR  CMake build directory holding bench/bench_bed (default: build,
               relative to the repository root). Configured (Release) and
               built if bench_bed is missing.
  --rebuild    run 'cmake --build DIR --target bench_bed' even if it exists
  -h, --help   this help

Installs Debian's lammps (and openmpi-bin) with apt-get if they are missing.
Logs go to bench_cache/ in the repository root.
EOF
}

# die, note, bench_paths, bed_label, apt_install, ensure_bench_bed, field
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

# ---------------------------------------------------------------- options
CASE=bed
GRAINS=
STEPS=
BUILD=build
REBUILD=0
ROUNDS=

while [[ $# -gt 0 ]]; do
  case "$1" in
    --case) [[ $# -ge 2 ]] || die "--case needs a value"; CASE=$2; shift 2 ;;
    --case=*) CASE=${1#*=}; shift ;;
    --grains) [[ $# -ge 2 ]] || die "--grains needs a value"; GRAINS=$2; shift 2 ;;
    --grains=*) GRAINS=${1#*=}; shift ;;
    --steps) [[ $# -ge 2 ]] || die "--steps needs a value"; STEPS=$2; shift 2 ;;
    --steps=*) STEPS=${1#*=}; shift ;;
    --build) [[ $# -ge 2 ]] || die "--build needs a value"; BUILD=$2; shift 2 ;;
    --build=*) BUILD=${1#*=}; shift ;;
    --rounds) [[ $# -ge 2 ]] || die "--rounds needs a value"; ROUNDS=$2; shift 2 ;;
    --rounds=*) ROUNDS=${1#*=}; shift ;;
    --rebuild) REBUILD=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) usage >&2; die "unknown argument: $1" ;;
  esac
done
case "$CASE" in
  bed)  GRAINS=${GRAINS:-100000}; STEPS=${STEPS:-2000}; ROUNDS=${ROUNDS:-3}
        WARM=200 ;;  # untimed LAMMPS steps before the timed run (contact history)
  pour) GRAINS=${GRAINS:-20000}; STEPS=${STEPS:-100000}; ROUNDS=${ROUNDS:-1}
        WARM=0 ;;    # timed from the release, as bench_bed times it
  *) die "--case must be bed or pour, got '$CASE'" ;;
esac
[[ "$GRAINS" =~ ^[1-9][0-9]*$ ]] || die "--grains must be a positive integer, got '$GRAINS'"
[[ "$STEPS" =~ ^[1-9][0-9]*$ ]] || die "--steps must be a positive integer, got '$STEPS'"
[[ "$ROUNDS" =~ ^[1-9][0-9]*$ ]] || die "--rounds must be a positive integer, got '$ROUNDS'"

bench_paths "$BUILD"
LMP_INPUT="$ROOT/bench/lammps/bed.in"
[[ -f "$LMP_INPUT" ]] || die "missing $LMP_INPUT"

LABEL=$(bed_label "$GRAINS")
BED="bench_cache/bed${LABEL}.bin"
DATA="bench_cache/${CASE}${LABEL}.data"
LABEL="${CASE}${LABEL}"   # the logs' names

# ------------------------------------------------------ physical parameters
# Must match what bench_bed simulates (see bench/README.md).
D=0.002            # diameter [m]
RHO=2500           # density [kg/m^3]
KN=500             # normal stiffness [N/m]
REST=0.5           # coefficient of restitution
MU=0.5             # Coulomb friction, pairs and walls
DT=1e-5            # time step [s]
SKIN=0.0004        # neighbor skin = 0.2 d [m]

# sandflow's normal dashpot is c_n = 2 beta sqrt(m_eff kn), and its normal
# force is clamped at zero. Its beta is not the textbook
# -ln e / sqrt(pi^2 + ln^2 e) (that gives e only for the unclamped law: the
# clamp lets grains leave faster) but the beta for which a head-on collision
# under the clamped law has restitution e (damping_beta() in
# src/dem/contact.cpp). bench_bed prints the beta it used ("beta=X"), and that
# is the one LAMMPS gets, so the two can never drift apart.

# lammps_damping BETA: sets GN GT GNW GTW, LAMMPS's damping rates [1/s].
# LAMMPS writes the dashpot as m_eff gamma v, so gamma_n = 2 beta sqrt(kn / m_eff)
# with m_eff = m/2 for two equal grains and m_eff = m against a wall (as in
# sandflow); gamma_t = gamma_n / 2 (sandflow: c_t = c_n / 2).
lammps_damping() {
  read -r GN GT GNW GTW < <(awk -v m="$MASS" -v kn="$KN" -v beta="$1" 'BEGIN {
    gn = 2 * beta * sqrt(kn / (m / 2)); gnw = 2 * beta * sqrt(kn / m)
    printf "%.12g %.12g %.12g %.12g\n", gn, gn / 2, gnw, gnw / 2
  }')
}

read -r KT MASS < <(awk -v d="$D" -v rho="$RHO" -v kn="$KN" 'BEGIN {
  printf "%.12g %.12g\n", kn * 2 / 7, rho * atan2(0, -1) / 6 * d * d * d
}')

# ------------------------------------------------------------- LAMMPS setup
# Debian's lammps depends on mpi-default-bin (openmpi-bin), so mpirun usually
# arrives with it; openmpi-bin is installed separately only if it did not.
command -v lmp >/dev/null 2>&1 || apt_install lammps
command -v lmp >/dev/null 2>&1 || die "lmp still not on PATH after installing lammps"
command -v mpirun >/dev/null 2>&1 || apt_install openmpi-bin
command -v mpirun >/dev/null 2>&1 || die "mpirun still not on PATH after installing openmpi-bin"
LMP=$(command -v lmp)
lmp_styles=$("$LMP" -h 2>/dev/null || true)
grep -q 'gran/hooke/history' <<<"$lmp_styles" \
  || die "$LMP has no pair_style gran/hooke/history (LAMMPS built without the GRANULAR package)"
grep -q 'contact/atom' <<<"$lmp_styles" || die "$LMP has no compute contact/atom"

MPIRUN=(mpirun)
[[ $(id -u) -eq 0 ]] && MPIRUN+=(--allow-run-as-root)
# Open MPI counts slots as physical cores; where it sees fewer than 2 it
# refuses -np 2 unless told --oversubscribe (which also makes waiting ranks
# yield the CPU, so use it only when needed).
if ! "${MPIRUN[@]}" -np 2 true >/dev/null 2>&1; then
  MPIRUN+=(--oversubscribe)
  "${MPIRUN[@]}" -np 2 true >/dev/null 2>&1 \
    || die "'${MPIRUN[*]} -np 2 true' fails: cannot start 2 MPI processes"
  note "mpirun needs --oversubscribe here (fewer than 2 cores seen)"
fi

# -------------------------------------------------------------- sandflow setup
ensure_bench_bed "$REBUILD"

# run_sandflow THREADS [extra args...]: sets SF_SECONDS SF_GSS SF_CPG
run_sandflow() {
  local t=$1; shift
  local log="$CACHE/sandflow_${LABEL}_t${t}.log"
  local cmd=("$BENCH_BED" --case "$CASE" --grains "$GRAINS" "$@" --threads "$t" --steps "$STEPS")
  [[ "$CASE" == bed ]] && cmd+=(--bed "$BED")
  note "sandflow, $t thread(s): ${cmd[*]}  (log: ${log#"$ROOT"/})"
  # threads bound to cores, one each, as mpirun binds LAMMPS's processes (--report-bindings:
  # "rank 0 bound to core 0, rank 1 to core 1"): unbound, the pour at 2 threads took 70.4 and
  # 71.9 s, bound 69.7 and 69.5 s (docs/performance.md, eighty-sixth)
  if ! OMP_NUM_THREADS=$t OMP_PROC_BIND=true OMP_PLACES=cores "${cmd[@]}" >"$log" 2>&1; then
    tail -n 20 "$log" >&2
    die "bench_bed failed (threads=$t), see $log"
  fi
  local line
  line=$(grep -E '^engine=' "$log" | tail -n1 || true)
  [[ -n "$line" ]] || { tail -n 20 "$log" >&2; die "no 'engine=' line in bench_bed's output, see $log"; }
  local g s
  g=$(field "$line" grains); s=$(field "$line" steps)
  SF_SECONDS=$(field "$line" seconds); SF_GSS=$(field "$line" grain_steps_per_s)
  SF_CPG=$(field "$line" contacts_per_grain); SF_Z=$(field "$line" mean_z)
  [[ "$g" == "$GRAINS" ]] || die "bench_bed reports grains=$g, expected $GRAINS: $line"
  [[ "$s" == "$STEPS" ]] || die "bench_bed reports steps=$s, expected $STEPS: $line"
  [[ -n "$SF_SECONDS" && -n "$SF_GSS" && -n "$SF_CPG" && -n "$SF_Z" ]] \
    || die "bench_bed's line lacks seconds, grain_steps_per_s, contacts_per_grain or mean_z: $line"
}

# run_lammps PROCS: sets LM_SECONDS LM_GSS LM_CPG
run_lammps() {
  local np=$1
  local log="$CACHE/lammps_${LABEL}_np${np}.log"
  local cmd=()
  # 1 process through mpirun too, so both runs get the same launcher and
  # core binding
  cmd=("${MPIRUN[@]}" -np "$np" "$LMP")
  cmd+=(-in "$LMP_INPUT" -log "$log" -screen none
        -var data "$ROOT/$DATA" -var kn "$KN" -var kt "$KT"
        -var gn "$GN" -var gt "$GT" -var gnw "$GNW" -var gtw "$GTW"
        -var mu "$MU" -var dt "$DT" -var skin "$SKIN"
        -var warm "$WARM" -var steps "$STEPS")
  note "LAMMPS, $np process(es)  (log: ${log#"$ROOT"/})"
  rm -f "$log"
  if ! OMP_NUM_THREADS=1 "${cmd[@]}" >"$CACHE/lammps_${LABEL}_np${np}.out" 2>&1; then
    { tail -n 20 "$log" 2>/dev/null; tail -n 20 "$CACHE/lammps_${LABEL}_np${np}.out"; } >&2
    die "LAMMPS failed ($np process(es)): ${cmd[*]}"
  fi
  # "Loop time of X on P procs for S steps with N atoms" of the timed run
  local loop
  loop=$(awk '/^SANDFLOW_BENCH_TIMED_RUN_BEGIN$/ {f = 1} f && /^Loop time of / {print; exit}' "$log")
  [[ -n "$loop" ]] || die "no 'Loop time' line after the timed-run marker in $log"
  local p s n
  read -r LM_SECONDS p s n < <(awk '{print $4, $6, $9, $12}' <<<"$loop")
  [[ "$p" == "$np" ]] || die "LAMMPS ran on $p procs, expected $np: $loop"
  [[ "$s" == "$STEPS" ]] || die "LAMMPS ran $s steps, expected $STEPS: $loop"
  [[ "$n" == "$GRAINS" ]] || die "LAMMPS has $n atoms at the end, expected $GRAINS (grains lost?): $loop"
  LM_CPG=$(awk '/^SANDFLOW_BENCH_CONTACTS_PER_GRAIN [-0-9.eE+]+$/ {v = $2} END {print v}' "$log")
  [[ -n "$LM_CPG" ]] || die "no contacts-per-grain line in $log"
  LM_Z=$(awk '/^SANDFLOW_BENCH_MEAN_Z [-0-9.eE+]+$/ {v = $2} END {print v}' "$log")
  [[ -n "$LM_Z" ]] || die "no mean-height line in $log"
  LM_GSS=$(awk -v n="$GRAINS" -v s="$STEPS" -v t="$LM_SECONDS" 'BEGIN {printf "%.6g", n * s / t}')
}

# ------------------------------------------------------------------ the runs
# Timings are only meaningful on an otherwise idle machine (2 cores here):
# a compile running alongside can slow the 2-process LAMMPS run several-fold.
# busy_percent: share of all CPU time spent busy over the next 2 seconds
busy_percent() {
  local a b
  a=$(head -n1 /proc/stat); sleep 2; b=$(head -n1 /proc/stat)
  awk -v a="$a" -v b="$b" 'BEGIN {
    na = split(a, x); split(b, y); tot = 0
    for (i = 2; i <= na; i++) tot += y[i] - x[i]
    idle = (y[5] - x[5]) + (y[6] - x[6])
    printf "%d\n", (tot > 0 ? 100 * (tot - idle) / tot : 0)
  }'
}
if [[ -r /proc/stat ]]; then
  busy=$(busy_percent)
  if (( busy > 10 )); then
    note "WARNING: the CPUs are ${busy}% busy before the benchmark starts: other work is running, timings will be unreliable"
  fi
fi
note "$CASE: $GRAINS grains, d=$D m, rho=$RHO kg/m^3, kn=$KN N/m, kt=$KT N/m, e=$REST, mu=$MU, dt=$DT s; timed steps: $STEPS; rounds: $ROUNDS"
[[ "$CASE" == pour || -f "$ROOT/$BED" ]] \
  || note "no cached bed $BED: bench_bed builds and settles it first (minutes)"

# The first sandflow run (2 threads: fastest if the bed must be settled) writes
# the settled bed for LAMMPS, so the two always start from one bed; it is not
# timed into the rounds (a bed built from scratch takes minutes).
run_sandflow 2 --write-lammps "$DATA"
[[ -s "$ROOT/$DATA" ]] || die "bench_bed did not write $DATA"
natoms=$(awk '$2 == "atoms" {print $1; exit}' "$ROOT/$DATA")
[[ "$natoms" == "$GRAINS" ]] || die "$DATA has '${natoms:-?}' atoms, expected $GRAINS"

# Each round: sandflow and LAMMPS on 1, then on 2. ROWS gathers one line a run:
# round engine threads seconds grain-steps/s contacts/grain mean_z.
ROWS=()
for ((round = 1; round <= ROUNDS; ++round)); do
  note "round $round of $ROUNDS"
  run_sandflow 1
  ROWS+=("$round sandflow 1 $SF_SECONDS $SF_GSS $SF_CPG $SF_Z")
  if [[ $round == 1 ]]; then
    # The beta bench_bed used (a "beta=X" word on its output) is the one LAMMPS gets.
    BETA=$(grep -ohE '(^|[[:space:]])beta=[-+0-9.eE]+' "$CACHE/sandflow_${LABEL}_t1.log" \
             | tail -n1 | sed 's/.*beta=//' || true)
    [[ -n "$BETA" ]] || die "bench_bed did not report the beta it used (beta=X)"
    lammps_damping "$BETA"
    note "sandflow beta=$BETA (as reported by bench_bed), m=$MASS kg"
    note "LAMMPS damping rates [1/s]: pairs gamma_n=$GN gamma_t=$GT, walls gamma_n=$GNW gamma_t=$GTW"
  fi
  run_lammps 1
  ROWS+=("$round LAMMPS 1 $LM_SECONDS $LM_GSS $LM_CPG $LM_Z")
  run_sandflow 2
  ROWS+=("$round sandflow 2 $SF_SECONDS $SF_GSS $SF_CPG $SF_Z")
  run_lammps 2
  ROWS+=("$round LAMMPS 2 $LM_SECONDS $LM_GSS $LM_CPG $LM_Z")
done

# ------------------------------------------------------------------- report
echo
if [[ "$CASE" == bed ]]; then
  echo "settled bed: $GRAINS grains, $STEPS timed steps (dt = $DT s), $ROUNDS round(s)"
else
  echo "pour: $GRAINS grains released onto the floor, $STEPS timed steps from the release (dt = $DT s), $ROUNDS round(s)"
fi
printf '%-6s %-9s %12s %10s %14s %15s %12s\n' round engine threads/procs seconds grain-steps/s contacts/grain mean_z_m
for r in "${ROWS[@]}"; do
  # shellcheck disable=SC2086  # (the row's words are its fields)
  printf '%-6s %-9s %12s %10.3f %14.4g %15.3f %12.5f\n' $r
done
echo

# the first round's figures for the like-for-like check (every round runs the same grains)
pick() { printf '%s\n' "${ROWS[@]}" | awk -v e="$1" -v t="$2" '$1 == 1 && $2 == e && $3 == t {print $4, $5, $6, $7}'; }
read -r -a SF1 <<<"$(pick sandflow 1)"
read -r -a SF2 <<<"$(pick sandflow 2)"
read -r -a LM1 <<<"$(pick LAMMPS 1)"
read -r -a LM2 <<<"$(pick LAMMPS 2)"

status=0
# bed: the same grains, so the same contacts; pour: two engines' chaotic paths part within
# milliseconds, but the heap they make is the same to within what its seeds scatter
if [[ "$CASE" == bed ]]; then CPG_LIMIT=5; Z_LIMIT=1; else CPG_LIMIT=10; Z_LIMIT=2; fi
check=$(awk -v s1="${SF1[2]}" -v s2="${SF2[2]}" -v l1="${LM1[2]}" -v l2="${LM2[2]}" \
            -v z1="${SF1[3]}" -v z2="${SF2[3]}" -v y1="${LM1[3]}" -v y2="${LM2[3]}" \
            -v climit="$CPG_LIMIT" -v zlimit="$Z_LIMIT" 'BEGIN {
  s = (s1 + s2) / 2; l = (l1 + l2) / 2; zs = (z1 + z2) / 2; zl = (y1 + y2) / 2
  if (l <= 0 || s <= 0 || zl <= 0) { printf "FAIL %.3f %.3f inf %.5f %.5f inf\n", s, l, zs, zl; exit }
  rel = (s > l ? s - l : l - s) / l * 100; zrel = (zs > zl ? zs - zl : zl - zs) / zl * 100
  printf "%s %.3f %.3f %.2f %.5f %.5f %.2f\n", (rel <= climit && zrel <= zlimit ? "OK" : "FAIL"),
         s, l, rel, zs, zl, zrel
}')
read -r verdict cs cl rel zs zl zrel <<<"$check"
what="contacts per grain: sandflow $cs, LAMMPS $cl (${rel}%, limit ${CPG_LIMIT}%); mean height: sandflow $zs m, LAMMPS $zl m (${zrel}%, limit ${Z_LIMIT}%)"
if [[ "$verdict" == OK ]]; then
  echo "$what: like for like"
else
  echo "FAIL: $what."
  echo "FAIL: the two engines are not simulating the same grains; the ratios below are NOT like for like."
  echo "compare_lammps.sh: FAIL: $what: not like for like" >&2
  status=3
fi
# each round's ratios, then their medians
printf '%s\n' "${ROWS[@]}" | awk -v rounds="$ROUNDS" '
  { gss[$1, $2, $3] = $5 }
  function median(a, n,   i, j, t) {
    for (i = 2; i <= n; i++) for (j = i; j > 1 && a[j - 1] > a[j]; j--) { t = a[j]; a[j] = a[j - 1]; a[j - 1] = t }
    return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
  }
  END {
    for (r = 1; r <= rounds; r++) {
      r1[r] = gss[r, "sandflow", 1] / gss[r, "LAMMPS", 1]; r2[r] = gss[r, "sandflow", 2] / gss[r, "LAMMPS", 2]
      ss[r] = gss[r, "sandflow", 2] / gss[r, "sandflow", 1]; sl[r] = gss[r, "LAMMPS", 2] / gss[r, "LAMMPS", 1]
      if (rounds > 1)
        printf "round %d: ratio_1=%.2f ratio_2=%.2f scaling_sandflow=%.2f scaling_lammps=%.2f\n", r, r1[r], r2[r], ss[r], sl[r]
    }
    printf "ratio_1=%.2f ratio_2=%.2f scaling_sandflow=%.2f scaling_lammps=%.2f\n",
           median(r1, rounds), median(r2, rounds), median(ss, rounds), median(sl, rounds)
  }'
exit $status
