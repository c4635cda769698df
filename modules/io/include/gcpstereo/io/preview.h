// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include <opencv2/core/mat.hpp>

namespace gcpstereo::io {

// Colour-maps a CV_32F depth (or disparity) map for a person to look at: values in [min, max] go
// through cv::COLORMAP_TURBO (min = dark blue, max = dark red; values outside are clamped), invalid
// pixels (non-finite or <= 0) are black, and a vertical colour scale bar with tick labels
// ("<value> <unit_label>") is appended on the right. Returns CV_8UC3 BGR, same height as `depth`
// (at least 160 rows: small maps are enlarged with nearest-neighbour so the labels stay legible).
// Throws Error when depth is not CV_32FC1 or min/max are not finite with min < max.
cv::Mat RenderDepthPreview(const cv::Mat& depth, double min, double max,
                           const std::string& unit_label);

// Chooses [min, max] for RenderDepthPreview as the 1st and 99th percentiles of the valid values
// (falls back to [0, 1] when there are none). Returns false when there is no valid value.
bool RobustValueRange(const cv::Mat& depth, double* min, double* max);

// Colour-maps an absolute error map (CV_32F, non-finite = not evaluated, black) on [0, max_error]
// with cv::COLORMAP_INFERNO and the same scale bar.
cv::Mat RenderErrorPreview(const cv::Mat& abs_error, double max_error,
                           const std::string& unit_label);

}  // namespace gcpstereo::io
