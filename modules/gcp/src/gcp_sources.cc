// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/gcp/gcp_sources.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"

namespace gcpstereo::gcp {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

void LidarGcpOptions::Check() const {
  if (consistency_radius_px < 0 || consistency_radius_px > 20) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.consistency_radius_px",
                                         std::to_string(consistency_radius_px),
                                         "0 <= consistency_radius_px <= 20"));
  }
  if (!(max_surface_slant_deg > 0.0 && max_surface_slant_deg < 90.0)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.max_surface_slant_deg",
                                         FormatNumber(max_surface_slant_deg),
                                         "0 < max_surface_slant_deg < 90"));
  }
  if (!(depth_tolerance >= 0.0) || !std::isfinite(depth_tolerance)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.depth_tolerance", FormatNumber(depth_tolerance),
                                         "depth_tolerance >= 0"));
  }
  if (!(sigma_multiplier >= 0.0) || !std::isfinite(sigma_multiplier)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.sigma_multiplier",
                                         FormatNumber(sigma_multiplier), "sigma_multiplier >= 0"));
  }
  if (!(default_sigma >= 0.0) || !std::isfinite(default_sigma)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.default_sigma", FormatNumber(default_sigma),
                                         "default_sigma >= 0"));
  }
  if (!(min_depth >= 0.0) || !std::isfinite(min_depth)) {
    throw ConfigError(
        ViolatedConstraint("gcp.lidar.min_depth", FormatNumber(min_depth), "min_depth >= 0"));
  }
}

GcpSet GcpsFromPointCloud(const PointCloud& cloud, const Eigen::Matrix4d& world_from_lidar,
                          const Camera& reference, const LidarGcpOptions& options,
                          GcpSourceSummary* summary) {
  options.Check();
  reference.Validate("GcpsFromPointCloud: reference camera");
  if (!cloud.sigma.empty() && cloud.sigma.size() != cloud.points.size()) {
    throw Error("GcpsFromPointCloud: the cloud has " + std::to_string(cloud.points.size()) +
                " points but " + std::to_string(cloud.sigma.size()) + " sigma values");
  }
  GcpSourceSummary local;
  local.source = GcpSourceName(GcpSource::kLidar);
  local.num_input = static_cast<int>(cloud.size());
  const int width = reference.width;
  const int height = reference.height;
  const size_t num_pixels = static_cast<size_t>(width) * height;

  // Projection and z-buffer (nearest point per pixel; ties keep the lower index).
  struct Projected {
    double col = 0.0, row = 0.0, depth = 0.0;
  };
  std::vector<Projected> projected(cloud.size());
  std::vector<int> winner(num_pixels, -1);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d point_lidar = cloud.points[i].cast<double>();
    if (!point_lidar.allFinite()) {
      ++local.num_invalid;
      continue;
    }
    const Eigen::Vector3d point_world =
        (world_from_lidar * point_lidar.homogeneous()).hnormalized();
    Eigen::Vector2d pixel;
    double depth = 0.0;
    if (!reference.Project(point_world, &pixel, &depth)) {
      ++local.num_behind_camera;
      continue;
    }
    if (depth <= options.min_depth) {
      ++local.num_invalid;
      continue;
    }
    if (!reference.InImage(pixel)) {
      ++local.num_outside_image;
      continue;
    }
    const int col = std::min(width - 1, std::max(0, static_cast<int>(std::lround(pixel.x()))));
    const int row = std::min(height - 1, std::max(0, static_cast<int>(std::lround(pixel.y()))));
    projected[i] = {pixel.x(), pixel.y(), depth};
    int& slot = winner[static_cast<size_t>(row) * width + col];
    if (slot < 0) {
      slot = static_cast<int>(i);
    } else if (depth < projected[slot].depth) {
      slot = static_cast<int>(i);
      ++local.num_same_pixel;
    } else {
      ++local.num_same_pixel;
    }
  }

  // Depth-consistency test against the nearer winners of the window.
  const double focal_px = 0.5 * (reference.K(0, 0) + reference.K(1, 1));
  const double slope = std::tan(options.max_surface_slant_deg * kPi / 180.0) / focal_px;
  const int radius = options.consistency_radius_px;
  GcpSet gcps;
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const int i = winner[static_cast<size_t>(row) * width + col];
      if (i < 0) continue;
      const Projected& p = projected[i];
      const double sigma = cloud.sigma.empty() ? options.default_sigma : cloud.sigma[i];
      const double base_tolerance =
          options.depth_tolerance + options.sigma_multiplier * (std::isfinite(sigma) ? sigma : 0.0);
      bool consistent = true;
      for (int dr = -radius; dr <= radius && consistent; ++dr) {
        for (int dc = -radius; dc <= radius; ++dc) {
          const int r = row + dr;
          const int c = col + dc;
          if ((dr == 0 && dc == 0) || r < 0 || r >= height || c < 0 || c >= width) continue;
          const int j = winner[static_cast<size_t>(r) * width + c];
          if (j < 0) continue;
          const Projected& q = projected[j];
          const double distance_px = std::hypot(q.col - p.col, q.row - p.row);
          if (p.depth - q.depth > base_tolerance + p.depth * distance_px * slope) {
            consistent = false;
            break;
          }
        }
      }
      if (!consistent) {
        ++local.num_inconsistent;
        continue;
      }
      Gcp gcp;
      gcp.col = col;
      gcp.row = row;
      gcp.depth = p.depth;
      gcp.sigma = sigma;
      gcp.source = GcpSource::kLidar;
      gcps.points.push_back(gcp);
    }
  }
  local.num_gcps = static_cast<int>(gcps.size());
  local.density_percent = DensityPercent(gcps, width, height);
  if (summary) *summary = local;
  return gcps;
}

GcpSet GcpsFromDepthMap(const cv::Mat& depth, double sigma, GcpSource source,
                        GcpSourceSummary* summary) {
  if (depth.empty() || depth.type() != CV_32F) {
    throw Error("GcpsFromDepthMap: the depth map must be a non-empty CV_32F image");
  }
  GcpSourceSummary local;
  local.source = GcpSourceName(source);
  GcpSet gcps;
  for (int row = 0; row < depth.rows; ++row) {
    const float* values = depth.ptr<float>(row);
    for (int col = 0; col < depth.cols; ++col) {
      if (!IsValidDepth(values[col])) continue;
      Gcp gcp;
      gcp.col = col;
      gcp.row = row;
      gcp.depth = values[col];
      gcp.sigma = sigma;
      gcp.source = source;
      gcps.points.push_back(gcp);
    }
  }
  local.num_input = static_cast<int>(gcps.size());
  local.num_gcps = static_cast<int>(gcps.size());
  local.density_percent = DensityPercent(gcps, depth.cols, depth.rows);
  if (summary) *summary = local;
  return gcps;
}

cv::Mat DisparityToDepth(const cv::Mat& disparity, double disparity_numerator) {
  if (disparity.empty() || disparity.type() != CV_32F) {
    throw Error("DisparityToDepth: the disparity map must be a non-empty CV_32F image");
  }
  if (!(disparity_numerator > 0.0) || !std::isfinite(disparity_numerator)) {
    throw Error("DisparityToDepth: disparity_numerator = " + FormatNumber(disparity_numerator) +
                " must be > 0");
  }
  cv::Mat depth(disparity.size(), CV_32F);
  for (int row = 0; row < disparity.rows; ++row) {
    const float* in = disparity.ptr<float>(row);
    float* out = depth.ptr<float>(row);
    for (int col = 0; col < disparity.cols; ++col) {
      out[col] = std::isfinite(in[col]) && in[col] > 0.0f
                     ? static_cast<float>(disparity_numerator / in[col])
                     : kInvalidDepth;
    }
  }
  return depth;
}

GcpSet Downsample(const GcpSet& gcps, int s, int width, int height) {
  if (s < 1) {
    throw Error("Downsample: gcp.downsample = " + std::to_string(s) + " must be >= 1");
  }
  if (width <= 0 || height <= 0) {
    throw Error("Downsample: image size " + std::to_string(width) + "x" + std::to_string(height) +
                " is not positive");
  }
  const int blocks_x = (width + s - 1) / s;
  const int blocks_y = (height + s - 1) / s;
  std::vector<int> best(static_cast<size_t>(blocks_x) * blocks_y, -1);
  std::vector<double> best_distance(best.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < gcps.size(); ++i) {
    const Gcp& g = gcps.points[i];
    if (g.col < 0 || g.col >= width || g.row < 0 || g.row >= height) {
      throw Error("Downsample: GCP " + std::to_string(i) + " at (" + std::to_string(g.col) + ", " +
                  std::to_string(g.row) + ") lies outside the " + std::to_string(width) + "x" +
                  std::to_string(height) + " image");
    }
    const int bx = g.col / s;
    const int by = g.row / s;
    // Centre of the clipped block, in pixel coordinates (doubled to stay integral).
    const int x0 = bx * s, x1 = std::min(width, x0 + s) - 1;
    const int y0 = by * s, y1 = std::min(height, y0 + s) - 1;
    const double dx = 2.0 * g.col - (x0 + x1);
    const double dy = 2.0 * g.row - (y0 + y1);
    const double distance = dx * dx + dy * dy;
    const size_t block = static_cast<size_t>(by) * blocks_x + bx;
    int& current = best[block];
    bool better = current < 0 || distance < best_distance[block];
    if (!better && current >= 0 && distance == best_distance[block]) {
      const Gcp& c = gcps.points[current];
      // Equal distance: prefer smaller sigma, then lower source enum, then the earlier GCP.
      better = g.sigma < c.sigma || (g.sigma == c.sigma && g.source < c.source);
    }
    if (better) {
      current = static_cast<int>(i);
      best_distance[block] = distance;
    }
  }
  GcpSet kept;
  std::vector<int> order;
  for (int index : best) {
    if (index >= 0) order.push_back(index);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const Gcp& ga = gcps.points[a];
    const Gcp& gb = gcps.points[b];
    return ga.row != gb.row ? ga.row < gb.row : ga.col < gb.col;
  });
  for (int index : order) kept.points.push_back(gcps.points[index]);
  return kept;
}

GcpSet MergeGcpSets(const std::vector<GcpSet>& sets) {
  GcpSet merged;
  for (const GcpSet& set : sets) {
    merged.points.insert(merged.points.end(), set.points.begin(), set.points.end());
  }
  return merged;
}

double DensityPercent(const GcpSet& gcps, int width, int height) {
  if (width <= 0 || height <= 0) return 0.0;
  return 100.0 * static_cast<double>(gcps.size()) / (static_cast<double>(width) * height);
}

}  // namespace gcpstereo::gcp
