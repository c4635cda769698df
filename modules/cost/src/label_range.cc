// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/label_range.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "cost_internal.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::cost {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

void CheckPercentiles(double low, double high, double margin) {
  if (!(low >= 0.0 && low < high && high <= 100.0)) {
    throw ConfigError(ViolatedConstraint("labels.auto.gcp_low_percentile, gcp_high_percentile",
                                         internal::Str(low) + ", " + internal::Str(high),
                                         "0 <= low < high <= 100"));
  }
  if (!(margin >= 0.0) || !std::isfinite(margin)) {
    throw ConfigError(
        ViolatedConstraint("labels.auto.margin", internal::Str(margin), "0 <= margin < inf"));
  }
}

// Percentile (0…100) of sorted values, linear interpolation between order statistics.
double Percentile(const std::vector<double>& sorted, double percent) {
  const double position = percent / 100.0 * static_cast<double>(sorted.size() - 1);
  const std::size_t i = static_cast<std::size_t>(std::floor(position));
  if (i + 1 >= sorted.size()) return sorted.back();
  const double f = position - static_cast<double>(i);
  return sorted[i] + (sorted[i + 1] - sorted[i]) * f;
}

// The interval of z >= 0 with α_i + β_i z >= 0 for all constraints; false when empty.
struct Interval {
  double lo = 0.0;
  double hi = kInf;
  void Constrain(double alpha, double beta) {
    if (beta > 0.0) {
      lo = std::max(lo, -alpha / beta);
    } else if (beta < 0.0) {
      hi = std::min(hi, -alpha / beta);
    } else if (alpha < 0.0) {
      hi = -1.0;  // never satisfied
    }
  }
  bool Empty() const { return !(lo <= hi); }
};

// Depths z at which the reference ray through `pixel` projects inside `camera` (in front of it).
Interval SeenInterval(const Camera& reference, const Camera& camera, const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d ray_world = reference.world_from_camera_rotation *
                                    (reference.K.inverse() * pixel.homogeneous());  // z = 1
  const Eigen::Matrix<double, 3, 4> P = camera.ProjectionMatrix();
  // p(z) = a + z·b in homogeneous neighbour pixels.
  const Eigen::Vector3d a = P * reference.center_world.homogeneous();
  const Eigen::Vector3d b = P.leftCols<3>() * ray_world;
  Interval interval;
  interval.Constrain(a.z(), b.z());  // in front (w > 0; w = 0 only at the border of validity)
  // Camera::InImage: −½ <= x < W − ½, −½ <= y < H − ½, i.e. with w > 0 …
  interval.Constrain(a.x() + 0.5 * a.z(), b.x() + 0.5 * b.z());
  interval.Constrain((camera.width - 0.5) * a.z() - a.x(), (camera.width - 0.5) * b.z() - b.x());
  interval.Constrain(a.y() + 0.5 * a.z(), b.y() + 0.5 * b.z());
  interval.Constrain((camera.height - 0.5) * a.z() - a.y(), (camera.height - 0.5) * b.z() - b.y());
  return interval;
}

}  // namespace

void LabelRangeOptions::Check() const {
  CheckPercentiles(gcp_low_percentile, gcp_high_percentile, margin);
  if (grid_step_px < 1) {
    throw ConfigError(ViolatedConstraint("labels.auto.grid_step_px", internal::Str(grid_step_px),
                                         "grid_step_px >= 1"));
  }
  if (min_neighbors < 1) {
    throw ConfigError(ViolatedConstraint("labels.auto.min_neighbors", internal::Str(min_neighbors),
                                         "min_neighbors >= 1"));
  }
  if (!(max_depth > 0.0)) {
    throw ConfigError(
        ViolatedConstraint("labels.auto.max_depth", internal::Str(max_depth), "max_depth > 0"));
  }
}

std::pair<double, double> DepthRangeFromGcps(const GcpSet& gcps, double low_percentile,
                                             double high_percentile, double margin) {
  CheckPercentiles(low_percentile, high_percentile, margin);
  std::vector<double> depths;
  depths.reserve(gcps.size());
  for (const Gcp& gcp : gcps.points) {
    if (std::isfinite(gcp.depth) && gcp.depth > 0.0) depths.push_back(gcp.depth);
  }
  if (depths.empty()) {
    throw Error("automatic label range: none of the " + std::to_string(gcps.size()) +
                " GCPs has a finite positive depth");
  }
  std::sort(depths.begin(), depths.end());
  const double low = Percentile(depths, low_percentile);
  const double high = Percentile(depths, high_percentile);
  return {low / (1.0 + margin), high * (1.0 + margin)};
}

std::pair<double, double> DepthRangeFromFrustumOverlap(const View& reference,
                                                       const std::vector<View>& neighbors,
                                                       const LabelRangeOptions& options) {
  options.Check();
  reference.camera.Validate("reference view '" + reference.name + "'");
  for (const View& view : neighbors) view.camera.Validate("neighbour view '" + view.name + "'");
  const Camera& ref = reference.camera;
  std::vector<int> cols, rows;
  for (int c = 0; c < ref.width; c += options.grid_step_px) cols.push_back(c);
  if (cols.back() != ref.width - 1) cols.push_back(ref.width - 1);
  for (int r = 0; r < ref.height; r += options.grid_step_px) rows.push_back(r);
  if (rows.back() != ref.height - 1) rows.push_back(ref.height - 1);

  double near = kInf;
  double far = -kInf;
  std::vector<std::pair<double, int>> events;
  for (int r : rows) {
    for (int c : cols) {
      events.clear();
      for (const View& view : neighbors) {
        const Interval seen = SeenInterval(ref, view.camera, Eigen::Vector2d(c, r));
        if (seen.Empty()) continue;
        events.emplace_back(seen.lo, +1);
        events.emplace_back(seen.hi, -1);
      }
      // Sort by z, starts before ends at the same z (closed intervals touching count as overlap).
      std::sort(events.begin(), events.end(), [](const auto& x, const auto& y) {
        return x.first < y.first || (x.first == y.first && x.second > y.second);
      });
      int count = 0;
      for (const auto& [z, delta] : events) {
        const int before = count;
        count += delta;
        if (before < options.min_neighbors && count >= options.min_neighbors) {
          near = std::min(near, z);
        }
        if (before >= options.min_neighbors && count < options.min_neighbors) {
          far = std::max(far, z);
        }
      }
    }
  }
  if (!(near <= far)) {
    throw Error("automatic label range: no ray of the reference view '" + reference.name +
                "' is seen by " + std::to_string(options.min_neighbors) +
                " neighbour(s) (labels.auto.min_neighbors); set labels.min and labels.max");
  }
  return {near, std::min(far, options.max_depth)};
}

LabelSpace MakeLabelSpace(LabelSpaceKind kind, int count, std::optional<double> min,
                          std::optional<double> max, const GcpSet& gcps, const View& reference,
                          const std::vector<View>& neighbors, double disparity_numerator,
                          const LabelRangeOptions& options, LabelRangeSummary* summary) {
  LabelRangeSummary info;
  info.source = "config";
  if (!min || !max) {
    options.Check();
    std::pair<double, double> depth_range;
    std::string source;
    if (!gcps.empty()) {
      depth_range = DepthRangeFromGcps(gcps, options.gcp_low_percentile,
                                       options.gcp_high_percentile, options.margin);
      source = "gcps";
    } else {
      depth_range = DepthRangeFromFrustumOverlap(reference, neighbors, options);
      source = "frustum";
    }
    info.source = (min || max) ? "config+" + source : source;
    info.depth_min = depth_range.first;
    info.depth_max = depth_range.second;
    const auto [z_min, z_max] = depth_range;
    double auto_min = 0.0, auto_max = 0.0;
    switch (kind) {
      case LabelSpaceKind::kDepth:
        auto_min = z_min;
        auto_max = z_max;
        break;
      case LabelSpaceKind::kInverseDepth:
        auto_min = 1.0 / z_max;  // 0 for an unbounded range
        auto_max = 1.0 / z_min;
        break;
      case LabelSpaceKind::kDisparity:
        auto_min = disparity_numerator / z_max;
        auto_max = disparity_numerator / z_min;
        break;
    }
    const std::string range_text = "automatic depth range [" + internal::Str(z_min) + ", " +
                                   internal::Str(z_max) + "] from the " +
                                   (source == "gcps" ? "GCPs" : "neighbours' frustum overlap");
    if (!max && kind == LabelSpaceKind::kDepth && !std::isfinite(z_max)) {
      throw ConfigError(ViolatedConstraint(
          "labels.max", "auto",
          range_text + " is unbounded; set labels.max or labels.auto.max_depth, or use "
                       "labels.space inverse_depth"));
    }
    if (!max && !std::isfinite(auto_max)) {
      throw ConfigError(ViolatedConstraint(
          "labels.max", "auto",
          range_text + " reaches depth 0 (the reference centre is inside a neighbour's frustum); "
                       "set labels.min/labels.max"));
    }
    if (!min) min = auto_min;
    if (!max) max = auto_max;
  }
  if (summary != nullptr) *summary = info;
  return LabelSpace(kind, count, *min, *max, disparity_numerator);
}

}  // namespace gcpstereo::cost
