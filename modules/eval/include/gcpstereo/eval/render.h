// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::eval {

// Ground truth given as a surface (mesh) or a scan (point cloud) is rendered into the reference
// view by a z-buffer, giving the depth (+ sigma) maps that EvaluateDepthSigma takes.

struct RenderSummary {
  std::int64_t primitives = 0;          // faces or points in the input
  std::int64_t skipped_behind = 0;      // faces with a vertex at depth <= near, points behind
  std::int64_t skipped_degenerate = 0;  // faces with a repeated/out-of-range vertex index
  std::int64_t pixels_covered = 0;      // pixels with a finite depth in the output
  nlohmann::json ToJson() const;
};

struct RenderedDepth {
  cv::Mat depth;  // CV_32F, camera z; kInvalidDepth where nothing was rendered
  cv::Mat sigma;  // CV_32F or empty (mesh without sigma; cloud without per-point sigma and
                  // default_sigma <= 0)
  RenderSummary summary;
};

struct RenderMeshOptions {
  // Faces with any vertex at camera depth <= near_depth are skipped (no near-plane clipping; a GT
  // surface lies well in front of the camera). Scene units, >= 0. YAML: eval.render.near_depth.
  double near_depth = 1e-6;
  // Sigma written for every covered pixel (scene units); <= 0 leaves `sigma` empty.
  // YAML: eval.render.mesh_sigma.
  double sigma = 0.0;
  void Check() const;
};

// Z-buffer rasterisation of `mesh` (vertices in the world frame of `camera`): for each face, every
// pixel centre (col, row) inside the projected triangle (closed: pixels on an edge belong to both
// faces sharing it) receives the perspective-correct depth of the triangle's plane along its ray,
// 1/z = Σ b_i / z_i with the screen-space barycentrics b_i; the nearest surface wins. Both face
// orientations are drawn (no culling).
RenderedDepth RenderMeshDepth(const TriangleMesh& mesh, const Camera& camera,
                              const RenderMeshOptions& options = {});

struct RenderPointsOptions {
  // Each point writes the (2·splat_radius_px + 1)² pixels around its nearest pixel. Range: 0 … 16.
  // YAML: eval.render.splat_radius_px.
  int splat_radius_px = 0;
  // Sigma for clouds without per-point sigma (scene units); <= 0: sigma output left empty.
  // YAML: eval.render.default_sigma.
  double default_sigma = 0.0;
  void Check() const;
};

// Point z-buffer: the nearest point per pixel wins (ties: the lower point index); its sigma (per
// point, or default_sigma) goes into `sigma`. world_from_cloud maps the cloud into the world frame.
RenderedDepth RenderPointDepth(
    const PointCloud& cloud, const Camera& camera,
    const Eigen::Matrix4d& world_from_cloud = Eigen::Matrix4d::Identity(),
    const RenderPointsOptions& options = {});

}  // namespace gcpstereo::eval
