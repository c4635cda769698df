// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// The held-out LiDAR protocol (eval.lidar_holdout): half of a scan feeds the GCPs, the other half
// scores the result. Shared by the pipeline and the SGBM baseline so that both score the same
// points.

#include <vector>

#include <Eigen/Core>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/eval/lidar.h"
#include "gcpstereo/gcp/gcp_sources.h"

namespace gcpstereo::gcp {

struct LidarHoldout {
  PointCloud gcp_part;                       // the points of the GCP blocks, for GcpsFromPointCloud
  std::vector<eval::ReferencePoint> scored;  // the scoring blocks' visible points
  int not_visible = 0;  // scoring-block points that fail the visibility test: not scored
};

// 1. Every point is projected into `camera` (eval::ProjectPointCloud, nearest point per pixel);
// 2. eval::CheckerboardSplit(block_px) sends whole blocks to the GCP part or the scoring part;
// 3. a scoring point is kept only when it is visible from the camera by the GCP test
//    (GcpsFromPointCloud with `options`: z-buffer + depth consistency) run on the FULL scan — a
//    point the scanner saw behind a nearer surface is not ground truth for the camera's depth map.
// Scored values: disparity_numerator / depth when disparity_numerator > 0 (rectified data, the
// map is a disparity map), else the depth. Points whose nearest pixel is outside the image are
// dropped. Throws ConfigError for block_px < 1.
LidarHoldout SplitScanForHoldout(const PointCloud& cloud, const Eigen::Matrix4d& world_from_lidar,
                                 const Camera& camera, const LidarGcpOptions& options, int block_px,
                                 double disparity_numerator);

}  // namespace gcpstereo::gcp
