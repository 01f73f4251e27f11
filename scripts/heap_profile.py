#!/usr/bin/python3
"""The radial profile of heaps: height and local slope against distance from an axis.

    scripts/heap_profile.py RUN_OR_PLY [RUN_OR_PLY ...] [--center X,Y] [--cell 0.01] [--step 3]

Each argument is a PLY frame or a run folder (its final_grains.ply). The top of each cell of
side --cell (m) is its highest grain top (z + r); a ring of width --cell about the axis at
--center (default the origin, the pour axis of scenes/floor.toml) takes the median of its cells'
tops. Prints every --step-th ring: its radius, each heap's height there, and each heap's slope in
degrees over the next --step rings. For reading where two heaps differ (the flank, the foot, the
apex), beside the single angle `sandflow measure` fits.
(Standard library only: the PLY reader is column_collapse.py's.)
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from column_collapse import median, read_ply  # noqa: E402


def profile(path, cx, cy, cell):
    tops = {}
    for x, y, z, r in read_ply(path):
        key = (math.floor(x / cell), math.floor(y / cell))
        tops[key] = max(tops.get(key, -math.inf), z + r)
    rings = {}
    for (i, j), top in tops.items():
        rho = math.hypot((i + 0.5) * cell - cx, (j + 0.5) * cell - cy)
        rings.setdefault(int(rho / cell), []).append(top)
    last = max(rings)
    return [median(rings[k]) if k in rings else math.nan for k in range(last + 1)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="PLY frames or run folders")
    ap.add_argument("--center", default="0,0", help="the axis, X,Y in m (default 0,0)")
    ap.add_argument("--cell", type=float, default=0.01, help="cell and ring width in m")
    ap.add_argument("--step", type=int, default=3, help="print every STEP-th ring")
    a = ap.parse_args()
    try:
        cx, cy = (float(v) for v in a.center.split(","))
    except ValueError:
        sys.exit(f"heap_profile.py: --center {a.center}: expected X,Y in metres")
    if not (a.cell > 0 and a.step >= 1):
        sys.exit("heap_profile.py: --cell must be > 0 and --step >= 1")
    paths = []
    for run in a.runs:
        p = os.path.join(run, "final_grains.ply") if os.path.isdir(run) else run
        if not os.path.isfile(p):
            sys.exit(f"heap_profile.py: {p}: no such file (a PLY frame or a run folder)")
        paths.append(p)
    profiles = [profile(p, cx, cy, a.cell) for p in paths]
    for k, p in enumerate(paths):
        print(f"# [{k}] {p}")
    n = max(len(pr) for pr in profiles)
    print("radius_m " + " ".join(f"h[{k}]_m" for k in range(len(paths))) + "  " +
          " ".join(f"slope[{k}]_deg" for k in range(len(paths))))
    for ring in range(0, n, a.step):
        h = [pr[ring] if ring < len(pr) else math.nan for pr in profiles]
        s = []
        for pr in profiles:
            far = ring + a.step
            if far < len(pr) and not math.isnan(pr[ring]) and not math.isnan(pr[far]):
                s.append(math.degrees(math.atan((pr[ring] - pr[far]) / (a.step * a.cell))))
            else:
                s.append(math.nan)
        print(f"{(ring + 0.5) * a.cell:.3f} " + " ".join(f"{v:.3f}" for v in h) + "  " +
              " ".join(f"{v:5.1f}" for v in s))


if __name__ == "__main__":
    main()
