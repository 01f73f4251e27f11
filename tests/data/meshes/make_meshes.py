#!/usr/bin/env python3
"""Writes the test meshes of tests/geometry/test_mesh_io.cpp: a unit cube in every format, a
tetrahedron, and the malformed corpus in bad/ (also the seed corpus for fuzzing the readers).
Deterministic: run it again and git sees no change (gzip files carry mtime 0)."""
import base64
import gzip
import json
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_F = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (0, 4, 7, 3), (1, 2, 6, 5)]


def write(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


def gz(data):
    return gzip.compress(data.encode() if isinstance(data, str) else data, mtime=0)


def cube_obj():
    s = "# unit cube: quads, v/vt/vn corners, relative indices\no cube\n"
    s += "".join(f"v {x} {y} {z}\n" for x, y, z in CUBE_V)
    s += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 -1\n"
    s += "f 1/1/1 4/4/1 3/3/1 2/2/1\n"  # bottom: i/t/n
    s += "f -4 -3 -2 -1\n"  # top: relative to the 8 vertices so far
    s += "f 1//1 2//1 6//1 5//1\n"  # front: i//n
    s += "f 3/1 4/2 8/3 7/4\n"  # back: i/t
    s += "usemtl stone\ns off\n"
    s += "f 1 5 8 4\nf 2 3 7 6\n"
    return s


def cube_off():
    s = "OFF\n# unit cube\n\n8 6 12\n"
    s += "".join(f"{x} {y} {z}\n" for x, y, z in CUBE_V)
    s += "".join("4 " + " ".join(map(str, f)) + "  # quad\n" for f in CUBE_F)
    return s


def ply_header(fmt, nv, nf, vtype="float", extra=True):
    h = f"ply\nformat {fmt} 1.0\ncomment unit cube\nelement vertex {nv}\n"
    h += "".join(f"property {vtype} {c}\n" for c in "xyz")
    if extra:
        h += "property float nx\nproperty uchar red\n"
    h += f"element face {nf}\nproperty list uchar int vertex_indices\n"
    if extra:
        h += "element material 1\nproperty list uint uchar name\n"
    return h + "end_header\n"


def cube_ply_ascii():
    s = ply_header("ascii", 8, 6)
    s += "".join(f"{x} {y} {z} 0.5 200\n" for x, y, z in CUBE_V)
    s += "".join("4 " + " ".join(map(str, f)) + "\n" for f in CUBE_F)
    return s + "3 1 2 3\n"


def cube_ply_binary(endian, vtype="float"):
    fmt = "binary_little_endian" if endian == "<" else "binary_big_endian"
    code = "f" if vtype == "float" else "d"
    b = ply_header(fmt, 8, 6, vtype).encode()
    for v in CUBE_V:
        b += struct.pack(endian + 3 * code + "fB", *v, 0.5, 200)
    for f in CUBE_F:
        b += struct.pack(endian + "B4i", 4, *f)
    return b + struct.pack(endian + "I3B", 3, 1, 2, 3)


# The cube's quads split as the readers fan them: (a, b, c), (a, c, d)
CUBE_T = [t for a, b, c, d in CUBE_F for t in ((a, b, c), (a, c, d))]


def facet_normal(t):
    p, q, r = (CUBE_V[i] for i in t)
    u = [q[k] - p[k] for k in range(3)]
    v = [r[k] - p[k] for k in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    length = sum(c * c for c in n) ** 0.5
    return [c / length for c in n]


def cube_stl_ascii(name="cube"):
    s = f"solid {name}\n"
    for t in CUBE_T:
        s += "  facet normal {:g} {:g} {:g}\n    outer loop\n".format(*facet_normal(t))
        s += "".join(f"      vertex {x} {y} {z}\n" for x, y, z in (CUBE_V[i] for i in t))
        s += "    endloop\n  endfacet\n"
    return s + f"endsolid {name}\n"


def cube_stl_binary(header=b"binary STL: unit cube", count=None):
    b = header.ljust(80, b"\0") + struct.pack("<I", len(CUBE_T) if count is None else count)
    for t in CUBE_T:
        b += struct.pack("<3f", *facet_normal(t))
        b += b"".join(struct.pack("<3f", *CUBE_V[i]) for i in t) + b"\0\0"
    return b


# glTF 2.0: the cube centred on the origin, moved to [0, 1]^3 by its node's translation
def cube_gltf_parts(uri=None, positions=None, indices=None, count=8):
    positions = positions or [(x - 0.5, y - 0.5, z - 0.5) for x, y, z in CUBE_V]
    indices = indices or [i for t in CUBE_T for i in t]
    pos = b"".join(struct.pack("<3f", *p) for p in positions)
    idx = b"".join(struct.pack("<H", i) for i in indices)
    buffer = pos + idx
    gltf = {
        "asset": {"version": "2.0", "generator": "make_meshes.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "translation": [0.5, 0.5, 0.5]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "buffers": [{"byteLength": len(buffer)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos), "target": 34962},
                        {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx),
                         "target": 34963}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
                       "min": [-0.5] * 3, "max": [0.5] * 3},
                      {"bufferView": 1, "componentType": 5123, "count": len(indices),
                       "type": "SCALAR"}],
    }
    if uri is not None:
        gltf["buffers"][0]["uri"] = uri
    return gltf, buffer


def cube_gltf(**kw):
    gltf, buffer = cube_gltf_parts(**kw)
    gltf["buffers"][0]["uri"] = ("data:application/octet-stream;base64," +
                                 base64.b64encode(buffer).decode())
    return json.dumps(gltf, indent=1) + "\n"


def cube_glb():
    gltf, buffer = cube_gltf_parts()
    text = json.dumps(gltf).encode()
    text += b" " * (-len(text) % 4)
    buffer += b"\0" * (-len(buffer) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    chunks += struct.pack("<I4s", len(buffer), b"BIN\0") + buffer
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


# COLLADA (not read: only the corpus has one): coordinates in centimetres, <unit> says so; z up
def cube_dae(p):
    coordinates = " ".join(f"{100 * c}" for v in CUBE_V for c in v)
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="cube-mesh" name="cube">
      <mesh>
        <source id="cube-positions">
          <float_array id="cube-positions-array" count="24">{coordinates}</float_array>
          <technique_common>
            <accessor source="#cube-positions-array" count="8" stride="3">
              <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
            </accessor>
          </technique_common>
        </source>
        <vertices id="cube-vertices"><input semantic="POSITION" source="#cube-positions"/></vertices>
        <polylist count="6">
          <input semantic="VERTEX" source="#cube-vertices" offset="0"/>
          <vcount>4 4 4 4 4 4</vcount>
          <p>{p}</p>
        </polylist>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="cube" name="cube"><instance_geometry url="#cube-mesh"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


# ASCII FBX 7.4 (not read: only the corpus has one): the cube centred on the origin in centimetres
# (UnitScaleFactor 1), moved to [0, 100]^3 cm by its model's translation; a polygon's last index
# is written as -(i + 1)
def cube_fbx():
    coordinates = ",".join(f"{100 * c - 50}" for v in CUBE_V for c in v)
    indices = ",".join(str(i) if k < 3 else str(-i - 1) for f in CUBE_F for k, i in enumerate(f))
    n_coordinates = coordinates.count(",") + 1
    n_indices = indices.count(",") + 1
    return f"""; FBX 7.4.0 project file
FBXHeaderExtension:  {{
\tFBXHeaderVersion: 1003
\tFBXVersion: 7400
}}
GlobalSettings:  {{
\tVersion: 1000
\tProperties70:  {{
\t\tP: "UpAxis", "int", "Integer", "",2
\t\tP: "UnitScaleFactor", "double", "Number", "",1
\t}}
}}
Definitions:  {{
\tVersion: 100
\tCount: 2
\tObjectType: "Geometry" {{
\t\tCount: 1
\t}}
\tObjectType: "Model" {{
\t\tCount: 1
\t}}
}}
Objects:  {{
\tGeometry: 1000, "Geometry::cube", "Mesh" {{
\t\tProperties70:  {{
\t\t}}
\t\tVertices: *{n_coordinates} {{
\t\t\ta: {coordinates}
\t\t}}
\t\tPolygonVertexIndex: *{n_indices} {{
\t\t\ta: {indices}
\t\t}}
\t\tGeometryVersion: 124
\t}}
\tModel: 2000, "Model::cube", "Mesh" {{
\t\tVersion: 232
\t\tProperties70:  {{
\t\t\tP: "Lcl Translation", "Lcl Translation", "", "A",50,50,50
\t\t}}
\t}}
}}
Connections:  {{
\tC: "OO",1000,2000
\tC: "OO",2000,0
}}
"""


def tetra_off():
    return ("COFF 4 4 6\n# coloured tetrahedron, counts on the header line\n"
            "0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n0 0 1 9 9 9 255\n"
            "3 0 2 1\n3 0 1 3 0.5 0.5 0.5\n3 0 3 2\n3 1 2 3\n")


def tetra_ply():
    return ("ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
            "property double z\nelement face 4\nproperty list uchar uint vertex_index\nend_header\n"
            "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")


def bad_files():
    le = cube_ply_binary("<")
    header_len = len(ply_header("binary_little_endian", 8, 6))
    be_header = ply_header("binary_big_endian", 8, 6).encode()
    nan_cube = bytearray(le)
    struct.pack_into("<f", nan_cube, header_len + 2 * 17 + 4, float("nan"))  # vertex 2, y
    bad_index = bytearray(cube_ply_binary(">"))
    struct.pack_into(">i", bad_index, len(be_header) + 8 * 17 + 3 * 17 + 1 + 8, 8)  # face 3, corner 2
    long_list = le[: header_len + 8 * 17] + struct.pack("<B4i", 4, 0, 1, 2, 3) + struct.pack("<B", 255)
    stl = cube_stl_binary()
    stl_solid = cube_stl_binary(header=b"solid cube (a binary STL whose header starts like ASCII)")
    nan_stl = bytearray(stl)
    struct.pack_into("<f", nan_stl, 84 + 2 * 50 + 12 + 12 + 4, float("nan"))  # facet 2, vertex 1, y
    ascii_stl = cube_stl_ascii()
    first_vertex = ascii_stl.index("      vertex 0 1 0")  # facet 0's second vertex
    four_vertices = ascii_stl.replace("    endloop", "      vertex 1 1 1\n    endloop", 1)
    gltf_nan = cube_gltf(positions=[(float("nan"), 0, 0)] + [(x - .5, y - .5, z - .5)
                                                             for x, y, z in CUBE_V[1:]])
    return {
        "obj_non_numeric.obj": "v 0 0 0\nv 1 0 0\nv 1 abc 0\nf 1 2 3\n",
        "obj_index_out_of_range.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n",
        "obj_relative_out_of_range.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\n# relative\nf -1 -2 -4\n",
        "obj_zero_index.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        "obj_nan.obj": "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
        "obj_inf.obj": "v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n",
        "obj_missing_coordinate.obj": "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
        "obj_short_face.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
        "obj_garbage.obj": b"v 0 0 0\n\x00\x17\xff\xfeELF\x01\x02\n",
        "obj_empty.obj": "# nothing but comments\n\n# and blank lines\n",
        "obj_degenerate.obj": "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n",
        "ply_not_ply.ply": "PLX\nformat ascii 1.0\nend_header\n",
        "ply_empty_file.ply": "",
        "ply_bad_format.ply": "ply\nformat binary_middle_endian 1.0\nend_header\n",
        "ply_no_end_header.ply": "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n",
        "ply_huge_count.ply": "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n"
                              "property float x\nproperty float y\nproperty float z\nend_header\n",
        "ply_count_exceeds_file.ply": "ply\nformat binary_little_endian 1.0\nelement vertex 1000000\n"
                                      "property float x\nproperty float y\nproperty float z\n"
                                      "element face 0\nproperty list uchar int vertex_indices\n"
                                      "end_header\n" + 60 * "\0",
        "ply_truncated_ascii.ply": cube_ply_ascii()[: cube_ply_ascii().index("4 2 3 7 6")],
        "ply_truncated_binary.ply": le[: header_len + 8 * 17 + 2 * 17 + 1 + 4 + 2],
        "ply_non_numeric.ply": cube_ply_ascii().replace("1 1 0 0.5", "1 one 0 0.5"),
        "ply_index_out_of_range.ply": cube_ply_ascii().replace("4 1 2 6 5", "4 1 2 6 8"),
        "ply_nan_binary.ply": bytes(nan_cube),
        "ply_index_out_of_range_be.ply": bytes(bad_index),
        "ply_list_too_long.ply": long_list,
        "ply_truncated_last_record.ply": le[:-5],  # inside the material's uint list count
        "ply_short_face.ply": cube_ply_ascii().replace("4 0 1 5 4", "2 0 1"),
        "off_bad_header.off": "OFFX\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        "off_binary.off": "OFF BINARY\n",
        "off_huge_count.off": "OFF\n1000000000000 1 0\n",
        "off_count_exceeds_file.off": "OFF\n# a lie\n5000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        "off_truncated.off": cube_off()[: cube_off().index("4 2 3 7 6")],
        "off_index_out_of_range.off": "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
        "off_non_numeric.off": "OFF\n3 1 0\n0 0 0\n1 0 0x\n0 1 0\n3 0 1 2\n",
        "off_face_too_short.off": "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n",
        "off_4d.off": "4OFF\n3 1 0\n0 0 0 0\n1 0 0 0\n0 1 0 0\n3 0 1 2\n",
        "gz_truncated.obj.gz": gz(cube_obj())[:60],
        "gz_not_gzip.obj.gz": cube_obj(),
        "unknown_format.3ds": "MM\0\0",
        "stl_empty_file.stl": "",
        "stl_short_header.stl": b"\0" * 60,
        "stl_empty_binary.stl": cube_stl_binary()[:80] + struct.pack("<I", 0),
        "stl_empty_ascii.stl": "solid empty\nendsolid empty\n",
        "stl_truncated_binary.stl": stl[: 84 + 5 * 50 + 20],
        "stl_truncated_binary_solid_header.stl": stl_solid[: 84 + 5 * 50 + 20],
        "stl_count_too_large.stl": cube_stl_binary(count=13),
        "stl_count_too_small.stl": cube_stl_binary(count=11),
        "stl_huge_count.stl": cube_stl_binary(count=0xFFFFFFFF),
        "stl_nan_binary.stl": bytes(nan_stl),
        "stl_nan_ascii.stl": ascii_stl[:first_vertex] + "      vertex nan 1 0" +
                             ascii_stl[first_vertex + len("      vertex 0 1 0"):],
        "stl_inf_ascii.stl": ascii_stl.replace("vertex 1 1 1", "vertex 1 1e999 1", 1),
        "stl_non_numeric_ascii.stl": ascii_stl.replace("vertex 1 1 1", "vertex 1 abc 1", 1),
        "stl_missing_coordinate_ascii.stl": ascii_stl.replace("vertex 1 1 1\n", "vertex 1 1\n", 1),
        "stl_truncated_ascii.stl": ascii_stl[: ascii_stl.index("vertex 1 1 1")],
        "stl_four_vertices_ascii.stl": four_vertices,
        "stl_degenerate_ascii.stl": "solid flat\n facet normal 0 0 0\n  outer loop\n"
                                    "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 2 0 0\n"
                                    "  endloop\n endfacet\nendsolid flat\n",
        "gltf_not_json.gltf": "this is not JSON\n",
        "gltf_truncated.gltf": cube_gltf()[:300],
        "gltf_missing_buffer.gltf": json.dumps(cube_gltf_parts(uri="missing.bin")[0]),
        "gltf_accessor_past_buffer.gltf": cube_gltf(count=800),
        "gltf_index_out_of_range.gltf": cube_gltf(indices=[0, 1, 99] + [i for t in CUBE_T[1:]
                                                                        for i in t]),
        "gltf_nan.gltf": gltf_nan,
        "gltf_number_overflow.gltf": '{"asset": {"version": "2.0"}, "scene": 1e999}\n',
        "glb_truncated.glb": cube_glb()[:100],
        # what assimp 5.2 did to FBX and COLLADA files, which are therefore not read: a model
        # connected to itself overflowed its FBX reader's stack (a crash), an index that is not a
        # number made its COLLADA reader take 12 GB in a minute, and more
        "fbx_model_connected_to_itself.fbx": cube_fbx().replace(
            'C: "OO",2000,0', 'C: "OO",2000,2000\n\tC: "OO",2000,0'),
        "dae_index_not_a_number.dae": cube_dae(p=" ".join(str(i) for f in CUBE_F for i in f)
                                               .replace("0 1 5 4", "0 ? 5 4", 1)),
    }


def main():
    write("cube.obj", cube_obj())
    write("cube.off", cube_off())
    write("cube_ascii.ply", cube_ply_ascii())
    write("cube_le.ply", cube_ply_binary("<"))
    write("cube_be.ply", cube_ply_binary(">"))
    write("cube_be_double.ply", cube_ply_binary(">", "double"))
    write("cube.obj.gz", gz(cube_obj()))
    write("cube.off.gz", gz(cube_off()))
    write("cube_le.ply.gz", gz(cube_ply_binary("<")))
    write("cube.stl", cube_stl_ascii())
    write("cube_binary.stl", cube_stl_binary())
    write("cube.stl.gz", gz(cube_stl_binary()))
    write("cube.gltf", cube_gltf())
    gltf, buffer = cube_gltf_parts(uri="cube_external.bin")
    write("cube_external.gltf", json.dumps(gltf, indent=1) + "\n")
    write("cube_external.bin", buffer)
    write("cube.glb", cube_glb())
    write("tetrahedron.off", tetra_off())
    write("tetrahedron.ply", tetra_ply())
    os.makedirs(os.path.join(HERE, "bad"), exist_ok=True)
    for name, data in bad_files().items():
        write(os.path.join("bad", name), data)
    h = len(ply_header("binary_little_endian", 8, 6))
    print("le header", h, "truncated fails at byte", h + 8 * 17 + 2 * 17 + 1 + 4,
          "nan vertex 2 ends at", h + 3 * 17)
    hb = len(ply_header("binary_big_endian", 8, 6))
    print("be header", hb, "bad index read ends at", hb + 8 * 17 + 3 * 17 + 1 + 12)


main()
