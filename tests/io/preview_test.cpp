// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/preview.h"

#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::io {
namespace {

cv::Mat Ramp(int rows, int cols) {
  cv::Mat depth(rows, cols, CV_32F);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) depth.at<float>(r, c) = 2.0f + 8.0f * c / (cols - 1);
  }
  return depth;
}

TEST(Preview, DepthPreviewColorsInvalidBlackAndAddsScale) {
  cv::Mat depth = Ramp(300, 400);
  depth(cv::Rect(10, 10, 20, 20)).setTo(kInvalidDepth);
  const cv::Mat preview = RenderDepthPreview(depth, 2.0, 10.0, "m");
  ASSERT_EQ(preview.type(), CV_8UC3);
  EXPECT_EQ(preview.rows, 300);
  EXPECT_GT(preview.cols, 400);  // the scale bar panel
  EXPECT_EQ(preview.at<cv::Vec3b>(15, 15), cv::Vec3b(0, 0, 0));
  // Near = blue end of TURBO, far = red end.
  const cv::Vec3b near = preview.at<cv::Vec3b>(150, 0);
  const cv::Vec3b far = preview.at<cv::Vec3b>(150, 399);
  EXPECT_GT(near[0], near[2]);
  EXPECT_GT(far[2], far[0]);
  // The panel holds dark text pixels (the tick labels) on white.
  const cv::Mat panel = preview(cv::Rect(400, 0, preview.cols - 400, 300));
  cv::Mat gray;
  cv::extractChannel(panel, gray, 1);
  EXPECT_GT(cv::countNonZero(gray < 64), 50);
}

TEST(Preview, SmallMapsAreEnlarged) {
  const cv::Mat preview = RenderDepthPreview(Ramp(20, 30), 2.0, 10.0, "m");
  EXPECT_GE(preview.rows, 160);
}

TEST(Preview, BadArguments) {
  EXPECT_THROW(RenderDepthPreview(cv::Mat(4, 4, CV_8U), 0, 1, "m"), Error);
  try {
    RenderDepthPreview(Ramp(4, 4), 3.0, 3.0, "m");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("min < max"), std::string::npos) << e.what();
  }
}

TEST(Preview, RobustRange) {
  double lo = 0, hi = 0;
  EXPECT_TRUE(RobustValueRange(Ramp(50, 101), &lo, &hi));
  EXPECT_NEAR(lo, 2.08, 0.05);
  EXPECT_NEAR(hi, 9.92, 0.05);
  cv::Mat invalid(5, 5, CV_32F, cv::Scalar(kInvalidDepth));
  EXPECT_FALSE(RobustValueRange(invalid, &lo, &hi));
}

TEST(Preview, ErrorPreview) {
  cv::Mat error = Ramp(200, 200) - 2.0f;
  const cv::Mat preview = RenderErrorPreview(error, 4.0, "px");
  EXPECT_EQ(preview.type(), CV_8UC3);
  EXPECT_EQ(preview.rows, 200);
}

}  // namespace
}  // namespace gcpstereo::io
