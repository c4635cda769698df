#!/usr/bin/env python3
# Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
"""The Snakemake workflow (pipeline/workflow/Snakefile) on the synthetic `tiny` set, views 0003-0007:

- its result equals the scene run's (`gcpstereo run` with dataset.reference=all): the views'
  outputs byte for byte, fused.ply, mesh.ply, mesh.obj and effective_config.yaml identical, the
  same report apart from times, memory and views[].status ("reused");
- a second invocation does nothing;
- deleting one view's folder reruns that view (and the fusion) only;
- a view that fails is tried twice, then reported, and the fusion runs on the others;
- a missing --config names what is required.

Usage: workflow_test.py GCPSTEREO SNAKEFILE. Exits 77 (CTest: skipped) when snakemake is not
installed (tools/install_deps.sh installs it).
"""

import filecmp
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

GCPSTEREO = SNAKEFILE = None
SNAKEMAKE = shutil.which("snakemake")
VIEWS = ["0003", "0004", "0005", "0006", "0007"]

# The fast setting of tests/pipeline/scene_test.cpp, as a configuration file.
CONFIG = """dataset:
  format: strecha
  path: {data}
  reference: all
labels:
  count: 48
gcp:
  sources: [lidar]
  lidar:
    path: {data}/gt/laser.ply
  downsample: 8
optimizer:
  tiles: [1, 1]
  refinement: parabola
scene_mesh:
  depth: 7
eval:
  scene:
    max_samples: 100000
runtime:
  log_level: warn
"""


def read(path):
    with open(path, "rb") as f:
        return f.read()


def without_times(value):
    """A report's value without the keys that hold times (they differ between any two runs)."""
    if isinstance(value, dict):
        return {k: without_times(v) for k, v in value.items() if "seconds" not in k}
    if isinstance(value, list):
        return [without_times(v) for v in value]
    return value


def snapshot(folder):
    """Every file under `folder` with its modification time (ns) and bytes."""
    files = {}
    for root, _, names in os.walk(folder):
        for name in names:
            path = os.path.join(root, name)
            files[os.path.relpath(path, folder)] = (os.stat(path).st_mtime_ns, read(path))
    return files


class Workflow(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="gcpstereo-workflow-")
        cls.dir = cls.tmp.name
        data = os.path.join(cls.dir, "data")
        subprocess.run([GCPSTEREO, "-q", "synth", "--preset", "tiny", "--seed", "7", "-o", data],
                       check=True, stdout=subprocess.DEVNULL)
        cls.config = os.path.join(cls.dir, "tiny.yaml")
        with open(cls.config, "w") as f:
            f.write(CONFIG.format(data=data))
        # The scene run the workflow must reproduce.
        cls.scene = os.path.join(cls.dir, "scene")
        subprocess.run([GCPSTEREO, "-q", "run", cls.config, "-o", cls.scene], check=True,
                       stdout=subprocess.DEVNULL)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def snakemake(self, out, extra_config=(), expect_success=True):
        command = [SNAKEMAKE, "-s", SNAKEFILE, "--cores", "2", "--config",
                   "config=" + self.config, "out=" + out, "gcpstereo=" + GCPSTEREO,
                   *extra_config]
        done = subprocess.run(command, cwd=self.dir, capture_output=True, text=True)
        log = done.stdout + done.stderr
        if expect_success:
            self.assertEqual(done.returncode, 0, log)
        return log

    @staticmethod
    def jobs(log, rule):
        """The wildcards (or "") of each job of `rule` Snakemake started, from its output."""
        started = []
        lines = log.splitlines()
        for i, line in enumerate(lines):
            if line.strip() in (f"rule {rule}:", f"localrule {rule}:"):
                name = ""
                for follow in lines[i + 1:i + 12]:
                    if follow.strip().startswith("wildcards: name="):
                        name = follow.strip()[len("wildcards: name="):]
                started.append(name)
        return started

    def test_result_equals_scene_run_then_reruns_only_what_is_missing(self):
        out = os.path.join(self.dir, "workflow")
        log = self.snakemake(out)
        self.assertEqual(sorted(self.jobs(log, "view")), VIEWS, log)
        self.assertEqual(len(self.jobs(log, "fuse")), 1, log)

        # 1. The scene run's result.
        for name in VIEWS:
            for f in ("depth.pfm", "propagated_depth.pfm", "gcps.ply", "mesh.ply", "mesh.obj",
                      "effective_config.yaml"):
                self.assertEqual(read(os.path.join(out, "views", name, f)),
                                 read(os.path.join(self.scene, "views", name, f)),
                                 f"views/{name}/{f}")
        for f in ("fused.ply", "mesh.ply", "mesh.obj", "effective_config.yaml"):
            self.assertEqual(read(os.path.join(out, f)), read(os.path.join(self.scene, f)), f)
        ours = json.loads(read(os.path.join(out, "report.json")))
        theirs = json.loads(read(os.path.join(self.scene, "report.json")))
        self.assertEqual([v["name"] for v in ours["views"]], VIEWS)
        self.assertEqual([v["status"] for v in ours["views"]], ["reused"] * len(VIEWS))
        self.assertEqual([v["neighbors"] for v in ours["views"]],
                         [v["neighbors"] for v in theirs["views"]])
        for key in ("fusion", "scene_mesh", "metrics", "fused_views", "fusion_input"):
            self.assertEqual(without_times(ours[key]), without_times(theirs[key]), key)
        # The same files, but for the workflow's own: its logs and each view's status marker.
        ours_files = {f for f in snapshot(out)
                      if not f.startswith(".workflow/") and not f.endswith(".workflow-status")}
        self.assertEqual(ours_files, set(snapshot(self.scene)))

        # 2. A second invocation does nothing: no job, not a file touched.
        before = snapshot(out)
        log = self.snakemake(out)
        self.assertIn("Nothing to be done", log)
        self.assertEqual(self.jobs(log, "view") + self.jobs(log, "fuse"), [], log)
        self.assertEqual(snapshot(out), before)

        # 3. A deleted view is redone, and the fusion after it; no other view.
        shutil.rmtree(os.path.join(out, "views", "0005"))
        log = self.snakemake(out)
        self.assertEqual(self.jobs(log, "view"), ["0005"], log)
        self.assertEqual(len(self.jobs(log, "fuse")), 1, log)
        after = snapshot(out)
        for f, (mtime, data) in before.items():
            if f.startswith("views/") and not f.startswith("views/0005/"):
                self.assertEqual(after[f][0], mtime, f + " was rewritten")
            # Reports (and the pages showing them) hold times; every other file is the same.
            if (not f.startswith(".workflow/")
                    and os.path.basename(f) not in ("report.json", "index.html")):
                self.assertEqual(after[f][1], data, f + " differs after the rerun")

    def test_failed_view_is_tried_twice_then_left_out_of_the_fusion(self):
        # A gcpstereo that fails every run of view 0006 and counts its attempts.
        attempts = os.path.join(self.dir, "attempts-0006")
        wrapper = os.path.join(self.dir, "failing-gcpstereo")
        with open(wrapper, "w") as f:
            f.write("#!/bin/sh\n"
                    'case "$*" in *\'dataset.reference="0006"\'*)\n'
                    f"  echo attempt >> {attempts}; echo 'view 0006 broken on purpose' >&2;"
                    " exit 1;;\n"
                    "esac\n"
                    f'exec {GCPSTEREO} "$@"\n')
        os.chmod(wrapper, 0o755)
        out = os.path.join(self.dir, "failing")
        command = [SNAKEMAKE, "-s", SNAKEFILE, "--cores", "2", "--config",
                   "config=" + self.config, "out=" + out, "gcpstereo=" + wrapper]
        done = subprocess.run(command, cwd=self.dir, capture_output=True, text=True)
        log = done.stdout + done.stderr
        self.assertEqual(done.returncode, 0, log)
        with open(attempts) as f:
            self.assertEqual(len(f.readlines()), 2, "view 0006 retried once, not more")
        report = json.loads(read(os.path.join(out, "report.json")))
        status = {v["name"]: v["status"] for v in report["views"]}
        self.assertEqual(status, {n: ("failed" if n == "0006" else "reused") for n in VIEWS})
        self.assertEqual(report["fused_views"], len(VIEWS) - 1)
        self.assertTrue(os.path.isfile(os.path.join(out, "fused.ply")))
        self.assertFalse(os.path.exists(os.path.join(out, "views", "0006", "depth.pfm")))
        with open(os.path.join(out, "views", "0006", ".workflow-status")) as f:
            self.assertTrue(f.read().startswith("failed"))
        with open(os.path.join(out, ".workflow", "logs", "view-0006.log")) as f:
            self.assertIn("view 0006 broken on purpose", f.read())

    def test_missing_configuration_is_named(self):
        done = subprocess.run([SNAKEMAKE, "-s", SNAKEFILE, "--cores", "1"], cwd=self.dir,
                              capture_output=True, text=True)
        self.assertNotEqual(done.returncode, 0)
        self.assertIn("--config config=... is required", done.stdout + done.stderr)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: workflow_test.py GCPSTEREO SNAKEFILE [unittest options]")
    GCPSTEREO, SNAKEFILE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if SNAKEMAKE is None:
        print("snakemake not found on PATH (tools/install_deps.sh installs it): skipping the "
              "workflow tests")
        sys.exit(77)
    unittest.main(argv=[sys.argv[0]] + sys.argv[3:], verbosity=2)
