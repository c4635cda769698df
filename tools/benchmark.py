#!/usr/bin/env python3
# Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
"""Benchmark suites for gcpstereo: runs the program on the benchmark data through its outside
contract (gcpstereo run / eval / synth, report.json) and writes one Markdown file per suite plus
one JSON file with every number to --out.

Suites
  costs     matching costs and GCPs alone (no energy minimisation):
            - winner-take-all bad-1 (nonocc / all) on the Middlebury scenes with the two-view
              Birchfield-Tomasi cost (configs/middlebury_stereo.yaml, the ground-truth pair) and with
              the multi-view plane sweep over all other views, at most 6
              (configs/middlebury_multiview.yaml, gcp.sources=[], cost.method=plane_sweep);
              both on the same integer disparity labels 0..max;
            - stereo GCPs (paper section 4.1) per scene: density and outlier rate (|d - gt| > 1 px;
              report.json gcps.outliers, cross-checked by this script from gcps.ply + the ground
              truth image), and the accuracy of the propagated map D^ (eq. 5) they give;
            - D^ from ground-truth-sampled GCPs at s = 16 (the range-sensor setting in miniature);
            - KITTI: WTA bad-3 on the held-out LiDAR points of each frame;
            - synthetic 'small' scene: WTA within-3-sigma share.
  table2    the paper's Table 2 on the Middlebury scenes (configs/middlebury_stereo.yaml):
            D without the GCP energy, D^ (propagated stereo GCPs), D with the GCP energy;
            bad-1 in nonocc / all / disc, and the run times.
  paired    every scene with and without the GCP energy, the cells where GCPs lose marked
            (issue 23): the Middlebury scenes two-view with stereo GCPs (table2's runs), the
            same scenes multi-view with ground truth kept one per 16x16 block as GCPs, each
            KITTI frame with the LiDAR half as GCPs (motion-compensated and raw scan), the
            synthetic fountain view 0005 with laser GCPs at s = 16. About 40 minutes on 2 cores.
  endtoend  full runs per data set: fountain-P11 (configs/fountain_p11.yaml), the synthetic
            fountain (configs/synthetic_fountain.yaml; generated with gcpstereo synth if missing),
            the Middlebury scenes two-view, each KITTI frame (configs/kitti_lidar.yaml with
            eval.lidar_holdout=true); per-stage times, total, peak memory, main metrics; and OpenCV
            SGBM (build/tools/benchmarks/gcpstereo_sgbm_baseline) on the rectified pairs, scored
            with gcpstereo eval (Middlebury) or on the same held-out LiDAR points (KITTI).
  scene     whole scenes (every view's depth map, fused and meshed; README "Whole scenes"):
            - the synthetic fountain, all 11 views, neighbours chosen automatically, at the
              paper's per-view setting (configs/synthetic_fountain.yaml): D+GCP (laser, s = 16),
              D without GCPs (gcp.sources=[]) and D^ alone (runtime.stop_after=propagation,
              fusion.input=propagated); F-score / accuracy / completeness at 1, 2, 5, 10 cm of
              the mesh and of the fused points against gt/mesh.ply and gt/laser.ply, the mean
              within-3-sigma share over the views, whole-scene time and peak memory; then
              `gcpstereo fuse` of the D+GCP views alone (the time and memory of fusion, meshing
              and evaluation without the views);
            - fountain-P11, all 11 views with image-match GCPs (configs/fountain_p11.yaml):
              time, memory, pictures (no ground truth here).
            Not part of 'all' (about 75 minutes on 2 cores): ask for it with --suite scene.
  speed     issue 25's three runs, timed: each KITTI frame (configs/kitti_lidar.yaml with
            eval.lidar_holdout=true; held-out bad-3 / bad-1), the Middlebury scenes two-view
            (configs/middlebury_stereo.yaml with the GCP energy; bad-1 nonocc / all; the <= 2 s
            target on teddy, or on Aloe when teddy's data is absent), fountain-P11 view 0005 as
            configs/fountain_p11.yaml ships it and the synthetic fountain's view 0005 (within
            3 sigma); per-stage seconds in pipeline order, total (report.json) and the whole
            process's wall time (start-up and exit included; the targets are checked on it),
            peak memory, accuracy, OpenCV SGBM's time on the same pair and the ratio, the
            issue's targets met or not.
            --repeat N: every timed run N times (median time, largest peak memory);
            --baseline-build DIR: every gcpstereo run also with DIR's program (runs under
            OUT/runs/speed/baseline/), the tables show after, before and after/before;
            --baseline-configs DIR: the baseline runs DIR's configuration files (an older
            commit's configs/) instead of this checkout's.
            Not part of 'all': it times endtoend's runs again, about 4-5 minutes per build and
            repetition on 2 cores (measured on an idle machine: a KITTI frame 2.2-2.8 s, Aloe
            7-8.5 s, the fountain-P11 view 1 min, the synthetic fountain view 46 s).
            Other work on the machine moves these times by a factor up to 2: compare builds in
            one invocation (--baseline-build), whose runs take turns.

Scenes run one after the other (the machine may be shared). A failing scene never stops a suite:
its error is recorded in the table and the JSON. Run folders stay under OUT/runs/ for inspection;
--reuse skips runs whose folder already holds a report from the same command.

Example (from the repository root, data in ../shared/data):
  tools/benchmark.py --suite costs --build build --out bench-out
  tools/benchmark.py --suite table2 --scenes tsukuba,venus
  tools/benchmark.py --suite scene --scenes synthetic   # the synthetic fountain scene only
  tools/benchmark.py --suite speed --baseline-build ../old/build --repeat 3
  tools/benchmark.py --suite speed --scenes kitti --baseline-build ../old/build \
      --baseline-configs ../old/configs      # a shipped configuration's change, timed
"""

import argparse
import datetime
import json
import os
import platform
import shutil
import statistics
import struct
import subprocess
import sys
import time
import zlib

from file_formats import header_tokens

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# ---------------------------------------------------------------------------------------------
# Data sets (datasets.md / the data README): names, views, ground truth files and label ranges.
# ---------------------------------------------------------------------------------------------

# Middlebury scenes: folder, the ground-truth pair (reference = left, neighbour = right), the other
# views for the multi-view sweep, the GT file and divisor, the right view's GT (for derived masks),
# and the disparity label range 0..max_disparity (integer labels, GT convention).
MIDDLEBURY = []


def _add_middlebury(name, reference, right, views, gt, gt_right, gt_scale, max_disparity,
                    sgbm_disparities):
    MIDDLEBURY.append({
        "name": name,
        "folder": name,
        "reference": reference,
        "right": right,
        "multiview_neighbors": [v for v in views if v != reference][:6],
        "gt": gt,
        "gt_right": gt_right,
        "gt_scale": gt_scale,
        "max_disparity": max_disparity,
        "sgbm_num_disparities": sgbm_disparities,
    })


_add_middlebury("tsukuba", "scene1.row3.col3", "scene1.row3.col4",
                ["scene1.row3.col%d" % i for i in range(1, 6)],
                "truedisp.row3.col3.pgm", None, 16, 15, 16)
_add_middlebury("venus", "im2", "im6", ["im%d" % i for i in range(0, 9) if i not in (7, 8)],
                "disp2.pgm", "disp6.pgm", 8, 19, 32)
# Teddy (2003, quarter size 450×375, disparities 0…59): the speed suite's two-view timing scene
# (issue 25). Not in the shared data; used by every suite when DATA/middlebury/teddy holds
# Middlebury's files (im0…im8.png, disp2.png, disp6.png; nonocc/all/disc.png when present).
_add_middlebury("teddy", "im2", "im6", ["im%d" % i for i in range(0, 9)],
                "disp2.png", "disp6.png", 4, 59, 64)
for _scene in ["Aloe", "Baby1", "Bowling1", "Flowerpots", "Midd1", "Rocks1"]:
    _add_middlebury(_scene, "view1", "view5", ["view%d" % i for i in range(0, 7)],
                    "disp1.png", "disp5.png", 3, 80, 96)
# venus has im0..im8; the sweep uses the 6 nearest to im2: im0, im1, im3, im4, im5, im6.

KITTI_DATE = "2011_09_26"
KITTI_DRIVE = "2011_09_26_drive_0009_sync"
KITTI_FRAMES = ["0000000000", "0000000010", "0000000020", "0000000030", "0000000040",
                "0000000050"]
KITTI_MAX_DISPARITY = 127  # configs/kitti_lidar.yaml labels 0..127
KITTI_LIDAR_MOTION = "registration"  # configs/kitti_lidar.yaml gcp.lidar.motion.mode

SUITES = ["costs", "table2", "paired", "endtoend", "scene", "speed"]


class BenchError(Exception):
    """A measurement that failed; its message goes into the table."""


# ---------------------------------------------------------------------------------------------
# Small readers (standard library only): PGM/PNG ground truth, the binary GCP PLY.
# ---------------------------------------------------------------------------------------------

def read_pgm(path):
    """Binary PGM (P5, maxval <= 65535) -> (width, height, list of ints, row-major)."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        tokens, pos = header_tokens(data, 4)
    except ValueError as e:
        raise BenchError("%s: %s" % (path, e))
    if tokens[0] != b"P5":
        raise BenchError("%s: not a binary PGM (P5)" % path)
    width, height, maxval = int(tokens[1]), int(tokens[2]), int(tokens[3])
    if maxval < 256:
        values = list(data[pos:pos + width * height])
    else:
        values = list(struct.unpack(">%dH" % (width * height), data[pos:pos + 2 * width * height]))
    if len(values) != width * height:
        raise BenchError("%s: truncated PGM" % path)
    return width, height, values


def read_png_grey(path):
    """Non-interlaced 8/16-bit PNG (grey, grey+alpha, RGB, RGBA; first channel) ->
    (width, height, list of ints, row-major)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise BenchError("%s: not a PNG" % path)
    pos, idat, header = 8, [], None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
    width, height, depth, color, _, _, interlace = header
    channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(color)
    if channels is None or depth not in (8, 16) or interlace:
        raise BenchError("%s: unsupported PNG (colour type %d, depth %d, interlace %d)"
                         % (path, color, depth, interlace))
    bpp = channels * depth // 8
    stride = width * bpp
    raw = zlib.decompress(b"".join(idat))
    out = bytearray(height * stride)
    prev = bytearray(stride)
    for r in range(height):
        ftype = raw[r * (stride + 1)]
        line = bytearray(raw[r * (stride + 1) + 1:(r + 1) * (stride + 1)])
        if ftype == 1:
            for i in range(bpp, stride):
                line[i] = (line[i] + line[i - bpp]) & 255
        elif ftype == 2:
            for i in range(stride):
                line[i] = (line[i] + prev[i]) & 255
        elif ftype == 3:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif ftype == 4:
            for i in range(stride):
                a = line[i - bpp] if i >= bpp else 0
                b = prev[i]
                c = prev[i - bpp] if i >= bpp else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if (pa <= pb and pa <= pc) else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        out[r * stride:(r + 1) * stride] = line
        prev = line
    if depth == 8:
        values = list(out[0::bpp])
    else:
        values = [(out[i] << 8) | out[i + 1] for i in range(0, len(out), bpp)]
    return width, height, values


def read_gt_disparity(path, divisor):
    """Ground-truth disparity (GT convention) as (width, height, list of float or None)."""
    reader = read_pgm if path.lower().endswith((".pgm", ".ppm")) else read_png_grey
    width, height, values = reader(path)
    return width, height, [v / divisor if v > 0 else None for v in values]


def read_gcp_ply(path):
    """gcps.ply (binary little-endian, written by gcpstereo) -> list of (col, row, depth)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if end < 0:
        raise BenchError("%s: no PLY header" % path)
    header = data[:end].decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in header:
        raise BenchError("%s: not a binary little-endian PLY" % path)
    types = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
             "float": "f", "double": "d", "int8": "b", "uint8": "B", "int32": "i",
             "float32": "f", "float64": "d"}
    count, names, fmt = 0, [], "<"
    for line in header:
        parts = line.split()
        if parts[:2] == ["element", "vertex"]:
            count = int(parts[2])
        elif parts[:1] == ["property"] and count:
            fmt += types[parts[1]]
            names.append(parts[2])
    for needed in ("col", "row", "depth"):
        if needed not in names:
            raise BenchError("%s: no vertex property '%s'" % (path, needed))
    size = struct.calcsize(fmt)
    body = data[end + len(b"end_header\n"):]
    if len(body) < count * size:
        raise BenchError("%s: truncated PLY" % path)
    ic, ir, idp = names.index("col"), names.index("row"), names.index("depth")
    return [(v[ic], v[ir], v[idp]) for v in struct.iter_unpack(fmt, body[:count * size])]


# ---------------------------------------------------------------------------------------------
# Running the programs.
# ---------------------------------------------------------------------------------------------

def fmt_seconds(s):
    return "%.1f s" % s if s < 120 else "%.1f min" % (s / 60)


class Runner:
    def __init__(self, args, build=None, configs=None):
        """Runs the programs of `build` (default: --build) on the configuration files in `configs`
        (default: this checkout's configs/) with the data, output folder, --reuse and --timeout of
        `args`."""
        self.build = os.path.abspath(build or args.build)
        self.configs = os.path.abspath(configs) if configs else os.path.join(REPO, "configs")
        self.data = os.path.abspath(args.data)
        self.out = os.path.abspath(args.out)
        self.reuse = args.reuse
        self.timeout = args.timeout
        self.extra_sets = list(getattr(args, "set", None) or [])  # --set: after every suite's own
        self.gcpstereo = os.path.join(self.build, "gcpstereo")
        self.sgbm_program = os.path.join(self.build, "tools", "benchmarks",
                                         "gcpstereo_sgbm_baseline")
        self.runs = os.path.join(self.out, "runs")
        self.count = 0
        self.done = {}  # key -> command run successfully in this invocation (reused, never rerun)

    def log(self, message):
        print("[%s] %s" % (datetime.datetime.now().strftime("%H:%M:%S"), message), flush=True)

    def _execute(self, key, command, folder, product):
        """Runs `command`, logging to folder/bench.log; returns product's path. With --reuse, a
        folder holding `product` and the same command is not run again."""
        stamp = os.path.join(folder, "bench_command.json")
        product_path = os.path.join(folder, product)
        if self.done.get(key) == command and os.path.exists(product_path):
            return product_path
        if self.reuse and os.path.exists(product_path) and os.path.exists(stamp):
            with open(stamp) as f:
                if json.load(f) == command:
                    self.log("reuse   %s" % key)
                    return product_path
        if os.path.isdir(folder):
            shutil.rmtree(folder)
        os.makedirs(folder)
        self.count += 1
        self.log("run     %s" % key)
        start = time.monotonic()
        try:
            with open(os.path.join(folder, "bench.log"), "w") as log:
                log.write(" ".join(command) + "\n")
                log.flush()
                proc = subprocess.run(command, stdout=log, stderr=subprocess.PIPE, text=True,
                                      timeout=self.timeout, cwd=REPO)
                log.write(proc.stderr)
        except subprocess.TimeoutExpired:
            raise BenchError("timed out after %d s" % self.timeout)
        except OSError as e:
            raise BenchError("cannot start %s: %s" % (command[0], e.strerror))
        elapsed = time.monotonic() - start
        if proc.returncode != 0:
            lines = [l for l in proc.stderr.strip().splitlines() if l.strip()]
            message = lines[-1] if lines else "exit status %d" % proc.returncode
            self.log("FAILED  %s (%s): %s" % (key, fmt_seconds(elapsed), message))
            raise BenchError(message)
        if not os.path.exists(product_path):
            raise BenchError("no %s written" % product)
        with open(stamp, "w") as f:
            json.dump(command, f)
        # The whole process's wall time (start-up, dynamic linking and exit included).
        with open(os.path.join(folder, "bench_seconds.json"), "w") as f:
            json.dump(elapsed, f)
        self.done[key] = command
        self.log("done    %s (%s)" % (key, fmt_seconds(elapsed)))
        return product_path

    def run(self, key, config, sets):
        """gcpstereo run CONFIG -o OUT/runs/KEY --set ...; returns (report dict, run folder)."""
        folder = os.path.join(self.runs, key)
        command = [self.gcpstereo, "run", os.path.join(self.configs, config), "-o", folder, "-q"]
        for item in list(sets) + self.extra_sets:
            command += ["--set", item]
        report = self._execute(key, command, folder, "report.json")
        with open(report) as f:
            return json.load(f), folder

    def eval_disparity(self, key, disparity, scene):
        folder = os.path.join(self.runs, key)
        d = os.path.join(self.data, "middlebury", scene["folder"])
        command = [self.gcpstereo, "eval", "-q", "--disparity", disparity,
                   "--gt-disparity", os.path.join(d, scene["gt"]),
                   "--gt-scale", str(scene["gt_scale"]), "--report",
                   os.path.join(folder, "eval.json")]
        masks = [m for m in ("nonocc", "all", "disc") if os.path.exists(os.path.join(d, m + ".png"))]
        for m in masks:
            command += ["--" + m, os.path.join(d, m + ".png")]
        if not masks and scene["gt_right"]:
            command += ["--gt-disparity-right", os.path.join(d, scene["gt_right"])]
        report = self._execute(key, command, folder, "eval.json")
        with open(report) as f:
            return json.load(f)

    def sgbm(self, key, args):
        folder = os.path.join(self.runs, key)
        command = [self.sgbm_program] + args + ["-o", os.path.join(folder, "disparity.pfm"),
                                        "--report", os.path.join(folder, "sgbm.json")]
        report = self._execute(key, command, folder, "sgbm.json")
        with open(report) as f:
            return json.load(f), folder

    def fuse(self, key, view_dirs, sets=()):
        """gcpstereo fuse VIEWDIR... -o OUT/runs/KEY --set ...; returns (report dict, folder)."""
        folder = os.path.join(self.runs, key)
        command = [self.gcpstereo, "fuse"] + list(view_dirs) + ["-o", folder, "-q"]
        for item in list(sets) + self.extra_sets:
            command += ["--set", item]
        report = self._execute(key, command, folder, "report.json")
        with open(report) as f:
            return json.load(f), folder

    def synth(self, preset):
        """The synthetic scene OUT/data/synth-<preset>, generated once."""
        folder = os.path.join(self.out, "data", "synth-" + preset)
        if os.path.exists(os.path.join(folder, "gt", "laser.ply")):
            return folder
        command = [self.gcpstereo, "synth", "--preset", preset, "-o", folder, "-q"]
        self._execute("synth-" + preset, command, folder, os.path.join("gt", "laser.ply"))
        return folder


def dig(obj, *path):
    """obj[path[0]][path[1]]...; BenchError naming the missing key."""
    for p in path:
        try:
            obj = obj[p]
        except (KeyError, IndexError, TypeError):
            raise BenchError("report has no %s" % ".".join(str(x) for x in path))
    return obj


def bad1(metrics_map, region):
    """bad-1 percent (threshold index 1 of 0.5/1/2) of a middlebury.<map>.<region> entry."""
    return dig(metrics_map, region, "bad_percent", 1)


def measure(results, name, function):
    """results[name] = function() or {"error": message}; never raises for BenchError/OSError."""
    try:
        results[name] = function()
    except BenchError as e:
        results[name] = {"error": str(e)}
    except Exception as e:  # a bug or an unexpected report: recorded, the suite goes on
        results[name] = {"error": "%s: %s" % (type(e).__name__, e)}
    return results[name]


# ---------------------------------------------------------------------------------------------
# Scene configuration helpers.
# ---------------------------------------------------------------------------------------------

def middlebury_path(runner, scene):
    return os.path.join(runner.data, "middlebury", scene["folder"])


def stereo_sets(runner, scene):
    """configs/middlebury_stereo.yaml on the ground-truth pair of `scene`."""
    return ["dataset.path=" + middlebury_path(runner, scene),
            "dataset.reference=" + scene["reference"],
            "dataset.neighbors=[%s]" % scene["right"],
            "labels.min=0", "labels.max=%d" % scene["max_disparity"],
            "labels.count=%d" % (scene["max_disparity"] + 1)]


def multiview_sets(runner, scene):
    """configs/middlebury_multiview.yaml on all other views (at most 6), same integer labels."""
    return ["dataset.path=" + middlebury_path(runner, scene),
            "dataset.reference=" + scene["reference"],
            "dataset.neighbors=[%s]" % ",".join(scene["multiview_neighbors"]),
            "labels.min=0", "labels.max=%d" % scene["max_disparity"],
            "labels.count=%d" % (scene["max_disparity"] + 1),
            "cost.method=plane_sweep"]


def kitti_sets(runner, frame):
    drive = kitti_drive_path(runner)
    return ["dataset.path=" + drive, "dataset.reference=" + frame,
            "gcp.lidar.path=" + os.path.join(drive, "velodyne_points", "data", frame + ".bin"),
            "eval.lidar_holdout=true"]


def kitti_drive_path(runner):
    return os.path.join(runner.data, "kitti", KITTI_DATE, KITTI_DRIVE)


def kitti_holdout(report):
    """Held-out LiDAR scores of a kitti_lidar.yaml run (eval.lidar_holdout=true)."""
    h = dig(report, "metrics", "lidar_holdout", "result")
    return {"bad3": h["bad3_percent"], "bad1": h["bad1_percent"], "held_out_points": h["counted"]}


def middlebury_bad1(report):
    """bad-1 nonocc / all of a Middlebury run's final map."""
    m = dig(report, "metrics", "middlebury", "result")
    return {"bad1_nonocc": bad1(m, "nonocc"), "bad1_all": bad1(m, "all")}


def within_3sigma(report):
    """Share of the synthetic scene's pixels within 3 sigma: the final map and D^."""
    h = dig(report, "metrics", "depth_sigma")
    return {"within_3sigma": dig(h, "result", "within_n_sigma_percent", 2),
            "propagated_within_3sigma": dig(h, "propagated", "within_n_sigma_percent", 2)}


def fountain_p11_sets(runner):
    """configs/fountain_p11.yaml on the shared data (its view 0005 unless more sets follow)."""
    return ["dataset.path=" + os.path.join(runner.data, "strecha", "fountain-P11")]


def synthetic_fountain_sets(data):
    """configs/synthetic_fountain.yaml on the synthetic scene in `data` with its laser GCPs."""
    return ["dataset.path=" + data, "gcp.lidar.path=" + os.path.join(data, "gt", "laser.ply")]


def sgbm_middlebury_args(runner, scene):
    """gcpstereo_sgbm_baseline on the ground-truth pair of `scene`."""
    return ["--format", "middlebury", "--path", middlebury_path(runner, scene),
            "--reference", scene["reference"], "--neighbor", scene["right"],
            "--num-disparities", str(scene["sgbm_num_disparities"])]


def sgbm_kitti_args(runner, frame):
    """gcpstereo_sgbm_baseline on a KITTI frame, scored on kitti_lidar.yaml's held-out points."""
    return ["--format", "kitti_raw", "--path", kitti_drive_path(runner), "--reference", frame,
            "--num-disparities", str(KITTI_MAX_DISPARITY + 1), "--lidar-holdout",
            # the held-out points of configs/kitti_lidar.yaml (gcp.lidar.motion.mode)
            "--lidar-motion", KITTI_LIDAR_MOTION]


def gcp_outliers_from_ply(runner, scene, report, folder):
    """Outlier rate of the GCPs in folder/gcps.ply against the scene's GT image, computed here
    independently of the program: disparity = numerator / depth with numerator = depth of the last
    label x its disparity (labels are disparities 0..max)."""
    numerator = dig(report, "labels", "depth_of_last_label") * dig(report, "labels", "max")
    width, height, gt = read_gt_disparity(
        os.path.join(middlebury_path(runner, scene), scene["gt"]), scene["gt_scale"])
    evaluated = outliers = 0
    for col, row, depth in read_gcp_ply(os.path.join(folder, "gcps.ply")):
        if not (0 <= col < width and 0 <= row < height) or not depth > 0:
            continue
        truth = gt[row * width + col]
        if truth is None:
            continue
        evaluated += 1
        # 1e-4: the PLY stores depth as float32; exact 1-px ties must stay inliers as in the
        # program (integer GCP disparities against integer or thirds-of-a-pixel ground truth).
        outliers += abs(numerator / depth - truth) > 1.0 + 1e-4
    return {"evaluated": evaluated, "outliers": outliers,
            "percent": 100.0 * outliers / evaluated if evaluated else None}


# ---------------------------------------------------------------------------------------------
# Suites. Each returns {"rows": {...}, "markdown": str}.
# ---------------------------------------------------------------------------------------------

def suite_costs(runner, scenes, frames, include_synthetic):
    rows = {}
    for scene in scenes:
        name = scene["name"]
        row = rows.setdefault(name, {})

        def bt_wta():
            # Stereo GCPs on (their density, outliers and D^ come with this run); WTA ignores them.
            report, folder = runner.run("costs/%s/bt_wta" % name, "middlebury_stereo.yaml",
                                        stereo_sets(runner, scene) + ["optimizer.method=wta"])
            m = dig(report, "metrics", "middlebury")
            out = {"wta_nonocc": bad1(m["result"], "nonocc"), "wta_all": bad1(m["result"], "all"),
                   "seconds": report.get("total_seconds"),
                   "gcp_count": dig(report, "gcps", "count"),
                   "gcp_density_percent": dig(report, "gcps", "density_percent"),
                   "gcp_outlier_percent": dig(report, "gcps", "outliers", "percent"),
                   "propagated_nonocc": bad1(dig(m, "propagated"), "nonocc"),
                   "propagated_all": bad1(dig(m, "propagated"), "all")}
            check = gcp_outliers_from_ply(runner, scene, report, folder)
            out["gcp_outlier_percent_script"] = check["percent"]
            out["gcp_outlier_evaluated_script"] = check["evaluated"]
            return out

        def ps_wta():
            report, _ = runner.run("costs/%s/planesweep_wta" % name, "middlebury_multiview.yaml",
                                   multiview_sets(runner, scene) +
                                   ["gcp.sources=[]", "optimizer.method=wta"])
            m = dig(report, "metrics", "middlebury", "result")
            return {"wta_nonocc": bad1(m, "nonocc"), "wta_all": bad1(m, "all"),
                    "neighbors": len(scene["multiview_neighbors"]),
                    "seconds": report.get("total_seconds")}

        def gt_gcps():
            d = middlebury_path(runner, scene)
            report, _ = runner.run("costs/%s/gt_gcps_s16" % name, "middlebury_multiview.yaml",
                                   multiview_sets(runner, scene) +
                                   ["gcp.sources=[depth_map]",
                                    "gcp.depth_map.path=" + os.path.join(d, scene["gt"]),
                                    "gcp.depth_map.kind=disparity",
                                    "gcp.depth_map.scale=%d" % scene["gt_scale"],
                                    "gcp.downsample=16", "optimizer.method=wta"])
            m = dig(report, "metrics", "middlebury", "propagated")
            return {"propagated_nonocc": bad1(m, "nonocc"), "propagated_all": bad1(m, "all"),
                    "gcp_count": dig(report, "gcps", "count"),
                    "gcp_density_percent": dig(report, "gcps", "density_percent")}

        measure(row, "birchfield_tomasi", bt_wta)
        measure(row, "plane_sweep", ps_wta)
        measure(row, "gt_gcps_s16", gt_gcps)

    kitti = {}
    for frame in frames:
        def kitti_wta():
            report, _ = runner.run("costs/kitti_%s/bt_wta" % frame, "kitti_lidar.yaml",
                                   kitti_sets(runner, frame) + ["optimizer.method=wta"])
            h = dig(report, "metrics", "lidar_holdout")
            return {"wta_bad3": dig(h, "result", "bad3_percent"),
                    "wta_bad1": dig(h, "result", "bad1_percent"),
                    "held_out_points": dig(h, "result", "counted"),
                    "propagated_bad3": dig(h, "propagated", "bad3_percent"),
                    "seconds": report.get("total_seconds")}
        measure(kitti, frame, kitti_wta)

    synthetic = {}

    def synth_wta():
        data = runner.synth("small")
        report, _ = runner.run("costs/synth_small/planesweep_wta", "synthetic_fountain.yaml",
                               ["dataset.path=" + data,
                                "gcp.lidar.path=" + os.path.join(data, "gt", "laser.ply"),
                                "labels.count=128", "optimizer.tiles=[1, 1]",
                                "optimizer.tile_overlap=0", "optimizer.method=wta"])
        h = dig(report, "metrics", "depth_sigma")
        return {"wta_within_3sigma": dig(h, "result", "within_n_sigma_percent", 2),
                "propagated_within_3sigma": dig(h, "propagated", "within_n_sigma_percent", 2),
                "neighbors": len(dig(report, "dataset", "neighbors")),
                "seconds": report.get("total_seconds")}
    if include_synthetic:
        measure(synthetic, "small", synth_wta)

    md = ["# costs — matching costs and GCPs without energy minimisation", "",
          "Middlebury, bad-1 (%, |d − gt| > 1 px in the GT convention, missing = bad). WTA = "
          "winner-take-all on integer disparity labels 0…max. BT = two-view Birchfield–Tomasi on "
          "the GT pair (middlebury_stereo.yaml); PS = multi-view plane sweep, reference + n "
          "neighbours (middlebury_multiview.yaml, gcp.sources=[]). Stereo GCPs (§4.1): density = "
          "% of pixels, outliers = |d − gt| > 1 px among GCPs with GT (report.json / recomputed "
          "by this script from gcps.ply); D̂ = propagated GCPs (eq. 5). GT GCPs: one ground-truth "
          "value per 16×16 block.", "",
          "| scene | BT WTA nonocc | BT WTA all | PS WTA nonocc | PS WTA all | PS n | "
          "stereo GCP density % | GCP outliers % (report / script) | D̂ stereo nonocc | "
          "D̂ stereo all | D̂ GT s=16 nonocc | D̂ GT s=16 all |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for scene in scenes:
        r = rows[scene["name"]]
        bt, ps, gt = r["birchfield_tomasi"], r["plane_sweep"], r["gt_gcps_s16"]
        md.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            scene["name"], cell(bt, "wta_nonocc"), cell(bt, "wta_all"), cell(ps, "wta_nonocc"),
            cell(ps, "wta_all"), cell(ps, "neighbors", "%d"), cell(bt, "gcp_density_percent"),
            pair_cell(bt, "gcp_outlier_percent", "gcp_outlier_percent_script"),
            cell(bt, "propagated_nonocc"), cell(bt, "propagated_all"),
            cell(gt, "propagated_nonocc"), cell(gt, "propagated_all")))
    md += ["", "KITTI raw %s, configs/kitti_lidar.yaml with eval.lidar_holdout=true (8×8 "
           "checkerboard: half of the scan as GCPs, half scored). WTA of the two-view BT cost; "
           "bad-3 = |e| > 3 px and > 5 %%; D̂ = propagated LiDAR GCPs." % KITTI_DRIVE, "",
           "| frame | held-out points | WTA bad-3 % | WTA bad-1 % | D̂ bad-3 % |",
           "|---|---:|---:|---:|---:|"]
    for frame in frames:
        k = kitti[frame]
        md.append("| %s | %s | %s | %s | %s |" % (frame, cell(k, "held_out_points", "%d"),
                                                  cell(k, "wta_bad3"), cell(k, "wta_bad1"),
                                                  cell(k, "propagated_bad3")))
    md += ["", "Synthetic `small` scene (gcpstereo synth, seed 1): synthetic_fountain.yaml with 128 "
           "depth labels, no tiling, plane sweep over the other views; share of pixels within "
           "3σ of the exact depth (σ = the simulated laser's).", "",
           "| scene | neighbours | WTA within 3σ % | D̂ (laser GCPs, s=16) within 3σ % |",
           "|---|---:|---:|---:|"]
    for name, s in synthetic.items():
        md.append("| %s | %s | %s | %s |" % (name, cell(s, "neighbors", "%d"),
                                             cell(s, "wta_within_3sigma"),
                                             cell(s, "propagated_within_3sigma")))
    return {"middlebury": rows, "kitti": kitti, "synthetic": synthetic, "markdown": "\n".join(md)}


def suite_table2(runner, scenes):
    rows = {}
    for scene in scenes:
        name = scene["name"]
        row = rows.setdefault(name, {})

        def variant(use_gcp_energy):
            def run():
                report, _ = runner.run(
                    "table2/%s/%s" % (name, "with_gcp" if use_gcp_energy else "without_gcp"),
                    "middlebury_stereo.yaml",
                    stereo_sets(runner, scene) +
                    ["optimizer.use_gcp_energy=%s" % ("true" if use_gcp_energy else "false")])
                m = dig(report, "metrics", "middlebury")
                out = {region: bad1(m["result"], region) for region in ("nonocc", "all", "disc")}
                out["seconds"] = report.get("total_seconds")
                out["cost_and_optimization_seconds"] = dig(
                    report, "stages", "cost_and_optimization", "seconds")
                if use_gcp_energy:
                    out["propagated"] = {region: bad1(dig(m, "propagated"), region)
                                         for region in ("nonocc", "all", "disc")}
                    out["gcp_count"] = dig(report, "gcps", "count")
                    out["gcp_outlier_percent"] = dig(report, "gcps", "outliers", "percent")
                return out
            return run

        measure(row, "without_gcp_energy", variant(False))
        measure(row, "with_gcp_energy", variant(True))

    md = ["# table2 — the paper's Table 2 (Middlebury, two-view)", "",
          "configs/middlebury_stereo.yaml on the GT pair, stereo GCPs (§4.1), integer disparity "
          "labels 0…max; bad-1 (%, |d − gt| > 1 px, missing = bad) in the nonocc / all / disc "
          "regions (official masks for tsukuba and venus; for the 2006 sets all three are derived "
          "by gcpstereo from a left-right check of disp1/disp5). D = graph cuts without the GCP energy "
          "(optimizer.use_gcp_energy=false); D̂ = the propagated GCPs (eq. 5); D + GCP = the full "
          "energy (eqs. 1–8). Times are the whole run (load … write).", "",
          "| scene | D nonocc | D all | D disc | D̂ nonocc | D̂ all | D̂ disc | D+GCP nonocc | "
          "D+GCP all | D+GCP disc | GCPs (outliers %) | time D | time D+GCP |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for scene in scenes:
        r = rows[scene["name"]]
        d, g = r["without_gcp_energy"], r["with_gcp_energy"]
        p = g.get("propagated", g if "error" in g else {})
        gcps = ("error" if "error" in g else
                "%s (%s)" % (cell(g, "gcp_count", "%d"), cell(g, "gcp_outlier_percent")))
        md.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            scene["name"], cell(d, "nonocc"), cell(d, "all"), cell(d, "disc"),
            cell(p, "nonocc"), cell(p, "all"), cell(p, "disc"),
            cell(g, "nonocc"), cell(g, "all"), cell(g, "disc"), gcps,
            cell(d, "seconds", "%.1f s"), cell(g, "seconds", "%.1f s")))
    add_errors(md, rows)
    return {"middlebury": rows, "markdown": "\n".join(md)}


# A cell where GCPs lose: the error with GCPs exceeds the one without by more than this many
# percentage points (issue 23's "ties within 0.02 points count").
PAIRED_TIE = 0.02


def suite_paired(runner, scenes, frames, include_synthetic):
    """Every scene with and without the GCP energy (optimizer.use_gcp_energy), same GCPs, same
    costs; the tables mark every cell where the GCPs lose."""
    rows = {"two-view": {}, "multi-view": {}, "kitti": {}, "kitti-raw": {}, "synthetic": {}}
    both = (("without", "false"), ("with", "true"))

    for scene in scenes:
        name = scene["name"]
        for tag, flag in both:
            # The same runs as table2's: one invocation running both suites runs them once.
            def two_view(flag=flag, tag=tag):
                report, _ = runner.run("table2/%s/%s_gcp" % (name, tag), "middlebury_stereo.yaml",
                                       stereo_sets(runner, scene) +
                                       ["optimizer.use_gcp_energy=" + flag])
                m = dig(report, "metrics", "middlebury", "result")
                return {region: bad1(m, region) for region in ("nonocc", "all", "disc")}
            measure(rows["two-view"].setdefault(name, {}), tag, two_view)

            def multi_view(flag=flag, tag=tag):
                gt = os.path.join(middlebury_path(runner, scene), scene["gt"])
                report, _ = runner.run(
                    "paired/multiview/%s/%s_gcp" % (name, tag), "middlebury_multiview.yaml",
                    multiview_sets(runner, scene) +
                    ["gcp.sources=[depth_map]", "gcp.depth_map.path=" + gt,
                     "gcp.depth_map.kind=disparity",
                     "gcp.depth_map.scale=%s" % scene["gt_scale"], "gcp.downsample=16",
                     "optimizer.use_gcp_energy=" + flag])
                m = dig(report, "metrics", "middlebury", "result")
                return {region: bad1(m, region) for region in ("nonocc", "all", "disc")}
            measure(rows["multi-view"].setdefault(name, {}), tag, multi_view)

    for frame in frames:
        for family, motion in (("kitti", KITTI_LIDAR_MOTION), ("kitti-raw", "off")):
            for tag, flag in both:
                def kitti(flag=flag, motion=motion, tag=tag):
                    report, _ = runner.run(
                        "paired/kitti/%s/%s/%s_gcp" % (frame, motion, tag), "kitti_lidar.yaml",
                        kitti_sets(runner, frame) + ["gcp.lidar.motion.mode=" + motion,
                                                     "optimizer.use_gcp_energy=" + flag])
                    return kitti_holdout(report)
                measure(rows[family].setdefault(frame, {}), tag, kitti)

    if include_synthetic:
        for tag, flag in both:
            def synthetic(flag=flag, tag=tag):
                data = runner.synth("fountain")
                report, _ = runner.run("paired/synthetic-fountain/%s_gcp" % tag,
                                       "synthetic_fountain.yaml",
                                       synthetic_fountain_sets(data) +
                                       ["optimizer.use_gcp_energy=" + flag])
                return {"within_3sigma": within_3sigma(report)["within_3sigma"]}
            measure(rows["synthetic"].setdefault("fountain view 0005", {}), tag, synthetic)

    losses = []

    def table(family, columns, lower_is_better=True):
        out = []
        for name, pair in rows[family].items():
            cells = [name]
            for column in columns:
                a, b = pair.get("without", {}), pair.get("with", {})
                if "error" in a or "error" in b or column not in a or column not in b:
                    cells.append("error" if ("error" in a or "error" in b) else "")
                    continue
                delta = b[column] - a[column]
                lose = delta > PAIRED_TIE if lower_is_better else delta < -PAIRED_TIE
                if lose:
                    losses.append("%s %s %s" % (family, name, column))
                cells.append("%.2f → %.2f%s" % (a[column], b[column],
                                                " **lose**" if lose else ""))
            out.append("| " + " | ".join(cells) + " |")
        means = []
        for column in columns:
            values = [(p["without"][column], p["with"][column]) for p in rows[family].values()
                      if column in p.get("without", {}) and column in p.get("with", {})]
            means.append("%.3f → %.3f" % (statistics.mean(v[0] for v in values),
                                          statistics.mean(v[1] for v in values))
                         if values else "")
        if len(rows[family]) > 1:
            out.append("| mean | " + " | ".join(means) + " |")
        return out

    md = ["# paired — every scene without → with the GCP energy",
          "", "Each cell: the error without the GCP energy (optimizer.use_gcp_energy=false) → "
          "with it, same GCPs and matching costs; **lose** marks a cell where the GCPs make it "
          "worse by more than %.2f points. Extra settings on every run: %s." % (
              PAIRED_TIE, ", ".join(runner.extra_sets) or "none")]
    if rows["two-view"]:
        md += ["", "Middlebury two-view with stereo GCPs (configs/middlebury_stereo.yaml, the "
               "paper's Table 2 setting): bad-1 %.", "",
               "| scene | nonocc | all | disc |", "|---|---:|---:|---:|"]
        md += table("two-view", ["nonocc", "all", "disc"])
    if rows["multi-view"]:
        md += ["", "Middlebury multi-view plane sweep with ground truth kept one per 16×16 block "
               "as GCPs (configs/middlebury_multiview.yaml, integer labels): bad-1 %.", "",
               "| scene | nonocc | all | disc |", "|---|---:|---:|---:|"]
        md += table("multi-view", ["nonocc", "all", "disc"])
    for family, scan in (("kitti", "the motion-compensated scan (gcp.lidar.motion.mode: %s)"
                          % KITTI_LIDAR_MOTION), ("kitti-raw", "the raw scan (motion.mode: off)")):
        if rows[family]:
            md += ["", "KITTI with half of %s as GCPs, scored on the other half "
                   "(configs/kitti_lidar.yaml, eval.lidar_holdout=true): held-out bad-3 / bad-1 %%."
                   % scan, "", "| frame | bad-3 | bad-1 |", "|---|---:|---:|"]
            md += table(family, ["bad3", "bad1"])
    if rows["synthetic"]:
        md += ["", "Synthetic fountain view 0005 with laser GCPs at s = 16 "
               "(configs/synthetic_fountain.yaml): pixels within 3σ, % (higher is better).", "",
               "| view | within 3σ |", "|---|---:|"]
        md += table("synthetic", ["within_3sigma"], lower_is_better=False)
    md += ["", "GCPs lose in %d cell(s)%s" % (len(losses), (": " + "; ".join(losses))
                                               if losses else ".")]
    errors = {}
    for family, family_rows in rows.items():
        for name, pair in family_rows.items():
            errors["%s %s" % (family, name)] = pair
    add_errors(md, errors)
    return {"paired": rows, "losses": losses, "markdown": "\n".join(md)}


def stage_seconds(report):
    return {name: stage.get("seconds") for name, stage in sorted(report.get("stages", {}).items())}


def run_summary(report):
    """Stage times, total, peak memory, GCPs, labels and image size of a run's report.json."""
    return {"stages": stage_seconds(report), "total_seconds": report.get("total_seconds"),
            "peak_memory_bytes": report.get("peak_memory_bytes"),
            "gcp_count": report.get("gcps", {}).get("count"),
            "labels": report.get("labels", {}).get("count"),
            "size": "%sx%s" % (report.get("dataset", {}).get("reference", {}).get("width"),
                               report.get("dataset", {}).get("reference", {}).get("height"))}


def suite_endtoend(runner, scenes, frames, include_fountain):
    rows = {}  # ordered: data set -> measurement

    for scene in scenes:
        name = scene["name"]

        def middlebury():
            report, _ = runner.run("table2/%s/with_gcp" % name, "middlebury_stereo.yaml",
                                   stereo_sets(runner, scene) + ["optimizer.use_gcp_energy=true"])
            out = run_summary(report)
            out.update(middlebury_bad1(report))
            out["metrics"] = "bad-1 nonocc %.2f %%, all %.2f %%" % (out["bad1_nonocc"],
                                                                    out["bad1_all"])
            return out
        measure(rows, "middlebury " + name, middlebury)

        def sgbm():
            filled = ["--filled-output", os.path.join(runner.runs, "endtoend", "sgbm_%s" % name,
                                                      "disparity_filled.pfm")]
            s, folder = runner.sgbm("endtoend/sgbm_%s" % name,
                                    sgbm_middlebury_args(runner, scene) + filled)
            e = runner.eval_disparity("endtoend/sgbm_%s/eval" % name,
                                      os.path.join(folder, "disparity.pfm"), scene)
            f = runner.eval_disparity("endtoend/sgbm_%s/eval_filled" % name,
                                      os.path.join(folder, "disparity_filled.pfm"), scene)
            m = dig(e, "metrics", "middlebury", "result")
            mf = dig(f, "metrics", "middlebury", "result")
            out = {"total_seconds": s["seconds"], "stages": {"sgbm": s["seconds"]},
                   "invalid_percent": s["invalid_percent"],
                   "bad1_nonocc": bad1(m, "nonocc"), "bad1_all": bad1(m, "all"),
                   "filled_bad1_nonocc": bad1(mf, "nonocc"), "filled_bad1_all": bad1(mf, "all"),
                   "size": "%dx%d" % (s["width"], s["height"])}
            out["metrics"] = ("bad-1 nonocc %.2f %%, all %.2f %% (%.1f %% invalid = bad); "
                              "background-filled: nonocc %.2f %%, all %.2f %%" % (
                                  out["bad1_nonocc"], out["bad1_all"], s["invalid_percent"],
                                  out["filled_bad1_nonocc"], out["filled_bad1_all"]))
            return out
        measure(rows, "SGBM middlebury " + name, sgbm)

    for frame in frames:
        def kitti():
            report, _ = runner.run("endtoend/kitti_%s" % frame, "kitti_lidar.yaml",
                                   kitti_sets(runner, frame))
            out = run_summary(report)
            out.update(kitti_holdout(report))
            out["metrics"] = "held-out LiDAR bad-3 %.2f %%, bad-1 %.2f %% (%d points)" % (
                out["bad3"], out["bad1"], out["held_out_points"])
            return out
        measure(rows, "kitti " + frame, kitti)

        def sgbm():
            filled = ["--filled-output", os.path.join(runner.runs, "endtoend",
                                                      "sgbm_kitti_%s" % frame,
                                                      "disparity_filled.pfm")]
            s, _ = runner.sgbm("endtoend/sgbm_kitti_%s" % frame,
                               sgbm_kitti_args(runner, frame) + filled)
            h = dig(s, "lidar_holdout", "result")
            hf = dig(s, "lidar_holdout", "filled")
            out = {"total_seconds": s["seconds"], "stages": {"sgbm": s["seconds"]},
                   "invalid_percent": s["invalid_percent"], "bad3": h["bad3_percent"],
                   "bad1": h["bad1_percent"], "filled_bad3": hf["bad3_percent"],
                   "filled_bad1": hf["bad1_percent"],
                   "size": "%dx%d" % (s["width"], s["height"])}
            out["metrics"] = ("held-out LiDAR bad-3 %.2f %%, bad-1 %.2f %% (%d points; %.1f %% "
                              "invalid = bad); background-filled: bad-3 %.2f %%, bad-1 %.2f %%"
                              % (h["bad3_percent"], h["bad1_percent"], h["counted"],
                                 s["invalid_percent"], hf["bad3_percent"], hf["bad1_percent"]))
            return out
        measure(rows, "SGBM kitti " + frame, sgbm)

    if include_fountain:
        def fountain():
            report, _ = runner.run("endtoend/fountain-P11", "fountain_p11.yaml",
                                   fountain_p11_sets(runner))
            out = run_summary(report)
            out["metrics"] = "none (no laser ground truth in the shared data)"
            return out
        measure(rows, "fountain-P11", fountain)

        def synthetic_fountain():
            data = runner.synth("fountain")
            report, _ = runner.run("endtoend/synthetic-fountain", "synthetic_fountain.yaml",
                                   synthetic_fountain_sets(data))
            out = run_summary(report)
            sigma = within_3sigma(report)
            out["metrics"] = "within 3σ: D+GCP %.2f %%, D̂ %.2f %%" % (
                sigma["within_3sigma"], sigma["propagated_within_3sigma"])
            out["within_3sigma"] = sigma["within_3sigma"]
            return out
        measure(rows, "synthetic fountain", synthetic_fountain)

    md = ["# endtoend — full runs: stage times, peak memory, main metrics; OpenCV SGBM alongside",
          "", "gcpstereo rows: the shipped configuration of each data set (Middlebury: "
          "middlebury_stereo.yaml with the GCP energy; KITTI: kitti_lidar.yaml with "
          "eval.lidar_holdout=true). SGBM rows: gcpstereo_sgbm_baseline (MODE_SGBM_3WAY, block 5, "
          "P1 = 8·3·5², P2 = 32·3·5²) on the same rectified GT pair, timed around compute() only, "
          "scored with gcpstereo eval (Middlebury) or on the same held-out LiDAR points (KITTI); "
          "invalid SGBM pixels count as bad; the 'background-filled' scores fill them first as "
          "the KITTI devkit does (interpolateBackground).", "",
          "| data set | size | labels | GCPs | load | gcps | propagation | cost+opt | "
          "left-right | plane fit | evaluation | write | total | peak MB | metrics |",
          "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for name, r in rows.items():
        if "error" in r:
            md.append("| %s | | | | | | | | | | | | | | error: %s |" % (name, r["error"]))
            continue
        st = r.get("stages", {})

        def sec(stage):
            return "%.2f" % st[stage] if st.get(stage) is not None else ""
        peak = r.get("peak_memory_bytes")
        md.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            name, r.get("size", ""), r.get("labels") or "", r.get("gcp_count") or "",
            sec("load"), sec("gcps"), sec("propagation"),
            sec("cost_and_optimization") or sec("sgbm"), sec("left_right_check"),
            sec("plane_fit"), sec("evaluation"), sec("write"),
            cell(r, "total_seconds"), "%.0f" % (peak / 1e6) if peak else "", r.get("metrics", "")))
    md += ["", "Times in seconds. SGBM's `cost+opt` column is its compute() time; `left-right` is "
           "the second solve from the other image and the fill (optimizer.left_right_check); "
           "`plane fit` the segment-plane fit (optimizer.plane_fit)."]
    return {"rows": rows, "markdown": "\n".join(md)}


SCENE_THRESHOLDS_CM = [1, 2, 5, 10]
SCENE_ALL_VIEWS = ["dataset.reference=all", "dataset.neighbors=auto"]


def scene_summary(report, folder):
    """The figures of a scene run's (or fuse's) report.json."""
    stages = report.get("stages", {})

    def seconds(stage):
        return stages.get(stage, {}).get("seconds")
    views = report.get("views", [])
    view_seconds = sorted(v["seconds"] for v in views if v.get("status") == "done"
                          and v.get("seconds") is not None)
    out = {"folder": folder,
           "total_seconds": report.get("total_seconds"),
           "peak_memory_bytes": report.get("peak_memory_bytes"),
           "views": len(views),
           "views_done": sum(v.get("status") == "done" for v in views),
           "views_reused": sum(v.get("status") == "reused" for v in views),
           "views_failed": [v.get("name") for v in views if v.get("status") == "failed"],
           "view_seconds_median": (view_seconds[len(view_seconds) // 2] if view_seconds
                                   else None),
           "view_seconds_max": view_seconds[-1] if view_seconds else None,
           "view_peak_memory_bytes": max([v.get("peak_memory_bytes", 0) for v in views] or [0]),
           "stages": {name: seconds(name) for name in stages},
           "fused_points": report.get("fusion", {}).get("points"),
           "mesh_faces": report.get("scene_mesh", {}).get("faces"),
           "pictures": sorted(f for f in os.listdir(folder) if f.endswith(".png"))}
    fusion, mesh = seconds("fusion"), seconds("scene_mesh")
    if fusion is not None and mesh is not None:
        out["fusion_and_mesh_seconds"] = fusion + mesh
    metrics = report.get("metrics", {})
    for what in ("mesh_vs_gt_mesh", "fused_points_vs_gt_mesh", "mesh_vs_gt_points",
                 "fused_points_vs_gt_points"):
        if what not in metrics:
            continue
        m = metrics[what]
        thresholds_cm = [round(t * 100, 3) for t in m["thresholds"]]
        if thresholds_cm != SCENE_THRESHOLDS_CM:
            raise BenchError("%s thresholds %s m, expected %s cm" % (what, m["thresholds"],
                                                                     SCENE_THRESHOLDS_CM))
        out[what] = {k: m[k] for k in ("f_score_percent", "accuracy_percent",
                                       "completeness_percent")}
    if "views_sigma" in metrics:
        s = metrics["views_sigma"]
        out["mean_depth_map_within_3_sigma_percent"] = s["mean_depth_map_within_3_sigma_percent"]
        out["mean_scene_mesh_within_3_sigma_percent"] = s["mean_scene_mesh_within_3_sigma_percent"]
    return out


def suite_scene(runner, include_synthetic, include_fountain):
    rows = {}
    if include_synthetic:
        def synthetic(sets):
            def run():
                data = runner.synth("fountain")
                key = "scene/synthetic-fountain/" + sets[0]
                report, folder = runner.run(key, "synthetic_fountain.yaml",
                                            synthetic_fountain_sets(data) + SCENE_ALL_VIEWS +
                                            sets[1])
                return scene_summary(report, folder)
            return run
        variants = [("D+GCP", ("d_gcp", [])),
                    ("D^", ("d_hat", ["runtime.stop_after=propagation",
                                      "fusion.input=propagated"])),
                    ("D", ("d", ["gcp.sources=[]"]))]
        for name, sets in variants:
            measure(rows, "synthetic fountain " + name, synthetic(sets))

        def fuse_only():
            d_gcp = rows.get("synthetic fountain D+GCP", {})
            if "folder" not in d_gcp:
                raise BenchError("no D+GCP scene to fuse")
            views = os.path.join(d_gcp["folder"], "views")
            dirs = [os.path.join(views, v) for v in sorted(os.listdir(views))]
            report, folder = runner.fuse("scene/synthetic-fountain/fuse_d_gcp", dirs)
            return scene_summary(report, folder)
        measure(rows, "synthetic fountain D+GCP, gcpstereo fuse", fuse_only)

    if include_fountain:
        def fountain():
            report, folder = runner.run("scene/fountain-P11", "fountain_p11.yaml",
                                        fountain_p11_sets(runner) + SCENE_ALL_VIEWS)
            return scene_summary(report, folder)
        measure(rows, "fountain-P11", fountain)

    def mb(value):
        return "%.0f" % (value / 1e6) if value else ""

    def seconds(value):
        return fmt_seconds(value) if value is not None else ""

    def fscores(r, what):
        m = r.get(what)
        return " / ".join("%.1f" % f for f in m["f_score_percent"]) if m else ""

    md = ["# scene — whole scenes: every view, fused and meshed", "",
          "All views of each data set (`dataset.reference=all`, `dataset.neighbors=auto`), one "
          "after the other in one process; fusion (`fusion.*` defaults), PCL screened Poisson "
          "(`scene_mesh.*` defaults), scene evaluation against the part of the ground truth at "
          "least `fusion.min_views` views observe. Synthetic fountain: "
          "`configs/synthetic_fountain.yaml` (1536×1024, 360 depth labels, 2×2 tiles, laser "
          "GCPs at s = 16); fountain-P11: `configs/fountain_p11.yaml` (scale 0.5, image-match "
          "GCPs).", "",
          "| run | views (done/reused/failed) | whole scene | peak MB | view time median / max | "
          "fusion + mesh | fused points | mesh faces | within 3σ: depth maps / scene mesh |",
          "|---|---|---:|---:|---|---:|---:|---:|---|"]
    for name, r in rows.items():
        if "error" in r:
            md.append("| %s | error: %s | | | | | | | |" % (name, r["error"]))
            continue
        sigma = ""
        if r.get("mean_depth_map_within_3_sigma_percent") is not None:
            sigma = "%.1f %% / %.1f %%" % (r["mean_depth_map_within_3_sigma_percent"],
                                          r["mean_scene_mesh_within_3_sigma_percent"])
        md.append("| %s | %d (%d/%d/%d) | %s | %s | %s / %s | %s | %s | %s | %s |" % (
            name, r["views"], r["views_done"], r["views_reused"], len(r["views_failed"]),
            seconds(r["total_seconds"]), mb(r["peak_memory_bytes"]),
            seconds(r["view_seconds_median"]), seconds(r["view_seconds_max"]),
            seconds(r.get("fusion_and_mesh_seconds")), r.get("fused_points") or "",
            r.get("mesh_faces") or "", sigma))
    md += ["", "F-score %% at %s cm (accuracy and completeness in results.json):" %
           " / ".join(str(t) for t in SCENE_THRESHOLDS_CM), "",
           "| run | mesh vs gt mesh | points vs gt mesh | mesh vs laser | points vs laser |",
           "|---|---|---|---|---|"]
    for name, r in rows.items():
        if "error" in r or "mesh_vs_gt_mesh" not in r:
            continue
        md.append("| %s | %s | %s | %s | %s |" % (
            name, fscores(r, "mesh_vs_gt_mesh"), fscores(r, "fused_points_vs_gt_mesh"),
            fscores(r, "mesh_vs_gt_points"), fscores(r, "fused_points_vs_gt_points")))

    targets = []
    with_gcp, without = rows.get("synthetic fountain D+GCP", {}), rows.get("synthetic fountain D", {})
    for what in ("mesh_vs_gt_mesh", "fused_points_vs_gt_mesh"):
        if what in with_gcp and what in without:
            a, b = with_gcp[what]["f_score_percent"], without[what]["f_score_percent"]
            beats = all(x > y for x, y in zip(a, b))
            targets.append("- laser GCPs beat no GCPs at every threshold (%s F-score): %s "
                           "(%s against %s)" % (what, "met" if beats else "NOT met",
                                                " / ".join("%.1f" % x for x in a),
                                                " / ".join("%.1f" % y for y in b)))
    if "total_seconds" in with_gcp and with_gcp["views_reused"] == 0:
        t, m = with_gcp["total_seconds"], with_gcp["peak_memory_bytes"]
        targets.append("- 11-view scene at the paper's setting in ≤ 11 min and ≤ 4 GB: time %s "
                       "(%s), memory %s MB (%s)" % (
                           fmt_seconds(t), "met" if t <= 660 else "NOT met", mb(m),
                           "met" if m <= 4e9 else "NOT met"))
    if "fusion_and_mesh_seconds" in with_gcp:
        t = with_gcp["fusion_and_mesh_seconds"]
        targets.append("- fusion plus meshing ≤ 60 s: %s (%s)" % (
            fmt_seconds(t), "met" if t <= 60 else "NOT met"))
    if targets:
        md += ["", "Targets (issue 20):"] + targets
    md += ["", "Laser metrics of the D+GCP and D^ runs are not independent: the laser scan is "
           "their GCP source. Pictures: `model_*.png` and `scene_sigma_histogram.png` in each "
           "run folder under runs/scene/."]
    return {"rows": rows, "markdown": "\n".join(md)}


# Issue 25's targets (wall time on 2 cores, peak memory): seconds, bytes (None = no target).
SPEED_TARGETS = {"kitti": (2.0, 500e6), "teddy": (2.0, None), "fountain-P11": (30.0, 2e9)}
# The issue times Teddy (2003, 450×375, 60 labels); without its data (not in the shared data) the
# Teddy target is checked on Aloe (427×370, 81 labels), the Teddy-size scene of
# tools/benchmarks/optimize_benchmark.cpp.
TEDDY_STAND_IN = "Aloe"
# report.json lists the stages by name; the tables show them in the order the pipeline runs them
# (pipeline/src/run.cc), then any others by name.
STAGE_ORDER = ["load", "gcps", "propagation", "cost_and_optimization", "left_right_check",
               "plane_fit", "evaluation", "mesh", "write", "colmap_export"]
# Accuracy figures where a larger value is better (all others are error rates).
HIGHER_IS_BETTER = {"within_3sigma", "propagated_within_3sigma"}


def combined(runs):
    """Repetitions [(summary, accuracy), ...] of one run as one: the median total, per-stage and
    untimed (total − stages) seconds, the largest peak memory, the first repetition's accuracy;
    every repetition's totals and peaks, and their accuracies when they differ (the runs are meant
    to be deterministic)."""
    summaries = [s for s, _ in runs]
    out = dict(summaries[0])
    out.update(runs[0][1])
    out["total_seconds_each"] = [s["total_seconds"] for s in summaries]
    out["total_seconds"] = statistics.median(out["total_seconds_each"])
    if all("process_seconds" in s for s in summaries):
        out["process_seconds_each"] = [s["process_seconds"] for s in summaries]
        out["process_seconds"] = statistics.median(out["process_seconds_each"])
    stages = [s.get("stages", {}) for s in summaries]
    out["stages"] = {name: statistics.median(st.get(name) or 0.0 for st in stages)
                     for name in stages[0]}
    if stages[0]:
        out["untimed_seconds"] = statistics.median(
            s["total_seconds"] - sum(v or 0.0 for v in s.get("stages", {}).values())
            for s in summaries)
    peaks = [s.get("peak_memory_bytes") for s in summaries]
    if any(p is not None for p in peaks):  # (SGBM's report has none)
        out["peak_memory_bytes_each"] = peaks
        out["peak_memory_bytes"] = max(p for p in peaks if p is not None)
    if any(a != runs[0][1] for _, a in runs):
        out["accuracy_each"] = [a for _, a in runs]
    return out


def suite_speed(runner, baseline, scenes, frames, include_fountain, include_synthetic, repeat):
    """Issue 25's three runs, each timed `repeat` times with this build (and with `baseline`, a
    Runner of another build, when given): KITTI frames, the two-view Middlebury scenes, one
    fountain view."""
    builds = [("after", runner)] + ([("before", baseline)] if baseline else [])

    def timed(table, name, what, config, sets, accuracy):
        """gcpstereo run of CONFIG + sets (a list, or a function giving it) by every build, run
        folders runs/speed[/baseline]/WHAT/runI; table[name][build] = the combined figures. The
        builds take turns (after 1, before 1, after 2, ...): a change of the machine's load
        reaches both. A build's first failure ends its repetitions."""
        row = table.setdefault(name, {})
        runs = {build: [] for build, _ in builds}
        for i in range(1, repeat + 1):
            for build, r in builds:
                if "error" in row.get(build, {}):
                    continue
                prefix = "speed/" if build == "after" else "speed/baseline/"

                def once():
                    items = sets() if callable(sets) else sets
                    report, folder = r.run("%s%s/run%d" % (prefix, what, i), config, items)
                    summary = run_summary(report)
                    elapsed = os.path.join(folder, "bench_seconds.json")
                    if os.path.exists(elapsed):
                        with open(elapsed) as f:
                            summary["process_seconds"] = json.load(f)
                    runs[build].append((summary, accuracy(report)))
                    return {}
                measure(row, build, once)
        for build, _ in builds:
            if "error" not in row[build]:
                row[build] = combined(runs[build])
        return row

    def sgbm_timed(row, what, args, accuracy):
        """OpenCV SGBM on the same pair (timed around compute() only), row["sgbm"]."""
        def run():
            def once(i):
                s, _ = runner.sgbm("speed/%s/run%d" % (what, i), args)
                return {"total_seconds": s["seconds"], "stages": {}}, accuracy(s)
            return combined([once(i) for i in range(1, repeat + 1)])
        measure(row, "sgbm", run)

    kitti = {}
    for frame in frames:
        row = timed(kitti, frame, "kitti_" + frame, "kitti_lidar.yaml", kitti_sets(runner, frame),
                    kitti_holdout)
        sgbm_timed(row, "sgbm_kitti_" + frame, sgbm_kitti_args(runner, frame),
                   lambda s: {"bad3": dig(s, "lidar_holdout", "result", "bad3_percent"),
                              "bad1": dig(s, "lidar_holdout", "result", "bad1_percent")})

    names = [s["name"] for s in scenes]
    teddy_data = os.path.isdir(os.path.join(runner.data, "middlebury", "teddy"))
    timing_scene = "teddy" if teddy_data else TEDDY_STAND_IN
    two_view = {}
    for scene in scenes:
        row = timed(two_view, scene["name"], "middlebury_" + scene["name"],
                    "middlebury_stereo.yaml",
                    stereo_sets(runner, scene) + ["optimizer.use_gcp_energy=true"],
                    middlebury_bad1)
        sgbm_timed(row, "sgbm_" + scene["name"], sgbm_middlebury_args(runner, scene),
                   lambda s: {})

    fountain = {}
    if include_fountain:
        timed(fountain, "fountain-P11", "fountain-P11", "fountain_p11.yaml",
              fountain_p11_sets(runner), lambda report: {})
    if include_synthetic:
        # one scene for both builds (made by this build's gcpstereo synth)
        timed(fountain, "synthetic fountain", "synthetic-fountain", "synthetic_fountain.yaml",
              lambda: synthetic_fountain_sets(runner.synth("fountain")), within_3sigma)

    def target_of(kind, name):
        if kind == "two_view":
            return SPEED_TARGETS["teddy"] if name == timing_scene else None
        return SPEED_TARGETS.get(kind if kind == "kitti" else name)

    tables = [("kitti", kitti, "KITTI frame, full pipeline with LiDAR GCPs",
               "configs/kitti_lidar.yaml with eval.lidar_holdout=true (8×8 checkerboard: half of "
               "the scan as GCPs, half scored) on %s; accuracy = bad-3 / bad-1 (%%) on the "
               "held-out LiDAR points." % KITTI_DRIVE,
               [("held-out bad-3 %", "bad3"), ("bad-1 %", "bad1")]),
              ("two_view", two_view, "Middlebury two-view with stereo GCPs",
               "configs/middlebury_stereo.yaml with optimizer.use_gcp_energy=true on the GT pair, "
               "integer disparity labels 0…max (as table2); accuracy = bad-1 (%%, |d − gt| > 1 px) "
               "in nonocc / all. The ≤ %.1f s target is the issue's Teddy's; %s" % (
                   SPEED_TARGETS["teddy"][0],
                   "it is checked on teddy." if teddy_data else
                   "Teddy is not in %s, so it is checked on %s (427×370, labels 0…80), the "
                   "Teddy-size stand-in of tools/benchmarks/optimize_benchmark.cpp%s." % (
                       os.path.join(runner.data, "middlebury"), TEDDY_STAND_IN,
                       "" if TEDDY_STAND_IN in names else " (not selected here)")),
               [("bad-1 nonocc %", "bad1_nonocc"), ("bad-1 all %", "bad1_all")]),
              ("fountain", fountain, "Fountain view 0005 at the paper's setting",
               "fountain-P11: configs/fountain_p11.yaml as shipped (view 0005, 6 neighbours, "
               "1536×1024, 360 depth labels, image-match GCPs; no ground truth here). Synthetic "
               "fountain: configs/synthetic_fountain.yaml (view 0005, laser GCPs at s = 16) on "
               "the scene of `gcpstereo synth --preset fountain`; accuracy = share of pixels "
               "within 3σ of the exact depth.",
               [("within 3σ %", "within_3sigma")])]

    md = ["# speed — issue 25: time, memory and accuracy of the three runs", "",
          "Each gcpstereo run %s; times are the median of %d run%s (per stage and total), peak "
          "memory the largest (report.json `peak_memory_bytes`), accuracy the first run's. "
          "Stage columns in seconds, in pipeline order; `untimed` = total − the stages (label "
          "choice, depth maps, mesh building, report); `total` = report.json's total_seconds "
          "(from the command's start to the report), `process` = the whole process's wall time "
          "(start-up, loading the shared libraries and exit included), which the targets are "
          "checked against. SGBM = gcpstereo_sgbm_baseline on the "
          "same rectified pair, timed around compute() only (as endtoend); × SGBM = gcpstereo "
          "total / SGBM time. Load average when the suite began: %s%s." % (
              "by this build (%s)" % runner.build if not baseline else
              "by this build (after: %s, configs %s) and by the baseline build (before: %s, "
              "configs %s) on the same inputs; after/before = ratios of the after row to the "
              "before row, and whether every accuracy figure is no worse" % (
                  runner.build, runner.configs, baseline.build, baseline.configs),
              repeat, "" if repeat == 1 else "s",
              " / ".join("%.2f" % x for x in os.getloadavg()),
              " (runs reused with --reuse were timed earlier)" if runner.reuse else "")]
    for kind, rows, title, note, accuracy in tables:
        if not rows:
            continue
        md += ["", "## " + title, "", note, ""]
        md += speed_table(kind, rows, accuracy, baseline is not None, target_of)
    md += speed_summary(kitti, two_view, fountain, builds)
    return {"kitti": kitti, "two_view": two_view, "fountain": fountain, "repeat": repeat,
            "build": runner.build, "baseline_build": baseline.build if baseline else None,
            "baseline_configs": baseline.configs if baseline else None,
            "teddy_target_scene": timing_scene, "load_average": os.getloadavg(),
            "markdown": "\n".join(md)}


def speed_table(kind, rows, accuracy, with_baseline, target_of):
    """One Markdown table of the speed suite: a row per data set and build."""
    stages = set()
    for row in rows.values():
        for build in ("after", "before"):
            stages.update(row.get(build, {}).get("stages", {}))
    stages = ([s for s in STAGE_ORDER if s in stages] +
              sorted(s for s in stages if s not in STAGE_ORDER))
    has_sgbm = any("sgbm" in row for row in rows.values())
    header = (["data set"] + (["build"] if with_baseline else []) + ["size", "labels"] + stages +
              ["untimed", "total s", "process s", "peak MB"] + [h for h, _ in accuracy] +
              (["SGBM s", "× SGBM"] if has_sgbm else []) + ["target"] +
              (["after/before"] if with_baseline else []))
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join("---" if h in ("data set", "build", "size", "target", "after/before")
                            else "---:" for h in header) + "|"]
    for name, row in rows.items():
        for build in ("after", "before") if with_baseline else ("after",):
            m = row.get(build, {"error": "not run"})
            sgbm = row.get("sgbm", {})
            first = [name] + ([build] if with_baseline else [])
            if "error" in m:
                lines.append("| " + " | ".join(first + ["error: %s" % m["error"]] +
                                                [""] * (len(header) - len(first) - 1)) + " |")
                continue
            cells = first + [m.get("size", ""), str(m.get("labels") or "")]
            cells += ["%.2f" % m["stages"][s] if s in m.get("stages", {}) else "" for s in stages]
            peak = m.get("peak_memory_bytes")
            cells += [cell(m, "untimed_seconds"), cell(m, "total_seconds"),
                      cell(m, "process_seconds"), "%.0f" % (peak / 1e6) if peak else ""]
            cells += [cell(m, key) for _, key in accuracy]
            if has_sgbm:
                if "error" in sgbm:
                    cells += ["error: %s" % sgbm["error"], ""]
                elif sgbm.get("total_seconds"):
                    ratio = m["total_seconds"] / sgbm["total_seconds"]
                    cells += ["%.2f" % sgbm["total_seconds"],
                              ("%.1f" if ratio < 10 else "%.0f") % ratio]
                else:
                    cells += ["", ""]
            cells.append(target_cell(m, target_of(kind, name)))
            if with_baseline:
                cells.append(after_before_cell(row, accuracy) if build == "after" else "")
            lines.append("| " + " | ".join(cells) + " |")
    varying = ["%s (%s): %s" % (name, build, row[build]["accuracy_each"])
               for name, row in rows.items() for build in ("after", "before")
               if "accuracy_each" in row.get(build, {})]
    if varying:
        lines += ["", "Accuracy differed between repetitions: " + "; ".join(varying)]
    return lines


def target_cell(m, target):
    if target is None:
        return ""
    seconds, memory = target
    missed = []
    # The wall time a user waits: the whole process's when measured.
    if m.get("process_seconds", m["total_seconds"]) > seconds:
        missed.append("time")
    peak = m.get("peak_memory_bytes")
    if memory is not None and (peak is None or peak > memory):
        missed.append("memory" if peak is not None else "memory unknown")
    wanted = "≤ %.0f s" % seconds + (", ≤ %.0f MB" % (memory / 1e6) if memory else "")
    return "%s: %s" % (wanted, "met" if not missed else "NOT met (%s)" % ", ".join(missed))


def after_before_cell(row, accuracy):
    after, before = row.get("after", {}), row.get("before", {})
    if "error" in after or "error" in before or not before:
        return ""
    parts = ["time ×%.2f" % (after["total_seconds"] / before["total_seconds"])]
    if after.get("peak_memory_bytes") and before.get("peak_memory_bytes"):
        parts.append("peak ×%.2f" % (after["peak_memory_bytes"] / before["peak_memory_bytes"]))
    worse = []
    for _, key in accuracy:
        a, b = after.get(key), before.get(key)
        if a is None or b is None:
            continue
        if (a < b) if key in HIGHER_IS_BETTER else (a > b):
            worse.append("%s %.2f → %.2f" % (key, b, a))
    if any(after.get(key) is not None for _, key in accuracy):
        parts.append("accuracy WORSE: " + ", ".join(worse) if worse else "accuracy kept")
    return ", ".join(parts)


def speed_summary(kitti, two_view, fountain, builds):
    """The accuracy lines of issue 25's 'nothing got worse' per build."""
    lines = []
    for build, _ in builds:
        label = build if len(builds) > 1 else "this build"
        bad3 = [row[build]["bad3"] for row in kitti.values()
                if "bad3" in row.get(build, {})]
        if bad3:
            lines.append("- %s, KITTI held-out bad-3 over %d frame%s: mean %.2f %%, worst %.2f %% "
                         "(issue 25, six dev frames at ec47109: mean 2.01 %%, worst 2.72 %%)" % (
                             label, len(bad3), "" if len(bad3) == 1 else "s",
                             sum(bad3) / len(bad3), max(bad3)))
        nonocc = ["%s %.2f" % (name, row[build]["bad1_nonocc"])
                  for name, row in two_view.items() if "bad1_nonocc" in row.get(build, {})]
        if nonocc:
            lines.append("- %s, Middlebury bad-1 nonocc %%: %s" % (label, ", ".join(nonocc)))
        sigma = fountain.get("synthetic fountain", {}).get(build, {})
        if "within_3sigma" in sigma:
            lines.append("- %s, synthetic fountain within 3σ: %.2f %% (D̂ %.2f %%)" % (
                label, sigma["within_3sigma"], sigma["propagated_within_3sigma"]))
    return ["", "## Accuracy", ""] + lines if lines else []


def cell(obj, key, fmt="%.2f"):
    if "error" in obj:
        return "error"
    value = obj.get(key)
    return "" if value is None else fmt % value


def pair_cell(obj, a, b):
    if "error" in obj:
        return "error"
    return "%s / %s" % (cell(obj, a), cell(obj, b))


def add_errors(md, rows):
    errors = ["- %s %s: %s" % (scene, what, r["error"])
              for scene, row in rows.items() for what, r in row.items() if "error" in r]
    if errors:
        md += ["", "Errors:"] + errors


def add_cost_errors(result):
    lines = []
    for scene, row in result["middlebury"].items():
        for what, r in row.items():
            if "error" in r:
                lines.append("- %s %s: %s" % (scene, what, r["error"]))
    for frame, r in result["kitti"].items():
        if "error" in r:
            lines.append("- kitti %s: %s" % (frame, r["error"]))
    for name, r in result["synthetic"].items():
        if "error" in r:
            lines.append("- synthetic %s: %s" % (name, r["error"]))
    if lines:
        result["markdown"] += "\n\nErrors:\n" + "\n".join(lines)


# ---------------------------------------------------------------------------------------------

def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="benchmark.py", description=__doc__.split("\n\n")[0],
        epilog=__doc__[__doc__.index("Suites"):], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--suite", choices=SUITES + ["all"], default="all",
                        help="which suite to run (default: all, which leaves out scene and speed)")
    parser.add_argument("--data", default=os.path.join("..", "shared", "data"),
                        help="benchmark data folder (default: ../shared/data)")
    parser.add_argument("--build", default="build",
                        help="build folder holding gcpstereo and tools/benchmarks/ (default: build)")
    parser.add_argument("--out", default="bench-out", help="output folder (default: bench-out)")
    parser.add_argument("--scenes", default="",
                        help="comma-separated filter: Middlebury scene names, KITTI frames "
                        "(e.g. 0000000010 or 'kitti' for all), 'synthetic', 'fountain' "
                        "(default: everything)")
    parser.add_argument("--reuse", action="store_true",
                        help="skip runs whose folder under OUT/runs already holds the result of "
                        "the same command (to resume an interrupted benchmark)")
    parser.add_argument("--timeout", type=int, default=3600,
                        help="seconds allowed per program run (default: 3600)")
    parser.add_argument("--baseline-build", metavar="DIR",
                        help="speed suite: a second build folder (e.g. of an older commit) whose "
                        "gcpstereo also runs every timed run, for before/after figures")
    parser.add_argument("--baseline-configs", metavar="DIR",
                        help="speed suite: the configs/ folder the baseline build runs (default: "
                        "this checkout's), e.g. an older commit's, to time a change of a shipped "
                        "configuration against the one before it")
    parser.add_argument("--repeat", type=int, default=1, metavar="N",
                        help="speed suite: run each timed run N times, report the median time and "
                        "the largest peak memory (default: 1)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a configuration override added to every gcpstereo run and fuse, "
                        "after the suite's own (repeatable), e.g. --set optimizer.gcp_confidence=0.5 "
                        "to measure an option on every scene; use a separate --out per variant")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")

    runner = Runner(args)
    if args.baseline_configs and not args.baseline_build:
        parser.error("--baseline-configs needs --baseline-build")
    if args.baseline_configs and not os.path.isdir(args.baseline_configs):
        parser.error("--baseline-configs %s is not a folder" % args.baseline_configs)
    baseline = (Runner(args, build=args.baseline_build, configs=args.baseline_configs)
                if args.baseline_build else None)
    for program in [runner.gcpstereo] + ([baseline.gcpstereo] if baseline else []):
        if not os.access(program, os.X_OK):
            parser.error("%s not found: build it first (cmake --build %s --target gcpstereo)"
                         % (program, os.path.dirname(program)))
    if not os.path.isdir(runner.data):
        parser.error("data folder %s not found (--data)" % runner.data)

    wanted = [s.strip() for s in args.scenes.split(",") if s.strip()]

    def selected(name, family=None):
        return not wanted or name in wanted or (family is not None and family in wanted)

    scenes = [s for s in MIDDLEBURY if selected(s["name"], "middlebury")
              and os.path.isdir(middlebury_path(runner, s))]
    for name in wanted:
        scene = [s for s in MIDDLEBURY if s["name"] == name]
        if scene and scene[0] not in scenes:
            runner.log("no data for Middlebury scene %s (%s): left out"
                       % (name, middlebury_path(runner, scene[0])))
    frames = [f for f in KITTI_FRAMES if selected(f, "kitti")]
    include_synthetic = selected("synthetic")
    include_fountain = selected("fountain")

    os.makedirs(runner.out, exist_ok=True)
    results_path = os.path.join(runner.out, "results.json")
    results = {}
    if os.path.exists(results_path):
        with open(results_path) as f:
            results = json.load(f)  # other suites' results are kept
    results["environment"] = {"build": runner.build, "data": runner.data,
                              "host": platform.node(), "python": platform.python_version(),
                              "cpus": os.cpu_count(), "command": " ".join(sys.argv),
                              "sets": runner.extra_sets}
    # 'all' leaves out the scene suite (about 75 minutes on 2 cores) and the speed suite (it times
    # endtoend's runs again)
    suites = ([s for s in SUITES if s not in ("scene", "speed")] if args.suite == "all"
              else [args.suite])
    started = time.monotonic()
    for suite in suites:
        runner.log("suite %s: %d Middlebury scenes, %d KITTI frames" % (suite, len(scenes),
                                                                       len(frames)))
        t0 = time.monotonic()
        if suite == "costs":
            result = suite_costs(runner, scenes, frames, include_synthetic)
            add_cost_errors(result)
        elif suite == "table2":
            result = suite_table2(runner, scenes)
        elif suite == "paired":
            result = suite_paired(runner, scenes, frames, include_synthetic)
        elif suite == "endtoend":
            result = suite_endtoend(runner, scenes, frames, include_fountain)
        elif suite == "speed":
            result = suite_speed(runner, baseline, scenes, frames, include_fountain,
                                 include_synthetic, args.repeat)
        else:
            result = suite_scene(runner, include_synthetic, include_fountain)
        result["seconds"] = time.monotonic() - t0
        result["finished"] = datetime.datetime.now().isoformat(timespec="seconds")
        results[suite] = result
        with open(os.path.join(runner.out, suite + ".md"), "w") as f:
            f.write(result["markdown"] + "\n")
        with open(results_path + ".tmp", "w") as f:
            json.dump(results, f, indent=2, sort_keys=True)
        os.replace(results_path + ".tmp", results_path)
        print()
        print(result["markdown"])
        print()
        runner.log("suite %s done in %s -> %s" % (suite, fmt_seconds(result["seconds"]),
                                                  os.path.join(runner.out, suite + ".md")))
    runner.log("all done in %s (%d program runs); results in %s"
               % (fmt_seconds(time.monotonic() - started),
                  runner.count + (baseline.count if baseline else 0), results_path))
    return 0


if __name__ == "__main__":
    sys.exit(main())
