// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/gcp/sfm_gcps.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gcpstereo/core/error.h"

namespace gcpstereo::gcp {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

void SfmGcpOptions::Check() const {
  if (min_track_length < 2) {
    throw ConfigError(ViolatedConstraint("gcp.sfm.min_track_length",
                                         std::to_string(min_track_length),
                                         "gcp.sfm.min_track_length >= 2"));
  }
  if (!(max_error_px > 0.0) || !std::isfinite(max_error_px)) {
    throw ConfigError(ViolatedConstraint("gcp.sfm.max_error_px", FormatNumber(max_error_px),
                                         "gcp.sfm.max_error_px > 0"));
  }
  if (!(min_angle_deg > 0.0) || !(min_angle_deg < 90.0)) {
    throw ConfigError(ViolatedConstraint("gcp.sfm.min_angle_deg", FormatNumber(min_angle_deg),
                                         "0 < gcp.sfm.min_angle_deg < 90"));
  }
  if (!(min_error_px > 0.0) || !std::isfinite(min_error_px)) {
    throw ConfigError(ViolatedConstraint("gcp.sfm.min_error_px", FormatNumber(min_error_px),
                                         "gcp.sfm.min_error_px > 0"));
  }
}

GcpSet GcpsFromSfmPoints(const std::vector<SfmPoint>& points, const Camera& reference,
                         double image_scale, const SfmGcpOptions& options,
                         GcpSourceSummary* summary, const LidarGcpOptions& lidar) {
  reference.Validate("GcpsFromSfmPoints: reference camera");
  options.Check();
  if (!(image_scale > 0.0)) throw Error("GcpsFromSfmPoints: image_scale must be > 0");
  GcpSourceSummary local;
  local.source = GcpSourceName(GcpSource::kSfm);
  int unobserved_kept = 0;  // unobserved points past the filters (options.projected)
  const int width = reference.width, height = reference.height;
  const double f_model = reference.K(0, 0) / image_scale;
  const double min_angle_rad = options.min_angle_deg * kPi / 180.0;

  // Per pixel: the index of the nearest kept observed point (−1: none), and of the nearest kept
  // point of either kind (options.projected).
  std::vector<int> winner(static_cast<size_t>(width) * height, -1);
  std::vector<int> any_winner(options.projected ? winner.size() : 0, -1);
  std::vector<Gcp> candidate(points.size());
  PointCloud filtered;  // options.projected: every point past the filters, for the visibility
  for (size_t i = 0; i < points.size(); ++i) {
    const SfmPoint& p = points[i];
    if (!p.observed && !options.projected) continue;
    ++local.num_input;
    if (!p.point_world.allFinite() || !std::isfinite(p.error_px)) {
      ++local.num_invalid;
      continue;
    }
    if (p.track_length < options.min_track_length) {
      ++local.num_short_track;
      continue;
    }
    if (p.error_px > options.max_error_px) {
      ++local.num_large_error;
      continue;
    }
    Eigen::Vector2d pixel;
    double depth = 0.0;
    if (!reference.Project(p.point_world, &pixel, &depth)) {
      ++local.num_behind_camera;
      continue;
    }
    if (!reference.InImage(pixel)) {
      ++local.num_outside_image;
      continue;
    }
    // The reference's ray fixes the point's pixel; another observer i at distance d_i, whose ray
    // meets it at θ_i, fixes where on the ray: its angular error e / f moves the point along the
    // ray by d_i · (e / f) / sin θ_i. The best observer gives σ.
    const Eigen::Vector3d ray = (p.point_world - reference.center_world).normalized();
    const double e = std::max(p.error_px, options.min_error_px) / f_model;
    double angle = 0.0;
    double sigma = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& c : p.other_centers_world) {
      const Eigen::Vector3d to_point = p.point_world - c;
      const double d = to_point.norm();
      if (!(d > 0.0)) continue;
      const double theta = std::acos(std::clamp(ray.dot(to_point / d), -1.0, 1.0));
      angle = std::max(angle, std::min(theta, kPi - theta));
      if (std::sin(theta) > 0.0) sigma = std::min(sigma, d * e / std::sin(theta));
    }
    if (angle < min_angle_rad) {
      ++local.num_small_angle;
      continue;
    }
    Gcp& g = candidate[i];
    g.col = std::clamp(static_cast<int>(std::lround(pixel.x())), 0, width - 1);
    g.row = std::clamp(static_cast<int>(std::lround(pixel.y())), 0, height - 1);
    g.depth = depth;
    g.sigma = sigma;
    g.source = GcpSource::kSfm;
    const size_t pixel_index = static_cast<size_t>(g.row) * width + g.col;
    if (options.projected) {
      filtered.points.push_back(p.point_world.cast<float>());
      filtered.sigma.push_back(static_cast<float>(sigma));
      int& a = any_winner[pixel_index];
      if (a < 0 || depth < candidate[a].depth) a = static_cast<int>(i);
    }
    if (!p.observed) {
      ++unobserved_kept;
      continue;
    }
    int& w = winner[pixel_index];
    if (w < 0) {
      w = static_cast<int>(i);
    } else {
      ++local.num_same_pixel;
      if (depth < candidate[w].depth) w = static_cast<int>(i);
    }
  }
  if (options.projected && !filtered.empty()) {
    // The LiDAR source's visibility over all the filtered points; its GCP on a pixel whose
    // nearest point is unobserved (and no observed GCP) adds that point.
    const GcpSet visible =
        GcpsFromPointCloud(filtered, Eigen::Matrix4d::Identity(), reference, lidar);
    std::vector<char> passed(winner.size(), 0);
    for (const Gcp& g : visible.points) {
      const size_t k = static_cast<size_t>(g.row) * width + g.col;
      const int a = any_winner[k];
      if (a >= 0 && !points[a].observed && winner[k] < 0 &&
          std::abs(g.depth - candidate[a].depth) <= 1e-4 * candidate[a].depth) {
        passed[k] = 1;
      }
    }
    int added = 0;
    for (size_t k = 0; k < winner.size(); ++k) {
      const int a = any_winner[k];
      if (a < 0 || points[a].observed || winner[k] >= 0) continue;
      if (passed[k]) {
        winner[k] = a;
        ++added;
      } else {
        ++local.num_inconsistent;
      }
    }
    // The other unobserved points lost their pixel to a nearer point or an observed GCP.
    local.num_same_pixel += unobserved_kept - added - local.num_inconsistent;
  }
  GcpSet out;
  for (const int w : winner) {
    if (w >= 0) out.points.push_back(candidate[w]);
  }
  local.num_gcps = static_cast<int>(out.size());
  local.density_percent = DensityPercent(out, width, height);
  if (summary) *summary = local;
  return out;
}

}  // namespace gcpstereo::gcp
