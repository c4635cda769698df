# Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
"""Small readers shared by the tools' scripts (standard library only): the header of a Netpbm-style
file (PGM, PFM), one-channel PFM images and Strecha .camera files. Errors raise ValueError with the
path; each script turns it into its own kind of failure."""

import array
import sys


def header_tokens(data, count):
    """The first `count` whitespace-separated tokens of `data` (bytes), '#' comments skipped, and
    the offset just past the single whitespace that ends the last one (where the pixels start)."""
    tokens, pos = [], 0
    while len(tokens) < count:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            while data[pos:pos + 1] not in (b"\n", b""):
                pos += 1
            continue
        if pos >= len(data):
            raise ValueError("header ends after %d of %d fields" % (len(tokens), count))
        start = pos
        while pos < len(data) and not data[pos:pos + 1].isspace():
            pos += 1
        tokens.append(data[start:pos])
    return tokens, pos + 1


def read_pfm(path):
    """(width, height, values) of a one-channel PFM; values: array('f'), rows top to bottom."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        tokens, pos = header_tokens(data, 4)
    except ValueError as e:
        raise ValueError("%s: %s" % (path, e))
    if tokens[0] != b"Pf":
        raise ValueError("%s: not a one-channel PFM (magic %r)" % (path, tokens[0]))
    width, height, scale = int(tokens[1]), int(tokens[2]), float(tokens[3])
    pixels = data[pos:pos + 4 * width * height]
    if len(pixels) != 4 * width * height:
        raise ValueError("%s: truncated PFM (%d of %d bytes of pixels)" %
                         (path, len(pixels), 4 * width * height))
    values = array.array("f")
    values.frombytes(pixels)
    if (scale < 0) != (sys.byteorder == "little"):  # negative scale: little-endian
        values.byteswap()
    top_down = array.array("f")
    for row in range(height - 1, -1, -1):  # PFM stores rows bottom to top
        top_down.extend(values[row * width:(row + 1) * width])
    return width, height, top_down


def read_strecha_camera(path):
    """{'K': 3x3, 'R': 3x3 camera-to-world, 'C': centre, 'size': (width, height)} of a Strecha
    .camera file (K, distortion, R, C, size: 9 lines), as gcpstereo's reader takes it."""
    with open(path) as f:
        lines = [line.split() for line in f if line.strip()]
    if len(lines) != 9:
        raise ValueError("%s: expected 9 lines (K, distortion, R, C, size)" % path)
    num = [[float(v) for v in line] for line in lines]
    return {"K": num[0:3], "R": num[4:7], "C": num[7], "size": (int(num[8][0]), int(num[8][1]))}
