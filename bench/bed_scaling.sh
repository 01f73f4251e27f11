#!/usr/bin/env bash
# How the cost of a frame grows with a bed at rest around the same disturbance (issue 26): a bed
# of 1 cm grains 10 cm deep in a sandbox, of about 1, 2, 4 and 8 million grains, with the same
# block of 1,000 grains thrown into its middle at 3 m/s, in surface mode. Per size it prints the
# grains, the grains simulated (ACTIVE + INTERFACE, mean over the timed frames), the seconds per
# frame (the mean over the frames after the first, which holds the start's one-off work: the
# first pass over the static grains), the peak resident memory, the static store's bytes per
# grain and the final checkpoint's size; the last line is
#   growth_per_doubling=X bytes_per_static=Y
# X: the geometric mean of the ratios of seconds per frame between successive sizes, taken to
# the power 1/log2(size ratio) (1.00: the cost does not follow the bed at all); Y: the largest
# bytes per static grain of the sizes.
#
# usage: bench/bed_scaling.sh [--sizes "1 2 4 8"] [--frames N] [--threads N] [--build DIR]
#        bench/bed_scaling.sh --sizes 10     (the ten-million-grain bed, once)
# Sizes are in millions of grains. Runs on an otherwise idle machine; the default sizes take about
# 10 minutes on 2 cores (most of it packing the beds: the loader and the world each pack one).
# Needs /usr/bin/python3 (no packages beyond the standard library).
set -euo pipefail

sizes="1 2 4 8"
frames=12
threads=1
build=build
while [ $# -gt 0 ]; do
  case "$1" in
    --sizes) sizes="$2"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    *) echo "usage: bench/bed_scaling.sh [--sizes \"1 2 4 8\"] [--frames N] [--threads N] [--build DIR]" >&2
       exit 2 ;;
  esac
done
root=$(cd "$(dirname "$0")/.." && pwd)
sandflow=$(realpath "$root/$build/sandflow" 2>/dev/null || true)
[ -x "$sandflow" ] || { echo "no sandflow in $root/$build (build it: ./setup.sh build)" >&2; exit 2; }
[ "$frames" -ge 3 ] || { echo "--frames must be at least 3" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

printf '%-9s %11s %10s %11s %12s %10s %12s\n' size grains simulated s/frame peak_MB B/static checkpoint_MB
results="$work/results.txt"
: >"$results"
for m in $sizes; do
  # a square footprint a whole number of centimetres wide (the grid's columns, so the sandbox's
  # walls run between them), holding about m million grains 10 cm deep at the bed's packing
  side=$(/usr/bin/python3 -c "import math; v=$m*1e6*math.pi/6*1e-6*1.03/0.58; print('%.2f' % (math.ceil(math.sqrt(v/0.1)*100)/100))")
  scene="$work/bed_$m.toml"
  cat >"$scene" <<EOF
[scene]
name = "bed_scaling_$m"
[material]
density = 2600.0
diameter = 0.01
diameter_spread = 0.1
k_n = 1.0e4
restitution = 0.3
friction = 0.6
rolling_friction = 0.3
wall_friction = 0.6
wall_rolling_friction = 0.3
[simulation]
mode = "surface"
seed = 1
[stiffness]
from_load = true
[surface]
repose_angle = 33        # (not calibrated: the same for every size, and no calibration run)
max_angle = 39
[output]
fps = 30
duration = $(/usr/bin/python3 -c "print($frames/30)")
export = []
[[geometry]]
type = "box"
container = true
center = [0, 0, 0.25]
size = [$side, $side, 0.5]
[[emitter]]
type = "bed"
center = [0, 0, 0]
size = [$side, $side, 0]
height = 0.1
[[emitter]]
type = "block"
count = 1000
center = [0, 0, 0.2]
size = [0.12, 0.12, 0.12]
velocity = [0, 0, -3]
EOF
  out="$work/run_$m"
  args=(run "$scene" --out "$out" --checkpoint-every 100000)
  [ -n "$threads" ] && args+=(--threads "$threads")
  "$sandflow" "${args[@]}" >"$work/log_$m.txt" 2>&1 || { cat "$work/log_$m.txt" >&2; exit 1; }
  /usr/bin/python3 - "$out" "$m" >>"$results" <<'PY'
import csv, json, os, sys
out, m = sys.argv[1], sys.argv[2]
s = json.load(open(os.path.join(out, "summary.json")))
rows = list(csv.DictReader(open(os.path.join(out, "stats.csv"))))[1:]
sec = sum(float(r["wall_seconds"]) for r in rows) / len(rows)
sim = sum(int(r["n_active"]) + int(r["n_interface"]) for r in rows) / len(rows)
grains = int(rows[-1]["n_total"])
ck = [os.path.join(out, f) for f in os.listdir(out) if f.startswith("checkpoint")]
ck_mb = sum(os.path.getsize(f) for f in ck if os.path.isfile(f)) / 1e6
print(m, grains, round(sim), sec, s["peak_memory_bytes"] / 1e6, s["bytes_per_static_grain"], ck_mb)
PY
  tail -1 "$results" | awk '{printf "%-9s %11d %10d %11.3f %12.0f %10.2f %12.1f\n", $1 "M", $2, $3, $4, $5, $6, $7}'
done
/usr/bin/python3 - "$results" <<'PY'
import math, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
g = [float(r[1]) for r in rows]
sec = [float(r[3]) for r in rows]
exps = [math.log(sec[i + 1] / sec[i]) / math.log2(g[i + 1] / g[i]) for i in range(len(rows) - 1)]
growth = "%.3f" % math.exp(sum(exps) / len(exps)) if exps else "n/a"  # one size: no ratio
print("growth_per_doubling=%s bytes_per_static=%.2f" % (growth, max(float(r[5]) for r in rows)))
PY
