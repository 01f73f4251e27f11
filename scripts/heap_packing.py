#!/usr/bin/python3
"""How densely a heap's core is packed, and how far its grains overlap there.

    scripts/heap_packing.py RUN_OR_PLY [RUN_OR_PLY ...] [--center X,Y]

For each heap (a PLY frame or a run folder's final_grains.ply): the apex height (the highest
grain centre within 3 cm of the axis), the foot (the radius holding 95 % of the grains), and in
the core, a cylinder about the axis of 0.4 times the foot's radius between 10 % and 50 % of the
apex height, the packing fraction (the grains' volume whose centres lie in it, over its volume),
the contacts per grain and the mean overlap of a contact in diameters (r_i + r_j - distance, over
r_i + r_j). Two runs of one scene with the same grains but packed differently stand differently:
the denser one has less sand left for its foot. (Standard library only: the PLY reader is
column_collapse.py's.)
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from column_collapse import read_ply  # noqa: E402


def core_figures(grains, cx, cy):
    rho = [math.hypot(x - cx, y - cy) for x, y, _, _ in grains]
    apex = max(g[2] for g, q in zip(grains, rho) if q < 0.03)
    foot = sorted(rho)[int(0.95 * (len(rho) - 1))]
    r_core, z_lo, z_hi = 0.4 * foot, 0.1 * apex, 0.5 * apex
    core = [k for k, (g, q) in enumerate(zip(grains, rho)) if q < r_core and z_lo < g[2] < z_hi]
    solid = sum(4 / 3 * math.pi * grains[k][3] ** 3 for k in core)
    packing = solid / (math.pi * r_core**2 * (z_hi - z_lo))
    # contacts of the core's grains, through a grid of cells of the largest diameter
    cell = 2 * max(g[3] for g in grains)
    cells = {}
    for k, (x, y, z, _) in enumerate(grains):
        cells.setdefault((math.floor(x / cell), math.floor(y / cell), math.floor(z / cell)), []).append(k)
    contacts, overlap = 0, 0.0
    for k in core:
        x, y, z, r = grains[k]
        i, j, l = math.floor(x / cell), math.floor(y / cell), math.floor(z / cell)
        for a in (-1, 0, 1):
            for b in (-1, 0, 1):
                for c in (-1, 0, 1):
                    for m in cells.get((i + a, j + b, l + c), ()):
                        if m == k:
                            continue
                        X, Y, Z, R = grains[m]
                        ov = (r + R - math.sqrt((x - X) ** 2 + (y - Y) ** 2 + (z - Z) ** 2)) / (r + R)
                        if ov > 0:
                            contacts += 1
                            overlap += ov
    return apex, foot, packing, contacts / max(len(core), 1), overlap / max(contacts, 1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="PLY frames or run folders")
    ap.add_argument("--center", default="0,0", help="the heap's axis, X,Y in m (default 0,0)")
    a = ap.parse_args()
    try:
        cx, cy = (float(v) for v in a.center.split(","))
    except ValueError:
        sys.exit(f"heap_packing.py: --center {a.center}: expected X,Y in metres")
    print("apex_m foot_m core_packing contacts_per_grain mean_overlap_d  run")
    for run in a.runs:
        p = os.path.join(run, "final_grains.ply") if os.path.isdir(run) else run
        if not os.path.isfile(p):
            sys.exit(f"heap_packing.py: {p}: no such file (a PLY frame or a run folder)")
        grains = list(read_ply(p))
        if not any(math.hypot(x - cx, y - cy) < 0.03 for x, y, _, _ in grains):
            sys.exit(f"heap_packing.py: {p}: no grain within 3 cm of the axis {a.center}")
        apex, foot, packing, per_grain, mean_ov = core_figures(grains, cx, cy)
        print(f"{apex:.3f} {foot:.3f} {packing:.4f} {per_grain:.2f} {mean_ov:.4f}  {run}")


if __name__ == "__main__":
    main()
