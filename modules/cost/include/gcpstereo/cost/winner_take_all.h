// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/core/labels.h"

namespace gcpstereo::cost {

// Winner-take-all: per pixel of the volume's region, the label of least cost among the labels that
// have data. Ties (equal quantised costs, frequent where a pixel-wise cost is flat) go to the
// middle one of the tied labels in label order (the lower middle for an even count): deterministic,
// and not biased towards the lowest label as "first minimum" would be. Returns a CV_32S map of the
// region's size; −1 where no label has data. Rows in parallel (deterministic).
cv::Mat WinnerTakeAll(const CostVolume& volume);

// How decisive each pixel's matching costs are, c_p in [0, 1] (CV_32F, the region's size): the
// peak ratio of the cost curve ("PKR" in Hu & Mordohai, "A Quantitative Evaluation of Confidence
// Measures for Stereo Vision", PAMI 2012), made bounded and defined where the best cost is 0:
//
//   c_p = 1 − (Φ1 + ε) / (Φ2 + ε)
//
// Φ1 = the lowest cost of the curve; Φ2 = the lowest cost among the curve's OTHER local minima
// (labels no higher than both neighbours, a plateau counted once at its first label), or the
// curve's highest cost when Φ1's minimum is the only one; ε = 1 % of the volume's max_cost, so
// that two small costs do not make a large ratio. Labels without data count as max_cost. A flat
// curve (sky, a blank wall) or two equally good minima (a repetitive texture) give 0; one sharp
// minimum gives close to 1; 0 where no label has data.
//
// radius > 0 first averages each label's cost over the (2·radius+1)² window around the pixel
// (clipped at the borders), as Hu & Mordohai score aggregated costs: a single pixel's
// Birchfield–Tomasi curve is noisy, the window's is not. O(pixels · labels) for any radius.
// Throws Error for an empty volume or a radius outside [0, kMaxConfidenceRadius]. Rows in
// parallel (deterministic).
inline constexpr int kMaxConfidenceRadius = 10;
cv::Mat PeakRatioConfidence(const CostVolume& volume, int radius = 0);

// Converts a label map — CV_32S (−1 or out of [0, count−1] = invalid) or CV_32F (fractional labels;
// negative, non-finite or beyond count−1 = invalid) — to CV_32F depth along the reference camera's
// z (labels.DepthOfLabel). Invalid labels, and labels of zero disparity / inverse depth, give
// kInvalidDepth (+inf).
cv::Mat LabelsToDepth(const cv::Mat& label_map, const LabelSpace& labels);

// Like LabelsToDepth but returns the label's value in the space's own unit (depth, inverse depth or
// disparity in the data set's GT convention); invalid labels give kInvalidDepth (+inf).
cv::Mat LabelsToValue(const cv::Mat& label_map, const LabelSpace& labels);

}  // namespace gcpstereo::cost
