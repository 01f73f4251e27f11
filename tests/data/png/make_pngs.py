#!/usr/bin/env python3
"""Writes the PNG test images of tests/io/test_png_gray.cpp: a few valid grey images (also the
fuzzing seeds) and the malformed corpus in bad/. Deterministic: run it again and git sees no change.
Only the standard library: chunks are written by hand, so that each bad file breaks one thing."""
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SIG = b"\x89PNG\r\n\x1a\n"


def chunk(kind, data, crc=None):
    if crc is None:
        crc = zlib.crc32(kind + data)
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc & 0xFFFFFFFF)


def ihdr(w, h, depth=8, colour=0, interlace=0):
    return chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, interlace))


def rows_bytes(rows, filter_byte=0):
    return b"".join(bytes([filter_byte]) + r for r in rows)


def grey8_rows(w, h):
    return [bytes((37 * x + 91 * y) % 256 for x in range(w)) for y in range(h)]


def grey16_rows(w, h):
    return [b"".join(struct.pack(">H", (x + 10 * y) * 1000) for x in range(w)) for y in range(h)]


def png(w, h, raw, depth=8, colour=0, interlace=0, extra=b""):
    return (SIG + ihdr(w, h, depth, colour, interlace) + extra +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def adam7(w, h, pixel_rows, bytes_per_pixel):
    """The raw (filter 0) data of an Adam7-interlaced image from its full rows."""
    passes = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2),
              (0, 1, 1, 2)]
    out = b""
    for x0, y0, dx, dy in passes:
        for y in range(y0, h, dy):
            row = b"".join(pixel_rows[y][x * bytes_per_pixel:(x + 1) * bytes_per_pixel]
                           for x in range(x0, w, dx))
            if row:
                out += b"\0" + row
    return out


def write(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


def main():
    g8 = grey8_rows(5, 4)
    good = png(5, 4, rows_bytes(g8))
    write("grey8_5x4.png", good)
    g16 = grey16_rows(5, 4)
    write("grey16_5x4.png", png(5, 4, rows_bytes(g16), depth=16))
    # the same 16-bit image, Adam7-interlaced: it must read back exactly as grey16_5x4.png
    write("grey16_5x4_interlaced.png", png(5, 4, adam7(5, 4, g16, 2), depth=16, interlace=1))
    ga = [b"".join(bytes([(50 * x + y) % 256, 255]) for x in range(3)) for y in range(2)]
    write("grey_alpha_3x2.png", png(3, 2, rows_bytes(ga), colour=4))
    write("grey1_8x2.png", png(8, 2, rows_bytes([b"\xa5", b"\x0f"]), depth=1))

    bad = os.path.join("bad")
    idat = chunk(b"IDAT", zlib.compress(rows_bytes(g8), 9))
    end = chunk(b"IEND", b"")
    cases = {
        "empty.png": b"",
        "text.png": b"this is not an image\n",
        "truncated_signature.png": SIG[:5],
        "truncated_ihdr.png": (SIG + ihdr(5, 4))[:20],
        "truncated_idat.png": good[: len(SIG) + 25 + 20],
        "no_iend.png": SIG + ihdr(5, 4) + idat,
        "bad_ihdr_crc.png": SIG + chunk(b"IHDR", struct.pack(">IIBBBBB", 5, 4, 8, 0, 0, 0, 0),
                                          crc=0x12345678) + idat + end,
        "huge_100000x100000.png": SIG + ihdr(100000, 100000, 16) + idat + end,
        "huge_width_2_31.png": SIG + ihdr(0x80000000, 4) + idat + end,
        "zero_width.png": SIG + ihdr(0, 4) + idat + end,
        "rgb.png": png(2, 2, rows_bytes([b"\x10" * 6] * 2), colour=2),
        "palette.png": (SIG + ihdr(2, 2, 8, 3) + chunk(b"PLTE", b"\0\0\0\xff\xff\xff") +
                        chunk(b"IDAT", zlib.compress(rows_bytes([b"\0\1"] * 2))) + end),
        "bad_bit_depth.png": SIG + ihdr(5, 4, 3) + idat + end,
        "bad_interlace_method.png": SIG + ihdr(5, 4, 8, 0, 2) + idat + end,
        "idat_not_zlib.png": SIG + ihdr(5, 4) + chunk(b"IDAT", b"\x00\x01garbage" * 4) + end,
        "idat_too_short.png": (SIG + ihdr(5, 4) +
                               chunk(b"IDAT", zlib.compress(rows_bytes(g8[:2]))) + end),
        "bad_filter_type.png": (SIG + ihdr(5, 4) +
                                chunk(b"IDAT", zlib.compress(rows_bytes(g8, filter_byte=9))) + end),
        "missing_ihdr.png": SIG + idat + end,
        "chunk_length_huge.png": SIG + ihdr(5, 4) + struct.pack(">I", 0x7FFFFFFF) + b"IDAT" + b"\0" * 16,
        # found by fuzzing: libpng allocated and zeroed the 1.4 GB this text chunk announces
        "itxt_announces_1_4_gb.png": SIG + ihdr(5, 4) + struct.pack(">I", 0x5268FD16) + b"iTXt" + b"abc",
        "garbage_after_signature.png": SIG + bytes((i * 97 + 13) % 256 for i in range(200)),
    }
    for name, data in cases.items():
        write(os.path.join(bad, name), data)


if __name__ == "__main__":
    main()
