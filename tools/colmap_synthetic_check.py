#!/usr/bin/env python3
# Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
"""Scores a gcpstereo run on a COLMAP model of the synthetic fountain against its exact truth.

Used by tools/colmap_synthetic_benchmark.sh (issue 21, "SfM GCPs on ground truth", "Alignment").
Standard library only. The run's model lives in COLMAP's own frame; the run aligned it to the
laser scan or to known centres (dataset.align: scan | centres) and recorded the similarity in
report.json ("alignment"). A relative dataset.path in the run's effective_config.yaml is taken
relative to the working directory, as gcpstereo takes it.

  align  RUN SYNTH           aligned camera centres versus the true ones (cameras/*.camera line 8),
                             the scale error from the distances between centres, orientation angles
  gcps   RUN SYNTH [VIEW]    the run's GCPs (gcps.ply) per source: density, outlier rate against
                             gt/VIEW.depth.pfm (outlier: |error| > 3 sigma of gt/VIEW.sigma.pfm and
                             > 1 % of the depth)
  dense  RUN SYNTH [VIEW]    within-n-sigma of the run's depth.pfm in the true camera's frame
  summary OUT                the markdown table of tools/colmap_synthetic_benchmark.sh's OUT/checks

Two ways of comparing are given, because the COLMAP camera is not the true one (COLMAP keeps the
principal point at the image centre and estimates the pose): "pixel" compares a depth at pixel p
with the true depth at p, as `gcpstereo eval --depth` does; "frame" back-projects the estimate
through the aligned COLMAP camera into a 3D point, projects that into the true camera and
compares its depth there with the true depth at the nearest pixel: the error of the 3D point,
free of the two cameras' different depth axes, but blind to a point slid along the surface.
Results are printed as JSON.
"""

import json
import math
import os
import struct
import sys

from file_formats import read_pfm, read_strecha_camera

# ---------------------------------------------------------------- files


def read_colmap_bin(sparse):
    """The cameras and images of a COLMAP binary model: {name: camera dict in model frame}."""
    params_of_model = {0: 3, 1: 4}  # SIMPLE_PINHOLE, PINHOLE: what image_undistorter writes
    cams = {}
    with open(os.path.join(sparse, "cameras.bin"), "rb") as f:
        (n,) = struct.unpack("<Q", f.read(8))
        for _ in range(n):
            cid, model, w, h = struct.unpack("<iiQQ", f.read(24))
            if model not in params_of_model:
                sys.exit(f"error: {sparse}/cameras.bin: camera {cid} is model {model}, not a pinhole")
            p = struct.unpack("<%dd" % params_of_model[model], f.read(8 * params_of_model[model]))
            fx, fy, cx, cy = (p[0], p[0], p[1], p[2]) if model == 0 else p
            # COLMAP's pixel centres are at +0.5; gcpstereo's (and Strecha's) at integers.
            cams[cid] = {"K": [[fx, 0, cx - 0.5], [0, fy, cy - 0.5], [0, 0, 1]], "size": (w, h)}
    images = {}
    with open(os.path.join(sparse, "images.bin"), "rb") as f:
        (n,) = struct.unpack("<Q", f.read(8))
        for _ in range(n):
            iid, qw, qx, qy, qz, tx, ty, tz, cid = struct.unpack("<I7dI", f.read(64))
            name = b""
            while (c := f.read(1)) != b"\0":
                name += c
            (npts,) = struct.unpack("<Q", f.read(8))
            f.seek(24 * npts, 1)
            Rcw = quat_to_matrix(qw, qx, qy, qz)  # camera_from_world
            Rwc = transpose(Rcw)
            C = [-v for v in mat_vec(Rwc, [tx, ty, tz])]
            images[name.decode()] = {"K": cams[cid]["K"], "R": Rwc, "C": C, "size": cams[cid]["size"]}
    return images


def read_gcps_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    expected = ("property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
                "property uchar green\nproperty uchar blue\nproperty float sigma\n"
                "property uchar source\nproperty int col\nproperty int row\nproperty float depth\n")
    if expected not in header:
        sys.exit(f"error: {path}: not a gcpstereo gcps.ply (unexpected properties)")
    n = int(header.split("element vertex ")[1].split()[0])
    rec = struct.Struct("<fffBBBfBiif")
    if len(data) - end != n * rec.size:
        sys.exit(f"error: {path}: {n} vertices announced, {len(data) - end} bytes follow")
    out = []
    for i in range(n):
        x, y, z, _, _, _, sigma, source, col, row, depth = rec.unpack_from(data, end + i * rec.size)
        out.append({"X": (x, y, z), "sigma": sigma, "source": source, "col": col, "row": row,
                    "depth": depth})
    return out


# ---------------------------------------------------------------- geometry


def quat_to_matrix(w, x, y, z):
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def transpose(m):
    return [list(r) for r in zip(*m)]


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mat_vec(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def norm(v):
    return math.sqrt(sum(x * x for x in v))


def aligned_cameras(run, model_sparse):
    """The model's cameras moved into the scan's frame by the run's alignment."""
    with open(os.path.join(run, "report.json")) as f:
        report = json.load(f)
    alignment = report.get("alignment")
    if not alignment or "world_from_model" not in alignment:
        sys.exit(f"error: {run}/report.json has no alignment.world_from_model (dataset.align?)")
    T = alignment["world_from_model"]
    A = [row[:3] for row in T[:3]]
    t = [row[3] for row in T[:3]]
    s = alignment["scale"]
    Ra = [[v / s for v in row] for row in A]
    out = {}
    for name, cam in read_colmap_bin(model_sparse).items():
        out[name] = {"K": cam["K"], "R": mat_mul(Ra, cam["R"]),
                     "C": [a + b for a, b in zip(mat_vec(A, cam["C"]), t)], "size": cam["size"]}
    return out, alignment


def rotation_angle_deg(Ra, Rb):
    m = mat_mul(transpose(Ra), Rb)
    c = max(-1.0, min(1.0, (m[0][0] + m[1][1] + m[2][2] - 1) / 2))
    return math.degrees(math.acos(c))


def true_camera(synth, view):
    path = os.path.join(synth, "cameras", view + ".camera")
    if not os.path.exists(path):
        path = os.path.join(synth, "cameras", view + ".png.camera")
    return read_strecha_camera(path)


def project(cam, X):
    """(u, v, z) of world point X in a camera (K, R world_from_camera, C)."""
    p = mat_vec(transpose(cam["R"]), sub(X, cam["C"]))
    K = cam["K"]
    return K[0][0] * p[0] / p[2] + K[0][1] * p[1] / p[2] + K[0][2], K[1][1] * p[1] / p[2] + K[1][2], p[2]


# ---------------------------------------------------------------- commands


def workspace_of(run):
    with open(os.path.join(run, "report.json")) as f:
        report = json.load(f)
    cfg = os.path.join(run, "effective_config.yaml")
    path = None
    with open(cfg) as f:
        in_dataset = False
        for line in f:
            if line.startswith("dataset:"):
                in_dataset = True
            elif in_dataset and line.strip().startswith("path:"):
                path = line.split("path:", 1)[1].split("#")[0].strip().strip('"')
                break
    if not path:
        sys.exit(f"error: {cfg}: no dataset.path")
    return path, report


def cmd_align(run, synth):
    ws, _ = workspace_of(run)
    cams, alignment = aligned_cameras(run, os.path.join(ws, "sparse"))
    names = sorted(cams)
    truth = {n: true_camera(synth, n) for n in names}
    per = {}
    for n in names:
        per[n] = {"centre_error": norm(sub(cams[n]["C"], truth[n]["C"])),
                  "rotation_deg": rotation_angle_deg(cams[n]["R"], truth[n]["R"])}
    est = true = 0.0
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            est += norm(sub(cams[a]["C"], cams[b]["C"]))
            true += norm(sub(truth[a]["C"], truth[b]["C"]))
    errors = sorted(p["centre_error"] for p in per.values())
    return {"registered_images": len(names),
            "alignment": {k: alignment.get(k) for k in
                          ("method", "scale", "rotation_deg", "residual_median",
                           "residual_p90", "residual_rms", "residual_median_relative",
                           "model_spread", "correspondences", "inliers", "inlier_share")},
            "scale_error_percent": 100.0 * (est / true - 1.0),
            "centre_error_mean": sum(errors) / len(errors),
            "centre_error_median": errors[len(errors) // 2],
            "centre_error_max": errors[-1],
            "rotation_deg_max": max(p["rotation_deg"] for p in per.values()),
            "per_camera": per}


def truth_maps(synth, view):
    w, h, depth = read_pfm(os.path.join(synth, "gt", view + ".depth.pfm"))
    w2, h2, sigma = read_pfm(os.path.join(synth, "gt", view + ".sigma.pfm"))
    if (w, h) != (w2, h2):
        sys.exit("error: depth and sigma maps differ in size")
    return w, h, depth, sigma


def known(g, s):
    return math.isfinite(g) and g > 0 and math.isfinite(s) and s > 0


def cmd_gcps(run, synth, view):
    w, h, gt, sigma = truth_maps(synth, view)
    cam = true_camera(synth, view)
    names = {0: "lidar", 1: "depth_map", 2: "stereo", 3: "sfm"}
    stats = {}
    for g in read_gcps_ply(os.path.join(run, "gcps.ply")):
        s = stats.setdefault(names.get(g["source"], str(g["source"])),
                             {"gcps": 0, "pixel": [0, 0, 0], "frame": [0, 0, 0], "abs_err": []})
        s["gcps"] += 1
        # pixel: the GCP's depth against the truth at its pixel.
        i = g["row"] * w + g["col"]
        if known(gt[i], sigma[i]):
            e = abs(g["depth"] - gt[i])
            s["pixel"][0] += 1
            s["pixel"][1] += e > 3 * sigma[i] and e > 0.01 * gt[i]
            s["pixel"][2] += e <= 3 * sigma[i]
        # frame: the GCP's 3D point in the true camera.
        u, v, z = project(cam, g["X"])
        c, r = int(round(u)), int(round(v))
        if 0 <= c < w and 0 <= r < h and z > 0:
            j = r * w + c
            if known(gt[j], sigma[j]):
                e = abs(z - gt[j])
                s["frame"][0] += 1
                s["frame"][1] += e > 3 * sigma[j] and e > 0.01 * gt[j]
                s["frame"][2] += e <= 3 * sigma[j]
                s["abs_err"].append(e)
    out = {"view": view, "pixels": w * h,
           "outlier_definition": "|error| > 3 sigma (gt sigma map) and > 1 % of the true depth"}
    for name, s in stats.items():
        errs = sorted(s.pop("abs_err"))
        for kind in ("pixel", "frame"):
            n, bad, within = s.pop(kind)
            s[kind] = {"evaluated": n, "outliers": bad,
                       "outlier_percent": 100.0 * bad / n if n else None,
                       "within_3_sigma_percent": 100.0 * within / n if n else None}
        s["density_per_pixel"] = s["gcps"] / (w * h)
        s["frame"]["median_abs_error"] = errs[len(errs) // 2] if errs else None
        out[name] = s
    return out


def cmd_dense(run, synth, view, name):
    ws, _ = workspace_of(run)
    cams, _ = aligned_cameras(run, os.path.join(ws, "sparse"))
    if name not in cams:
        sys.exit(f"error: {name} is not an image of the model {ws}")
    est_cam, cam = cams[name], true_camera(synth, view)
    w, h, gt, sigma = truth_maps(synth, view)
    wd, hd, depth = read_pfm(os.path.join(run, "depth.pfm"))
    if (wd, hd) != (w, h):
        sys.exit(f"error: depth.pfm is {wd}x{hd}, the truth {w}x{h} (dataset.scale?)")
    # p_true = c0 + d * M r(u, v), r = K_est^-1 (u, v, 1), M = R_true^T R_est.
    Rt_T = transpose(cam["R"])
    M = mat_mul(Rt_T, est_cam["R"])
    c0 = mat_vec(Rt_T, sub(est_cam["C"], cam["C"]))
    Ke, Kt = est_cam["K"], cam["K"]
    col_part = [[M[k][0] * (u - Ke[0][2]) / Ke[0][0] for k in range(3)] for u in range(w)]
    row_part = [[M[k][1] * (v - Ke[1][2]) / Ke[1][1] + M[k][2] for k in range(3)] for v in range(h)]
    fx, skew, cx, fy, cy = Kt[0][0], Kt[0][1], Kt[0][2], Kt[1][1], Kt[1][2]
    counted = missing = 0
    within = [0] * 10
    for v in range(h):
        rp0, rp1, rp2 = row_part[v]
        base = v * w
        for u in range(w):
            i = base + u
            if not known(gt[i], sigma[i]):
                continue
            counted += 1
            d = depth[i]
            if not (math.isfinite(d) and d > 0):
                missing += 1
                continue
            cp = col_part[u]
            x = c0[0] + d * (cp[0] + rp0)
            y = c0[1] + d * (cp[1] + rp1)
            z = c0[2] + d * (cp[2] + rp2)
            if z <= 0:
                continue
            c = int(round(fx * x / z + skew * y / z + cx))
            r = int(round(fy * y / z + cy))
            if not (0 <= c < w and 0 <= r < h):
                continue
            j = r * w + c
            if not known(gt[j], sigma[j]):
                continue
            e = abs(z - gt[j]) / sigma[j]
            n = math.ceil(e) if e > 0 else 1
            if n <= 10:
                within[n - 1] += 1
    for n in range(1, 10):
        within[n] += within[n - 1]
    pct = lambda k: 100.0 * k / counted if counted else None
    return {"view": view, "comparison": "frame", "counted": counted,
            "missing_percent": pct(missing),
            "within_n_sigma_percent": [pct(k) for k in within]}


def read_time(path):
    """(wall seconds, peak resident MB) from a GNU time -v file."""
    wall = peak = None
    with open(path) as f:
        for line in f:
            if "Elapsed (wall clock)" in line:
                parts = [float(p) for p in line.rsplit(" ", 1)[1].split(":")]
                wall = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
            elif "Maximum resident set size" in line:
                peak = int(line.rsplit(" ", 1)[1]) / 1024.0
    return wall, peak


def cmd_summary(out):
    checks = os.path.join(out, "checks")
    load = lambda name: json.load(open(os.path.join(checks, name)))
    fmt = lambda v, spec: "–" if v is None else format(v, spec)
    lines = ["| dataset.align | gcp.sources | GCPs / px | SfM GCP outliers (pixel / frame) "
             "| D+GCP within 3σ (pixel) | (frame) | D̂ within 3σ (pixel) | time s | peak MB |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, align, label in (("sfm", "scan", "[sfm]"), ("lidar", "scan", "[lidar]"),
                               ("sfm+lidar", "scan", "[sfm, lidar]"), ("none", "scan", "[] (none)"),
                               ("centres-sfm", "centres", "[sfm]"),
                               ("centres-lidar", "centres", "[lidar]")):
        if not os.path.exists(os.path.join(checks, name + ".gcps.json")):
            continue
        gcps = load(name + ".gcps.json")
        ev = load(name + ".eval.json")["metrics"]["depth_sigma"]["result"]
        dense = load(name + ".dense.json")
        wall, peak = read_time(os.path.join(checks, name + ".time"))
        prop = None
        if os.path.exists(os.path.join(out, "run-" + name, "propagated_depth.pfm")):
            # D̂ as gcpstereo eval scores it (the run itself has no ground truth to score).
            prop_json = os.path.join(checks, name + ".propagated.eval.json")
            if os.path.exists(prop_json):
                prop = json.load(open(prop_json))["metrics"]["depth_sigma"]["result"]
        total = sum(v["gcps"] for v in gcps.values() if isinstance(v, dict) and "gcps" in v)
        sfm = gcps.get("sfm")
        outl = ("–" if not sfm else "%s %% / %s %%" % (fmt(sfm["pixel"]["outlier_percent"], ".2f"),
                                                   fmt(sfm["frame"]["outlier_percent"], ".2f")))
        lines.append("| %s | %s | %s | %s | %s %% | %s %% | %s | %s | %s |" % (
            align, label, fmt(total / gcps["pixels"], ".5f"), outl,
            fmt(ev["within_n_sigma_percent"][2], ".2f"),
            fmt(dense["within_n_sigma_percent"][2], ".2f"),
            "–" if prop is None else fmt(prop["within_n_sigma_percent"][2], ".2f") + " %",
            fmt(wall, ".0f"), fmt(peak, ".0f")))
    for name in ("align.json", "align-centres.json"):
        if not os.path.exists(os.path.join(checks, name)):
            continue
        a = load(name)
        al = a["alignment"]
        lines += ["", "Alignment (%s, %d registered images): scale %.4f, residuals median %.4g, "
                  "90th percentile %.4g, RMS %.4g (scan units), inliers %.2f %% of %d; camera "
                  "centres within %.4g (mean %.4g, median %.4g) of the true ones, scale error "
                  "%+.3f %% (distances between centres), orientations within %.3f°." % (
                      al["method"], a["registered_images"], al["scale"], al["residual_median"],
                      al["residual_p90"], al["residual_rms"], 100 * al["inlier_share"],
                      al["correspondences"], a["centre_error_max"], a["centre_error_mean"],
                      a["centre_error_median"], a["scale_error_percent"], a["rotation_deg_max"])]
    print("\n".join(lines))


def main(argv):
    if len(argv) == 2 and argv[0] == "summary":
        cmd_summary(argv[1])
        return
    if len(argv) < 3 or argv[0] not in ("align", "gcps", "dense"):
        sys.exit(__doc__)
    cmd, run, synth = argv[0], argv[1], argv[2]
    view = argv[3] if len(argv) > 3 else "0005"
    if cmd == "align":
        result = cmd_align(run, synth)
    elif cmd == "gcps":
        result = cmd_gcps(run, synth, view)
    else:
        result = cmd_dense(run, synth, view, argv[4] if len(argv) > 4 else view + ".png")
    json.dump(result, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except ValueError as e:  # a malformed input file (file_formats)
        sys.exit("error: %s" % e)
