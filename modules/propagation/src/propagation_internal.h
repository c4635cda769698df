// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Input checks shared by the two propagation methods (propagation.cc, weighted_median.cc).
#pragma once

#include <opencv2/core/mat.hpp>

#include "gcpstereo/propagation/propagation.h"

namespace gcpstereo::propagation::internal {

// options.Check(), then: image_bgr a non-empty CV_8UC3, sparse_values CV_32F of its size. Throws
// ConfigError / Error with the messages documented on Propagate.
void CheckPropagationInputs(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                            const PropagationOptions& options);

}  // namespace gcpstereo::propagation::internal
