#!/usr/bin/python3
"""What sand poured onto a bed left on it, plain DEM against surface flow, against the seeds' noise.

    scripts/deposit_compare.py COMPARE_DIR BED_RUN [BED_RUN ...] [--cell 0.01] [--below Z]

COMPARE_DIR is a `sandflow compare --seeds K` folder; BED_RUN k is a run of the same scene and
overrides with `simulation.seed` = seed k, stopped before the poured sand reaches the bed (for
example `sandflow run SCENE ... --set simulation.seed=K --frames 1 --export none --out BED_RUN`):
its grains below --below (m, default: all) are the bed as packed, the same in both modes for a
seed. Per cell of side --cell (m), the deposit is a run's final top (the highest grain top, z + r)
minus the bed's. Prints per seed and mode the deposit's volume (its positive part) and peak, then
the RMS difference of the deposits over the cells where either exceeds a cell's side: surface flow
against plain DEM of the same seed, and plain DEM between seeds (the noise floor). The deposit
takes the bed's packing out of the comparison, which a surface-to-surface distance over the whole
bed does not (two seeds' beds differ everywhere, one seed's two modes nowhere but where sand fell).
(Standard library only: the PLY reader is column_collapse.py's.)
"""
import argparse
import itertools
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from column_collapse import read_ply  # noqa: E402


def top(grains, cell, below=math.inf):
    m = {}
    for x, y, z, r in grains:
        if z > below:
            continue
        k = (math.floor(x / cell), math.floor(y / cell))
        m[k] = max(m.get(k, -math.inf), z + r)
    return m


def rms(a, b, cell):
    cells = [k for k in a if k in b and (a[k] > cell or b[k] > cell)]
    if not cells:
        return 0.0, 0
    return math.sqrt(sum((a[k] - b[k]) ** 2 for k in cells) / len(cells)), len(cells)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("compare_dir")
    ap.add_argument("bed_runs", nargs="+")
    ap.add_argument("--cell", type=float, default=0.01)
    ap.add_argument("--below", type=float, default=math.inf)
    a = ap.parse_args()
    with open(os.path.join(a.compare_dir, "compare_plan.json")) as f:
        seeds = json.load(f).get("seeds", 1)
    if len(a.bed_runs) != seeds:
        sys.exit(f"{a.compare_dir} holds {seeds} seeds per mode: give one bed run per seed")
    dep = {}
    for s in range(seeds):
        folder = a.compare_dir if s == 0 else os.path.join(a.compare_dir, f"seed-{s + 1}")
        bed = top(read_ply(os.path.join(a.bed_runs[s], "final_grains.ply")), a.cell, a.below)
        for mode in ("dem", "surface"):
            t = top(read_ply(os.path.join(folder, mode, "final_grains.ply")), a.cell)
            d = {k: t.get(k, h) - h for k, h in bed.items()}
            dep[(s, mode)] = d
            volume = sum(max(v, 0.0) for v in d.values()) * a.cell * a.cell
            print(f"seed {s + 1} {mode:8s} deposit {volume * 1e6:8.0f} cm3, "
                  f"peak {max(d.values()) * 100:6.2f} cm")
    c = a.cell
    same = [rms(dep[(s, "surface")], dep[(s, "dem")], c) for s in range(seeds)]
    print("surface flow vs plain DEM, same seed: " +
          ", ".join(f"{r / c:.2f} cells over {n}" for r, n in same) +
          f"; mean {sum(r for r, _ in same) / len(same) / c:.2f} cells")
    if seeds > 1:
        noise = [rms(dep[(i, "dem")], dep[(j, "dem")], c)
                 for i, j in itertools.combinations(range(seeds), 2)]
        print("plain DEM vs plain DEM, seed pairs: " +
              ", ".join(f"{r / c:.2f} cells over {n}" for r, n in noise) +
              f"; mean {sum(r for r, _ in noise) / len(noise) / c:.2f} cells")


if __name__ == "__main__":
    main()
