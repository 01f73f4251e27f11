#!/usr/bin/env python3
"""Random command lines against the sandflow binary (docs/fuzzing.md, "The command line").

    scripts/fuzz_cli.py [--seconds S] [--seed N] [--binary PATH]

Each command gets a random scene or folder and a few of its options (and some it does not take),
with values drawn from what goes wrong: nan, inf, -0, 1e309, huge counts, empty words, ranges
written wrongly, paths that are devices or missing. Runs are bounded (one frame, a calibration
rig of one fast trial), each command by a timeout: 20 s, 60 s for `report` (a table1 folder's
report renders ten pictures; the dragon's alone takes 10 s, POV-Ray reading its mesh). A finding is an exit status other than 0,
2, 3 or 4, a timeout, a crash, a sanitizer report or an uncaught exception, or a bad-input exit
whose message neither starts with "error:" nor says which --help to read. The libFuzzer targets
(scripts/fuzz.sh) feed files to the readers; this feeds words to the command line, where the
fuzzers do not look. Exit status: 0 nothing found, 1 a finding. Only Python's standard library.
"""
import argparse
import os
import random
import subprocess
import sys
import tempfile
import time

ODD = ["nan", "inf", "-inf", "-0", "0", "1e309", "-1", "1e-320", "99999999999999999999", "", " ",
       "1,5", "0x10", "1e3", "3.5", "ä", "--", "-", "all", ":", "1:", ":2", "2-", "0:0", "4096",
       "4097", "1 2", "done", "s.toml", "/dev/null", "/dev/zero", "/proc/self", "missing",
       "x=1", "material.k_n=", "=3", "material.k_n=nan", "material.diameter=1e-9",
       "output.fps=1e9", "simulation.dt=1e-12", "emitter.0.count=0", "geometry.9.type=plane",
       "simulation.mode=dem", "stiffness.impact_overlap=2", "ply,vtk", "none", "y", "q"]

# the options of each command (`sandflow CMD --help`); flags take no value
COMMANDS = {
    "run": ["--out", "--frames", "--grains", "--threads", "--set", "--export", "--up-axis",
            "--mode", "--check", "--force", "--profile", "--resume", "--checkpoint-every"],
    "compare": ["--out", "--frames", "--grains", "--threads", "--set", "--seeds",
                "--equal-stiffness", "--resume", "--force"],
    "calibrate": ["--trials", "--again", "--base", "--tilt-rate", "--set", "--threads"],
    "render": ["--frames", "--movie", "--width", "--height", "--jobs", "--fps", "--again"],
    "report": ["--no-render"],
    "measure": [],
    "table1": ["--scale", "--only", "--seeds", "--out", "--frames", "--resume", "--force",
               "--threads"],
}
FLAGS = {"--check", "--force", "--profile", "--equal-stiffness", "--again", "--movie",
         "--no-render"}

SCENE = """[scene]
name = "tiny"
[material]
diameter = 0.01
k_n = 1.0e4
[[geometry]]
type = "plane"
[[geometry]]
type = "mesh"
file = "tet.stl"
position = [0.3, 0.0, 0.0]
[[emitter]]
type = "block"
count = 60
center = [0.0, 0.0, 0.05]
size = [0.05, 0.05, 0.05]
"""


def tetrahedron_stl():
    p = [(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    lines = ["solid tet"]
    for f in faces:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += ["vertex %g %g %g" % p[k] for k in f]
        lines += ["endloop", "endfacet"]
    return "\n".join(lines + ["endsolid tet", ""])


def command_line(rng, serial):
    command = rng.choice(list(COMMANDS))
    args = [command]
    if rng.random() < 0.8:
        args.append(rng.choice(["s.toml", "done", "missing", "tet.stl"] + ODD[:6]))
    for _ in range(rng.randint(0, 4)):
        option = rng.choice(COMMANDS[command] + ["--bogus", "-x"])
        args.append(option)
        if option not in FLAGS and rng.random() < 0.9:
            args.append(rng.choice(ODD + ["1", "2", "3", "out_%d" % (serial % 5)]))
    # bounded: one frame, one fast calibration trial
    if command in ("run", "compare", "table1") and "--frames" not in args:
        args += ["--frames", "1"]
    if command == "table1" and "--scale" not in args:
        args += ["--scale", "0.002"]  # (the five scenes at their default tenth take a minute)
    if command == "calibrate" and "--trials" not in args:
        args += ["--trials", "1", "--base", "7", "--tilt-rate", "20"]
    return args


def time_limit(args):
    return 60 if args[0] == "report" else 20


def finding(status, output, limit):
    if status == 124:
        return "took more than %d s" % limit
    if status not in (0, 2, 3, 4):
        return "exit status %d" % status
    for word in ("terminate called", "Sanitizer", "Assertion", "runtime error"):
        if word in output:
            return word
    if status == 2 and "error:" not in output and "Run sandflow" not in output:
        return "a bad-input exit that names no error"
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=300)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--binary", default=os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "build", "sandflow"))
    a = parser.parse_args()
    binary = os.path.abspath(a.binary)
    if not os.access(binary, os.X_OK):
        sys.exit("scripts/fuzz_cli.py: no binary at %s (./setup.sh build makes it)" % binary)
    rng = random.Random(a.seed)
    with tempfile.TemporaryDirectory(prefix="sandflow_fuzz_cli_") as work:
        with open(os.path.join(work, "s.toml"), "w") as f:
            f.write(SCENE)
        with open(os.path.join(work, "tet.stl"), "w") as f:
            f.write(tetrahedron_stl())
        env = dict(os.environ, SANDFLOW_NO_CALIBRATION="1",
                   SANDFLOW_CACHE_DIR=os.path.join(work, "cache"))
        subprocess.run([binary, "run", "s.toml", "--frames", "3", "--out", "done"], cwd=work,
                       env=env, capture_output=True, check=True)
        end = time.time() + a.seconds
        tried = found = 0
        while time.time() < end:
            args = command_line(rng, tried)
            limit = time_limit(args)
            p = subprocess.run(["timeout", str(limit), binary] + args, cwd=work, env=env,
                               capture_output=True, text=True, errors="replace")
            tried += 1
            output = p.stdout + p.stderr
            what = finding(p.returncode, output, limit)
            if what:
                found += 1
                last = output.strip().splitlines()[-1][:200] if output.strip() else "(no output)"
                print("finding (%s): sandflow %s\n  %s" % (what, " ".join(repr(w) for w in args),
                                                           last), flush=True)
        print("%d command lines (seed %d), %d finding(s)" % (tried, a.seed, found))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
