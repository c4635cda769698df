// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/cost/cost_filter.h"

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
  // [cost.census_window_px]: side of the square census-transform window (Zabih & Woodfill, ECCV
  // 1994) on the grey image, in pixels; 1 = no census term (the paper). With a census window the
  // pixel cost becomes min(BT, bt_truncation) + census_weight · Hamming(census_L, census_R), as in
  // the AD-Census family of costs (Mei et al. 2011): the census term is invariant to monotonic
  // intensity changes between the views and lends the cost the local texture. Range: odd,
  // 1 <= census_window_px <= 7 (at most 48 bits).
  int census_window_px = 1;
  // [cost.census_weight]: cost of one differing census bit, in the grey levels of the BT term.
  // Range: census_weight >= 0.
  double census_weight = 2.0;
  // [cost.census_mask_threshold]: census bits only from the neighbours whose grey level differs
  // from the centre's by at most this many levels, in the reference image; 0 = every bit. Near a
  // depth edge, the neighbours across it usually differ in colour and belong to the other surface:
  // at the true disparity their bits disagree between the views and pull the cost toward the
  // other surface's disparity (foreground fattening). The Hamming distance over the kept bits is
  // scaled by (all bits / kept bits) to stay comparable between pixels; a pixel with fewer than a
  // quarter of its bits kept (a bright speck) uses them all. Not in the paper. Measured on
  // Middlebury (configs/middlebury_stereo.yaml). Range: 0 <= threshold <= 255.
  int census_mask_threshold = 0;
  // [cost.window_px], [cost.window_filter], [cost.guided_epsilon]: aggregation of the pixel cost
  // over a window (see cost_filter.h); window_px 1 = pixel-wise (the paper).
  CostFilterOptions window;

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
// Extensions beyond the paper (both off by default): options.census_window_px > 1 adds
// census_weight · Hamming(census of L at x, census of R at x_r) (grey census, bit = neighbour
// darker than the centre, border replicated; fractional x_r interpolates the Hamming distances of
// the two integer neighbours linearly; options.census_mask_threshold > 0 counts only the bits of
// the neighbours of similar grey level in `left`, scaled to the full count); options.window filters
// each disparity's slice with a box or guided filter (FilterCostVolume) — the pixel costs are then
// computed on `region` grown by the filter's margin (clipped to the image), so a tile's costs equal
// the whole image's. Quantisation: max_cost = truncation + census_weight · (census_window_px² − 1);
// 16-bit step max_cost / 65534 (CostVolume). Fractional d: R(x_r) and R(x_r ± ½) are sampled by
// linear interpolation (integer d reduces to the textbook definition). Border policy: x_r outside
// [0, width−1] → no data (CostVolume::kNoData); half-pixel neighbours beyond the border replicate
// the border pixel. The volume covers `region` of `left`; label l is disparities_px[l]; max_cost =
// truncation without census. Images: CV_8UC3 (BGR) or CV_8UC1, same type and size. Rows are
// computed in parallel; the result does not depend on the thread count. Throws Error for bad
// images, an empty disparity list, a non-finite disparity or a region outside `left`; ConfigError
// for bad options. With `bands` (over `region`, see LabelBands), only the entries in them are
// computed (and, with a window, the pixel costs within the filter's margin of them).
CostVolume ComputeBirchfieldTomasiCost(const cv::Mat& left, const cv::Mat& right,
                                       const std::vector<double>& disparities_px,
                                       const cv::Rect& region,
                                       const BirchfieldTomasiOptions& options = {},
                                       const LabelBands* bands = nullptr);

}  // namespace gcpstereo::cost
