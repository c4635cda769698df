// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/winner_take_all.h"

#include <cmath>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::cost {
namespace {

TEST(WinnerTakeAll, PicksLeastCostSkipsNoDataAndBreaksTiesInTheMiddle) {
  CostVolume v(cv::Rect(10, 20, 3, 2), 4, 100.0f);
  // (0,0): plain minimum at label 2.
  v.SetCost(0, 0, 0, 50);
  v.SetCost(0, 0, 1, 40);
  v.SetCost(0, 0, 2, 10);
  v.SetCost(0, 0, 3, 60);
  // (0,1): tie between labels 1 and 3 → the lower middle, 1; label 0 has no data.
  v.SetNoData(0, 1, 0);
  v.SetCost(0, 1, 1, 5);
  v.SetCost(0, 1, 2, 9);
  v.SetCost(0, 1, 3, 5);
  // (0,2): only label 3 has data, at the maximum cost.
  v.SetCost(0, 2, 3, 100);
  // (1,0): no data at all. (1,1): costs above max_cost are clamped; label 0 wins at 0.
  v.SetCost(1, 1, 0, 0);
  v.SetCost(1, 1, 1, 1e6f);
  const cv::Mat wta = WinnerTakeAll(v);
  ASSERT_EQ(wta.type(), CV_32S);
  ASSERT_EQ(wta.size(), cv::Size(3, 2));
  EXPECT_EQ(wta.at<int>(0, 0), 2);
  EXPECT_EQ(wta.at<int>(0, 1), 1);
  EXPECT_EQ(wta.at<int>(0, 2), 3);
  EXPECT_EQ(wta.at<int>(1, 0), -1);
  EXPECT_EQ(wta.at<int>(1, 1), 0);
  EXPECT_EQ(wta.at<int>(1, 2), -1);
}

// Flat costs (a run of equal minima, typical of pixel-wise BT in weak texture) go to the middle of
// the tied labels, not to the lowest one.
TEST(WinnerTakeAll, TiesGoToTheMiddleOfTheTiedLabels) {
  CostVolume v(cv::Rect(0, 0, 4, 1), 7, 100.0f);
  const float costs[4][7] = {{9, 1, 1, 1, 9, 9, 9},   // tied 1, 2, 3 → 2
                             {0, 0, 0, 0, 0, 0, 0},   // all tied → 3
                             {5, 2, 7, 2, 7, 2, 2},   // tied 1, 3, 5, 6 → lower middle 3
                             {2, 4, 4, 4, 4, 4, 4}};  // unique minimum 0
  for (int c = 0; c < 4; ++c) {
    for (int l = 0; l < 7; ++l) v.SetCost(0, c, l, costs[c][l]);
  }
  v.SetNoData(0, 3, 5);
  const cv::Mat wta = WinnerTakeAll(v);
  EXPECT_EQ(wta.at<int>(0, 0), 2);
  EXPECT_EQ(wta.at<int>(0, 1), 3);
  EXPECT_EQ(wta.at<int>(0, 2), 3);
  EXPECT_EQ(wta.at<int>(0, 3), 0);
}

TEST(WinnerTakeAll, LabelsToDepthAndValue) {
  const LabelSpace disparity(LabelSpaceKind::kDisparity, 5, 0.0, 8.0, 16.0);  // step 2 px
  cv::Mat labels = (cv::Mat_<int>(1, 5) << -1, 0, 1, 4, 5);
  const cv::Mat depth = LabelsToDepth(labels, disparity);
  const cv::Mat value = LabelsToValue(labels, disparity);
  ASSERT_EQ(depth.type(), CV_32F);
  EXPECT_EQ(depth.at<float>(0, 0), kInvalidDepth);
  EXPECT_EQ(depth.at<float>(0, 1), kInvalidDepth);  // disparity 0: infinitely far
  EXPECT_FLOAT_EQ(depth.at<float>(0, 2), 8.0f);     // 16 / 2
  EXPECT_FLOAT_EQ(depth.at<float>(0, 3), 2.0f);     // 16 / 8
  EXPECT_EQ(depth.at<float>(0, 4), kInvalidDepth);  // beyond the last label
  EXPECT_EQ(value.at<float>(0, 0), kInvalidDepth);
  EXPECT_FLOAT_EQ(value.at<float>(0, 1), 0.0f);
  EXPECT_FLOAT_EQ(value.at<float>(0, 3), 8.0f);

  const LabelSpace depth_space(LabelSpaceKind::kDepth, 3, 2.0, 4.0);
  cv::Mat fractional = (cv::Mat_<float>(1, 4) << 0.5f, 2.0f, NAN, -0.1f);
  const cv::Mat d2 = LabelsToDepth(fractional, depth_space);
  EXPECT_FLOAT_EQ(d2.at<float>(0, 0), 2.5f);
  EXPECT_FLOAT_EQ(d2.at<float>(0, 1), 4.0f);
  EXPECT_EQ(d2.at<float>(0, 2), kInvalidDepth);
  EXPECT_EQ(d2.at<float>(0, 3), kInvalidDepth);

  try {
    LabelsToDepth(cv::Mat(2, 2, CV_8U), depth_space);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "LabelsToDepth: the label map must be CV_32S or CV_32F");
  }
}

}  // namespace
}  // namespace gcpstereo::cost
