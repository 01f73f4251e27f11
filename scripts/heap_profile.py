#!/usr/bin/python3
"""The radial profile of heaps: height and local slope against distance from an axis.

    scripts/heap_profile.py RUN_OR_PLY [RUN_OR_PLY ...] [--center X,Y] [--cell 0.01] [--step 3]
                            [--stream-speed 1.0] [--speeds]

Each argument is a PLY frame or a run folder (its final_grains.ply). The top of each cell of
side --cell (m) is its highest grain top (z + r); a ring of width --cell about the axis at
--center (default the origin, the pour axis of scenes/floor.toml) takes the median of its cells'
tops. Prints every --step-th ring: its radius, each heap's height there, and each heap's slope in
degrees over the next --step rings. For reading where two heaps differ (the flank, the foot, the
apex), beside the single angle `sandflow measure` fits.

Mid-run frames: grains falling faster than --stream-speed (m/s; a pour's stream in flight) are
left out, so the stream does not stand as a spike on the apex. A surface run's frame
(RUN/frames/NNNN.ply) holds only its simulated grains; the sand's top in a column whose grains
sleep is the height field's H, so when RUN/heightfield/H_NNNN.png is there (the `height`
export) every cell's top is at least H there. --speeds adds, per ring and heap, the mean speed
(m/s) of the grains whose top lies within two cells of their cell's top: how fast the surface
layer flows.
(Standard library only: the PLY reader is column_collapse.py's, and the 16-bit grey PNG of
sandflow's own height export is decoded here in a few lines rather than adding a Python package
to the set-up for one script.)
"""
import argparse
import json
import math
import os
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from column_collapse import median, read_ply  # noqa: E402


def read_grains(path):
    """(x, y, z, radius, vx, vy, vz) of every vertex; velocities 0 where the PLY has none."""
    return read_ply(path, ("x", "y", "z", "radius", "vx", "vy", "vz"))


def read_png16(path):
    """Rows of a 16-bit grey, non-interlaced PNG (sandflow's height export), top row first."""
    with open(path, "rb") as f:
        data = f.read()
    pos, idat, width, height = 8, b"", 0, 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", chunk[:10])
            if depth != 16 or colour != 0 or chunk[12] != 0:
                sys.exit(f"heap_profile.py: {path}: not a 16-bit grey, non-interlaced PNG")
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + n
    raw, stride, rows = zlib.decompress(idat), 2 * width, []
    prev = bytearray(stride)
    for k in range(height):
        kind = raw[k * (stride + 1)]
        line = bytearray(raw[k * (stride + 1) + 1:(k + 1) * (stride + 1)])
        for i in range(stride):  # the five PNG filters, 2 bytes a pixel
            a = line[i - 2] if i >= 2 else 0
            b, c = prev[i], (prev[i - 2] if i >= 2 else 0)
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([line[2 * i] << 8 | line[2 * i + 1] for i in range(width)])
        prev = line
    return rows


def height_field_tops(ply_path):
    """(x, y, H) of every column holding sand, for a surface run's frame; [] when none."""
    frames = os.path.dirname(os.path.abspath(ply_path))
    run = os.path.dirname(frames)
    number = os.path.splitext(os.path.basename(ply_path))[0]
    meta_path = os.path.join(run, "heightfield", "heightfield.json")
    png_path = os.path.join(run, "heightfield", f"H_{number}.png")
    if os.path.basename(frames) != "frames" or not os.path.isfile(png_path):
        return []
    with open(meta_path) as f:
        meta = json.load(f)
    z_min, z_max = meta["png"]["z_min"], meta["png"]["z_max"]
    (ox, oy), cell = meta["origin"], meta["cell_size"]
    rows = read_png16(png_path)
    out = []
    for r, row in enumerate(rows):
        y = oy + (len(rows) - 1 - r + 0.5) * cell  # row 0 holds the highest y
        for i, grey in enumerate(row):
            out.append((ox + (i + 0.5) * cell, y, z_min + grey / 65535 * (z_max - z_min)))
    return out


def profile(path, cx, cy, cell, stream_speed):
    """Per ring: (median top, mean speed of the surface layer)."""
    grains = [g for g in read_grains(path) if g[6] >= -stream_speed]
    tops = {}
    for x, y, z, r, *_ in grains:
        key = (math.floor(x / cell), math.floor(y / cell))
        tops[key] = max(tops.get(key, -math.inf), z + r)
    columns = height_field_tops(path)
    # a column holds sand where H stands above the lowest grain's bottom by half a grain (an
    # empty column's H is the terrain)
    floor = min((z - r for _, _, z, r, *_ in grains), default=0.0)
    half = min((r for _, _, _, r, *_ in grains), default=0.0)
    for x, y, top in columns:
        key = (math.floor(x / cell), math.floor(y / cell))
        if top > floor + half:
            tops[key] = max(tops.get(key, -math.inf), top)
    rings, speeds = {}, {}
    for (i, j), top in tops.items():
        rho = math.hypot((i + 0.5) * cell - cx, (j + 0.5) * cell - cy)
        rings.setdefault(int(rho / cell), []).append(top)
    for x, y, z, r, vx, vy, vz in grains:
        top = tops[(math.floor(x / cell), math.floor(y / cell))]
        if top - (z + r) <= 2 * cell:
            ring = int(math.hypot(x - cx, y - cy) / cell)
            speeds.setdefault(ring, []).append(math.sqrt(vx * vx + vy * vy + vz * vz))
    last = max(rings)
    return ([median(rings[k]) if k in rings else math.nan for k in range(last + 1)],
            [sum(speeds[k]) / len(speeds[k]) if k in speeds else math.nan
             for k in range(last + 1)])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="PLY frames or run folders")
    ap.add_argument("--center", default="0,0", help="the axis, X,Y in m (default 0,0)")
    ap.add_argument("--cell", type=float, default=0.01, help="cell and ring width in m")
    ap.add_argument("--step", type=int, default=3, help="print every STEP-th ring")
    ap.add_argument("--stream-speed", type=float, default=1.0,
                    help="leave out grains falling faster than this, m/s (default 1)")
    ap.add_argument("--speeds", action="store_true",
                    help="also print each ring's mean surface-layer speed, m/s")
    a = ap.parse_args()
    try:
        cx, cy = (float(v) for v in a.center.split(","))
    except ValueError:
        sys.exit(f"heap_profile.py: --center {a.center}: expected X,Y in metres")
    if not (a.cell > 0 and a.step >= 1 and a.stream_speed > 0):
        sys.exit("heap_profile.py: --cell and --stream-speed must be > 0 and --step >= 1")
    paths = []
    for run in a.runs:
        p = os.path.join(run, "final_grains.ply") if os.path.isdir(run) else run
        if not os.path.isfile(p):
            sys.exit(f"heap_profile.py: {p}: no such file (a PLY frame or a run folder)")
        paths.append(p)
    results = [profile(p, cx, cy, a.cell, a.stream_speed) for p in paths]
    profiles = [r[0] for r in results]
    for k, p in enumerate(paths):
        print(f"# [{k}] {p}")
    n = max(len(pr) for pr in profiles)
    print("radius_m " + " ".join(f"h[{k}]_m" for k in range(len(paths))) + "  " +
          " ".join(f"slope[{k}]_deg" for k in range(len(paths))) +
          ("  " + " ".join(f"speed[{k}]_m/s" for k in range(len(paths))) if a.speeds else ""))
    for ring in range(0, n, a.step):
        h = [pr[ring] if ring < len(pr) else math.nan for pr in profiles]
        s = []
        for pr in profiles:
            far = ring + a.step
            if far < len(pr) and not math.isnan(pr[ring]) and not math.isnan(pr[far]):
                s.append(math.degrees(math.atan((pr[ring] - pr[far]) / (a.step * a.cell))))
            else:
                s.append(math.nan)
        line = (f"{(ring + 0.5) * a.cell:.3f} " + " ".join(f"{v:.3f}" for v in h) + "  " +
                " ".join(f"{v:5.1f}" for v in s))
        if a.speeds:
            line += "  " + " ".join(f"{r[1][ring] if ring < len(r[1]) else math.nan:.3f}"
                                    for r in results)
        print(line)


if __name__ == "__main__":
    main()
