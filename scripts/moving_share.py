#!/usr/bin/python3
"""The share of a run's grains that move over its last half, and what a surface run simulates.

    scripts/moving_share.py RUN [RUN ...] [--speed 0.02] [--every 5] [--first F]

For each run folder (RUN/frames/NNNN.ply and RUN/stats.csv) and every --every-th frame from --first
(default: the second half of the frames, as `compare`'s simulated_fraction_last_half), the grains
faster than --speed (m/s), and those at rest that touch one (centres nearer than the two radii).
As in `compare`, each share is the sum over the frames divided by the sum of all grains present
(n_total in stats.csv): a plain-DEM run gives a floor under what any split of the grains into a
moving layer and a frozen layer in contact with it must simulate. Where the PLY has `state` (in
plain DEM every grain is ACTIVE), also the ACTIVE grains by speed, the slow ones touching a fast
one or within 2 d of one, and the INTERFACE grains (docs/performance.md, 2026-12-07).
(Standard library only, the frame reader of flowing_layer.py.)
"""
import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flowing_layer import ACTIVE, INTERFACE, grains_of  # noqa: E402


def totals_of(run):
    """n_total per frame, from RUN/stats.csv."""
    path = os.path.join(run, "stats.csv")
    try:
        with open(path, newline="") as f:
            return {int(row["frame"]): int(row["n_total"]) for row in csv.DictReader(f)}
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"moving_share.py: {path}: {e}")


def near_counts(grains, fast, reach):
    """Per grain not in `fast`: whether a fast grain's centre lies within r_i + r_j (touching) and
    within `reach` (m) of its surface. Neighbours come from a grid of cells of the search radius."""
    rmax = max(g[3] for g in grains)
    cell = 2 * rmax + reach
    grid = {}
    for k in fast:
        g = grains[k]
        grid.setdefault((math.floor(g[0] / cell), math.floor(g[1] / cell),
                         math.floor(g[2] / cell)), []).append(k)
    touching, within = set(), set()
    for i, g in enumerate(grains):
        if i in fast:
            continue
        cx, cy, cz = math.floor(g[0] / cell), math.floor(g[1] / cell), math.floor(g[2] / cell)
        for a in (-1, 0, 1):
            for b in (-1, 0, 1):
                for c in (-1, 0, 1):
                    for k in grid.get((cx + a, cy + b, cz + c), ()):
                        f = grains[k]
                        gap = math.dist(g[:3], f[:3]) - g[3] - f[3]
                        if gap < 0:
                            touching.add(i)
                        if gap < reach:
                            within.add(i)
    return touching, within


def shares(run, speed, every, first):
    totals = totals_of(run)
    folder = os.path.join(run, "frames")
    frames = sorted(int(n[:-4]) for n in (os.listdir(folder) if os.path.isdir(folder) else [])
                    if n.endswith(".ply") and n[:-4].isdigit())
    if not frames:
        sys.exit(f"moving_share.py: {run}/frames: no PLY frames (run with --export ply)")
    # (compare's last half: frames n/2 + 1 to n of a run of n frames)
    start = first if first is not None else max(frames) // 2 + 1
    picked = [f for f in frames if f >= start and (f - start) % every == 0]
    if not picked:
        sys.exit(f"moving_share.py: {run}/frames: no frame from {start} on")
    sums = {}

    def add(key, value):
        sums[key] = sums.get(key, 0) + value

    for fr in picked:
        if fr not in totals:
            sys.exit(f"moving_share.py: {run}: frame {fr} is not in stats.csv")
        grains = grains_of(os.path.join(folder, f"{fr:04d}.ply"))
        d = 2 * sum(g[3] for g in grains) / max(len(grains), 1)
        fast = {i for i, g in enumerate(grains) if g[4] > speed}
        touching, within = near_counts(grains, fast, 2 * d)
        add("all grains", totals[fr])
        add("in the frames", len(grains))
        add(f"faster than {speed:g} m/s", len(fast))
        add("  and those touching them", len(fast) + len(touching))
        state = [g[5] for g in grains]
        if any(s >= 0 for s in state):
            add("ACTIVE", state.count(ACTIVE))
            add(f"  faster than {speed:g} m/s", sum(1 for i in fast if state[i] == ACTIVE))
            slow = [i for i, s in enumerate(state) if s == ACTIVE and i not in fast]
            add("  slower", len(slow))
            add("    touching a faster one", sum(1 for i in slow if i in touching))
            add("    within 2 d of a faster one", sum(1 for i in slow if i in within))
            add("INTERFACE", state.count(INTERFACE))
    print(f"# {run}: frames {picked[0]}-{picked[-1]}, every {every} ({len(picked)} frames); "
          f"share of all grains present")
    for key, value in sums.items():
        if key != "all grains":
            print(f"{key:34s} {100 * value / sums['all grains']:6.2f} %")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="run folders (with frames/*.ply and stats.csv)")
    ap.add_argument("--speed", type=float, default=0.02, help="moving: faster than this, m/s")
    ap.add_argument("--every", type=int, default=5, help="take every N-th frame")
    ap.add_argument("--first", type=int, help="first frame (default: the last half's first)")
    a = ap.parse_args()
    if not (a.speed > 0) or a.every < 1 or (a.first is not None and a.first < 0):
        sys.exit("moving_share.py: --speed must be > 0, --every >= 1, --first >= 0")
    for run in a.runs:
        shares(run, a.speed, a.every, a.first)


if __name__ == "__main__":
    main()
