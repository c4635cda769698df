// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>

namespace gcpstereo::eval {

// Strecha-style depth evaluation against a ground-truth depth + sigma pair (Strecha, von Hansen,
// Van Gool, Fua, Thoennessen, CVPR 2008, §4 and its error histograms; Wang & Yang, CVPR 2011,
// Figure 4 and §4.2: "34.7 % of the depth estimates are within the 3 Sigma range").
//
// Definitions (all maps CV_32F of the same size; `mask` CV_8U, empty = every pixel):
//   counted pixel  p: mask(p) != 0, gt_depth(p) finite and > 0, gt_sigma(p) finite and > 0.
//                     Other pixels are "GT unknown" and are not in any denominator.
//   missing        : a counted pixel whose estimate is not a valid depth (non-finite or <= 0).
//                     It is in the denominator and never within any n·σ (counted as wrong).
//   e(p)           = |depth(p) − gt_depth(p)| / gt_sigma(p) for counted, non-missing pixels.
//   within n·σ     : e(p) <= n (inclusive), n = 1 … 10, cumulative.
//   bin n          : (n−1) < e(p) <= n for n = 2 … 10, and e(p) <= 1 for n = 1 (the bars of the
//                     paper's Figure 4); `beyond_10`: e(p) > 10.
// Shares are in PERCENT of `counted` (0 … 100); with counted == 0 every share is 0.
// Deviation from Strecha's published histograms: they merge "> 10σ" and "missing" into one
// eleventh bar; we keep them apart (both are reported and drawn).
struct SigmaHistogram {
  static constexpr int kNumBins = 10;

  std::int64_t counted = 0;     // pixels with known GT (and in the mask)
  std::int64_t gt_unknown = 0;  // pixels in the mask (or image) without usable GT
  std::int64_t missing = 0;     // counted pixels without a valid estimate
  std::int64_t beyond_10 = 0;   // counted pixels with e > 10
  std::array<std::int64_t, kNumBins> bin_count{};     // bin_count[n-1]: bin n as defined above
  std::array<std::int64_t, kNumBins> within_count{};  // within_count[n-1]: e <= n

  // Mean and RMS of the absolute depth error |depth − gt| (depth units) and of e, over counted
  // pixels with a valid estimate (missing pixels cannot enter a mean; see `missing`).
  double mean_abs_error = 0.0;
  double rms_error = 0.0;
  double mean_error_sigma = 0.0;
  double median_error_sigma = 0.0;

  double WithinPercent(int n) const;  // n = 1 … 10; throws Error otherwise
  double BinPercent(int n) const;     // n = 1 … 10; throws Error otherwise
  double MissingPercent() const;
  double Beyond10Percent() const;

  nlohmann::json ToJson() const;
};

// Computes the histogram defined above. Throws gcpstereo::Error when the maps are not CV_32F
// single-channel, the mask is not CV_8U, or the sizes differ (the message names both sizes).
SigmaHistogram EvaluateDepthSigma(const cv::Mat& depth, const cv::Mat& gt_depth,
                                  const cv::Mat& gt_sigma, const cv::Mat& mask = cv::Mat());

// One series of a histogram figure (e.g. "with GCPs" and "without GCPs" in Figure 4).
struct NamedHistogram {
  std::string name;
  SigmaHistogram histogram;
};

struct SigmaHistogramPlotOptions {
  int width_px = 800;       // image width in pixels, >= 320
  int height_px = 480;      // image height in pixels, >= 240
  bool cumulative = false;  // false: per-bin shares (Figure 4); true: cumulative "within n·σ"
  std::string title = "Depth error histogram (|depth - gt| / sigma)";

  // Throws ConfigError naming `eval.histogram.width_px` / `eval.histogram.height_px`.
  void Check() const;
};

// A bar chart in the style of the paper's Figure 4: x = bins 1σ … 10σ, ">10σ" and "missing",
// y = percent of counted pixels, one coloured bar per series per bin, a legend with each series'
// name and its "within 3σ" share. CV_8UC3 (BGR), white background. Throws Error when `series` is
// empty.
cv::Mat RenderSigmaHistogram(const std::vector<NamedHistogram>& series,
                             const SigmaHistogramPlotOptions& options = {});

// Error map of a depth estimate, colour-coded by e = |depth − gt| / σ (CV_8UC3, BGR):
//   counted, valid estimate: OpenCV's TURBO colour map of min(e, max_sigma) / max_sigma
//                            (dark blue = exact … dark red = max_sigma or worse);
//   counted, missing estimate: magenta (255, 0, 255);
//   GT unknown or outside the mask: black.
// Same input checks as EvaluateDepthSigma; max_sigma must be > 0.
cv::Mat RenderDepthErrorMap(const cv::Mat& depth, const cv::Mat& gt_depth, const cv::Mat& gt_sigma,
                            const cv::Mat& mask = cv::Mat(), double max_sigma = 10.0);

}  // namespace gcpstereo::eval
