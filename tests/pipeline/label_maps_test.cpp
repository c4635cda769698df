// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The pipeline's label-map conversions (internal to the pipeline, pipeline/src/stages.h).
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/labels.h"
#include "stages.h"

namespace gcpstereo::pipeline::internal {
namespace {

// Labels a rounding error above label 0 of a disparity range starting at 0 are label 0 (+inf
// depth, disparity 0), not depths of 10²⁷ m; other labels convert exactly.
TEST(LabelMaps, LabelsJustAboveZeroAreLabelZero) {
  const LabelSpace labels(LabelSpaceKind::kDisparity, 128, 0.0, 127.0, 384.0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const cv::Mat map = (cv::Mat_<float>(1, 7) << 0.0f, 7.9e-26f, 5e-4f, 0.5f, 96.0f, -1.0f, nan);
  const cv::Mat depth = LabelMapToDepth(map, labels);
  const cv::Mat disparity = LabelMapToDisparity(map, labels, 384.0);
  const float inf = std::numeric_limits<float>::infinity();
  const float expected_depth[] = {inf, inf, inf, 768.0f, 4.0f, inf, inf};
  const float expected_disparity[] = {0.0f, 0.0f, 0.0f, 0.5f, 96.0f, inf, inf};
  for (int c = 0; c < 7; ++c) {
    EXPECT_EQ(depth.at<float>(0, c), expected_depth[c]) << c;
    EXPECT_EQ(disparity.at<float>(0, c), expected_disparity[c]) << c;
  }
}

}  // namespace
}  // namespace gcpstereo::pipeline::internal
