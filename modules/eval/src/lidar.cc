// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/lidar.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "common.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::eval {
namespace {

// The nearest pixel of a sub-pixel position (pixel centres at integers).
inline std::int64_t NearestIndex(double x) {
  return static_cast<std::int64_t>(std::floor(x + 0.5));
}

// floor(a / b) for b > 0, also for negative a.
inline std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

}  // namespace

std::vector<ProjectedPoint> ProjectPointCloud(const PointCloud& cloud, const Camera& camera,
                                              const Eigen::Matrix4d& world_from_cloud,
                                              bool keep_nearest_per_pixel) {
  std::vector<ProjectedPoint> projected;
  const Eigen::Matrix3d rotation = world_from_cloud.topLeftCorner<3, 3>();
  const Eigen::Vector3d translation = world_from_cloud.topRightCorner<3, 1>();
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3d world = rotation * cloud.points[i].cast<double>() + translation;
    ProjectedPoint p;
    if (!camera.Project(world, &p.pixel, &p.depth) || !camera.InImage(p.pixel)) continue;
    p.index = static_cast<int>(i);
    projected.push_back(p);
  }
  if (!keep_nearest_per_pixel) return projected;
  // Z-buffer over nearest pixels: the nearest point wins, ties go to the lower index (first seen).
  std::vector<int> winner(static_cast<size_t>(camera.width) * camera.height, -1);
  for (size_t k = 0; k < projected.size(); ++k) {
    const std::int64_t col = NearestIndex(projected[k].pixel.x());
    const std::int64_t row = NearestIndex(projected[k].pixel.y());
    if (col < 0 || row < 0 || col >= camera.width || row >= camera.height) continue;
    int& w = winner[static_cast<size_t>(row) * camera.width + col];
    if (w < 0 || projected[k].depth < projected[w].depth) w = static_cast<int>(k);
  }
  std::vector<ProjectedPoint> kept;
  for (size_t k = 0; k < projected.size(); ++k) {
    const std::int64_t col = NearestIndex(projected[k].pixel.x());
    const std::int64_t row = NearestIndex(projected[k].pixel.y());
    if (col < 0 || row < 0 || col >= camera.width || row >= camera.height) continue;
    if (winner[static_cast<size_t>(row) * camera.width + col] == static_cast<int>(k)) {
      kept.push_back(projected[k]);
    }
  }
  return kept;
}

LidarSplit CheckerboardSplit(const std::vector<Eigen::Vector2d>& pixels, int block_px) {
  if (block_px < 1) {
    throw ConfigError(
        ViolatedConstraint("eval.lidar.block_px", std::to_string(block_px), "block_px >= 1"));
  }
  LidarSplit split;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const std::int64_t block_col = FloorDiv(NearestIndex(pixels[i].x()), block_px);
    const std::int64_t block_row = FloorDiv(NearestIndex(pixels[i].y()), block_px);
    if (((block_col + block_row) % 2 + 2) % 2 == 0) {
      split.gcp_indices.push_back(static_cast<int>(i));
    } else {
      split.score_indices.push_back(static_cast<int>(i));
    }
  }
  return split;
}

void LidarScoreOptions::Check() const {
  if (!(bad_abs_px > 0.0)) {
    throw ConfigError(ViolatedConstraint("eval.lidar.bad_abs_px",
                                         internal::FormatDouble(bad_abs_px), "bad_abs_px > 0"));
  }
  if (!(bad_rel >= 0.0)) {
    throw ConfigError(
        ViolatedConstraint("eval.lidar.bad_rel", internal::FormatDouble(bad_rel), "bad_rel >= 0"));
  }
  if (!(bad1_abs_px > 0.0)) {
    throw ConfigError(ViolatedConstraint("eval.lidar.bad1_abs_px",
                                         internal::FormatDouble(bad1_abs_px), "bad1_abs_px > 0"));
  }
}

nlohmann::json LidarScore::ToJson() const {
  nlohmann::json j;
  j["definition"] =
      "bad3: |e| > 3 px and > 5 % of the reference; bad1: |e| > 1 px; missing estimates are bad";
  j["counted"] = counted;
  j["outside"] = outside;
  j["invalid_reference"] = invalid_reference;
  j["missing"] = missing;
  j["bad3_count"] = bad3_count;
  j["bad1_count"] = bad1_count;
  j["bad3_percent"] = internal::JsonNumber(bad3_percent);
  j["bad1_percent"] = internal::JsonNumber(bad1_percent);
  j["mean_abs_error"] = internal::JsonNumber(mean_abs_error);
  j["rms_error"] = internal::JsonNumber(rms_error);
  return j;
}

// KITTI 2015 (Menze & Geiger, CVPR 2015) outlier rate "D1": a disparity is an outlier when its
// error exceeds both 3 px and 5 % of the true disparity. Here the truth is the held-out half of the
// projected LiDAR scan (see CheckerboardSplit), which never fed the GCP energy.
namespace {

// The map's estimate at a reference point's nearest pixel, with the outside / invalid_reference
// / missing definitions of LidarScore (shared by every score against points).
enum class PointEstimate { kOutside, kInvalidReference, kMissing, kValid };
PointEstimate EstimateAt(const cv::Mat& map, const ReferencePoint& p, double* estimate) {
  const std::int64_t col = NearestIndex(p.pixel.x());
  const std::int64_t row = NearestIndex(p.pixel.y());
  if (!std::isfinite(p.pixel.x()) || !std::isfinite(p.pixel.y()) || col < 0 || row < 0 ||
      col >= map.cols || row >= map.rows) {
    return PointEstimate::kOutside;
  }
  if (!std::isfinite(p.value) || p.value <= 0.0) return PointEstimate::kInvalidReference;
  const float value = map.at<float>(static_cast<int>(row), static_cast<int>(col));
  if (!std::isfinite(value) || value <= 0.0f) return PointEstimate::kMissing;
  *estimate = value;
  return PointEstimate::kValid;
}

// How one reference point scores against `map` (the definitions of LidarScore).
enum class PointClass { kOutside, kInvalidReference, kMissing, kBad3, kBad1, kGood };
PointClass ClassifyPoint(const cv::Mat& map, const ReferencePoint& p,
                         const LidarScoreOptions& options, double* error) {
  double estimate = 0.0;
  switch (EstimateAt(map, p, &estimate)) {
    case PointEstimate::kOutside:
      return PointClass::kOutside;
    case PointEstimate::kInvalidReference:
      return PointClass::kInvalidReference;
    case PointEstimate::kMissing:
      return PointClass::kMissing;
    case PointEstimate::kValid:
      break;
  }
  *error = std::abs(estimate - p.value);
  if (*error > options.bad_abs_px && *error > options.bad_rel * std::abs(p.value)) {
    return PointClass::kBad3;
  }
  return *error > options.bad1_abs_px ? PointClass::kBad1 : PointClass::kGood;
}

}  // namespace

LidarScore EvaluateAgainstPoints(const cv::Mat& map, const std::vector<ReferencePoint>& points,
                                 const LidarScoreOptions& options) {
  options.Check();
  internal::CheckFloatMap(map, "evaluated map");
  LidarScore score;
  double sum_abs = 0.0, sum_sq = 0.0;
  std::int64_t valid = 0;
  for (const ReferencePoint& p : points) {
    double error = 0.0;
    const PointClass c = ClassifyPoint(map, p, options, &error);
    if (c == PointClass::kOutside) {
      ++score.outside;
      continue;
    }
    if (c == PointClass::kInvalidReference) {
      ++score.invalid_reference;
      continue;
    }
    ++score.counted;
    if (c == PointClass::kMissing) {
      ++score.missing;
      ++score.bad3_count;
      ++score.bad1_count;
      continue;
    }
    ++valid;
    sum_abs += error;
    sum_sq += error * error;
    if (c == PointClass::kBad3) ++score.bad3_count;
    if (c == PointClass::kBad3 || c == PointClass::kBad1) ++score.bad1_count;
  }
  score.bad3_percent = internal::Percent(score.bad3_count, score.counted);
  score.bad1_percent = internal::Percent(score.bad1_count, score.counted);
  if (valid > 0) {
    score.mean_abs_error = sum_abs / valid;
    score.rms_error = std::sqrt(sum_sq / valid);
  }
  return score;
}

cv::Mat RenderPointErrors(const cv::Mat& image_bgr, const cv::Mat& map,
                          const std::vector<ReferencePoint>& points,
                          const LidarScoreOptions& options) {
  options.Check();
  internal::CheckFloatMap(map, "evaluated map");
  if (image_bgr.type() != CV_8UC3 || image_bgr.size() != map.size()) {
    throw Error("RenderPointErrors: the image must be CV_8UC3 of the map's size");
  }
  cv::Mat grey, out;
  cv::cvtColor(image_bgr, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(grey, CV_8U, 0.6);
  cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
  const int radius = std::max(1, image_bgr.cols / 600);
  for (const ReferencePoint& p : points) {
    double error = 0.0;
    cv::Scalar color;
    switch (ClassifyPoint(map, p, options, &error)) {
      case PointClass::kOutside:
      case PointClass::kInvalidReference:
        continue;
      case PointClass::kMissing:
        color = cv::Scalar(255, 0, 255);  // magenta
        break;
      case PointClass::kBad3:
        color = cv::Scalar(0, 0, 255);  // red
        break;
      case PointClass::kBad1:
        color = cv::Scalar(0, 220, 255);  // yellow
        break;
      case PointClass::kGood:
        color = cv::Scalar(0, 200, 0);  // green
        break;
    }
    cv::circle(out,
               cv::Point(static_cast<int>(NearestIndex(p.pixel.x())),
                         static_cast<int>(NearestIndex(p.pixel.y()))),
               radius, color, cv::FILLED);
  }
  return out;
}

nlohmann::json RelativeDepthScore::ToJson() const {
  nlohmann::json j;
  j["definition"] =
      "relative depth error |z - z_ref| / z_ref at the point's nearest pixel; a missing estimate "
      "counts as above every threshold";
  j["counted"] = counted;
  j["outside"] = outside;
  j["invalid_reference"] = invalid_reference;
  j["missing"] = missing;
  for (size_t i = 0; i < thresholds.size(); ++i) {
    j["above_" + internal::FormatDouble(100.0 * thresholds[i]) + "_percent"] =
        internal::JsonNumber(above_percent[i]);
  }
  j["median_relative_error_percent"] = internal::JsonNumber(median_percent);
  return j;
}

RelativeDepthScore EvaluateRelativeDepth(const cv::Mat& depth,
                                         const std::vector<ReferencePoint>& points,
                                         const std::vector<double>& thresholds) {
  internal::CheckFloatMap(depth, "evaluated depth map");
  for (const double t : thresholds) {
    if (!(t > 0.0)) {
      throw ConfigError(ViolatedConstraint("relative depth threshold", FormatNumber(t), "> 0"));
    }
  }
  RelativeDepthScore score;
  score.thresholds = thresholds;
  std::vector<double> errors;
  errors.reserve(points.size());
  for (const ReferencePoint& p : points) {
    double estimate = 0.0;
    switch (EstimateAt(depth, p, &estimate)) {
      case PointEstimate::kOutside:
        ++score.outside;
        break;
      case PointEstimate::kInvalidReference:
        ++score.invalid_reference;
        break;
      case PointEstimate::kMissing:
        ++score.counted;
        ++score.missing;
        errors.push_back(std::numeric_limits<double>::infinity());
        break;
      case PointEstimate::kValid:
        ++score.counted;
        errors.push_back(std::abs(estimate - p.value) / p.value);
        break;
    }
  }
  for (const double t : thresholds) {
    const auto above = std::count_if(errors.begin(), errors.end(), [t](double r) { return r > t; });
    score.above_percent.push_back(internal::Percent(above, score.counted));
  }
  score.median_percent =
      errors.empty() ? std::numeric_limits<double>::quiet_NaN() : 100.0 * internal::Median(&errors);
  return score;
}

}  // namespace gcpstereo::eval
