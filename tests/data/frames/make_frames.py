#!/usr/bin/env python3
"""Writes the frame files of tests/io/test_ply_corpus.cpp: two valid frames (also the fuzzing seeds)
and the malformed corpus in bad/, each file breaking one thing. Deterministic: run it again and git
sees no change."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
PROPS = ["float x", "float y", "float z", "float radius", "float vx", "float vy", "float vz",
         "uint id", "uchar state"]


def header(fmt, count, props=PROPS, before="", after=""):
    return ("ply\nformat " + fmt + " 1.0\ncomment sandflow test frame\n" + before +
            f"element vertex {count}\n" + "".join(f"property {p}\n" for p in props) + after +
            "end_header\n")


def record(x, y, z, r, vx=0.0, vy=0.0, vz=0.0, gid=0, state=0):
    return struct.pack("<7fIB", x, y, z, r, vx, vy, vz, gid, state)


GRAINS = [(0.0, 0.0, 0.005, 0.005, 0.0, 0.0, -0.5, 7, 0),
          (0.01, 0.0, 0.005, 0.005, 0.1, 0.0, 0.0, 8, 1),
          (0.005, 0.009, 0.005, 0.0045, 0.0, 0.0, 0.0, 9, 2)]


def binary(grains, count=None):
    return header("binary_little_endian", len(grains) if count is None else count).encode() + \
        b"".join(record(*g) for g in grains)


def ascii_frame(lines, props=PROPS, count=None):
    return header("ascii", len(lines) if count is None else count, props) + "".join(
        line + "\n" for line in lines)


def write(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def main():
    write("frame_binary.ply", binary(GRAINS))
    write("frame_ascii.ply", ascii_frame([" ".join(str(v) for v in g) for g in GRAINS]))

    xyzr = ["float x", "float y", "float z", "float radius"]
    good_bin = binary(GRAINS)
    cases = {
        "empty.ply": b"",
        "not_ply.ply": "PLX\nformat ascii 1.0\nend_header\n",
        "binary_garbage.ply": bytes((i * 151 + 7) % 256 for i in range(300)),
        "no_end_header.ply": header("ascii", 1)[: -len("end_header\n")],
        "no_format.ply": "ply\nelement vertex 0\nproperty float x\nend_header\n",
        "big_endian.ply": "ply\nformat binary_big_endian 1.0\nend_header\n",
        "unknown_format.ply": "ply\nformat binary_middle_endian 1.0\nend_header\n",
        "negative_count.ply": "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n",
        "count_not_a_number.ply": "ply\nformat ascii 1.0\nelement vertex many\nend_header\n",
        "huge_count_10_12.ply": header("binary_little_endian", 10**12).encode() + record(*GRAINS[0]),
        "huge_count_u64.ply": header("binary_little_endian", 2**64 - 1).encode() + b"0123456789abcdef",
        "count_exceeds_data.ply": binary(GRAINS, count=1000),
        "truncated_binary.ply": good_bin[:-5],
        "truncated_ascii.ply": ascii_frame(["0 0 0 0.005", "1 1"], xyzr, count=2),
        "nan_position.ply": ascii_frame(["0 0 0 0.005", "0 nan 0 0.005"], xyzr),
        "inf_velocity.ply": binary([GRAINS[0], (0.0, 0.0, 0.0, 0.005, float("inf"), 0.0, 0.0, 1, 0)]),
        "negative_radius.ply": ascii_frame(["0 0 0 0.005", "1 0 0 0.005", "2 0 0 -0.005"], xyzr),
        "zero_radius.ply": binary([GRAINS[0], (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1, 0)]),
        "no_radius.ply": ascii_frame(["0 0 0"], xyzr[:3]),
        "no_x.ply": ascii_frame(["0 0 0.005"], xyzr[1:]),
        "no_vertex_element.ply": "ply\nformat ascii 1.0\nelement face 0\n"
                                 "property list uchar int vertex_indices\nend_header\n",
        "non_numeric.ply": ascii_frame(["0 0 0 0.005", "1 0 zero 0.005"], xyzr),
        "bad_state.ply": ascii_frame(["0 0 0 0.005 7"], xyzr + ["uchar state"]),
        "bad_id.ply": ascii_frame(["0 0 0 0.005 1.5"], xyzr + ["double id"]),
        "list_runs_past_end.ply": header("binary_little_endian", 1,
                                         xyzr + ["list uchar int neighbours"]).encode() +
                                  struct.pack("<4fB", 0, 0, 0, 0.005, 200) + b"\0" * 12,
        "bad_list_length.ply": ascii_frame(["0 0 0 0.005 -1"], xyzr + ["list uchar int n"]),
        "property_before_element.ply": "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
        "unknown_property_type.ply": ascii_frame(["0 0 0 0.005"], ["float x", "float y", "flaot z",
                                                                    "float radius"]),
        "float_list_count.ply": ascii_frame(["0 0 0 0.005"], xyzr[:3] + ["list float int radius"]),
        "duplicate_property.ply": ascii_frame(["0 0 0 0.005"], xyzr + ["float x"]),
        "vertex_list_property.ply": ascii_frame(["1 0 0 0 0.005"], ["list uchar float x"] + xyzr[1:]),
        "unexpected_header_word.ply": "ply\nformat ascii 1.0\nvertex 3\nend_header\n",
        "count_exceeds_ascii_data.ply": "ply\nformat ascii 1.0\nelement vertex 1\n" +
                               "".join(f"property {p}\n" for p in xyzr) + "end_header\n0 0 0\n",
    }
    for name, data in cases.items():
        write(os.path.join("bad", name), data)


if __name__ == "__main__":
    main()
