"""Loads a sandflow run folder into Blender as an animated point cloud.

    blender -b --python tools/blender/sandflow_blender.py -- RUN_DIR [--render FRAME] [--output PNG]
        [--resolution 1280x720] [--samples 32] [--save FILE.blend] [--subdivisions 2]

or, installed as an add-on (Edit > Preferences > Add-ons > Install..., this file), File > Import >
sandflow run. docs/blender.md says what it makes; the run folder's files: docs/scenes.md, "Exports".

Why one object whose data is replaced on frame change, not one object per frame keyed visible: the
frames of a 100,000-grain run hold 100,000 grains each, and hundreds of them would have to sit in
memory (and in a saved .blend) at once; here memory and load time are those of one frame, and a
frame of 100,000 grains loads in a fraction of a second. The cost: the grains animate only while
this script or the add-on is loaded (a .blend reopened without it shows the last frame loaded).

Why our own PLY reader: Blender's PLY importer keeps the positions and drops radius, velocity, id
and state. The reader follows sandflow's own (src/io/ply.hpp): binary_little_endian or ascii, any
property order and numeric types, x, y, z and radius required, velocity 0, id the index and state 0
when absent, a `comment up_axis y` frame turned back to z up (Blender's up axis, and the scene's).
Standard library only: Debian's Blender has no numpy.
"""

import json
import math
import os
import re
import sys
from array import array

import bpy
from bpy.app.handlers import persistent

bl_info = {
    "name": "sandflow run",
    "author": "sandflow",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > sandflow run",
    "description": "A sandflow run folder as animated grains (radius, velocity, id, state) and "
    "its static layer",
    "category": "Import-Export",
}

PROG = "sandflow_blender"
GRAINS_PROP = "sandflow_grains"  # on the grain object: its run folder
STATIC_PROP = "sandflow_static"  # on the static-layer object: its run folder
SAND_RGB = (0.56, 0.40, 0.22)  # linear; a dry quartz sand
FLOOR_RGB = (0.30, 0.30, 0.30)


class RunError(Exception):
    """A run folder or one of its files that cannot be loaded; the message names the file."""


# ---------------------------------------------------------------------------------------------
# PLY frames

PLY_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
             "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
             "float": "f", "float32": "f", "double": "d", "float64": "d"}
PLY_SIZES = {"b": 1, "B": 1, "h": 2, "H": 2, "i": 4, "I": 4, "f": 4, "d": 8}
FRAME_NAME = re.compile(r"^(\d{4,})\.ply$")


class PlyHeader:
    def __init__(self):
        self.encoding = None  # "ascii" or "binary_little_endian"
        self.comments = []
        self.elements = []  # [name, count, [(name, code) or (name, count_code, item_code)]]
        self.body = 0  # byte offset of the data
        self.lines = 0

    def up_axis(self):
        for c in self.comments:
            if c.split() == ["up_axis", "y"]:
                return "y"
        return "z"


def parse_ply_header(data, path):
    h = PlyHeader()
    pos = 0
    while True:
        end = data.find(b"\n", pos)
        if end < 0:
            raise RunError(f"{path}: the header has no 'end_header' line (file truncated?)")
        h.lines += 1
        line = data[pos:end].decode("ascii", "replace").rstrip("\r")
        pos = end + 1
        words = line.split()
        where = f"{path}: header line {h.lines}"
        if h.lines == 1:
            if line != "ply":
                raise RunError(f"{where}: not a PLY file (expected the first line 'ply')")
            continue
        if not words:
            continue
        if words[0] == "end_header":
            break
        if words[0] == "format":
            if len(words) != 3 or words[2] != "1.0":
                raise RunError(f"{where}: expected 'format <kind> 1.0'")
            if words[1] not in ("ascii", "binary_little_endian"):
                raise RunError(f"{where}: {words[1]} PLY is not supported "
                               "(ascii or binary_little_endian)")
            h.encoding = words[1]
        elif words[0] in ("comment", "obj_info"):
            h.comments.append(line.split(None, 1)[1] if len(words) > 1 else "")
        elif words[0] == "element":
            if len(words) != 3 or not words[2].isdigit():
                raise RunError(f"{where}: expected 'element <name> <count>'")
            h.elements.append([words[1], int(words[2]), []])
        elif words[0] == "property":
            if not h.elements:
                raise RunError(f"{where}: property before any element")
            if len(words) == 5 and words[1] == "list":
                if words[2] not in PLY_TYPES or words[3] not in PLY_TYPES:
                    raise RunError(f"{where}: unknown list type in '{line}'")
                h.elements[-1][2].append((words[4], PLY_TYPES[words[2]], PLY_TYPES[words[3]]))
            elif len(words) == 3 and words[1] in PLY_TYPES:
                h.elements[-1][2].append((words[2], PLY_TYPES[words[1]]))
            else:
                raise RunError(f"{where}: expected 'property <type> <name>'")
        else:
            raise RunError(f"{where}: unexpected '{words[0]}'")
    if h.encoding is None:
        raise RunError(f"{path}: no 'format' line before 'end_header'")
    h.body = pos
    return h


def typed(raw, code):
    a = array(code)
    a.frombytes(raw)
    if sys.byteorder == "big":
        a.byteswap()
    return a


def binary_column(data, start, count, stride, offset, code):
    """One property of `count` fixed-size records as an array: a strided copy per byte, so that
    100,000 grains take no Python loop."""
    size = PLY_SIZES[code]
    out = bytearray(count * size)
    for k in range(size):
        first = start + offset + k
        out[k::size] = data[first:first + stride * count:stride]
    return typed(bytes(out), code)


def skip_binary_element(data, pos, element, path):
    _, count, props = element
    if all(len(p) == 2 for p in props):
        return pos + count * sum(PLY_SIZES[p[1]] for p in props)
    for _ in range(count):  # records with lists: walked one by one
        for p in props:
            if len(p) == 2:
                pos += PLY_SIZES[p[1]]
            else:
                n = typed(data[pos:pos + PLY_SIZES[p[1]]], p[1])
                if not n:
                    raise RunError(f"{path}: ends inside element '{element[0]}'")
                pos += PLY_SIZES[p[1]] + n[0] * PLY_SIZES[p[2]]
    return pos


class Frame:
    """One frame's grains, each field an array with one entry a grain (velocity three)."""

    def __init__(self, count):
        self.count = count
        self.position = array("f")  # x, y, z, x, y, z, ... [m]
        self.radius = array("f")  # [m]
        self.velocity = array("f")  # vx, vy, vz, ... [m/s]
        self.id = array("i")  # sandflow's uint ids fit: a scene has at most 2e9 grains
        self.state = array("i")  # 0 ACTIVE, 1 INTERFACE, 2 STATIC
        self.missing = []  # optional properties the file lacks


def interleave3(a, b, c):
    out = array("f", bytes(4 * 3 * len(a)))
    out[0::3], out[1::3], out[2::3] = a, b, c
    return out


def read_frame(path):
    """A frame's grains in the scene's frame (z up). Raises RunError naming the file and place."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise RunError(f"{path}: cannot read ({e.strerror})") from None
    h = parse_ply_header(data, path)
    pos = h.body
    for element in h.elements:
        if element[0] == "vertex":
            columns = read_vertices(data, pos, h, element, path)
            break
        if h.encoding == "ascii":
            raise RunError(f"{path}: an ascii PLY whose first element is not 'vertex'")
        pos = skip_binary_element(data, pos, element, path)
    else:
        raise RunError(f"{path}: header line {h.lines}: no 'vertex' element")

    count = element[1]
    frame = Frame(count)
    for name in ("x", "y", "z", "radius"):
        if name not in columns:
            raise RunError(f"{path}: the vertex element has no property '{name}' "
                           "(x, y, z and radius are required)")

    def floats(name, default=0.0):
        if name in columns:
            return columns[name] if columns[name].typecode == "f" else array("f", columns[name])
        frame.missing.append(name)
        return array("f", [default]) * count

    x, y, z = floats("x"), floats("y"), floats("z")
    vx, vy, vz = floats("vx"), floats("vy"), floats("vz")
    if h.up_axis() == "y":  # written as (x, z, -y): back to z up
        y, z = array("f", (-v for v in z)), y
        vy, vz = array("f", (-v for v in vz)), vy
    frame.position = interleave3(x, y, z)
    frame.velocity = interleave3(vx, vy, vz)
    frame.radius = floats("radius")
    if "id" in columns:
        frame.id = array("i", columns["id"]) if columns["id"].typecode != "I" else \
            typed(columns["id"].tobytes(), "i")
    else:
        frame.missing.append("id")
        frame.id = array("i", range(count))
    if "state" in columns:
        frame.state = array("i", columns["state"])
    else:
        frame.missing.append("state")
        frame.state = array("i", bytes(4 * count))
    return frame


def read_vertices(data, pos, h, element, path):
    name, count, props = element
    if any(len(p) != 2 for p in props):
        raise RunError(f"{path}: the vertex element has a list property (grains have none)")
    if h.encoding == "binary_little_endian":
        stride = sum(PLY_SIZES[p[1]] for p in props)
        if len(data) - pos < stride * count:
            raise RunError(f"{path}: byte {len(data)}: the file ends inside its {count} grains "
                           f"({stride * count} bytes after the header, {len(data) - pos} there; "
                           "truncated?)")
        columns, offset = {}, 0
        for pname, code in props:
            columns[pname] = binary_column(data, pos, count, stride, offset, code)
            offset += PLY_SIZES[code]
        return columns
    lines = data[pos:].decode("ascii", "replace").splitlines()
    if len(lines) < count:
        raise RunError(f"{path}: line {h.lines + len(lines)}: the file ends inside its {count} "
                       "grains (truncated?)")
    columns = {pname: array(code) for pname, code in props}
    for k in range(count):
        words = lines[k].split()
        if len(words) < len(props):
            raise RunError(f"{path}: line {h.lines + 1 + k}: expected {len(props)} numbers")
        try:
            for (pname, code), w in zip(props, words):
                columns[pname].append(float(w) if code in "fd" else int(w))
        except (ValueError, OverflowError):
            raise RunError(f"{path}: line {h.lines + 1 + k}: '{lines[k]}' is not "
                           f"{len(props)} numbers of the header's types") from None
    return columns


def frame_count_in_header(path):
    """The grain count a frame's header gives, with its properties and size checked: a whole run
    is checked when it is loaded, not when the animation reaches a broken frame."""
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 16)
            size = os.fstat(f.fileno()).st_size
    except OSError as e:
        raise RunError(f"{path}: cannot read ({e.strerror})") from None
    h = parse_ply_header(head, path)
    vertex = [e for e in h.elements if e[0] == "vertex"]
    if not vertex:
        raise RunError(f"{path}: header line {h.lines}: no 'vertex' element")
    names = [p[0] for p in vertex[0][2]]
    for name in ("x", "y", "z", "radius"):
        if name not in names:
            raise RunError(f"{path}: the vertex element has no property '{name}' "
                           "(x, y, z and radius are required)")
    if h.encoding == "binary_little_endian" and all(len(p) == 2 for e in h.elements
                                                    for p in e[2]):
        need = sum(e[1] * sum(PLY_SIZES[p[1]] for p in e[2]) for e in h.elements)
        if size - h.body < need:
            raise RunError(f"{path}: byte {size}: the file ends inside its {vertex[0][1]} grains "
                           f"({need} bytes after the header, {size - h.body} there; truncated?)")
    return vertex[0][1]


# ---------------------------------------------------------------------------------------------
# The run folder

class Run:
    """What a run folder holds, found and checked before anything is made in Blender."""

    def __init__(self, folder):
        self.folder = os.path.abspath(folder)
        if not os.path.exists(self.folder):
            raise RunError(f"{folder}: no such folder")
        if not os.path.isdir(self.folder):
            raise RunError(f"{folder}: not a folder (give the run's output folder, the one "
                           "holding run.json and frames/)")
        self.name = os.path.basename(self.folder.rstrip(os.sep)) or "run"
        self.frames = self.find_frames()
        self.first, self.last = min(self.frames), max(self.frames)
        gaps = [n for n in range(self.first, self.last + 1) if n not in self.frames]
        if gaps:
            raise RunError(f"{self.folder}/frames: frames {self.first}-{self.last} miss "
                           f"{len(gaps)} of them (first: {gaps[0]:04d}.ply)")
        self.counts = {n: frame_count_in_header(p) for n, p in sorted(self.frames.items())}
        self.summary = self.read_json("summary.json")
        self.record = self.read_json("run.json")
        self.scene = self.read_scene()
        self.fps = self.find_fps()
        self.static = self.find_static_layer()

    def find_frames(self):
        folder = os.path.join(self.folder, "frames")
        if not os.path.isdir(folder):
            hint = ("a run folder holds run.json and frames/"
                    if not os.path.exists(os.path.join(self.folder, "run.json"))
                    else "the run wrote no PLY frames: run it with `--export ply`")
            raise RunError(f"{self.folder}: no frames/ folder ({hint})")
        frames = {int(m.group(1)): os.path.join(folder, m.group(0))
                  for m in map(FRAME_NAME.match, sorted(os.listdir(folder))) if m}
        if not frames:
            raise RunError(f"{folder}: no NNNN.ply frames (the run wrote none: was `ply` in its "
                           "exports? `sandflow run ... --export ply,height`)")
        return frames

    def read_json(self, name):
        path = os.path.join(self.folder, name)
        if not os.path.exists(path):
            return None  # a run still going has no summary.json yet
        try:
            with open(path, encoding="utf-8") as f:
                value = json.load(f)
        except (OSError, UnicodeDecodeError) as e:
            raise RunError(f"{path}: cannot read ({e})") from None
        except json.JSONDecodeError as e:
            raise RunError(f"{path}: line {e.lineno}: not valid JSON ({e.msg})") from None
        if not isinstance(value, dict):
            raise RunError(f"{path}: expected a JSON object")
        return value

    def read_scene(self):
        """The run's scene as run.json records it, its --set overrides applied (as far as this
        script reads it: fps, floors, camera); {} when it cannot be read."""
        start = (self.record or {}).get("start") or {}
        text = start.get("scene_text")
        try:
            import tomllib  # Python 3.11 (Debian's Blender 3.4); without it, summary.json only
        except ImportError:
            return {}
        try:
            scene = tomllib.loads(text) if isinstance(text, str) else {}
        except tomllib.TOMLDecodeError:
            return {}
        for item in start.get("sets") or []:
            key, _, value = str(item).partition("=")
            path = [p for p in re.split(r"[.\[\]]", key) if p]
            try:
                value = tomllib.loads("v = " + value)["v"]
            except tomllib.TOMLDecodeError:
                pass  # sandflow takes text that is no TOML value as a string
            node = scene
            for p in path[:-1]:
                node = node[int(p)] if isinstance(node, list) and p.isdigit() else \
                    node.setdefault(p, {}) if isinstance(node, dict) else None
                if node is None:
                    break
            if isinstance(node, dict) and path:
                node[path[-1]] = value
        return scene

    def find_fps(self):
        fps = (self.summary or {}).get("fps")
        if fps is None:
            fps = (self.scene.get("output") or {}).get("fps", 30.0 if self.scene else None)
        if not isinstance(fps, (int, float)) or not fps > 0:
            print(f"{PROG}: warning: {self.folder}: no frame rate in summary.json or run.json; "
                  "taking 30 fps", file=sys.stderr)
            fps = 30.0
        return float(fps)

    def find_static_layer(self):
        """Where the static layer h comes from: the 16-bit PNGs with heightfield.json (read by
        Blender's own loader, fast), else the OBJ meshes; None without a height field."""
        folder = os.path.join(self.folder, "heightfield")
        sidecar_path = os.path.join(folder, "heightfield.json")
        if not os.path.exists(sidecar_path):
            return None
        sidecar = self.read_json(os.path.join("heightfield", "heightfield.json"))
        for key in ("nx", "ny", "extent"):
            if key not in sidecar:
                raise RunError(f"{sidecar_path}: no '{key}'")
        for kind, ext in (("png", "png"), ("obj", "obj")):
            if all(os.path.exists(os.path.join(folder, f"h_{n:04d}.{ext}")) for n in self.frames):
                if kind == "png" and "png" not in sidecar:
                    continue
                return {"kind": kind, "folder": folder, "sidecar": sidecar}
        return None


# ---------------------------------------------------------------------------------------------
# The static layer: a grid mesh through the column centres

def static_grid(sidecar):
    nx, ny = int(sidecar["nx"]), int(sidecar["ny"])
    x0, y0, x1, y1 = (float(v) for v in sidecar["extent"])
    dx = (x1 - x0) / (nx - 1) if nx > 1 else 0.0
    dy = (y1 - y0) / (ny - 1) if ny > 1 else 0.0
    verts = [(x0 + i * dx, y0 + j * dy, 0.0) for j in range(ny) for i in range(nx)]
    faces = []  # as write_height_obj: two triangles a cell, counter-clockwise from above
    for j in range(ny - 1):
        for i in range(nx - 1):
            k = j * nx + i
            faces += [(k, k + 1, k + nx + 1), (k, k + nx + 1, k + nx)]
    return verts, faces


def static_heights_png(path, sidecar):
    """h per column, x fastest then y, from a 16-bit PNG (row 0 the highest y; Blender stores
    the bottom row first, so its rows already run from the lowest y)."""
    png = sidecar["png"]
    z_min, z_max = float(png["z_min"]), float(png["z_max"])
    try:
        image = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as e:
        raise RunError(f"{path}: cannot load ({e})") from None
    try:
        image.colorspace_settings.name = "Non-Color"  # greys are heights, not colours
        w, h = image.size
        if (w, h) != (int(sidecar["nx"]), int(sidecar["ny"])):
            raise RunError(f"{path}: {w} x {h} pixels, but heightfield.json has "
                           f"{sidecar['nx']} x {sidecar['ny']} columns")
        pixels = array("f", bytes(4 * len(image.pixels)))
        image.pixels.foreach_get(pixels)
        grey = pixels[0::image.channels]
    finally:
        bpy.data.images.remove(image)
    scale = z_max - z_min
    return array("f", (z_min + g * scale for g in grey))


def static_mesh_obj(path, up_axis):
    """Vertices and faces of an OBJ height mesh, in the scene's frame."""
    verts, faces = [], []
    try:
        with open(path, encoding="ascii", errors="replace") as f:
            for n, line in enumerate(f, 1):
                w = line.split()
                if not w:
                    continue
                if w[0] == "v":
                    x, y, z = float(w[1]), float(w[2]), float(w[3])
                    verts.append((x, -z, y) if up_axis == "y" else (x, y, z))
                elif w[0] == "f":
                    faces.append(tuple(int(v.split("/")[0]) - 1 for v in w[1:]))
    except OSError as e:
        raise RunError(f"{path}: cannot read ({e.strerror})") from None
    except (ValueError, IndexError):
        raise RunError(f"{path}: line {n}: not an OBJ vertex or face") from None
    return verts, faces


def load_static_frame(obj, number):
    run_folder = obj[STATIC_PROP]
    kind, sidecar = obj["sandflow_static_kind"], json.loads(obj["sandflow_sidecar"])
    folder = os.path.join(run_folder, "heightfield")
    mesh = obj.data
    if kind == "png":
        z = static_heights_png(os.path.join(folder, f"h_{number:04d}.png"), sidecar)
        co = array("f", bytes(4 * 3 * len(mesh.vertices)))
        mesh.vertices.foreach_get("co", co)
        co[2::3] = z
    else:
        up = (sidecar.get("obj") or {}).get("up_axis", "z")
        verts, faces = static_mesh_obj(os.path.join(folder, f"h_{number:04d}.obj"), up)
        if len(verts) != len(mesh.vertices):
            mesh.clear_geometry()
            mesh.from_pydata(verts, [], faces)
        co = array("f", (c for v in verts for c in v))
    mesh.vertices.foreach_set("co", co)
    mesh.update()


# ---------------------------------------------------------------------------------------------
# The grains: one mesh of vertices, its data replaced on each frame

def load_grain_frame(obj, number):
    path = os.path.join(obj[GRAINS_PROP], "frames", f"{number:04d}.ply")
    frame = read_frame(path)
    mesh = obj.data
    mesh.clear_geometry()  # removes the attributes too: a frame's count may differ
    mesh.vertices.add(frame.count)
    mesh.vertices.foreach_set("co", frame.position)
    for name, kind, field, values in (("radius", "FLOAT", "value", frame.radius),
                                      ("velocity", "FLOAT_VECTOR", "vector", frame.velocity),
                                      ("id", "INT", "value", frame.id),
                                      ("state", "INT", "value", frame.state)):
        mesh.attributes.new(name, kind, "POINT").data.foreach_set(field, values)
    mesh.update()
    if frame.missing and not obj.get("sandflow_warned"):
        obj["sandflow_warned"] = True
        print(f"{PROG}: warning: {path} has no {', '.join(frame.missing)}: taken as "
              "velocity 0, id the index, state 0", file=sys.stderr)


def run_frame(obj, scene_frame):
    """The run's frame shown at a scene frame: the nearest one inside the run."""
    return min(max(scene_frame, obj["sandflow_first"]), obj["sandflow_last"])


def update_object(obj, scene_frame):
    number = run_frame(obj, scene_frame)
    if obj.get("sandflow_loaded") == number:
        return
    if GRAINS_PROP in obj:
        load_grain_frame(obj, number)
    else:
        load_static_frame(obj, number)
    obj["sandflow_loaded"] = number


@persistent
def sandflow_frame_change(scene, *_):
    for obj in scene.objects:
        if GRAINS_PROP in obj or STATIC_PROP in obj:
            try:
                update_object(obj, scene.frame_current)
            except RunError as e:  # a handler cannot stop the animation: say it and go on
                print(f"{PROG}: error: {e}", file=sys.stderr)


def install_handler():
    # one handler, whether this file ran as a script, an add-on or both
    handlers = bpy.app.handlers.frame_change_pre
    for h in [h for h in handlers if getattr(h, "__name__", "") == sandflow_frame_change.__name__]:
        handlers.remove(h)
    handlers.append(sandflow_frame_change)


# ---------------------------------------------------------------------------------------------
# Materials and Geometry Nodes

def sand_material():
    """A rough sand colour, each grain a little lighter or darker (Object Info's random value,
    one per instance)."""
    mat = bpy.data.materials.get("sandflow sand")
    if mat:
        return mat
    mat = bpy.data.materials.new("sandflow sand")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes.get("Principled BSDF")
    bsdf.inputs["Roughness"].default_value = 0.9
    info = nodes.new("ShaderNodeObjectInfo")
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (*(0.75 * c for c in SAND_RGB), 1.0)
    ramp.color_ramp.elements[1].color = (*(min(1.0, 1.15 * c) for c in SAND_RGB), 1.0)
    links.new(info.outputs["Random"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    mat.diffuse_color = (*SAND_RGB, 1.0)  # the viewport's solid colour
    return mat


def plain_material(name, rgb):
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.9
    mat.diffuse_color = (*rgb, 1.0)
    return mat


def new_socket(tree, name, in_out):
    if hasattr(tree, "interface"):  # Blender 4
        tree.interface.new_socket(name=name, in_out=in_out, socket_type="NodeSocketGeometry")
    else:
        (tree.inputs if in_out == "INPUT" else tree.outputs).new("NodeSocketGeometry", name)


def grain_nodes(material, subdivisions):
    """Geometry Nodes: an icosphere of radius 1 on every point, scaled by its `radius`."""
    tree = bpy.data.node_groups.new("sandflow grains", "GeometryNodeTree")
    new_socket(tree, "Geometry", "INPUT")
    new_socket(tree, "Geometry", "OUTPUT")
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_out = nodes.new("NodeGroupOutput")
    sphere = nodes.new("GeometryNodeMeshIcoSphere")
    sphere.inputs["Radius"].default_value = 1.0
    sphere.inputs["Subdivisions"].default_value = subdivisions
    smooth = nodes.new("GeometryNodeSetShadeSmooth")
    set_material = nodes.new("GeometryNodeSetMaterial")
    set_material.inputs["Material"].default_value = material
    radius = nodes.new("GeometryNodeInputNamedAttribute")
    radius.data_type = "FLOAT"
    radius.inputs["Name"].default_value = "radius"
    on_points = nodes.new("GeometryNodeInstanceOnPoints")
    links.new(sphere.outputs["Mesh"], smooth.inputs["Geometry"])
    links.new(smooth.outputs["Geometry"], set_material.inputs["Geometry"])
    links.new(group_in.outputs[0], on_points.inputs["Points"])
    links.new(set_material.outputs["Geometry"], on_points.inputs["Instance"])
    links.new([s for s in radius.outputs if s.enabled][0], on_points.inputs["Scale"])
    links.new(on_points.outputs["Instances"], group_out.inputs[0])
    for k, node in enumerate((group_in, sphere, smooth, set_material, radius, on_points,
                              group_out)):
        node.location = (200 * k, -150 * (k % 2))
    return tree


# ---------------------------------------------------------------------------------------------
# Building the scene

def load_run(folder, context=None, subdivisions=2):
    """Makes the run's objects in the current scene; returns (grains, static layer or None)."""
    run = Run(folder)
    context = context or bpy.context
    scene = context.scene
    collection = bpy.data.collections.new(f"sandflow {run.name}")
    scene.collection.children.link(collection)
    material = sand_material()

    mesh = bpy.data.meshes.new(f"{run.name} grains")
    grains = bpy.data.objects.new(f"{run.name} grains", mesh)
    grains[GRAINS_PROP] = run.folder
    grains["sandflow_first"], grains["sandflow_last"] = run.first, run.last
    collection.objects.link(grains)
    modifier = grains.modifiers.new("sandflow grains", "NODES")
    modifier.node_group = grain_nodes(material, subdivisions)

    static = None
    if run.static:
        verts, faces = static_grid(run.static["sidecar"])
        mesh = bpy.data.meshes.new(f"{run.name} static layer")
        mesh.from_pydata(verts, [], faces)
        mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
        mesh.materials.append(material)
        static = bpy.data.objects.new(f"{run.name} static layer", mesh)
        static[STATIC_PROP] = run.folder
        static["sandflow_static_kind"] = run.static["kind"]
        static["sandflow_sidecar"] = json.dumps(run.static["sidecar"])
        static["sandflow_first"], static["sandflow_last"] = run.first, run.last
        collection.objects.link(static)
    else:
        print(f"{PROG}: note: {run.folder} has no height field (heightfield/ with h_NNNN.png "
              "or h_NNNN.obj and heightfield.json: a DEM-mode run, or a run without `height` "
              "in its exports): no static layer", file=sys.stderr)

    # the run's frame range and rate; Blender's rate is fps / fps_base with an integer fps
    scene.frame_start, scene.frame_end = run.first, run.last
    scene.render.fps = max(1, round(run.fps))
    scene.render.fps_base = scene.render.fps / run.fps
    scene.render.use_lock_interface = True  # the handler replaces mesh data while rendering
    install_handler()
    for obj in (grains, static):
        if obj:
            update_object(obj, run.first)
    scene.frame_set(run.first)
    print(f"{PROG}: {run.folder}: frames {run.first}-{run.last} at {run.fps:g} fps, "
          f"{run.counts[run.first]}-{max(run.counts.values())} grains a frame, static layer: "
          f"{run.static['kind'] if run.static else 'none'}")
    return run, grains, static


def floor_planes(run):
    """The scene's floors (planes within 45 degrees of +z): (point, normal) each."""
    floors = []
    for g in run.scene.get("geometry") or []:
        if isinstance(g, dict) and g.get("type", "plane") == "plane" and \
                g.get("render", "solid") != "hidden":
            p, n = g.get("point", [0, 0, 0]), g.get("normal", [0, 0, 1])
            length = math.sqrt(sum(c * c for c in n)) or 1.0
            n = [c / length for c in n]
            if n[2] >= math.cos(math.radians(45)):
                floors.append((p, n))
    return floors


def add_view(context, run, grains, static):
    """A floor, a sun, a sky and a camera, for a render from the command line: the scene's
    [camera] when it has one, else from 35 degrees up, a three-quarter view from the +x, -y side
    (as `sandflow render` looks), framing the last frame's grains and the static layer."""
    from mathutils import Vector

    scene = context.scene
    collection = grains.users_collection[0]
    for k, (p, n) in enumerate(floor_planes(run)):
        half = 20.0  # m: past the horizon of any view of a run
        mesh = bpy.data.meshes.new(f"{run.name} floor {k}")
        mesh.from_pydata([(-half, -half, 0), (half, -half, 0), (half, half, 0), (-half, half, 0)],
                         [], [(0, 1, 2, 3)])
        mesh.materials.append(plain_material("sandflow floor", FLOOR_RGB))
        floor = bpy.data.objects.new(f"{run.name} floor {k}", mesh)
        floor.rotation_euler = Vector((0, 0, 1)).rotation_difference(Vector(n)).to_euler()
        # a hair above the plane: the static layer's grid lies on it where there is no sand,
        # and would draw a sand-coloured square over the whole grid
        floor.location = Vector(p) + 1e-4 * Vector(n)
        collection.objects.link(floor)

    sun = bpy.data.objects.new("sandflow sun", bpy.data.lights.new("sandflow sun", "SUN"))
    sun.data.energy = 4.0
    sun.data.angle = math.radians(3)
    sun.rotation_euler = (math.radians(40), 0, math.radians(30))
    collection.objects.link(sun)
    world = scene.world or bpy.data.worlds.new("sandflow sky")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.6, 0.7, 0.85, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.4

    cam = bpy.data.objects.new("sandflow camera", bpy.data.cameras.new("sandflow camera"))
    collection.objects.link(cam)
    scene.camera = cam
    config = run.scene.get("camera") or {}
    cam.data.sensor_fit = "HORIZONTAL"
    cam.data.angle = math.radians(float(config.get("fov", 40.0)))
    if "position" in config and "look_at" in config:
        position, target = Vector(config["position"]), Vector(config["look_at"])
    else:
        target, radius = view_sphere(grains, static)
        elevation, azimuth = math.radians(35), math.radians(-45)
        direction = Vector((math.cos(elevation) * math.cos(azimuth),
                            math.cos(elevation) * math.sin(azimuth), math.sin(elevation)))
        aspect = scene.render.resolution_y / scene.render.resolution_x
        half = math.atan(math.tan(cam.data.angle / 2) * min(1.0, aspect))
        position = target + direction * (1.15 * radius / math.sin(half))
    cam.location = position
    cam.rotation_euler = (target - position).to_track_quat("-Z", "Y").to_euler()
    cam.data.clip_start = max(1e-4, 1e-3 * (target - position).length)
    cam.data.clip_end = 1e3 * (target - position).length


def view_sphere(grains, static):
    """Centre and radius of what the camera frames: the grains of the last frame and the
    static layer where it is above its lowest point (sand, not bare floor)."""
    from mathutils import Vector

    scene = bpy.context.scene
    saved = scene.frame_current
    scene.frame_set(grains["sandflow_last"])
    points = [grains.matrix_world @ v.co for v in grains.data.vertices]
    if static:
        zs = [v.co.z for v in static.data.vertices]
        low = min(zs) if zs else 0.0
        points += [static.matrix_world @ v.co for v in static.data.vertices if v.co.z > low + 1e-4]
    scene.frame_set(saved)
    if not points:
        return Vector((0, 0, 0)), 1.0
    lo = Vector((min(p[i] for p in points) for i in range(3)))
    hi = Vector((max(p[i] for p in points) for i in range(3)))
    centre = (lo + hi) / 2
    return centre, max(0.05, (hi - lo).length / 2)


def render_frame(context, number, output, resolution, samples):
    scene = context.scene
    scene.render.engine = "CYCLES"  # runs on the CPU, headless; Eevee needs an OpenGL context
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = output
    scene.frame_set(number)
    bpy.ops.render.render(write_still=True)
    print(f"{PROG}: rendered frame {number}: {output}")


# ---------------------------------------------------------------------------------------------
# The add-on: File > Import > sandflow run

class ImportSandflowRun(bpy.types.Operator):
    """Load a sandflow run folder: its grains as animated points with radius, velocity, id and
    state, drawn as spheres, and its static layer"""

    bl_idname = "import_scene.sandflow_run"
    bl_label = "Import sandflow run"
    bl_options = {"REGISTER", "UNDO"}

    directory: bpy.props.StringProperty(subtype="DIR_PATH")
    subdivisions: bpy.props.IntProperty(name="Sphere subdivisions", default=2, min=1, max=6)

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        try:
            load_run(self.directory, context, self.subdivisions)
        except RunError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}


def menu_import(self, context):
    self.layout.operator(ImportSandflowRun.bl_idname, text="sandflow run (folder)")


def register():
    bpy.utils.register_class(ImportSandflowRun)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)
    install_handler()


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    bpy.utils.unregister_class(ImportSandflowRun)
    handlers = bpy.app.handlers.frame_change_pre
    if sandflow_frame_change in handlers:
        handlers.remove(sandflow_frame_change)


# ---------------------------------------------------------------------------------------------
# The command line: blender -b --python sandflow_blender.py -- RUN_DIR [options]

def parse_args(argv):
    import argparse

    ap = argparse.ArgumentParser(
        prog="blender -b --python tools/blender/sandflow_blender.py --",
        description="Load a sandflow run folder: grains as animated points with radius, "
        "velocity, id and state, drawn as spheres by Geometry Nodes, the static layer as a "
        "mesh, and the run's frame range and fps (docs/blender.md).")
    ap.add_argument("run", help="the run folder (holding run.json, frames/NNNN.ply)")
    ap.add_argument("--render", type=int, metavar="FRAME",
                    help="render this frame with Cycles on the CPU (adds a floor, a sun and a "
                    "camera)")
    ap.add_argument("--output", help="the rendered PNG (default RUN/blender/NNNN.png)")
    ap.add_argument("--resolution", default="1280x720", help="WIDTHxHEIGHT (default 1280x720)")
    ap.add_argument("--samples", type=int, default=32, help="Cycles samples (default 32)")
    ap.add_argument("--subdivisions", type=int, default=2, choices=range(1, 7),
                    help="icosphere subdivisions of a grain (default 2: 80 faces)")
    ap.add_argument("--save", metavar="FILE.blend", help="save the scene as a .blend file")
    args = ap.parse_args(argv)
    m = re.fullmatch(r"(\d+)x(\d+)", args.resolution)
    if not m or not all(4 <= int(v) <= 16384 for v in m.groups()):
        ap.error(f"--resolution {args.resolution}: expected WIDTHxHEIGHT, e.g. 1280x720")
    args.resolution = (int(m.group(1)), int(m.group(2)))
    return args


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    args = parse_args(argv)
    context = bpy.context
    if not bpy.data.filepath:
        # started without a .blend: the startup file's cube, camera and light would stand in
        # the run (the cube is 2 m wide), so the scene starts empty
        for obj in list(context.scene.objects):
            bpy.data.objects.remove(obj)
    try:
        run, grains, static = load_run(args.run, context, args.subdivisions)
        if args.render is not None:
            if not run.first <= args.render <= run.last:
                raise RunError(f"--render {args.render}: the run has frames "
                               f"{run.first}-{run.last}")
            context.scene.render.resolution_x, context.scene.render.resolution_y = \
                args.resolution
            add_view(context, run, grains, static)
            output = args.output or os.path.join(run.folder, "blender", f"{args.render:04d}.png")
            render_frame(context, args.render, os.path.abspath(output), args.resolution,
                         args.samples)
        if args.save:
            bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save))
    except RunError as e:
        print(f"{PROG}: error: {e}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
