// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/label_range.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "cost_internal.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/cost/rectify.h"

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
  if (!(matching_far_percentile >= 0.0 && matching_far_percentile < 50.0)) {
    throw ConfigError(ViolatedConstraint("labels.auto.matching_far_percentile",
                                         internal::Str(matching_far_percentile),
                                         "0 <= matching_far_percentile < 50"));
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

std::optional<std::pair<double, double>> DisparityRangeFromMatching(const cv::Mat& left,
                                                                    const cv::Mat& right,
                                                                    const cv::Mat& left_valid,
                                                                    double low_percentile) {
  if (!(low_percentile >= 0.0 && low_percentile < 50.0)) {
    throw Error("DisparityRangeFromMatching: low_percentile must lie in [0, 50), not " +
                internal::Str(low_percentile));
  }
  if (left.empty() || left.size() != right.size() || left.type() != right.type() ||
      left.depth() != CV_8U || (left.channels() != 1 && left.channels() != 3) ||
      (!left_valid.empty() && (left_valid.size() != left.size() || left_valid.type() != CV_8U))) {
    throw Error(
        "DisparityRangeFromMatching: the images must be non-empty 8-bit grey or BGR "
        "images of one size and type (and the mask CV_8U of their size)");
  }
  // Half resolution (at most 640 px wide): the range needs no sub-pixel precision, and small
  // mismatched regions merge into their surroundings.
  const double scale = left.cols >= 200 ? std::min(0.5, 640.0 / left.cols) : 1.0;
  cv::Mat l = left, r = right, valid = left_valid;
  if (scale != 1.0) {
    cv::resize(left, l, cv::Size(), scale, scale, cv::INTER_AREA);
    cv::resize(right, r, cv::Size(), scale, scale, cv::INTER_AREA);
    if (!left_valid.empty()) {
      cv::resize(left_valid, valid, l.size(), 0.0, 0.0, cv::INTER_NEAREST);
    }
  }
  // Every disparity below the width (the matcher wants a multiple of 16). The matcher leaves the
  // first `search` columns unmatched, so both images get that many replicated columns on the left.
  const int search = (l.cols + 15) / 16 * 16;
  cv::Mat left_padded, right_padded;
  cv::copyMakeBorder(l, left_padded, 0, 0, search, 0, cv::BORDER_REPLICATE);
  cv::copyMakeBorder(r, right_padded, 0, 0, search, 0, cv::BORDER_REPLICATE);
  constexpr int kBlock = 5;
  const int area = kBlock * kBlock * l.channels();
  const int speckle_px = std::max(1, static_cast<int>(0.005 * static_cast<double>(l.total())));
  const cv::Ptr<cv::StereoSGBM> matcher = cv::StereoSGBM::create(
      /*minDisparity=*/0, search, kBlock, /*P1=*/8 * area, /*P2=*/32 * area,
      /*disp12MaxDiff=*/1, /*preFilterCap=*/0, /*uniquenessRatio=*/10, speckle_px,
      /*speckleRange=*/1, cv::StereoSGBM::MODE_SGBM);
  cv::Mat fixed_point;  // CV_16S, disparity · 16, negative = no match
  matcher->compute(left_padded, right_padded, fixed_point);
  const cv::Mat disparity16 = fixed_point.colRange(search, fixed_point.cols);
  // A block without texture matches every disparity at the same cost, and the matcher's
  // uniqueness test does not reject exact ties: such pixels are not counted.
  cv::Mat grey, mean, mean_of_squares;
  if (l.channels() == 3) {
    cv::cvtColor(l, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = l;
  }
  grey.convertTo(grey, CV_32F);
  cv::boxFilter(grey, mean, CV_32F, cv::Size(kBlock, kBlock));
  cv::boxFilter(grey.mul(grey), mean_of_squares, CV_32F, cv::Size(kBlock, kBlock));
  std::vector<std::int16_t> counted;
  for (int y = 0; y < disparity16.rows; ++y) {
    const auto* row = disparity16.ptr<std::int16_t>(y);
    const float* m = mean.ptr<float>(y);
    const float* m2 = mean_of_squares.ptr<float>(y);
    const std::uint8_t* in_mask = valid.empty() ? nullptr : valid.ptr<std::uint8_t>(y);
    for (int x = 0; x < disparity16.cols; ++x) {
      if (row[x] < 0 || m2[x] - m[x] * m[x] < 1.0f) continue;  // grey-level variance < 1
      if (in_mask != nullptr && in_mask[x] == 0) continue;
      counted.push_back(row[x]);
    }
  }
  if (counted.empty()) return std::nullopt;
  const int highest = *std::max_element(counted.begin(), counted.end());
  const auto rank = static_cast<std::ptrdiff_t>(
      std::floor(low_percentile / 100.0 * static_cast<double>(counted.size() - 1)));
  std::nth_element(counted.begin(), counted.begin() + rank, counted.end());
  const int lowest = counted[static_cast<std::size_t>(rank)];
  return std::make_pair(lowest / 16.0 / scale, highest / 16.0 / scale);
}

std::optional<std::pair<double, double>> DepthRangeFromMatching(const View& reference,
                                                                const std::vector<View>& neighbors,
                                                                bool rectified_pair,
                                                                double low_percentile) {
  if (neighbors.empty()) return std::nullopt;
  if (rectified_pair) {
    // d = f·B / depth, B the baseline to the first neighbour (the right image).
    const View& right = neighbors.front();
    if (reference.image.empty() || right.image.size() != reference.image.size())
      return std::nullopt;
    const double numerator = reference.camera.K(0, 0) *
                             (right.camera.center_world.x() - reference.camera.center_world.x());
    if (!(numerator > 0.0)) return std::nullopt;
    const auto matched =
        DisparityRangeFromMatching(reference.image, right.image, cv::Mat(), low_percentile);
    if (!matched || !(matched->second > 0.0)) return std::nullopt;
    return std::make_pair(numerator / matched->second,
                          matched->first > 0.0 ? numerator / matched->first : kInf);
  }
  // Calibrated views: the nearest neighbour (camera centres; ties: list order) that rectifies
  // horizontally with the reference.
  for (const std::size_t i : NeighborsByDistance(reference, neighbors)) {
    const View& neighbor = neighbors[i];
    if (neighbor.image.size() != reference.image.size() || reference.image.empty()) continue;
    const RectifiedCalibratedPair pair = RectifyCalibratedPair(reference, neighbor);
    if (pair.vertical) continue;
    const auto matched =
        DisparityRangeFromMatching(pair.left, pair.right, pair.left_valid, low_percentile);
    if (!matched || !(matched->second > 0.0)) return std::nullopt;
    // z_rect = f·B / d; the reference camera's z of the point at rectified pixel (x, y) is
    // z_rect · (row 3 of ref_from_rect) · ((x − cx)/f, (y − cy)/f, 1), affine in x and y, so its
    // extremes over the image lie at the corners.
    const double fb = pair.focal_px * pair.baseline;
    const Eigen::RowVector3d row = pair.ref_from_rect.row(2);
    double lowest = kInf, highest = 0.0;
    for (const double x : {0.0, reference.image.cols - 1.0}) {
      for (const double y : {0.0, reference.image.rows - 1.0}) {
        const double factor = row.dot(
            Eigen::Vector3d((x - pair.cx) / pair.focal_px, (y - pair.cy) / pair.focal_px, 1.0));
        lowest = std::min(lowest, factor);
        highest = std::max(highest, factor);
      }
    }
    if (!(lowest > 0.0)) return std::nullopt;
    return std::make_pair(fb / matched->second * lowest,
                          matched->first > 0.0 ? fb / matched->first * highest : kInf);
  }
  return std::nullopt;
}

LabelSpace MakeLabelSpace(LabelSpaceKind kind, std::optional<int> count, std::optional<double> min,
                          std::optional<double> max, const GcpSet& gcps, const View& reference,
                          const std::vector<View>& neighbors, double disparity_numerator,
                          bool rectified_pair, const LabelRangeOptions& options,
                          LabelRangeSummary* summary, MatchedDepthRange* matched_cache) {
  LabelRangeSummary info;
  info.source = "config";
  if (!min || !max) {
    options.Check();
    std::pair<double, double> depth_range;
    std::string source;
    // What the images show, unless a range sensor measured the scene (a LiDAR, a depth image):
    // stereo GCPs are scarce on the nearest surfaces.
    const bool measured = std::any_of(gcps.points.begin(), gcps.points.end(),
                                      [](const Gcp& g) { return g.source != GcpSource::kStereo; });
    std::optional<std::pair<double, double>> matched;
    if (!measured) {
      if (matched_cache != nullptr && matched_cache->computed) {
        matched = matched_cache->depths;
      } else {
        matched = DepthRangeFromMatching(reference, neighbors, rectified_pair);
        if (matched_cache != nullptr) *matched_cache = {true, matched};
      }
    }
    if (!gcps.empty()) {
      depth_range = DepthRangeFromGcps(gcps, options.gcp_low_percentile,
                                       options.gcp_high_percentile, options.margin);
      source = "gcps";
      if (matched) {  // the near end only: the matcher's far end is often the sky (disparity 0)
        depth_range.first = std::min(depth_range.first, matched->first / (1.0 + options.margin));
        source = "gcps+matching";
      }
    } else if (matched) {
      // labels.auto.max_depth caps the far end, as for the frustum (the sky matches disparity 0).
      depth_range = {matched->first / (1.0 + options.margin),
                     std::min(matched->second * (1.0 + options.margin), options.max_depth)};
      source = "matching";
      if (!std::isfinite(depth_range.second) && kind == LabelSpaceKind::kDepth && !max) {
        // A depth space needs a bounded far end, and a few pixels matched at disparity 0 (a
        // mismatch along a border, a patch of distant background) should not make the whole run
        // fail: the far end is then taken at a low percentile of the matched disparities.
        const auto robust = DepthRangeFromMatching(reference, neighbors, rectified_pair,
                                                   options.matching_far_percentile);
        if (robust && std::isfinite(robust->second)) {
          depth_range.second = std::min(robust->second * (1.0 + options.margin), options.max_depth);
          source = "matching-percentile";
        }
      }
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
    const std::string range_text =
        "automatic depth range [" + internal::Str(z_min) + ", " + internal::Str(z_max) +
        "] from the " +
        (source == "gcps"       ? "GCPs"
         : source == "matching" ? "views' matched disparities"
         : source == "matching-percentile"
             ? "views' matched disparities (far end at labels.auto.matching_far_percentile)"
         : source == "frustum" ? "neighbours' frustum overlap"
                               : "GCPs and the views' matched disparities");
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
    if (kind == LabelSpaceKind::kDisparity) {
      auto_min = 0.0;
      if (!count) auto_max = std::ceil(auto_max);
    }
    if (!min) min = auto_min;
    if (!max) max = auto_max;
  }
  if (!count) {
    if (kind != LabelSpaceKind::kDisparity) {
      throw ConfigError(ViolatedConstraint(
          "labels.count", "auto", "one label per pixel of disparity needs labels.space disparity"));
    }
    count = std::max(2, static_cast<int>(std::ceil(*max - *min - 1e-9)) + 1);
  }
  if (summary != nullptr) *summary = info;
  return LabelSpace(kind, *count, *min, *max, disparity_numerator);
}

}  // namespace gcpstereo::cost
