#!/usr/bin/env python3
"""Mesh helper for scripts/fetch_meshes.sh (standard library only, python3 >= 3.7).

  mesh_tool.py convert SRC OUT [--comment TEXT]...
      Reads a triangle mesh from SRC (ASCII PLY or OFF, optionally gzip-compressed; the format is
      told from the first line, not the name) and writes OUT as binary little-endian PLY:
          element vertex N   property float x, y, z
          element face M     property list uchar int vertex_indices   (always 3 indices)
      Every --comment becomes a 'comment' line of the header. Faces that are not triangles, indices
      out of range and non-finite coordinates are errors (nothing is triangulated or repaired).
      OUT is written to OUT.tmp and renamed only after it validated.

  mesh_tool.py validate FILE [--expect V T]
      Checks that FILE is exactly such a PLY: the header's counts match the file's size to the
      byte, every face has 3 indices in [0, V), every coordinate is finite, and (with --expect)
      that it has V vertices and T triangles. Prints one line
          V T xmin xmax ymin ymax zmin zmax degenerate source
      where 'degenerate' counts triangles that repeat a vertex index (reported, not an error) and
      'source' is the header's 'comment source: ...' text (or '-'). Exits 1 with a message on
      stderr if the file is not valid.

  mesh_tool.py npm-integrity TARBALL METADATA_JSON
      Checks TARBALL against the registry's dist.integrity (sha512, base64) and dist.shasum (sha1,
      hex) in METADATA_JSON (the registry document of one version); prints its tarball URL.
"""

import array
import base64
import gzip
import hashlib
import json
import math
import os
import struct
import sys

FACE = struct.Struct("<Biii")  # uchar count (3), int a, b, c


class MeshError(Exception):
    pass


def open_text(path):
    with open(path, "rb") as f:
        magic = f.read(2)
    if magic == b"\x1f\x8b":
        return gzip.open(path, "rt", encoding="ascii", errors="strict")
    return open(path, "rt", encoding="ascii", errors="strict")


# ------------------------------------------------------------------------------------------------
# Reading


def read_ascii_ply(f, path):
    """Returns (vertices as flat list of floats, faces as flat list of ints)."""
    if f.readline().strip() != "ply":
        raise MeshError(f"{path}: not a PLY file")
    elements = []  # [name, count, [(name, is_list)]]
    fmt = None
    while True:
        line = f.readline()
        if not line:
            raise MeshError(f"{path}: PLY header has no end_header")
        tok = line.split()
        if not tok or tok[0] in ("comment", "obj_info"):
            continue
        if tok[0] == "format":
            fmt = tok[1] if len(tok) > 1 else None
        elif tok[0] == "element":
            elements.append([tok[1], int(tok[2]), []])
        elif tok[0] == "property":
            if not elements:
                raise MeshError(f"{path}: property before any element")
            if tok[1] == "list":
                elements[-1][2].append((tok[4], True))
            else:
                elements[-1][2].append((tok[2], False))
        elif tok[0] == "end_header":
            break
    if fmt != "ascii":
        raise MeshError(f"{path}: PLY format {fmt!r}; only ascii PLY is read as a source")
    verts, faces = [], []
    for name, count, props in elements:
        if name == "vertex":
            names = [p for p, is_list in props]
            if any(is_list for _, is_list in props):
                raise MeshError(f"{path}: list property in vertex element")
            try:
                ix, iy, iz = names.index("x"), names.index("y"), names.index("z")
            except ValueError:
                raise MeshError(f"{path}: vertex element lacks x, y or z") from None
            for i in range(count):
                tok = f.readline().split()
                if len(tok) != len(props):
                    raise MeshError(f"{path}: vertex {i} has {len(tok)} values, not {len(props)}")
                verts += (float(tok[ix]), float(tok[iy]), float(tok[iz]))
        elif name == "face":
            if len(props) != 1 or not props[0][1]:
                raise MeshError(f"{path}: face element must hold exactly one list property")
            for i in range(count):
                tok = f.readline().split()
                if not tok or int(tok[0]) != 3 or len(tok) != 4:
                    raise MeshError(f"{path}: face {i} is not a triangle: {' '.join(tok)!r}")
                faces += (int(tok[1]), int(tok[2]), int(tok[3]))
        else:  # skip an unknown element (one line per item in ASCII PLY)
            for _ in range(count):
                f.readline()
    return verts, faces


def read_off(f, path):
    """OFF: 'OFF', then 'nv nf ne', nv lines 'x y z', nf lines 'n i0 .. in-1' ('#' comments)."""

    def lines():
        for raw in f:
            s = raw.split("#", 1)[0].split()
            if s:
                yield s

    it = lines()
    first = next(it, None)
    if not first or first[0] != "OFF":
        raise MeshError(f"{path}: not an OFF file (first word {first[0] if first else None!r})")
    counts = first[1:] if len(first) > 1 else next(it, [])
    if len(counts) < 2:
        raise MeshError(f"{path}: OFF counts line missing")
    nv, nf = int(counts[0]), int(counts[1])
    verts, faces = [], []
    for i in range(nv):
        tok = next(it, None)
        if tok is None or len(tok) < 3:
            raise MeshError(f"{path}: vertex {i} missing or short")
        verts += (float(tok[0]), float(tok[1]), float(tok[2]))
    for i in range(nf):
        tok = next(it, None)
        if tok is None or int(tok[0]) != 3 or len(tok) < 4:
            raise MeshError(f"{path}: face {i} missing or not a triangle: {tok!r}")
        faces += (int(tok[1]), int(tok[2]), int(tok[3]))
    return verts, faces


def read_mesh(path):
    with open_text(path) as f:
        head = f.readline().strip()
    with open_text(path) as f:
        if head == "ply":
            return read_ascii_ply(f, path)
        if head.startswith("OFF"):
            return read_off(f, path)
    raise MeshError(f"{path}: unknown mesh format (first line {head[:20]!r})")


# ------------------------------------------------------------------------------------------------
# Writing and validating binary PLY


def header_bytes(nv, nf, comments):
    lines = ["ply", "format binary_little_endian 1.0"]
    lines += [f"comment {c}" for c in comments]
    lines += [f"element vertex {nv}", "property float x", "property float y", "property float z",
              f"element face {nf}", "property list uchar int vertex_indices", "end_header"]
    return ("\n".join(lines) + "\n").encode("ascii")


def write_ply(path, verts, faces, comments):
    nv, nf = len(verts) // 3, len(faces) // 3
    for v in verts:
        if not math.isfinite(v):
            raise MeshError("source has a non-finite coordinate")
    lo, hi = (min(faces), max(faces)) if faces else (0, -1)
    if faces and (lo < 0 or hi >= nv):
        raise MeshError(f"source has a vertex index out of range [0, {nv}): {lo if lo < 0 else hi}")
    va = array.array("f", verts)
    if sys.byteorder != "little":
        va.byteswap()
    fb = bytearray(FACE.size * nf)
    for k in range(nf):
        FACE.pack_into(fb, FACE.size * k, 3, faces[3 * k], faces[3 * k + 1], faces[3 * k + 2])
    tmp = path + ".tmp"
    with open(tmp, "wb") as out:
        out.write(header_bytes(nv, nf, comments))
        out.write(va.tobytes())
        out.write(fb)
    return tmp


def parse_binary_ply_header(data, path):
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise MeshError(f"{path}: not a PLY file with an end_header line")
    body = end + len(b"end_header\n")
    lines = data[:end].decode("ascii", errors="replace").split("\n")
    nv = nf = None
    source = "-"
    expected = ["ply", "format binary_little_endian 1.0", None, "property float x",
                "property float y", "property float z", None,
                "property list uchar int vertex_indices"]
    structural = []
    for ln in lines:
        if ln.startswith("comment "):
            if ln.startswith("comment source: "):
                source = ln[len("comment source: "):]
            continue
        if ln:
            structural.append(ln)
    if len(structural) != len(expected):
        raise MeshError(f"{path}: header is not the expected vertex(float xyz) + face(list) layout")
    for want, got in zip(expected, structural):
        if want is None:
            continue
        if got != want:
            raise MeshError(f"{path}: header line {got!r}, expected {want!r}")
    ev, ef = structural[2].split(), structural[6].split()
    if ev[:2] != ["element", "vertex"] or ef[:2] != ["element", "face"] or len(ev) != 3 or len(ef) != 3:
        raise MeshError(f"{path}: header elements are not 'vertex' then 'face'")
    nv, nf = int(ev[2]), int(ef[2])
    return nv, nf, body, source


def validate(path, expect=None):
    with open(path, "rb") as f:
        data = f.read()
    nv, nf, body, source = parse_binary_ply_header(data, path)
    want = body + 12 * nv + FACE.size * nf
    if len(data) != want:
        raise MeshError(f"{path}: {len(data)} bytes, but the header's counts ({nv} vertices, "
                        f"{nf} faces) need {want}")
    if expect and (nv, nf) != expect:
        raise MeshError(f"{path}: {nv} vertices and {nf} triangles, expected {expect[0]} and {expect[1]}")
    va = array.array("f")
    va.frombytes(data[body:body + 12 * nv])
    if sys.byteorder != "little":
        va.byteswap()
    for v in va:
        if not math.isfinite(v):
            raise MeshError(f"{path}: non-finite coordinate")
    xs, ys, zs = va[0::3], va[1::3], va[2::3]
    bbox = (min(xs), max(xs), min(ys), max(ys), min(zs), max(zs)) if nv else (0,) * 6
    degenerate = 0
    lo, hi = 0, -1
    off = body + 12 * nv
    for k, (n, a, b, c) in enumerate(FACE.iter_unpack(data[off:])):
        if n != 3:
            raise MeshError(f"{path}: face {k} has {n} indices, not 3")
        lo = min(lo, a, b, c)
        hi = max(hi, a, b, c)
        if a == b or b == c or a == c:
            degenerate += 1
    if lo < 0 or hi >= nv:
        raise MeshError(f"{path}: vertex index {lo if lo < 0 else hi} out of range [0, {nv})")
    return nv, nf, bbox, degenerate, source


# ------------------------------------------------------------------------------------------------


def npm_integrity(tarball, meta_path):
    with open(meta_path, "rb") as f:
        meta = json.load(f)
    dist = meta.get("dist", {})
    with open(tarball, "rb") as f:
        blob = f.read()
    checked = []
    integ = dist.get("integrity", "")
    if integ.startswith("sha512-"):
        got = base64.b64encode(hashlib.sha512(blob).digest()).decode()
        if got != integ[len("sha512-"):]:
            raise MeshError(f"{tarball}: sha512 {got} does not match the registry's {integ}")
        checked.append("sha512")
    shasum = dist.get("shasum", "")
    if shasum:
        got = hashlib.sha1(blob).hexdigest()
        if got != shasum:
            raise MeshError(f"{tarball}: sha1 {got} does not match the registry's shasum {shasum}")
        checked.append("sha1")
    if not checked:
        raise MeshError(f"{meta_path}: registry metadata has neither dist.integrity nor dist.shasum")
    print(dist.get("tarball", ""))


def main(argv):
    if len(argv) >= 3 and argv[0] == "convert":
        src, out, rest = argv[1], argv[2], argv[3:]
        comments = []
        while rest:
            if rest[0] != "--comment" or len(rest) < 2:
                raise SystemExit(f"mesh_tool.py convert: unexpected argument {rest[0]!r}")
            comments.append(rest[1])
            rest = rest[2:]
        verts, faces = read_mesh(src)
        tmp = write_ply(out, verts, faces, comments)
        try:
            validate(tmp, (len(verts) // 3, len(faces) // 3))
        except MeshError:
            os.unlink(tmp)
            raise
        os.replace(tmp, out)
    elif len(argv) in (2, 5) and argv[0] == "validate":
        expect = None
        if len(argv) == 5:
            if argv[2] != "--expect":
                raise SystemExit("usage: mesh_tool.py validate FILE [--expect V T]")
            expect = (int(argv[3]), int(argv[4]))
        nv, nf, bbox, degenerate, source = validate(argv[1], expect)
        print(nv, nf, " ".join(f"{b:.6g}" for b in bbox), degenerate, source)
    elif len(argv) == 3 and argv[0] == "npm-integrity":
        npm_integrity(argv[1], argv[2])
    else:
        raise SystemExit(__doc__)


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except (MeshError, OSError, ValueError, EOFError, UnicodeDecodeError) as e:
        print(f"mesh_tool.py: {e}", file=sys.stderr)
        sys.exit(1)
