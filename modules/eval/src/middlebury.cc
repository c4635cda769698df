// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/middlebury.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "common.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::eval {
namespace {

inline bool DisparityKnown(float d) { return std::isfinite(d) && d > 0.0f; }

inline bool InsideBorder(int row, int col, int rows, int cols, int border) {
  return row >= border && col >= border && row < rows - border && col < cols - border;
}

BadPixelStats ScoreRegion(const std::string& name, const cv::Mat& disparity,
                          const cv::Mat& gt_disparity, const cv::Mat& mask, bool mask_optional,
                          const MiddleburyOptions& options) {
  BadPixelStats stats;
  stats.region = name;
  stats.thresholds_px = options.thresholds_px;
  stats.bad_count.assign(options.thresholds_px.size(), 0);
  stats.bad_percent.assign(options.thresholds_px.size(), 0.0);
  if (mask.empty() && !mask_optional) return stats;  // region not available
  stats.available = true;
  const int rows = disparity.rows, cols = disparity.cols;
  double sum_abs = 0.0, sum_sq = 0.0;
  std::int64_t finite = 0;
  for (int row = 0; row < rows; ++row) {
    const float* d = disparity.ptr<float>(row);
    const float* g = gt_disparity.ptr<float>(row);
    const std::uint8_t* m = mask.empty() ? nullptr : mask.ptr<std::uint8_t>(row);
    for (int col = 0; col < cols; ++col) {
      if (m != nullptr && m[col] != 255) continue;
      if (!DisparityKnown(g[col]) || !InsideBorder(row, col, rows, cols, options.border_px)) {
        continue;
      }
      ++stats.counted;
      if (!std::isfinite(d[col])) {
        ++stats.missing;
        for (auto& count : stats.bad_count) ++count;
        continue;
      }
      const double error = std::abs(static_cast<double>(d[col]) - static_cast<double>(g[col]));
      ++finite;
      sum_abs += error;
      sum_sq += error * error;
      for (size_t t = 0; t < options.thresholds_px.size(); ++t) {
        if (error > options.thresholds_px[t]) ++stats.bad_count[t];
      }
    }
  }
  for (size_t t = 0; t < options.thresholds_px.size(); ++t) {
    stats.bad_percent[t] = internal::Percent(stats.bad_count[t], stats.counted);
  }
  if (finite > 0) {
    stats.mean_abs_error_px = sum_abs / finite;
    stats.rms_error_px = std::sqrt(sum_sq / finite);
  }
  return stats;
}

void CheckDisparityPair(const cv::Mat& disparity, const std::string& name, const cv::Mat& gt,
                        const std::string& gt_name) {
  internal::CheckFloatMap(disparity, name);
  internal::CheckFloatMap(gt, gt_name);
  internal::CheckSameSize(gt, gt_name, disparity, name);
}

}  // namespace

void DeriveMasksOptions::Check() const {
  if (!(lr_tolerance_px >= 0.0)) {
    throw ConfigError(ViolatedConstraint("eval.masks.lr_tolerance_px",
                                         internal::FormatDouble(lr_tolerance_px),
                                         "lr_tolerance_px >= 0"));
  }
  if (!(disc_gap_px > 0.0)) {
    throw ConfigError(ViolatedConstraint("eval.masks.disc_gap_px",
                                         internal::FormatDouble(disc_gap_px), "disc_gap_px > 0"));
  }
  if (disc_width_px < 1 || disc_width_px % 2 == 0) {
    throw ConfigError(ViolatedConstraint("eval.masks.disc_width_px", std::to_string(disc_width_px),
                                         "disc_width_px odd and >= 1"));
  }
  if (border_px < 0) {
    throw ConfigError(
        ViolatedConstraint("eval.border_px", std::to_string(border_px), "border_px >= 0"));
  }
}

void MiddleburyOptions::Check() const {
  if (thresholds_px.empty()) {
    throw ConfigError(
        ViolatedConstraint("eval.middlebury.thresholds_px", "[]", "at least one threshold"));
  }
  for (size_t i = 0; i < thresholds_px.size(); ++i) {
    if (!(thresholds_px[i] > 0.0) || !std::isfinite(thresholds_px[i]) ||
        (i > 0 && !(thresholds_px[i] > thresholds_px[i - 1]))) {
      throw ConfigError(ViolatedConstraint(
          "eval.middlebury.thresholds_px[" + std::to_string(i) + "]",
          internal::FormatDouble(thresholds_px[i]), "finite, > 0 and strictly ascending"));
    }
  }
  if (border_px < 0) {
    throw ConfigError(
        ViolatedConstraint("eval.border_px", std::to_string(border_px), "border_px >= 0"));
  }
}

// Scharstein & Szeliski, IJCV 2002, §5.1: "occluded regions O: regions that are occluded in the
// matching image" (found by cross-checking the two GT maps) and "depth discontinuity regions D:
// pixels whose neighbouring disparities differ by more than disp_gap, dilated by a window of width
// discont_width" (defaults 2 and 9). Deviation: the neighbour test uses 4-neighbours of known GT
// only, and the right GT is sampled at the nearest pixel (no interpolation).
MiddleburyMasks DeriveMasks(const cv::Mat& gt_left, const cv::Mat& gt_right,
                            const DeriveMasksOptions& options) {
  options.Check();
  internal::CheckFloatMap(gt_left, "left ground-truth disparity");
  if (!gt_right.empty()) {
    internal::CheckFloatMap(gt_right, "right ground-truth disparity");
    internal::CheckSameSize(gt_right, "right ground-truth disparity", gt_left,
                            "the left ground-truth disparity");
  }
  const int rows = gt_left.rows, cols = gt_left.cols;
  MiddleburyMasks masks;
  masks.all = cv::Mat(rows, cols, CV_8UC1, cv::Scalar(0));
  for (int row = 0; row < rows; ++row) {
    const float* g = gt_left.ptr<float>(row);
    for (int col = 0; col < cols; ++col) {
      if (DisparityKnown(g[col]) && InsideBorder(row, col, rows, cols, options.border_px)) {
        masks.all.at<std::uint8_t>(row, col) = 255;
      }
    }
  }
  if (!gt_right.empty()) {
    masks.nonocc = cv::Mat(rows, cols, CV_8UC1, cv::Scalar(0));
    for (int row = 0; row < rows; ++row) {
      const float* g = gt_left.ptr<float>(row);
      const float* r = gt_right.ptr<float>(row);
      for (int col = 0; col < cols; ++col) {
        if (masks.all.at<std::uint8_t>(row, col) == 0) continue;
        const double x_right = std::floor(col - static_cast<double>(g[col]) + 0.5);
        if (x_right < 0.0 || x_right > cols - 1) continue;
        const float d_right = r[static_cast<int>(x_right)];
        if (!DisparityKnown(d_right)) continue;
        if (std::abs(static_cast<double>(g[col]) - d_right) <= options.lr_tolerance_px) {
          masks.nonocc.at<std::uint8_t>(row, col) = 255;
        }
      }
    }
  }
  // Discontinuities: both pixels of a 4-neighbour pair of known GT whose disparities differ by
  // more than disc_gap_px.
  cv::Mat jumps(rows, cols, CV_8UC1, cv::Scalar(0));
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      const float d = gt_left.at<float>(row, col);
      if (!DisparityKnown(d)) continue;
      if (col + 1 < cols) {
        const float e = gt_left.at<float>(row, col + 1);
        if (DisparityKnown(e) && std::abs(static_cast<double>(d) - e) > options.disc_gap_px) {
          jumps.at<std::uint8_t>(row, col) = jumps.at<std::uint8_t>(row, col + 1) = 255;
        }
      }
      if (row + 1 < rows) {
        const float e = gt_left.at<float>(row + 1, col);
        if (DisparityKnown(e) && std::abs(static_cast<double>(d) - e) > options.disc_gap_px) {
          jumps.at<std::uint8_t>(row, col) = jumps.at<std::uint8_t>(row + 1, col) = 255;
        }
      }
    }
  }
  cv::Mat dilated;
  cv::dilate(jumps, dilated,
             cv::getStructuringElement(cv::MORPH_RECT,
                                       cv::Size(options.disc_width_px, options.disc_width_px)));
  const cv::Mat& base = masks.nonocc.empty() ? masks.all : masks.nonocc;
  masks.disc = cv::Mat(rows, cols, CV_8UC1, cv::Scalar(0));
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      if (base.at<std::uint8_t>(row, col) != 255) continue;
      masks.disc.at<std::uint8_t>(row, col) = dilated.at<std::uint8_t>(row, col) ? 255 : 128;
    }
  }
  return masks;
}

double BadPixelStats::BadPercent(double t) const {
  for (size_t i = 0; i < thresholds_px.size(); ++i) {
    if (thresholds_px[i] == t) return bad_percent[i];
  }
  throw Error("BadPixelStats(" + region + "): no threshold " + internal::FormatDouble(t) +
              " px was evaluated");
}

nlohmann::json BadPixelStats::ToJson() const {
  nlohmann::json j;
  j["available"] = available;
  if (!available) return j;
  j["counted"] = counted;
  j["missing"] = missing;
  j["thresholds_px"] = internal::JsonNumbers(thresholds_px);
  j["bad_count"] = bad_count;
  j["bad_percent"] = internal::JsonNumbers(bad_percent);
  j["mean_abs_error_px"] = internal::JsonNumber(mean_abs_error_px);
  j["rms_error_px"] = internal::JsonNumber(rms_error_px);
  return j;
}

nlohmann::json MiddleburyResult::ToJson() const {
  nlohmann::json j;
  j["definition"] =
      "bad = |d - gt| > t (non-finite estimate = bad), percent of region pixels with known gt";
  j["nonocc"] = nonocc.ToJson();
  j["all"] = all.ToJson();
  j["disc"] = disc.ToJson();
  return j;
}

// Scharstein & Szeliski, IJCV 2002, §5.1, eq. (2): B = (1/N) Σ (|d_C(x, y) − d_T(x, y)| > δ_d),
// over the pixels of each region; also the RMS error R of eq. (1). Wang & Yang report B at δ_d = 1
// in non-occluded regions (Table 3). Deviation: non-finite estimates (no disparity) are counted as
// bad rather than filled in.
MiddleburyResult EvaluateDisparity(const cv::Mat& disparity, const cv::Mat& gt_disparity,
                                   const MiddleburyMasks& masks, const MiddleburyOptions& options) {
  options.Check();
  CheckDisparityPair(disparity, "disparity estimate", gt_disparity, "ground-truth disparity");
  const std::pair<const cv::Mat*, const char*> named[] = {
      {&masks.nonocc, "nonocc mask"}, {&masks.all, "all mask"}, {&masks.disc, "disc mask"}};
  for (const auto& [mask, name] : named) {
    internal::CheckMask(*mask, name);
    internal::CheckSameSize(*mask, name, disparity, "the disparity estimate");
  }
  MiddleburyResult result;
  result.nonocc = ScoreRegion("nonocc", disparity, gt_disparity, masks.nonocc, false, options);
  result.all = ScoreRegion("all", disparity, gt_disparity, masks.all, true, options);
  result.disc = ScoreRegion("disc", disparity, gt_disparity, masks.disc, false, options);
  return result;
}

cv::Mat RenderDisparityErrorMap(const cv::Mat& disparity, const cv::Mat& gt_disparity,
                                const cv::Mat& region_mask, double threshold_px, int border_px) {
  CheckDisparityPair(disparity, "disparity estimate", gt_disparity, "ground-truth disparity");
  internal::CheckMask(region_mask, "region mask");
  internal::CheckSameSize(region_mask, "region mask", disparity, "the disparity estimate");
  double max_gt = 0.0;
  for (int row = 0; row < gt_disparity.rows; ++row) {
    for (int col = 0; col < gt_disparity.cols; ++col) {
      const float g = gt_disparity.at<float>(row, col);
      if (DisparityKnown(g)) max_gt = std::max(max_gt, static_cast<double>(g));
    }
  }
  if (max_gt <= 0.0) max_gt = 1.0;
  const int rows = disparity.rows, cols = disparity.cols;
  cv::Mat image(rows, cols, CV_8UC3);
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      const float d = disparity.at<float>(row, col);
      const float g = gt_disparity.at<float>(row, col);
      const double grey_level = std::isfinite(d) ? std::clamp(255.0 * d / max_gt, 0.0, 255.0) : 0.0;
      const auto grey = static_cast<std::uint8_t>(std::lround(grey_level));
      const bool counted = (region_mask.empty() || region_mask.at<std::uint8_t>(row, col) == 255) &&
                           DisparityKnown(g) && InsideBorder(row, col, rows, cols, border_px);
      cv::Vec3b& out = image.at<cv::Vec3b>(row, col);
      if (!counted) {
        const auto dim = static_cast<std::uint8_t>(grey / 3);
        out = cv::Vec3b(dim, dim, dim);
      } else if (!std::isfinite(d)) {
        out = cv::Vec3b(0, 255, 255);  // yellow: no estimate
      } else if (std::abs(static_cast<double>(d) - g) > threshold_px) {
        out = cv::Vec3b(0, 0, 255);  // red: bad
      } else {
        out = cv::Vec3b(grey, grey, grey);
      }
    }
  }
  return image;
}

}  // namespace gcpstereo::eval
