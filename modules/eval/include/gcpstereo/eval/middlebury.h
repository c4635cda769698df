// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>

namespace gcpstereo::eval {

// Middlebury v2 evaluation (Scharstein & Szeliski, IJCV 2002, §5.1; the v2 online table used by
// Wang & Yang, CVPR 2011, Tables 2–3): the percentage of "bad" pixels whose disparity error exceeds
// a threshold, in the non-occluded ("nonocc"), all-with-GT ("all") and near-discontinuity ("disc")
// regions.
//
// Region masks are CV_8U; a pixel belongs to a region when its mask value is exactly 255. This
// matches the official files: nonocc.png / all.png (255 = counted) and disc.png (255 = near a
// discontinuity, 128 = other non-occluded, 0 = excluded). An empty Mat = region not available.
struct MiddleburyMasks {
  cv::Mat nonocc;
  cv::Mat all;
  cv::Mat disc;
};

// How masks are derived when a data set has no mask files (the 2005/2006 sets), mimicking the v2
// definitions of Scharstein & Szeliski 2002 (§5.1, "occluded" by cross-checking the two GT maps;
// "depth discontinuity regions: pixels whose neighbouring disparities differ by more than
// disp_gap = 2, dilated by a window of width 9").
struct DeriveMasksOptions {
  // Left-right tolerance in pixels: a pixel x of the left GT is non-occluded when
  // x_r = round(x − d_left(x)) lies in the image, d_right(x_r) is known and
  // |d_left(x) − d_right(x_r)| <= lr_tolerance_px. Range: >= 0. YAML: eval.masks.lr_tolerance_px.
  double lr_tolerance_px = 1.0;
  // Disparity jump (px) between 4-neighbours (both known) that marks a discontinuity; both
  // pixels of the pair are marked. Range: > 0. YAML: eval.masks.disc_gap_px.
  double disc_gap_px = 2.0;
  // Side of the square dilation window (pixels, odd) applied to the discontinuity pixels
  // (9 = a 9×9 box). Range: odd, >= 1. YAML: eval.masks.disc_width_px.
  int disc_width_px = 9;
  // Pixels within this distance of the image edge are excluded from every mask (Middlebury v2:
  // 18 px tsukuba, 10 px venus). Range: >= 0. YAML: eval.border_px.
  int border_px = 0;

  void Check() const;
};

// Derives the masks from the left (reference) GT disparity and, when available, the right view's
// GT disparity (CV_32F; non-finite or <= 0 = unknown). Convention: a left pixel x sees the point
// that appears at x − d_left(x) in the right view.
//   all    = 255 where d_left is known (inside the border), else 0;
//   nonocc = 255 where `all` and the left-right check passes, else 0; EMPTY when gt_right is empty
//            (cannot be derived — the result then has no nonocc region);
//   disc   = 255 on (dilated discontinuity pixels ∩ nonocc), 128 on the other nonocc pixels,
//            0 elsewhere (computed on `all` when nonocc is not available).
// Throws Error when the types or sizes are wrong.
MiddleburyMasks DeriveMasks(const cv::Mat& gt_left, const cv::Mat& gt_right,
                            const DeriveMasksOptions& options = {});

struct MiddleburyOptions {
  // Bad-pixel thresholds in pixels: bad = |d − d_gt| > t (strictly). Each > 0, ascending,
  // non-empty. YAML: eval.middlebury.thresholds_px.
  std::vector<double> thresholds_px = {0.5, 1.0, 2.0};
  // Pixels within this distance of the image edge are excluded from every region (the official
  // tsukuba/venus masks already exclude their border; this is for derived masks). Range: >= 0.
  // YAML: eval.border_px.
  int border_px = 0;

  void Check() const;
};

// Scores of one region.
struct BadPixelStats {
  std::string region;        // "nonocc", "all" or "disc"
  bool available = false;    // false when the region's mask was not given
  std::int64_t counted = 0;  // pixels of the region with known GT (inside the border)
  std::int64_t missing = 0;  // counted pixels with a non-finite estimate: always bad
  std::vector<double> thresholds_px;
  std::vector<std::int64_t> bad_count;  // per threshold
  std::vector<double> bad_percent;      // per threshold, percent of `counted` (0 when counted = 0)
  double mean_abs_error_px = 0.0;       // over counted pixels with a finite estimate
  double rms_error_px = 0.0;            // idem

  // The bad percentage for threshold t (must be one of thresholds_px; throws Error otherwise).
  double BadPercent(double t) const;
  nlohmann::json ToJson() const;
};

struct MiddleburyResult {
  BadPixelStats nonocc;
  BadPixelStats all;
  BadPixelStats disc;
  nlohmann::json ToJson() const;
};

// Evaluates a disparity map against the GT disparity (both CV_32F, same convention and size).
// A pixel is counted in a region when the region's mask is 255 there, the GT is known (finite and
// > 0; convert the files' 0 to kInvalidDepth or leave it 0) and it is at least border_px from the
// edge. If masks.all is empty, "all" is every GT-known pixel. Estimates that are non-finite are bad
// at every threshold (never skipped); finite negative or zero disparities are scored like any other
// value. Throws Error on wrong types/sizes, ConfigError on bad options.
MiddleburyResult EvaluateDisparity(const cv::Mat& disparity, const cv::Mat& gt_disparity,
                                   const MiddleburyMasks& masks,
                                   const MiddleburyOptions& options = {});

// Error map (CV_8UC3, BGR): counted pixels of `region_mask` (255, GT known, outside border) show
// the estimate as grey (disparity / max GT disparity, clipped), bad pixels (|d − gt| >
// threshold_px) red, counted pixels with a non-finite estimate yellow; excluded pixels are drawn at
// a third of their grey level. Empty region_mask = every GT-known pixel.
cv::Mat RenderDisparityErrorMap(const cv::Mat& disparity, const cv::Mat& gt_disparity,
                                const cv::Mat& region_mask, double threshold_px = 1.0,
                                int border_px = 0);

}  // namespace gcpstereo::eval
