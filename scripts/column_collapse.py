#!/usr/bin/python3
"""Column collapse against the law of Lube et al. (2004), in both of sandflow's modes.

Runs scenes/column.toml at aspect ratios a = H0 / R0 (default 0.5, 1, 2, 4) in surface and plain
DEM mode, measures the column's height H0 when the tube is lifted and the runout radius R_inf of
the deposit, and prints (R_inf - R0) / R0 beside the law: 1.24 a for a <= 1.7, 1.6 a^(1/2) above.

    scripts/column_collapse.py [--ratios 0.5,1,2,4] [--modes surface,dem] [--out DIR]
                               [--sandflow build/sandflow] [--threads N] [--seeds 1] [--r0 0.1]

H0: the median, over the cells of side d within 0.7 R0 of the axis, of the highest grain top in
each cell, in the last frame before the tube goes. R_inf: the radius that holds 99 % of the grains
at the end (a few grains thrown further do not count; Lube et al. measured the deposit's edge).
Writes OUT/column.json with every figure. Exit status 0 when every run ended, whatever the
figures; the figures are for reading against the law, not a test.
(Standard library only: the PLY frames are read here, so no numpy is needed.)
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCENE = os.path.join(ROOT, "scenes", "column.toml")

R0_SCENE = 0.1    # the tube's inner radius in scenes/column.toml [m]
D = 0.01          # mean grain diameter [m]
PACKING = 0.6     # the count that fills the tube to a R0 at this packing
RATE = 10000.0    # the scene's pour rate [grains/s]
SETTLE = 0.8      # s between the end of the pour and the tube's removal
COLLAPSE = 1.5    # s after the removal


R0 = R0_SCENE     # the tube's radius of this run (--r0)


def law(a):
    return 1.24 * a if a <= 1.7 else 1.6 * math.sqrt(a)


def read_ply(path, names=("x", "y", "z", "radius")):
    """The named properties of every vertex of a sandflow PLY (binary little endian or ASCII), as
    tuples in the order of `names`; x, y, z and radius must be there, any other is 0 where the
    PLY does not hold it (velocities in a final state, say)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    fmt = header[1].split()[1]
    count, props = 0, []
    kinds = {"float": "f", "double": "d", "uint": "I", "int": "i", "uchar": "B", "char": "b",
             "ushort": "H", "short": "h", "float32": "f", "float64": "d", "uint32": "I",
             "int32": "i", "uint8": "B"}
    for line in header:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            count = int(w[2])
        elif w and w[0] == "property":
            props.append((w[2], kinds[w[1]]))
    have = [p[0] for p in props]
    for n in ("x", "y", "z", "radius"):
        if n in names and n not in have:
            raise ValueError(f"{path}: the PLY has no vertex property {n}")
    cols = [have.index(n) if n in have else None for n in names]
    if fmt == "ascii":
        lines = data[end:].decode("ascii").split("\n")
        rows = ([float(t) for t in lines[k].split()] for k in range(count))
    else:
        rec = struct.Struct("<" + "".join(p[1] for p in props))
        rows = rec.iter_unpack(data[end:end + count * rec.size])
    return [tuple(v[c] if c is not None else 0.0 for c in cols) for v in rows]


def median(v):
    v = sorted(v)
    n = len(v)
    return 0.0 if n == 0 else (v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2]))


def column_height(grains):
    tops = {}
    for x, y, z, r in grains:
        if math.hypot(x, y) > 0.7 * R0:
            continue
        key = (math.floor(x / D), math.floor(y / D))
        tops[key] = max(tops.get(key, 0.0), z + r)
    return median(list(tops.values()))


def runout(grains, fraction=0.99):
    d = sorted(math.hypot(x, y) for x, y, _, _ in grains)
    return d[min(len(d) - 1, int(fraction * len(d)))] if d else 0.0


def run(args, a, mode, seed):
    count = round(PACKING * math.pi * R0 * R0 * a * R0 / (math.pi / 6 * D ** 3))
    remove_at = count / RATE + SETTLE
    fps = 30
    frames = math.ceil((remove_at + COLLAPSE) * fps)
    out = os.path.join(args.out, f"a{a:g}-r{R0:g}-{mode}-seed{seed}")
    cmd = [args.sandflow, "run", SCENE, "--mode", mode, "--out", out, "--force",
           "--export", "ply", "--frames", str(frames),
           "--set", f"emitter.0.count={count}", "--set", f"geometry.1.remove_at={remove_at:.6f}",
           "--set", f"simulation.seed={seed}"]
    if R0 != R0_SCENE:  # a wider tube, the pour over all of it, the grid over the whole runout
        reach = max(0.6, 6 * R0)
        cmd += ["--set", f"geometry.1.radius={R0:g}", "--set", f"emitter.0.radius={R0 - 0.006:g}",
                "--set", f"surface.extent=[{-reach:g}, {-reach:g}, {reach:g}, {reach:g}]"]
    if args.threads:
        cmd += ["--threads", str(args.threads)]
    print("$ " + " ".join(cmd), flush=True)
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        sys.stderr.write(done.stdout[-3000:])
        raise SystemExit(f"the run a = {a:g}, {mode}, seed {seed} failed ({done.returncode})")
    # the last frame before the removal: frame k holds the state at t = k / fps
    before = math.floor(remove_at * fps - 1e-9)
    h0 = column_height(read_ply(os.path.join(out, "frames", f"{before:04d}.ply")))
    end = read_ply(os.path.join(out, "final_grains.ply"))
    r_inf = runout(end)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    a_measured = h0 / R0
    return {"a_asked": a, "mode": mode, "seed": seed, "r0": R0, "grains": count,
            "remove_at": remove_at,
            "h0": h0, "a": a_measured, "r_inf": r_inf, "runout": (r_inf - R0) / R0,
            "law": law(a_measured), "wall_seconds": summary.get("wall_seconds"), "out": out}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--ratios", default="0.5,1,2,4")
    p.add_argument("--modes", default="surface,dem")
    p.add_argument("--out", default="out/column")
    p.add_argument("--sandflow", default=os.path.join(ROOT, "build", "sandflow"))
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--seeds", type=int, default=1)
    p.add_argument("--r0", type=float, default=R0_SCENE,
                   help="the tube's radius [m] (default the scene's 0.1: ten diameters)")
    args = p.parse_args()
    global R0
    R0 = args.r0
    if not 0.03 <= R0 <= 1.0:
        raise SystemExit("--r0: expected a radius in [0.03, 1] m")
    ratios = [float(t) for t in args.ratios.split(",")]
    modes = args.modes.split(",")
    for m in modes:
        if m not in ("surface", "dem"):
            raise SystemExit(f"--modes: '{m}' is not surface or dem")
    if not os.access(args.sandflow, os.X_OK):
        raise SystemExit(f"{args.sandflow}: no sandflow binary (./setup.sh build, or --sandflow)")
    os.makedirs(args.out, exist_ok=True)
    results = [run(args, a, m, s) for a in ratios for m in modes for s in range(1, args.seeds + 1)]
    print()
    print(f"{'a asked':>8} {'mode':>8} {'seed':>4} {'H0 [m]':>8} {'a':>6} {'R_inf [m]':>9} "
          f"{'(R-R0)/R0':>9} {'law':>6} {'off':>7}")
    for r in results:
        off = r["runout"] / r["law"] - 1
        print(f"{r['a_asked']:8g} {r['mode']:>8} {r['seed']:4d} {r['h0']:8.4f} {r['a']:6.2f} "
              f"{r['r_inf']:9.4f} {r['runout']:9.3f} {r['law']:6.3f} {100 * off:+6.1f}%")
    if "surface" in modes and "dem" in modes:
        print()
        for a in ratios:
            s = [r["r_inf"] for r in results if r["a_asked"] == a and r["mode"] == "surface"]
            d = [r["r_inf"] for r in results if r["a_asked"] == a and r["mode"] == "dem"]
            ms, md = sum(s) / len(s), sum(d) / len(d)
            print(f"a = {a:g}: runout surface {ms:.4f} m, plain DEM {md:.4f} m: "
                  f"{100 * (ms / md - 1):+.1f}%")
    with open(os.path.join(args.out, "column.json"), "w") as f:
        json.dump(results, f, indent=2)
    print(f"\n{os.path.join(args.out, 'column.json')}")


if __name__ == "__main__":
    main()
