#!/usr/bin/env python3
"""Writes the test meshes of tests/geometry/test_mesh_io.cpp: a unit cube in every format, a
tetrahedron, and the malformed corpus in bad/ (also the seed corpus for fuzzing the readers).
Deterministic: run it again and git sees no change (gzip files carry mtime 0)."""
import gzip
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
        "unknown_format.stl": "solid cube\nendsolid cube\n",
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
