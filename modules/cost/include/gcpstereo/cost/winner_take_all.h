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

// Converts a label map — CV_32S (−1 or out of [0, count−1] = invalid) or CV_32F (fractional labels;
// negative, non-finite or beyond count−1 = invalid) — to CV_32F depth along the reference camera's
// z (labels.DepthOfLabel). Invalid labels, and labels of zero disparity / inverse depth, give
// kInvalidDepth (+inf).
cv::Mat LabelsToDepth(const cv::Mat& label_map, const LabelSpace& labels);

// Like LabelsToDepth but returns the label's value in the space's own unit (depth, inverse depth or
// disparity in the data set's GT convention); invalid labels give kInvalidDepth (+inf).
cv::Mat LabelsToValue(const cv::Mat& label_map, const LabelSpace& labels);

}  // namespace gcpstereo::cost
