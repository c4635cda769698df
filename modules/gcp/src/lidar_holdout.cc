// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/gcp/lidar_holdout.h"

#include <cmath>

#include <opencv2/core.hpp>

namespace gcpstereo::gcp {

LidarHoldout SplitScanForHoldout(const PointCloud& cloud, const Eigen::Matrix4d& world_from_lidar,
                                 const Camera& camera, const LidarGcpOptions& options, int block_px,
                                 double disparity_numerator) {
  const auto projected =
      eval::ProjectPointCloud(cloud, camera, world_from_lidar, /*keep_nearest_per_pixel=*/true);
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(projected.size());
  for (const auto& p : projected) pixels.push_back(p.pixel);
  const eval::LidarSplit split = eval::CheckerboardSplit(pixels, block_px);

  LidarHoldout out;
  for (int i : split.gcp_indices) {
    const int k = projected[i].index;
    out.gcp_part.points.push_back(cloud.points[k]);
    if (!cloud.sigma.empty()) out.gcp_part.sigma.push_back(cloud.sigma[k]);
  }

  const GcpSet visible = GcpsFromPointCloud(cloud, world_from_lidar, camera, options);
  cv::Mat visible_depth(camera.height, camera.width, CV_64F, cv::Scalar(0.0));
  for (const Gcp& g : visible.points) visible_depth.at<double>(g.row, g.col) = g.depth;
  for (int i : split.score_indices) {
    const auto& p = projected[i];
    const int c = static_cast<int>(std::floor(p.pixel.x() + 0.5));
    const int r = static_cast<int>(std::floor(p.pixel.y() + 0.5));
    if (c < 0 || r < 0 || c >= camera.width || r >= camera.height) continue;
    // The same point won the z-buffer and passed the depth-consistency test (same depth up to
    // the rounding of two evaluations of the projection).
    if (std::abs(visible_depth.at<double>(r, c) - p.depth) > 1e-6 * p.depth) {
      ++out.not_visible;
      continue;
    }
    const double value = disparity_numerator > 0.0 ? disparity_numerator / p.depth : p.depth;
    out.scored.push_back({p.pixel, value});
  }
  return out;
}

}  // namespace gcpstereo::gcp
