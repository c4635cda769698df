#!/usr/bin/env python3
# Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
"""Scores point clouds (PLY, ASCII or binary) against a synthetic set's exact depth maps: any
cloud in the set's world frame, e.g. what `colmap stereo_fusion` or `colmap poisson_mesher` made
of a gcpstereo run's output.colmap workspace (README, "Using gcpstereo depth maps in COLMAP"),
beside gcpstereo's own fused.ply.

Each point is projected into every view of DATA (Strecha cameras, DATA/cameras/*.camera) and
compared with the exact depth at the nearest pixel (DATA/gt/<view>.depth.pfm); its error is the
smallest |z - z_gt| over the views it projects into (the view that sees it). Prints per cloud: the
point count, the bounding box, the median error and the share of the points within 1, 2, 5 and
10 cm (points no view sees count as outside).

Usage: score_cloud_on_synth.py DATA CLOUD.ply [CLOUD.ply ...]
Pure Python (no numpy): meant for the tiny and small presets.
"""
import math
import os
import struct
import sys

from file_formats import read_pfm, read_strecha_camera


def read_ply_points(path):
    """The x, y, z of every vertex of a PLY file."""
    with open(path, 'rb') as f:
        data = f.read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    header = data[:end].decode().splitlines()
    encoding = [line.split()[1] for line in header if line.startswith('format')][0]
    count, properties, in_vertex = 0, [], False
    for line in header:
        t = line.split()
        if t[:2] == ['element', 'vertex']:
            count, in_vertex = int(t[2]), True
        elif t and t[0] == 'element':
            in_vertex = False
        elif t and t[0] == 'property' and in_vertex:
            properties.append((t[2], t[1]))
    names = [p[0] for p in properties]
    ix, iy, iz = names.index('x'), names.index('y'), names.index('z')
    points = []
    if encoding == 'ascii':
        for line in data[end:].decode().splitlines()[:count]:
            v = line.split()
            points.append((float(v[ix]), float(v[iy]), float(v[iz])))
        return points
    codes = {'float': 'f', 'float32': 'f', 'double': 'd', 'float64': 'd', 'uchar': 'B',
             'uint8': 'B', 'char': 'b', 'int8': 'b', 'ushort': 'H', 'uint16': 'H', 'short': 'h',
             'int16': 'h', 'uint': 'I', 'uint32': 'I', 'int': 'i', 'int32': 'i'}
    record = ('<' if 'little' in encoding else '>') + ''.join(codes[p[1]] for p in properties)
    size = struct.calcsize(record)
    for k in range(count):
        v = struct.unpack_from(record, data, end + k * size)
        points.append((v[ix], v[iy], v[iz]))
    return points


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    data = sys.argv[1]
    views = []
    for name in sorted(os.listdir(os.path.join(data, 'cameras'))):
        camera = read_strecha_camera(os.path.join(data, 'cameras', name))
        K, R, C, (width, height) = camera['K'], camera['R'], camera['C'], camera['size']
        gt_width, gt_height, gt = read_pfm(
            os.path.join(data, 'gt', name.split('.')[0] + '.depth.pfm'))
        if (gt_width, gt_height) != (width, height):
            raise SystemExit(name + ': the ground truth is not of the camera\'s size')
        views.append((K, R, C, width, height, gt))
    for cloud in sys.argv[2:]:
        points = read_ply_points(cloud)
        if not points:
            print('%s: no points' % cloud)
            continue
        errors = []
        for X in points:
            best = math.inf
            for K, R, C, width, height, gt in views:
                d = [X[i] - C[i] for i in range(3)]
                x = [R[0][j] * d[0] + R[1][j] * d[1] + R[2][j] * d[2] for j in range(3)]  # Rᵀ d
                if x[2] <= 0:
                    continue
                u = (K[0][0] * x[0] + K[0][1] * x[1]) / x[2] + K[0][2]
                v = K[1][1] * x[1] / x[2] + K[1][2]
                col, row = int(round(u)), int(round(v))
                if 0 <= col < width and 0 <= row < height:
                    z = gt[row * width + col]
                    if math.isfinite(z) and z > 0:
                        best = min(best, abs(x[2] - z))
            errors.append(best)
        seen = sorted(e for e in errors if math.isfinite(e))
        median = seen[len(seen) // 2] if seen else math.nan
        within = ', '.join('%.1f %% <= %g cm' % (100.0 * sum(e <= t / 100.0 for e in seen) /
                                                  len(points), t) for t in (1, 2, 5, 10))
        lo = [min(p[i] for p in points) for i in range(3)]
        hi = [max(p[i] for p in points) for i in range(3)]
        print('%s: %d points, bbox [%s] .. [%s], %d seen by a view, median |z - z_gt| %.4f m, %s'
              % (cloud, len(points), ' '.join('%.2f' % c for c in lo),
                 ' '.join('%.2f' % c for c in hi), len(seen), median, within))


if __name__ == '__main__':
    try:
        main()
    except ValueError as e:  # a malformed input file (file_formats)
        raise SystemExit('error: %s' % e)
