#!/usr/bin/env python3
# Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
"""Writes the seed corpora of the libFuzzer harnesses (tests/fuzz/*_fuzzer.cc): a few tiny VALID
files per reader, made here from scratch, so that the fuzzer starts from inputs the reader
accepts. Usage: make_corpus.py OUT_DIR  (writes OUT_DIR/<harness>/<seed>)."""
import os
import struct
import sys
import zlib

SPLIT = b"\n--gcpstereo-fuzz-file--\n"  # fuzz_util.h kSplit


def png(width, height, channels, pixel):
    """A minimal 8-bit PNG (colour type 0 grey or 2 RGB), every pixel `pixel`."""
    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body +
                struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))
    colour_type = 0 if channels == 1 else 2
    rows = b"".join(b"\x00" + bytes(pixel) * width for _ in range(height))
    return (b"\x89PNG\r\n\x1a\n" +
            chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def seeds():
    s = {}
    xyz = [(0.0, 0.0, 1.0), (1.0, 0.5, 2.0), (-1.0, 0.25, 3.0)]
    s["ply"] = {
        "ascii.ply": ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                      "property float y\nproperty float z\nproperty float sigma\nend_header\n" +
                      "".join(f"{x} {y} {z} 0.01\n" for x, y, z in xyz)).encode(),
        "binary.ply": (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                       b"property float x\nproperty float y\nproperty float z\n"
                       b"property uchar intensity\nelement face 1\n"
                       b"property list uchar int vertex_indices\nend_header\n" +
                       b"".join(struct.pack("<fffB", x, y, z, 7) for x, y, z in xyz) +
                       struct.pack("<Biii", 3, 0, 1, 2)),
    }
    pcd_header = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\n"
                  "TYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                  "POINTS 3\n")
    s["pcd"] = {
        "ascii.pcd": (pcd_header + "DATA ascii\n" +
                      "".join(f"{x} {y} {z} 5\n" for x, y, z in xyz)).encode(),
        "binary.pcd": (pcd_header + "DATA binary\n").encode() +
                      b"".join(struct.pack("<ffff", x, y, z, 5) for x, y, z in xyz),
    }
    s["kitti_bin"] = {"scan.bin": b"".join(struct.pack("<ffff", x, y, z, 0.5) for x, y, z in xyz)}
    s["pfm"] = {
        "grey_le.pfm": b"Pf\n3 2\n-1.0\n" + struct.pack("<6f", 1, 2, 3, 4, float("inf"), 6),
        "grey_be.pfm": b"Pf\n2 2\n1.0\n" + struct.pack(">4f", 1, 2, 3, 4),
        "colour.pfm": b"PF\n2 1\n-1.0\n" + struct.pack("<6f", 1, 2, 3, 4, 5, 6),
    }
    s["strecha_camera"] = {"0000.png.camera": (
        b"100 0 15.5\n0 100 11.5\n0 0 1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.5 -0.25 2\n32 24\n")}
    s["known_centres"] = {"centres.txt": (
        b"# name X Y Z\n0004.jpg 1.5 -2.25 0.5\n0005.jpg 2 -2 0.5\nsub/0006.jpg 2.5 -1.75 0.625\n")}
    s["middlebury"] = {
        "disp2_pgm": b"\x00P5\n8 6\n255\n" + bytes([12] * 48),
        "disp2_png": b"\x01" + png(8, 6, 1, [12]),
        "nonocc_png": b"\x02" + png(8, 6, 1, [255]),
        "im2_png": b"\x03" + png(8, 6, 3, [160, 90, 40]),
    }
    cam = ("S_rect_02: 8.000000e+00 6.000000e+00\n"
           "P_rect_02: 7.0e+00 0 3.5 4.4e-01 0 7.0e+00 2.5 -2.0e-03 0 0 1 2.7e-03\n"
           "P_rect_03: 7.0e+00 0 3.5 -3.3e+00 0 7.0e+00 2.5 2.3e-03 0 0 1 3.6e-03\n"
           "R_rect_00: 1 0 0 0 1 0 0 0 1\n")
    velo = "calib_time: 15-Mar-2012 11:37:16\nR: 0 -1 0 0 0 -1 1 0 0\nT: -0.004 -0.076 -0.27\n"
    s["kitti_calibration"] = {"calib": cam.encode() + SPLIT + velo.encode()}
    s["kitti_timestamps"] = {"stamps.txt": b"".join(
        b"2011-09-26 13:02:25.%09d\n" % (100000000 * i + 12345) for i in range(4))}
    s["config"] = {
        "strecha.yaml": (b"dataset:\n  format: strecha\n  path: data\n  reference: '0005'\n"
                         b"  neighbors: ['0004', '0006']\n  scale: 0.5\nlabels:\n  count: 32\n"
                         b"  min: 2.0\n  max: 9.0\ngcp:\n  sources: [stereo]\n" + SPLIT +
                         b"optimizer.lambda_s=0.3\nlabels.spacing=inverse_depth"),
        "scene.yaml": (b"dataset:\n  format: colmap\n  path: ws\n  reference: all\n"
                       b"  neighbors: auto\n" + SPLIT + b"fusion.min_views=3"),
    }
    # COLMAP: one PINHOLE and one OPENCV camera, two images, two points.
    cams_txt = ("# Camera list\n1 PINHOLE 16 12 20 21 8 6\n"
                "2 OPENCV 16 12 20 20 8 6 0.01 -0.002 0.001 0.0005\n")
    imgs_txt = ("# Image list\n1 1 0 0 0 0 0 0 1 a.png\n8 6 1 3 4 -1\n"
                "2 0.999 0.0447 0 0 -0.5 0 0 2 sub/b.png\n7 6 2\n")
    pts_txt = "# 3D points\n1 0 0 5 10 20 30 0.5 1 0 2 0\n2 0.1 0.1 4 1 2 3 0.25 1 1\n"
    s["colmap_txt"] = {"model": cams_txt.encode() + SPLIT + imgs_txt.encode() + SPLIT +
                       pts_txt.encode()}
    cams = (struct.pack("<Q", 2) + struct.pack("<IiQQ4d", 1, 1, 16, 12, 20, 21, 8, 6) +
            struct.pack("<IiQQ8d", 2, 4, 16, 12, 20, 20, 8, 6, 0.01, -0.002, 0.001, 0.0005))
    none = 2**64 - 1
    imgs = (struct.pack("<Q", 2) +
            struct.pack("<I7dI", 1, 1, 0, 0, 0, 0, 0, 0, 1) + b"a.png\0" +
            struct.pack("<Q", 2) + struct.pack("<ddQddQ", 8, 6, 1, 3, 4, none) +
            struct.pack("<I7dI", 2, 0.999, 0.0447, 0, 0, -0.5, 0, 0, 2) + b"sub/b.png\0" +
            struct.pack("<Q", 1) + struct.pack("<ddQ", 7, 6, 2))
    pts = (struct.pack("<Q", 2) +
           struct.pack("<Q3d3BdQ", 1, 0, 0, 5, 10, 20, 30, 0.5, 2) + struct.pack("<IIII", 1, 0, 2, 0) +
           struct.pack("<Q3d3BdQ", 2, 0.1, 0.1, 4, 1, 2, 3, 0.25, 1) + struct.pack("<II", 1, 1))
    s["colmap_bin"] = {"model": cams + SPLIT + imgs + SPLIT + pts}
    fused_header = (b"ply\nformat binary_little_endian 1.0\ncomment written by gcpstereo\n"
                    b"element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                    b"property float nx\nproperty float ny\nproperty float nz\n"
                    b"property uchar red\nproperty uchar green\nproperty uchar blue\n"
                    b"property ushort views\nproperty float sigma\nend_header\n")
    s["oriented_cloud"] = {"fused.ply": fused_header + b"".join(
        struct.pack("<6f3BHf", x, y, z, 0, 0, -1, 200, 100, 50, 3, 0.01) for x, y, z in xyz[:2])}
    return s


def main():
    out = sys.argv[1]
    for harness, files in seeds().items():
        os.makedirs(os.path.join(out, harness), exist_ok=True)
        for name, data in files.items():
            with open(os.path.join(out, harness, name), "wb") as f:
                f.write(data)


if __name__ == "__main__":
    main()
