#!/usr/bin/python3
"""How deep the sand moves, and what a surface run simulates beside it, frame by frame.

    scripts/flowing_layer.py RUN [RUN ...] --frames 300,420,449 [--speed 0.02] [--cell 0.02]

For each run folder and frame (RUN/frames/NNNN.ply), the grains moving faster than --speed (m/s)
below the sand's top, how deep they lie (in grain diameters below the top of their cell of side
--cell), and in how many cells. Where the PLY has `state` also the ACTIVE and INTERFACE grains,
and the ACTIVE grains idle: with no moving grain in their cell or the eight around it (in plain
DEM every grain is ACTIVE, so there "idle" counts the grains at rest). With the `height` export (RUN/heightfield/) a surface run adds the rolling layer R = H - h
of its sand columns in diameters and the share of those columns (R over 1.5 d) whose static top
stands at theta_max towards a lower neighbour, where the exchange deposits nothing more.
Plain DEM and surface flow side by side say whether the surface run's ACTIVE layer is deeper
than the sand that moves (docs/performance.md, 2026-11-29).
(Standard library only, the PLY and PNG readers of column_collapse.py and heap_profile.py.)
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from column_collapse import read_ply  # noqa: E402
from heap_profile import read_png16  # noqa: E402

ACTIVE, INTERFACE = 0, 1


def quantiles(values, ps):
    v = sorted(values)
    return [v[int(p * (len(v) - 1))] if v else math.nan for p in ps]


def grains_of(path):
    """(x, y, z, radius, speed, state) per grain; state -1 where the PLY has none (plain DEM)."""
    with open(path, "rb") as f:
        has_state = b"property uchar state" in f.read(4096)
    names = ("x", "y", "z", "radius", "vx", "vy", "vz") + (("state",) if has_state else ())
    out = []
    for g in read_ply(path, names):
        state = int(g[7]) if has_state else -1
        out.append((g[0], g[1], g[2], g[3], math.sqrt(g[4] ** 2 + g[5] ** 2 + g[6] ** 2), state))
    return out


def frame_line(run, frame, speed, cell):
    path = os.path.join(run, "frames", f"{frame:04d}.ply")
    if not os.path.isfile(path):
        sys.exit(f"flowing_layer.py: {path}: no such frame")
    grains = grains_of(path)
    d = 2 * sum(g[3] for g in grains) / max(len(grains), 1)
    key = lambda g: (math.floor(g[0] / cell), math.floor(g[1] / cell))  # noqa: E731
    top = {}
    for g in grains:
        top[key(g)] = max(top.get(key(g), -math.inf), g[2] + g[3])
    deepest, depths = {}, []
    for g in grains:
        depth = (top[key(g)] - g[2]) / d
        # (a stream in free fall has no top below it: only grains within the sand count)
        if g[4] > speed and depth < 50:
            depths.append(depth)
            deepest[key(g)] = max(deepest.get(key(g), 0.0), depth)
    q50, q90 = quantiles(depths, (0.5, 0.9))
    line = (f"{frame:5d} {len(grains):8d} {len(depths):8d} {q50:6.2f} {q90:6.2f} "
            f"{len(deepest):6d}/{len(top):<6d}")
    active = [g for g in grains if g[5] == ACTIVE]
    if any(g[5] >= 0 for g in grains):
        near = lambda k: any((k[0] + a, k[1] + b) in deepest  # noqa: E731
                             for a in (-1, 0, 1) for b in (-1, 0, 1))
        idle = sum(1 for g in active if not near(key(g)))
        line += (f" {len(active):8d} {sum(1 for g in grains if g[5] == INTERFACE):8d} "
                 f"{idle:8d}")
    line += rolling_layer(run, frame, d)
    return line


def rolling_layer(run, frame, d):
    """R quantiles over the sand columns and the share of those with R > 1.5 d held at theta_max."""
    folder = os.path.join(run, "heightfield")
    try:
        with open(os.path.join(folder, "heightfield.json")) as f:
            meta = json.load(f)
        with open(os.path.join(run, "summary.json")) as f:
            theta_max = math.radians(json.load(f)["height_field"]["max_angle_deg"])
        H = read_png16(os.path.join(folder, f"H_{frame:04d}.png"))
        h = read_png16(os.path.join(folder, f"h_{frame:04d}.png"))
    except (OSError, KeyError, ValueError):
        return ""
    scale = (meta["png"]["z_max"] - meta["png"]["z_min"]) / 65535
    dx = meta["cell_size"]
    ny, nx = len(H), len(H[0])
    R, deep, pinned = [], 0, 0
    for y in range(ny):
        for x in range(nx):
            if H[y][x] <= 0:  # (no sand: H is the terrain, the floor at z_min here)
                continue
            r = (H[y][x] - h[y][x]) * scale / d
            R.append(r)
            if r <= 1.5:
                continue
            deep += 1
            # the exchange's slope: on each axis the steeper edge down from the column
            gx = max([0.0] + [(h[y][x] - h[y][i]) * scale / dx for i in (x - 1, x + 1) if 0 <= i < nx])
            gy = max([0.0] + [(h[y][x] - h[j][x]) * scale / dx for j in (y - 1, y + 1) if 0 <= j < ny])
            # (within 1 %: h is read back from 16-bit levels)
            pinned += math.hypot(gx, gy) >= math.tan(theta_max) * 0.99
    q = quantiles(R, (0.25, 0.5, 0.75))
    return (f"  {q[0]:5.2f} {q[1]:5.2f} {q[2]:5.2f} {deep:6d} "
            f"{pinned / deep if deep else 0:5.1%}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="run folders (with frames/)")
    ap.add_argument("--frames", required=True, help="comma-separated frame numbers")
    ap.add_argument("--speed", type=float, default=0.02, help="moving: faster than this, m/s")
    ap.add_argument("--cell", type=float, default=0.02, help="cell side for the sand's top, m")
    a = ap.parse_args()
    try:
        frames = [int(f) for f in a.frames.split(",")]
    except ValueError:
        sys.exit(f"flowing_layer.py: --frames {a.frames}: expected frame numbers, comma-separated")
    if not (a.speed > 0 and a.cell > 0) or any(f < 0 for f in frames):
        sys.exit("flowing_layer.py: --speed and --cell must be > 0, frames >= 0")
    for run in a.runs:
        print(f"# {run}")
        print("frame   grains   moving dep50d dep90d  cells(moving/all)   active interface"
              "     idle    R25d  R50d  R75d R>1.5d at_theta_max")
        for f in frames:
            print(frame_line(run, f, a.speed, a.cell))


if __name__ == "__main__":
    main()
