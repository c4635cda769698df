// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

namespace gcpstereo::pipeline {

// What `gcpstereo eval` scores, and against what. Exactly one estimate: a finished run's folder,
// a depth map or a disparity map; ground truth from the run's data set or from files.
struct EvalRequest {
  std::string run_folder;  // a finished `gcpstereo run` folder: its depth.pfm / disparity.pfm
                           // and propagated_*.pfm (D̂) against the ground truth of the data set
                           // in its effective_config.yaml
  std::string depth;       // a depth map (PFM, +inf/0/NaN = no estimate)
  std::string disparity;   // a disparity map (PFM)

  // Strecha-style: depth ± sigma per pixel, or a mesh / point cloud rendered into `camera`.
  std::string gt_depth;   // PFM
  std::string gt_sigma;   // PFM of per-pixel sigma; or use `sigma`
  double sigma = 0.0;     // constant laser sigma when no gt_sigma map (data set unit)
  std::string gt_mesh;    // PLY mesh of the true surface (world coordinates)
  std::string gt_points;  // PLY/PCD point cloud of the true surface (world coordinates)
  std::string camera;     // Strecha .camera of the depth map's view (for gt_mesh / gt_points)

  // Middlebury-style.
  std::string gt_disparity;        // PFM, or 8/16-bit PNG/PGM divided by gt_scale (0 = unknown)
  std::string gt_disparity_right;  // the right view's map, to derive occlusion masks
  double gt_scale = 1.0;
  std::string mask_nonocc, mask_all, mask_disc;  // official masks (255 = counted)
  int border_px = 0;                             // ignored border for derived masks

  std::string report;   // write the JSON here (default: not written)
  std::string figures;  // write error maps / histograms into this folder (default: none)
};

// Runs the evaluation, prints the metrics tables to stdout and returns the JSON text.
// Throws Error on bad input (a missing file, sizes that differ, no ground truth given).
std::string RunEvaluation(const EvalRequest& request);

}  // namespace gcpstereo::pipeline
