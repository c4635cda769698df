// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// Whole scenes (../shared/CONTRACT.md, "Whole scenes"): every reference view's depth map by the
// per-view run, then one fused, meshed and evaluated model of the scene.

#include <string>
#include <vector>

#include "gcpstereo/pipeline/pipeline_config.h"
#include "gcpstereo/pipeline/run.h"

namespace gcpstereo::pipeline {

// The scene run of `gcpstereo run` when dataset.reference is a list or `all`:
//   1. each reference's per-view run into OUT/views/<name>/ (the outputs of a single-reference
//      run, its neighbours chosen per view when dataset.neighbors is auto). A view folder that
//      is complete — report.json and depth.pfm committed, with the effective configuration this
//      run would write — is reused: an interrupted scene run resumes with the missing views. A
//      view that fails is recorded in report.json with its error and left out of the fusion;
//   2. the fusion of the finished views into OUT/ (FuseViewFolders' work): fused.ply, mesh.ply,
//      mesh.obj, report.json, index.html, effective_config.yaml.
// Throws Error when no view finishes (naming each view's error) or the fusion fails.
struct SceneRunOptions {
  // false (`gcpstereo run --fuse-only`): compute no view. The complete folders under OUT/views/
  // are reused and every other view is recorded as failed (with the error its folder's run.log
  // ends on, if any): the views were computed apart, one job each (pipeline/workflow/Snakefile).
  bool compute_views = true;
};
RunSummary RunScene(const LoadedConfig& config, const std::string& output_dir,
                    const SceneRunOptions& options = {});

// `gcpstereo fuse VIEWDIR... -o OUT [--set KEY=VALUE]...`: the fusion, meshing and evaluation of
// finished per-view folders. The configuration is the first folder's effective_config.yaml with
// `overrides` applied (fusion.*, scene_mesh.*, eval.scene.*). Throws Error for a folder that is
// not a finished view, and for folders of different scenes (data set, format or scale) or of the
// same view twice.
struct FuseRequest {
  std::vector<std::string> view_dirs;
  std::string output_dir;
  std::vector<std::string> overrides;
};
RunSummary FuseViewFolders(const FuseRequest& request);

// The view names dataset.reference stands for: the list, or every view of the data set for
// `all`. Throws ConfigError naming an unknown view and the valid names.
std::vector<std::string> SceneReferenceNames(const PipelineConfig& options);

// One view of a scene as a job of its own (`gcpstereo views`, the workflow's per-view rule):
// `gcpstereo run CONFIG -o OUT/views/<name> --set KEY=VALUE... --set <overrides>` writes the
// folder the scene run writes for it, byte for byte, and that the scene run then reuses.
struct ViewJob {
  std::string name;
  int width_px = 0;  // the reference image at dataset.scale
  int height_px = 0;
  std::vector<std::string> overrides;  // dataset.reference, and the neighbours of an explicit list
};
// The views dataset.reference stands for, in the scene's order. A single reference (no scene) is
// one job with no overrides: the run as configured.
std::vector<ViewJob> PlanViewJobs(const LoadedConfig& config);

}  // namespace gcpstereo::pipeline
