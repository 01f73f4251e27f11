"""Checks, inside Blender, what tools/blender/sandflow_blender.py made of a run folder.

    blender -b --factory-startup --python-exit-code 1 --python tools/blender/sandflow_blender.py \
        --python tests/blender/check_blender_load.py -- RUN

Run after the loader, in the same Blender. Every frame of the run is set in turn, and the grain
object's mesh is compared with the frame's PLY file, read here by a reader of its own (struct, the
layout sandflow writes: src/io/ply.hpp), not the loader's: the grain count, and the attributes
radius, velocity, id and state present on the points with the right type and, for every grain,
the file's values exactly (float32 in, float32 out). Also the scene's frame range and fps
against the run's files, the Geometry Nodes spheres (one per grain, at its place, scaled by its
radius) and the static layer against the run's h_NNNN.obj meshes. Exits 1 naming every failure.
"""

import json
import os
import struct
import sys

import bpy

RECORD = struct.Struct("<7fIB")  # x, y, z, radius, vx, vy, vz, id, state: 33 bytes
ATTRIBUTES = {"radius": ("FLOAT", 1), "velocity": ("FLOAT_VECTOR", 3), "id": ("INT", 1),
              "state": ("INT", 1)}
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print(f"check: FAIL {what}")
    return ok


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    props = [line.split()[2] for line in header if line.startswith("property")]
    assert props == ["x", "y", "z", "radius", "vx", "vy", "vz", "id", "state"], props
    count = int(next(line.split()[2] for line in header if line.startswith("element vertex")))
    assert len(data) - end == count * RECORD.size, path
    return [RECORD.unpack_from(data, end + k * RECORD.size) for k in range(count)]


def read_obj_z(path):
    return [float(line.split()[3]) for line in open(path) if line.startswith("v ")]


def values(mesh, name, width):
    attr = mesh.attributes[name]
    field = "vector" if width == 3 else "value"
    flat = [0.0 if attr.data_type.startswith("FLOAT") else 0] * (width * len(attr.data))
    attr.data.foreach_get(field, flat)
    return [tuple(flat[k * width:(k + 1) * width]) for k in range(len(attr.data))]


def check_values(where, name, got, want):
    """Every grain's value, exactly: float32 in the file, float32 in Blender."""
    wrong = [k for k, (a, b) in enumerate(zip(got, want)) if tuple(a) != tuple(b)]
    if wrong:
        k = wrong[0]
        check(False, f"{where}: {name} of {len(wrong)} grains differs from the PLY's (grain {k}: "
                     f"{tuple(got[k])}, the PLY says {tuple(want[k])})")


def check_grains(obj, number, grains):
    mesh = obj.data
    where = f"frame {number}"
    if not check(len(mesh.vertices) == len(grains),
                 f"{where}: {len(mesh.vertices)} points, the PLY has {len(grains)} grains"):
        return
    co = [0.0] * (3 * len(grains))
    mesh.vertices.foreach_get("co", co)
    check_values(where, "position", [tuple(co[3 * k:3 * k + 3]) for k in range(len(grains))],
                 [g[0:3] for g in grains])
    expected = {"radius": lambda g: (g[3],), "velocity": lambda g: g[4:7],
                "id": lambda g: (g[7],), "state": lambda g: (g[8],)}
    for name, (data_type, width) in ATTRIBUTES.items():
        attr = mesh.attributes.get(name)
        if not check(attr is not None, f"{where}: the points have no attribute '{name}'"):
            continue
        if not check((attr.data_type, attr.domain) == (data_type, "POINT"),
                     f"{where}: '{name}' is {attr.data_type} on {attr.domain}, expected "
                     f"{data_type} on POINT"):
            continue
        check_values(where, name, values(mesh, name, width), [expected[name](g) for g in grains])
    return {g[8] for g in grains}


def check_spheres(obj, number, grains):
    """The Geometry Nodes spheres: one per grain, in the points' order, centred on it and scaled
    by its radius (the sphere has radius 1)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    spheres = [(tuple(inst.matrix_world.translation), inst.matrix_world.to_scale())
               for inst in depsgraph.object_instances
               if inst.is_instance and inst.parent and inst.parent.original == obj]
    if not check(len(spheres) == len(grains),
                 f"frame {number}: {len(spheres)} spheres for {len(grains)} grains"):
        return
    # 1e-6 m: the float32 rounding of a matrix, well below a grain's size
    wrong = [k for k, ((centre, scale), g) in enumerate(zip(spheres, grains))
             if max(abs(a - b) for a, b in zip(centre, g[0:3])) > 1e-6 or
             max(abs(s - g[3]) for s in scale) > 1e-6]
    check(not wrong, f"frame {number}: {len(wrong)} spheres not at their grain's place or not of "
                     f"its radius (first: grain {wrong[0] if wrong else ''})")


def check_static(obj, run, number, sidecar):
    z_obj = read_obj_z(os.path.join(run, "heightfield", f"h_{number:04d}.obj"))
    mesh = obj.data
    where = f"frame {number}: static layer"
    if not check(len(mesh.vertices) == len(z_obj) == sidecar["nx"] * sidecar["ny"],
                 f"{where}: {len(mesh.vertices)} vertices, h_{number:04d}.obj has {len(z_obj)}"):
        return
    # the loader reads the PNG when there is one: within half a grey level of the OBJ's heights
    png = sidecar.get("png")
    tolerance = 0.51 * png["metres_per_level"] + 1e-6 if png else 1e-6
    worst = max(abs(v.co.z - z) for v, z in zip(mesh.vertices, z_obj))
    check(worst <= tolerance, f"{where}: {worst:.3g} m from h_{number:04d}.obj (tolerance "
                              f"{tolerance:.3g} m)")
    return max(z_obj) > min(z_obj)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    run = os.path.abspath(argv[0])
    # the files the loaded data must equal: the run's own, or (SANDFLOW_CHECK_AGAINST) those of
    # the same run written z up, when the loaded one was written y up
    truth = os.path.abspath(os.environ.get("SANDFLOW_CHECK_AGAINST", run))
    scene = bpy.context.scene
    frames = sorted(int(f[:-4]) for f in os.listdir(os.path.join(run, "frames"))
                    if f.endswith(".ply"))
    summary = json.load(open(os.path.join(run, "summary.json")))
    sidecar = json.load(open(os.path.join(truth, "heightfield", "heightfield.json")))

    check((scene.frame_start, scene.frame_end) == (frames[0], frames[-1]) == (1, summary["frames"]),
          f"frame range {scene.frame_start}-{scene.frame_end}, the run has {frames[0]}-"
          f"{frames[-1]} ({summary['frames']} in summary.json)")
    fps = scene.render.fps / scene.render.fps_base
    check(abs(fps - summary["fps"]) < 1e-6, f"{fps} fps, the run has {summary['fps']}")

    owners = [o for o in scene.objects if "sandflow_grains" in o]
    statics = [o for o in scene.objects if "sandflow_static" in o]
    if not check(len(owners) == 1 and len(statics) == 1,
                 f"{len(owners)} grain objects and {len(statics)} static layers, expected 1 each"):
        sys.exit(1)
    grains_obj, static_obj = owners[0], statics[0]
    check(any(m.type == "NODES" for m in grains_obj.modifiers), "no Geometry Nodes modifier")

    states = set()
    for number in frames:
        scene.frame_set(number)
        grains = read_ply(os.path.join(truth, "frames", f"{number:04d}.ply"))
        states |= check_grains(grains_obj, number, grains) or set()
        sand = check_static(static_obj, truth, number, sidecar)
        if number in (frames[0], frames[len(frames) // 2], frames[-1]):
            check_spheres(grains_obj, number, grains)
    # the test's run must give the checks something to see (a short y-up copy may not)
    full = truth == run
    check(sand or not full, f"frame {frames[-1]}: the static layer is flat (the test's run "
                            "should make a heap, so that its heights are checked)")
    check(states == {0, 1} or not full, f"the run's grains have the states {sorted(states)}: the "
                                        "test's run should have ACTIVE (0) and INTERFACE (1) grains")
    # outside the run, the nearest frame of it
    scene.frame_set(frames[-1] + 5)
    check(len(grains_obj.data.vertices) == len(read_ply(
        os.path.join(truth, "frames", f"{frames[-1]:04d}.ply"))),
        f"frame {frames[-1] + 5} (past the end) does not show the last frame")

    if failures:
        print(f"check: {len(failures)} failures")
        sys.exit(1)
    print(f"check: ok: {len(frames)} frames, every grain count; positions, radius, velocity, "
          "id and state of every grain; spheres; static layer")


main()
