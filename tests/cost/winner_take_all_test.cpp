// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/winner_take_all.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

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

// The peak ratio by hand: c = 1 − (Φ1 + ε)/(Φ2 + ε), ε = 1 % of max_cost, Φ2 the next local
// minimum (or the highest cost); quantisation of the stored costs ≤ max_cost/65534.
TEST(PeakRatioConfidence, HandComputedCurves) {
  CostVolume v(cv::Rect(0, 0, 6, 1), 7, 100.0f);
  const float costs[6][7] = {
      {50, 50, 50, 50, 50, 50, 50},  // flat: 0
      {90, 10, 60, 70, 10, 80, 90},  // two equal minima (a repeated texture): 0
      {90, 30, 0, 30, 60, 80, 90},   // one minimum, no other: Φ2 = the highest cost, 90
      {20, 30, 10, 40, 50, 40, 60},  // minima 10 (label 2), 20 (label 0), 40 (label 5): Φ2 = 20
      {60, 0, 0, 0, 40, 30, 70},     // a plateau of minima is one minimum: Φ2 = 30
      {0, 0, 0, 0, 0, 0, 0}};        // no data at all (set below): 0
  for (int c = 0; c < 6; ++c) {
    for (int l = 0; l < 7; ++l) v.SetCost(0, c, l, costs[c][l]);
  }
  for (int l = 0; l < 7; ++l) v.SetNoData(0, 5, l);
  const cv::Mat c = PeakRatioConfidence(v);
  ASSERT_EQ(c.type(), CV_32F);
  ASSERT_EQ(c.size(), cv::Size(6, 1));
  const double tolerance = 100.0 / 65534.0;
  EXPECT_NEAR(c.at<float>(0, 0), 0.0, 1e-6);
  EXPECT_NEAR(c.at<float>(0, 1), 0.0, 1e-6);
  EXPECT_NEAR(c.at<float>(0, 2), 1.0 - (0.0 + 1.0) / (90.0 + 1.0), tolerance);
  EXPECT_NEAR(c.at<float>(0, 3), 1.0 - (10.0 + 1.0) / (20.0 + 1.0), tolerance);
  EXPECT_NEAR(c.at<float>(0, 4), 1.0 - (0.0 + 1.0) / (30.0 + 1.0), tolerance);
  EXPECT_EQ(c.at<float>(0, 5), 0.0f);
  // Labels without data count as max_cost: they neither win nor make a minimum.
  CostVolume w(cv::Rect(0, 0, 1, 1), 4, 100.0f);
  w.SetNoData(0, 0, 0);
  w.SetCost(0, 0, 1, 20);
  w.SetNoData(0, 0, 2);
  w.SetCost(0, 0, 3, 50);
  EXPECT_NEAR(PeakRatioConfidence(w).at<float>(0, 0), 1.0 - 21.0 / 51.0, tolerance);
  EXPECT_THROW(PeakRatioConfidence(CostVolume()), Error);
}

// With a window, c_p is the peak ratio of the window's mean cost curve (clipped at the borders):
// a lone sharp pixel among flat ones is far less certain than its own curve says, and a region
// of one repeated curve is as certain as that curve.
TEST(PeakRatioConfidence, WindowAveragesTheCostsFirst) {
  CostVolume v(cv::Rect(0, 0, 5, 4), 3, 100.0f);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 5; ++c) {
      v.SetCost(r, c, 0, 90);
      v.SetCost(r, c, 1, 90);
      v.SetCost(r, c, 2, 90);
    }
  }
  v.SetCost(1, 1, 0, 0);  // one sharp pixel
  const double tolerance = 100.0 / 65534.0;
  const cv::Mat own = PeakRatioConfidence(v, 0);
  EXPECT_NEAR(own.at<float>(1, 1), 1.0 - 1.0 / 91.0, tolerance);
  EXPECT_NEAR(own.at<float>(2, 3), 0.0, 1e-6);
  const cv::Mat window = PeakRatioConfidence(v, 1);
  // (1, 1)'s 3×3 window: label 0 averages (8·90 + 0)/9 = 80.
  EXPECT_NEAR(window.at<float>(1, 1), 1.0 - 81.0 / 91.0, tolerance);
  // (0, 0)'s window is clipped to 2×2 and holds the sharp pixel: (3·90 + 0)/4 = 67.5.
  EXPECT_NEAR(window.at<float>(0, 0), 1.0 - 68.5 / 91.0, tolerance);
  // (3, 4) is out of the sharp pixel's reach: flat.
  EXPECT_NEAR(window.at<float>(3, 4), 0.0, 1e-6);
  // radius 2 at (3, 3): the window rows 1…3, cols 1…4 (12 pixels) holds it: (11·90)/12 = 82.5.
  EXPECT_NEAR(PeakRatioConfidence(v, 2).at<float>(3, 3), 1.0 - 83.5 / 91.0, tolerance);

  CostVolume same(cv::Rect(0, 0, 6, 5), 4, 100.0f);
  const float curve[4] = {40, 5, 60, 30};
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 6; ++c) {
      for (int l = 0; l < 4; ++l) same.SetCost(r, c, l, curve[l]);
    }
  }
  const cv::Mat a = PeakRatioConfidence(same, 0);
  const cv::Mat b = PeakRatioConfidence(same, 3);
  EXPECT_EQ(cv::countNonZero(a != b), 0);
  EXPECT_NEAR(a.at<float>(2, 2), 1.0 - 6.0 / 31.0, tolerance);
  EXPECT_THROW(PeakRatioConfidence(same, -1), Error);
  EXPECT_THROW(PeakRatioConfidence(same, kMaxConfidenceRadius + 1), Error);
}

// The sliding window against a direct sum over every window, on random costs (some without data)
// and enough rows for the rows to be split between threads.
TEST(PeakRatioConfidence, SlidingWindowMatchesDirectSums) {
  const int width = 23, height = 97, num_labels = 9;
  CostVolume v(cv::Rect(0, 0, width, height), num_labels, 50.0f);
  cv::RNG rng(7);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      for (int l = 0; l < num_labels; ++l) {
        if (rng.uniform(0, 20) == 0) {
          v.SetNoData(r, c, l);
        } else {
          v.SetCost(r, c, l, rng.uniform(0.0f, 50.0f));
        }
      }
    }
  }
  constexpr double kFullScale = CostVolume::kNoData - 1;
  for (int radius : {1, 3}) {
    const cv::Mat c = PeakRatioConfidence(v, radius);
    for (int row = 0; row < height; ++row) {
      for (int col = 0; col < width; ++col) {
        std::vector<double> curve(num_labels, 0.0);
        int count = 0;
        for (int r = std::max(0, row - radius); r <= std::min(height - 1, row + radius); ++r) {
          for (int q = std::max(0, col - radius); q <= std::min(width - 1, col + radius); ++q) {
            ++count;
            for (int l = 0; l < num_labels; ++l) {
              curve[l] += std::min<double>(v.PixelData(r, q)[l], kFullScale);
            }
          }
        }
        for (double& x : curve) x /= count;
        const int best =
            static_cast<int>(std::min_element(curve.begin(), curve.end()) - curve.begin());
        double second = *std::max_element(curve.begin(), curve.end());
        for (int l = 0; l < num_labels; ++l) {
          const bool minimum = (l == 0 || curve[l] < curve[l - 1]) &&
                               (l + 1 == num_labels || curve[l] <= curve[l + 1]);
          if (l != best && minimum) second = std::min(second, curve[l]);
        }
        const double epsilon = 0.01 * kFullScale;
        ASSERT_NEAR(c.at<float>(row, col), 1.0 - (curve[best] + epsilon) / (second + epsilon), 1e-5)
            << "radius " << radius << " at " << row << ", " << col;
      }
    }
  }
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
