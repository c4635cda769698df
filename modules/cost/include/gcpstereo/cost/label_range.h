// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "gcpstereo/core/labels.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::cost {

// How an automatic label range is found when labels.min / labels.max are omitted.
// YAML keys in brackets.
struct LabelRangeOptions {
  // [labels.auto.gcp_low_percentile], [labels.auto.gcp_high_percentile]: robust bounds of the GCP
  // depths, in percent (linear interpolation between order statistics).
  // Range: 0 <= low < high <= 100.
  double gcp_low_percentile = 1.0;
  double gcp_high_percentile = 99.0;
  // [labels.auto.margin]: relative widening of the range, dimensionless: [lo / (1 + m), hi · (1 +
  // m)] (multiplicative, so it stays positive and is symmetric in inverse depth). Range: m >= 0.
  double margin = 0.1;
  // [labels.auto.grid_step_px]: spacing of the reference pixels whose rays are intersected with the
  // neighbours' frusta, in pixels. Range: >= 1.
  int grid_step_px = 8;
  // [labels.auto.min_neighbors]: a depth counts when at least this many neighbours see it.
  // Range: >= 1.
  int min_neighbors = 1;
  // [labels.auto.max_depth]: upper bound of the frustum-overlap and matched ranges, in the data
  // set's depth unit (metres); +inf = unbounded (fine for inverse depth / disparity labels, where
  // depth +inf is the value 0; depth labels then need labels.max). Range: > 0.
  double max_depth = std::numeric_limits<double>::infinity();
  // [labels.auto.matching_far_percentile]: depth labels without GCPs and without labels.max, when
  // the smallest matched disparity is 0 (the range would be unbounded): the far end is taken at
  // this percentile of the matched disparities instead, in percent. A few percent of mismatches
  // at disparity 0 are common (the synthetic tiny scene's view 0003: between 2 and 5 %); a far
  // background larger than this share still leaves the range unbounded (use inverse depth).
  // Range: 0 <= p < 50 (0 keeps the error).
  double matching_far_percentile = 5.0;

  // Throws ConfigError naming the YAML key of the first invalid field.
  void Check() const;
};

// [low, high] percentiles of the GCP depths (in percent, 0…100), widened by `margin` as
// [p_low / (1 + margin), p_high · (1 + margin)]. GCPs with a non-finite or non-positive depth are
// ignored. Throws Error when no valid GCP remains; ConfigError for bad percentiles or margin
// (keys labels.auto.*).
std::pair<double, double> DepthRangeFromGcps(const GcpSet& gcps, double low_percentile,
                                             double high_percentile, double margin);

// The depths (reference camera z) at which the reference view's rays are seen by neighbours.
// For the reference pixels on a grid of options.grid_step_px (plus the last row/column), the ray
// X(z) = C + z·d is intersected exactly with each neighbour's viewing frustum: "in front of the
// camera and projecting inside the image (Camera::InImage)" is a set of linear inequalities in z
// (the projection is a ratio of affine functions of z), so each neighbour sees an interval of z.
// A depth counts when at least options.min_neighbors intervals contain it; the result is the
// smallest and largest counting depth over all rays, the far end capped at options.max_depth
// (+inf when unbounded and uncapped). Throws Error when no sampled ray is seen by enough
// neighbours, or on invalid cameras; ConfigError for bad options.
std::pair<double, double> DepthRangeFromFrustumOverlap(const View& reference,
                                                       const std::vector<View>& neighbors,
                                                       const LabelRangeOptions& options = {});

// The disparities a rectified pair's images show, for an automatic range before any stereo
// matching of the pipeline: OpenCV's semi-global matcher (cv::StereoSGBM, 5×5 blocks, uniqueness
// 10 %, left-right check to 1 px) on both images at half resolution (at most 640 px wide; full
// resolution below 200 px), searched over every disparity below the width (the left image is
// padded by the search range so that its left columns are matched too). Disparities of connected
// regions smaller than 0.5 % of the image, or varying by more than 1 px inside a region, are
// dropped as mismatches; so are pixels whose 5×5 block has no texture (grey-level variance below
// 1), which match every disparity alike, and pixels where `left_valid` (optional, CV_8U) is 0.
// The result is the smallest (or, with `low_percentile` > 0, that percentile, in percent, of the)
// and the largest surviving disparity, in pixels of `left` (left x minus right x); std::nullopt
// when nothing survives (e.g. a textureless pair). `left` and `right` are 8-bit BGR or grey images
// of one size.
std::optional<std::pair<double, double>> DisparityRangeFromMatching(
    const cv::Mat& left, const cv::Mat& right, const cv::Mat& left_valid = cv::Mat(),
    double low_percentile = 0.0);

// The depths (reference camera z) the views show, [near, far] (far = +inf for disparity 0), from
// DisparityRangeFromMatching: on the rectified pair of the reference and its first neighbour
// (`rectified_pair`, the neighbour right of the reference), or, for calibrated views, on the
// reference rectified with its nearest neighbour (RectifyCalibratedPair; the first that
// rectifies horizontally), the rectified depths bounded in the reference's z over the image's
// corners. std::nullopt when there is no usable neighbour or nothing matched. `low_percentile`
// is DisparityRangeFromMatching's (it sets the far end).
std::optional<std::pair<double, double>> DepthRangeFromMatching(const View& reference,
                                                                const std::vector<View>& neighbors,
                                                                bool rectified_pair,
                                                                double low_percentile = 0.0);

// Where MakeLabelSpace took its range from.
struct LabelRangeSummary {
  std::string source;  // "config", "gcps", "matching", "matching-percentile" (far end from
                       // labels.auto.matching_far_percentile), "gcps+matching", "frustum", or e.g.
                       // "config+gcps" when a bound was given
  double depth_min = 0.0;  // the automatic depth range, when one was computed (else 0)
  double depth_max = 0.0;
};

// The result of DepthRangeFromMatching kept between calls of MakeLabelSpace on the same views (a
// run builds a provisional label space for the stereo GCPs' search and then the final one; the
// images, and so the matched range, are the same both times).
struct MatchedDepthRange {
  bool computed = false;
  std::optional<std::pair<double, double>> depths;
};

// Builds the label space of the run (configuration keys labels.space, labels.count, labels.min,
// labels.max): `count` labels equally spaced in `kind` between min and max (in the space's unit;
// disparity in the data set's GT convention, disparity = disparity_numerator / depth).
// A missing bound is filled from an automatic depth range. When no GCP comes from a range sensor
// (all are stereo GCPs, or there are none), the depths the views show (DepthRangeFromMatching,
// widened by options.margin as the GCP range) come first: without GCPs they are the range; with
// stereo GCPs they extend its near end, since image matches are scarce on the nearest surfaces (the
// matcher's far end is often the sky at disparity 0, so the far end stays the GCPs'). Otherwise
// (LiDAR or depth-image GCPs, or nothing matched) the range is the GCPs' (DepthRangeFromGcps), or
// without GCPs the frustum overlap of `reference` and `neighbors`. The depth range [z_min, z_max]
// maps to [z_min, z_max] (depth), [1/z_max, 1/z_min] (inverse depth) or [num/z_max, num/z_min]
// (disparity), with 1/+inf = 0. Throws ConfigError when a depth space would need an unbounded
// maximum (set labels.max or labels.auto.max_depth), or when the result is not a valid LabelSpace.
// Disparity labels: an automatic minimum is 0 (infinite depth). A range starting at the nearest
// matched background leaves the band along the left border, which the right image does not see,
// without a label of any data (Rocks1, labels 17…61 against 0…61: bad-1 all 10.61 % against
// 4.72 %). Without `count` (labels.count auto) there is one label per pixel of disparity: the
// automatic bounds are rounded outward to whole pixels and count = ⌈max − min⌉ + 1; other spaces
// need a count. `matched_cache` (optional): the views' matched range is taken from it when it has
// been computed, and stored in it otherwise; pass the same one only for the same views.
LabelSpace MakeLabelSpace(LabelSpaceKind kind, std::optional<int> count, std::optional<double> min,
                          std::optional<double> max, const GcpSet& gcps, const View& reference,
                          const std::vector<View>& neighbors, double disparity_numerator,
                          bool rectified_pair, const LabelRangeOptions& options = {},
                          LabelRangeSummary* summary = nullptr,
                          MatchedDepthRange* matched_cache = nullptr);

}  // namespace gcpstereo::cost
