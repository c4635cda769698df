// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/cost_volume.h"

namespace gcpstereo::cost {

// Options of the Birchfield–Tomasi cost for a rectified pair. YAML keys in brackets.
struct BirchfieldTomasiOptions {
  // [cost.bt_truncation]: the cost is min(BT, truncation), in grey levels of the combined channels
  // (sum over RGB: 0…765; max over RGB or grey images: 0…255). The paper (eq. 2) does not truncate;
  // the default 765 keeps sums untruncated (a lower value, e.g. 60, makes the data term robust to
  // occlusions for the optimiser). Range: truncation > 0.
  double truncation = 765.0;
  // [cost.bt_channels]: how the per-channel dissimilarities are combined: "sum" (default) or "max".
  std::string channels = "sum";

  // Throws ConfigError naming the YAML key of the first invalid field.
  void Check() const;
};

// Birchfield & Tomasi, "A pixel dissimilarity measure that is insensitive to image sampling",
// PAMI 20(4), 1998 — the data cost Φ of Wang & Yang (CVPR 2011), eq. (2), for rectified pairs.
//
// Reference pixel (x, y) of `left` at disparity d is matched with position x_r = x − d of the same
// row of `right` (d ≥ 0 for a left reference; pass negative d for a right reference). Per channel,
// with I⁻ / I⁺ the linearly interpolated values half a pixel left / right:
//   d(L→R) = max(0, L(x) − R_max, R_min − L(x)),  R_min/max = min/max{R(x_r−½), R(x_r), R(x_r+½)}
//   d(R→L) = max(0, R(x_r) − L_max, L_min − R(x_r)),  L_min/max likewise around x
//   BT = min(d(L→R), d(R→L))
// combined over the channels by options.channels (sum or max) and truncated at options.truncation.
// Fractional d: R(x_r) and R(x_r ± ½) are sampled by linear interpolation (integer d reduces to the
// textbook definition). Border policy: x_r outside [0, width−1] → no data (CostVolume::kNoData);
// half-pixel neighbours beyond the border replicate the border pixel.
// The volume covers `region` of `left`; label l is disparities_px[l]; max_cost = truncation.
// Images: CV_8UC3 (BGR) or CV_8UC1, same type and size. Rows are computed in parallel; the result
// does not depend on the thread count. Throws Error for bad images, an empty disparity list, a
// non-finite disparity or a region outside `left`; ConfigError for bad options.
CostVolume ComputeBirchfieldTomasiCost(const cv::Mat& left, const cv::Mat& right,
                                       const std::vector<double>& disparities_px,
                                       const cv::Rect& region,
                                       const BirchfieldTomasiOptions& options = {});

}  // namespace gcpstereo::cost
