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
                         GcpSourceSummary* summary) {
  reference.Validate("GcpsFromSfmPoints: reference camera");
  options.Check();
  if (!(image_scale > 0.0)) throw Error("GcpsFromSfmPoints: image_scale must be > 0");
  GcpSourceSummary local;
  local.source = GcpSourceName(GcpSource::kSfm);
  local.num_input = static_cast<int>(points.size());
  const int width = reference.width, height = reference.height;
  const double f_model = reference.K(0, 0) / image_scale;
  const double min_angle_rad = options.min_angle_deg * kPi / 180.0;

  // Per pixel: the index of the nearest kept point (−1: none).
  std::vector<int> winner(static_cast<size_t>(width) * height, -1);
  std::vector<Gcp> candidate(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const SfmPoint& p = points[i];
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
    int& w = winner[static_cast<size_t>(g.row) * width + g.col];
    if (w < 0) {
      w = static_cast<int>(i);
    } else {
      ++local.num_same_pixel;
      if (depth < candidate[w].depth) w = static_cast<int>(i);
    }
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
