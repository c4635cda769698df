// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/view_selection.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "cost_internal.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::cost {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerRad = 180.0 / kPi;
// At most this many given points are scored (every ⌈n / kMaxPoints⌉-th is kept).
constexpr std::size_t kMaxPoints = 20000;
// OpenMVS's tolerance for a candidate that sees the surface finer than the reference.
constexpr double kFinerScaleTolerance = 1.6;
// Two optical axes crossing at less than this are treated as parallel (no convergence depth).
constexpr double kMinAxisCrossingDeg = 1.0;

double MeanFocal(const Camera& camera) { return 0.5 * (camera.K(0, 0) + camera.K(1, 1)); }

Eigen::Vector3d OpticalAxis(const Camera& camera) {
  return camera.world_from_camera_rotation.col(2);
}

// w_θ of SelectNeighbors.
double AngleWeight(double angle_deg, const ViewSelectionOptions& options) {
  if (angle_deg < options.min_angle_deg) return 0.0;
  if (angle_deg < options.optimal_angle_deg) {
    return (angle_deg - options.min_angle_deg) /
           (options.optimal_angle_deg - options.min_angle_deg);
  }
  if (angle_deg <= options.max_angle_deg) return 1.0;
  const double c = std::cos(angle_deg / kDegPerRad);
  if (c <= 0.0) return 0.0;
  const double ratio = c / std::cos(options.max_angle_deg / kDegPerRad);
  return ratio * ratio;
}

// w_s of SelectNeighbors; r = footprint_ref / footprint_candidate.
double ScaleWeight(double r) {
  if (r < 1.0) return r * r;
  if (r <= kFinerScaleTolerance) return 1.0;
  const double q = kFinerScaleTolerance / r;
  return q * q;
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  const double lower =
      *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

// The scene depth z₀ of the "frustum" basis (see the header).
double SceneDepth(const std::vector<Camera>& cameras, int reference_index,
                  double optimal_angle_deg) {
  const Camera& reference = cameras[static_cast<std::size_t>(reference_index)];
  const Eigen::Vector3d c0 = reference.center_world;
  const Eigen::Vector3d d0 = OpticalAxis(reference);
  const double min_sin = std::sin(kMinAxisCrossingDeg / kDegPerRad);
  std::vector<double> crossing_depths;
  std::vector<double> baselines;
  for (std::size_t j = 0; j < cameras.size(); ++j) {
    if (static_cast<int>(j) == reference_index) continue;
    const Eigen::Vector3d c1 = cameras[j].center_world;
    const Eigen::Vector3d d1 = OpticalAxis(cameras[j]);
    baselines.push_back((c1 - c0).norm());
    // Closest points c0 + t d0 and c1 + s d1 of the two axes (unit directions).
    const double b = d0.dot(d1);
    const double denominator = 1.0 - b * b;
    if (denominator < min_sin * min_sin) continue;  // (nearly) parallel axes
    const Eigen::Vector3d w = c0 - c1;
    const double t = (b * d1.dot(w) - d0.dot(w)) / denominator;
    const double s = (d1.dot(w) - b * d0.dot(w)) / denominator;
    if (t > 0.0 && s > 0.0) crossing_depths.push_back(t);  // t is the reference's camera z
  }
  if (!crossing_depths.empty()) return Median(crossing_depths);
  const double baseline = Median(baselines);
  return baseline / std::tan(optimal_angle_deg / kDegPerRad);
}

}  // namespace

void ViewSelectionOptions::Check() const {
  using internal::Str;
  if (!(count >= 1 && count <= 64)) {
    throw ConfigError(ViolatedConstraint("dataset.neighbor_count", Str(count), "1 <= count <= 64"));
  }
  if (!(min_angle_deg > 0.0 && min_angle_deg < optimal_angle_deg)) {
    throw ConfigError(ViolatedConstraint(
        "dataset.neighbor_selection.min_angle_deg", FormatNumber(min_angle_deg),
        "0 < min_angle_deg < optimal_angle_deg (" + FormatNumber(optimal_angle_deg) + ")"));
  }
  if (!(optimal_angle_deg < max_angle_deg)) {
    throw ConfigError(ViolatedConstraint(
        "dataset.neighbor_selection.optimal_angle_deg", FormatNumber(optimal_angle_deg),
        "optimal_angle_deg < max_angle_deg (" + FormatNumber(max_angle_deg) + ")"));
  }
  if (!(max_angle_deg < 90.0)) {
    throw ConfigError(ViolatedConstraint("dataset.neighbor_selection.max_angle_deg",
                                         FormatNumber(max_angle_deg), "max_angle_deg < 90"));
  }
  if (!(grid_step_px >= 1)) {
    throw ConfigError(ViolatedConstraint("dataset.neighbor_selection.grid_step_px",
                                         Str(grid_step_px), "grid_step_px >= 1"));
  }
}

nlohmann::json ViewSelection::ToJson(const std::vector<std::string>& names) const {
  const auto name_of = [&names](int index) -> std::string {
    if (names.empty()) return std::to_string(index);
    if (index < 0 || static_cast<std::size_t>(index) >= names.size()) {
      throw Error("view selection: no name for view index " + std::to_string(index) + " (" +
                  std::to_string(names.size()) + " names)");
    }
    return names[static_cast<std::size_t>(index)];
  };
  nlohmann::json json;
  json["reference"] = name_of(reference_index);
  json["basis"] = basis;
  json["points_given"] = points_given;
  json["points_used"] = points_used;
  json["neighbors"] = nlohmann::json::array();
  for (int index : neighbors) json["neighbors"].push_back(name_of(index));
  json["candidates"] = nlohmann::json::array();
  for (const NeighborScore& c : candidates) {
    json["candidates"].push_back({{"name", name_of(c.index)},
                                  {"index", c.index},
                                  {"score", c.score},
                                  {"median_angle_deg", c.median_angle_deg},
                                  {"shared_fraction", c.shared_fraction},
                                  {"shared_points", c.shared_points}});
  }
  return json;
}

ViewSelection SelectNeighbors(const std::vector<Camera>& cameras, int reference_index,
                              const std::vector<Eigen::Vector3d>& points_world,
                              const ViewSelectionOptions& options, double min_depth,
                              double max_depth) {
  options.Check();
  if (reference_index < 0 || static_cast<std::size_t>(reference_index) >= cameras.size()) {
    throw Error("view selection: reference index " + std::to_string(reference_index) +
                " outside 0 … " + std::to_string(static_cast<int>(cameras.size()) - 1));
  }
  if (!(min_depth >= 0.0 && min_depth < max_depth)) {
    throw Error("view selection: depth bounds [" + FormatNumber(min_depth) + ", " +
                FormatNumber(max_depth) + "] need 0 <= min_depth < max_depth");
  }
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    cameras[i].Validate("view selection: camera " + std::to_string(i));
  }
  const Camera& reference = cameras[static_cast<std::size_t>(reference_index)];

  ViewSelection result;
  result.reference_index = reference_index;
  result.points_given = static_cast<int>(points_world.size());

  // The reference's sample points.
  std::vector<Eigen::Vector3d> samples;
  for (const Eigen::Vector3d& point : points_world) {
    if (!point.allFinite()) continue;
    Eigen::Vector2d pixel;
    double depth = 0.0;
    if (!reference.Project(point, &pixel, &depth) || !reference.InImage(pixel)) continue;
    if (depth < min_depth || depth > max_depth) continue;
    samples.push_back(point);
  }
  if (samples.size() > kMaxPoints) {
    const std::size_t stride = (samples.size() + kMaxPoints - 1) / kMaxPoints;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < samples.size(); i += stride) samples[kept++] = samples[i];
    samples.resize(kept);
  }
  const bool grid_basis = samples.empty();
  double grid_depth = 0.0;  // z₀ of the "frustum" basis
  if (!grid_basis) {
    result.basis = "points";
  } else {
    result.basis = "frustum";
    double depth = SceneDepth(cameras, reference_index, options.optimal_angle_deg);
    depth = std::clamp(depth, min_depth, max_depth);
    // A single camera (no baseline) or all centres at the reference's: any positive depth will do,
    // every candidate then scores 0.
    if (!(depth > 0.0) || !std::isfinite(depth)) depth = std::isfinite(max_depth) ? max_depth : 1.0;
    const int step = options.grid_step_px;
    for (int y = step / 2; y < reference.height; y += step) {
      for (int x = step / 2; x < reference.width; x += step) {
        samples.push_back(reference.BackProject(Eigen::Vector2d(x, y), depth));
      }
    }
    grid_depth = depth;
  }
  result.points_used = static_cast<int>(samples.size());

  // Per-point quantities of the reference.
  const double reference_focal = MeanFocal(reference);
  std::vector<double> reference_footprint(samples.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    reference_footprint[k] = reference.CameraFromWorld(samples[k]).z() / reference_focal;
  }

  const double n = static_cast<double>(samples.size());
  for (std::size_t j = 0; j < cameras.size(); ++j) {
    if (static_cast<int>(j) == reference_index) continue;
    const Camera& candidate = cameras[j];
    const double focal = MeanFocal(candidate);
    double sum = 0.0;
    std::vector<double> angles_deg;
    // The grid's points stand for a fronto-parallel surface at z₀: a candidate level with it or
    // behind it would see it edge-on or from the back.
    const bool sees_front =
        !grid_basis || reference.CameraFromWorld(candidate.center_world).z() < grid_depth;
    for (std::size_t k = 0; sees_front && k < samples.size(); ++k) {
      Eigen::Vector2d pixel;
      double depth = 0.0;
      if (!candidate.Project(samples[k], &pixel, &depth) || !candidate.InImage(pixel)) continue;
      const Eigen::Vector3d to_reference = (reference.center_world - samples[k]).normalized();
      const Eigen::Vector3d to_candidate = (candidate.center_world - samples[k]).normalized();
      const double cosine = std::clamp(to_reference.dot(to_candidate), -1.0, 1.0);
      const double angle_deg = std::acos(cosine) * kDegPerRad;
      angles_deg.push_back(angle_deg);
      const double r = reference_footprint[k] / (depth / focal);
      sum += AngleWeight(angle_deg, options) * ScaleWeight(r);
    }
    NeighborScore score;
    score.index = static_cast<int>(j);
    score.shared_points = static_cast<int>(angles_deg.size());
    score.shared_fraction = n > 0.0 ? static_cast<double>(angles_deg.size()) / n : 0.0;
    score.score = n > 0.0 ? sum / n : 0.0;
    score.median_angle_deg = Median(std::move(angles_deg));
    result.candidates.push_back(score);
  }
  std::sort(result.candidates.begin(), result.candidates.end(),
            [](const NeighborScore& a, const NeighborScore& b) {
              if (a.score != b.score) return a.score > b.score;
              return a.index < b.index;
            });
  for (const NeighborScore& c : result.candidates) {
    if (static_cast<int>(result.neighbors.size()) >= options.count || !(c.score > 0.0)) break;
    result.neighbors.push_back(c.index);
  }
  return result;
}

}  // namespace gcpstereo::cost
