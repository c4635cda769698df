// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Segment-wise plane fitting on two-region scenes whose true disparities are known.
#include "gcpstereo/optimize/plane_fit.h"

#include <cmath>
#include <cstdint>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::optimize {
namespace {

// 120×60: the left 60 columns orange, the rest blue (two colour segments). True disparity: a
// slanted plane on the left, a fronto-parallel one at 12 on the right.
constexpr int kCols = 120, kRows = 60, kSplit = 60;
double TrueDisparity(int x, int y) { return x < kSplit ? 3.0 + 0.05 * x + 0.02 * y : 12.0; }

cv::Mat TwoRegionImage() {
  cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar(40, 120, 220));
  image.colRange(kSplit, kCols).setTo(cv::Scalar(200, 90, 30));
  return image;
}
cv::Mat TrueMap() {
  cv::Mat d(kRows, kCols, CV_32F);
  for (int y = 0; y < kRows; ++y) {
    for (int x = 0; x < kCols; ++x) d.at<float>(y, x) = static_cast<float>(TrueDisparity(x, y));
  }
  return d;
}
// The right surface spills 2 px over the left one's edge (foreground fattening), and a few
// mismatches lie inside the left one, two nearer than it, one farther.
cv::Mat CorruptedMap() {
  cv::Mat d = TrueMap();
  d.colRange(kSplit - 2, kSplit).setTo(12.0f);
  d.at<float>(10, 5) = 0.0f;
  d.at<float>(30, 20) = 19.0f;
  d.at<float>(50, 30) = 7.5f;
  return d;
}
// Flat colours: hardly any smoothing before segmenting, or the blended columns at the edge form
// thin segments of their own.
PlaneFitOptions Sharp() {
  PlaneFitOptions options;
  options.segmentation.sigma = 0.1;
  return options;
}
double MaxError(const cv::Mat& d) {
  double worst = 0.0;
  for (int y = 0; y < kRows; ++y) {
    for (int x = 0; x < kCols; ++x) {
      worst = std::max(worst, std::abs(d.at<float>(y, x) - TrueDisparity(x, y)));
    }
  }
  return worst;
}

TEST(PlaneFit, ColourSegmentsFollowTheImage) {
  const cv::Mat segments = SegmentImage(TwoRegionImage(), Sharp().segmentation);
  ASSERT_EQ(segments.type(), CV_32S);
  EXPECT_NE(segments.at<int>(0, 0), segments.at<int>(0, kCols - 1));
  for (int y = 0; y < kRows; ++y) {
    for (int x = 0; x < kCols; ++x) {
      const int expected = x < kSplit ? segments.at<int>(0, 0) : segments.at<int>(0, kCols - 1);
      ASSERT_EQ(segments.at<int>(y, x), expected) << x << "," << y;
    }
  }
}

TEST(PlaneFit, FatteningAndNearerMismatchesTakeTheirSegmentsPlane) {
  cv::Mat d = CorruptedMap();
  ASSERT_GT(MaxError(d), 6.0);
  const PlaneFitSummary summary =
      FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), Sharp(), &d);
  EXPECT_EQ(summary.segments, 2);
  EXPECT_EQ(summary.fitted_segments, 2);
  EXPECT_EQ(summary.changed_pixels, 2 * kRows + 2);
  // The farther mismatch keeps its value (only_farther): a dip below a plane is relief as often
  // as it is an error; every other pixel is the truth.
  EXPECT_FLOAT_EQ(d.at<float>(10, 5), 0.0f);
  d.at<float>(10, 5) = static_cast<float>(TrueDisparity(5, 10));
  EXPECT_LT(MaxError(d), 1e-3);
}

TEST(PlaneFit, BothDirectionsWithoutOnlyFarther) {
  cv::Mat d = CorruptedMap();
  PlaneFitOptions options = Sharp();
  options.only_farther = false;
  EXPECT_EQ(FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), options, &d).changed_pixels,
            2 * kRows + 3);
  EXPECT_LT(MaxError(d), 1e-3);
}

TEST(PlaneFit, FrozenPixelsKeepTheirValues) {
  cv::Mat d = CorruptedMap();
  cv::Mat frozen(kRows, kCols, CV_8U, cv::Scalar(0));
  frozen.colRange(kSplit - 1, kSplit).setTo(255);  // e.g. occluded pixels already filled
  FitSegmentPlanes(TwoRegionImage(), cv::Mat(), frozen, Sharp(), &d);
  for (int y = 0; y < kRows; ++y) {
    EXPECT_EQ(d.at<float>(y, kSplit - 1), 12.0f);
    EXPECT_NEAR(d.at<float>(y, kSplit - 2), TrueDisparity(kSplit - 2, y), 1e-3);
  }
}

TEST(PlaneFitOutliersOnly, PixelsOnThePlaneKeepTheirValues) {
  // Integer disparities of the slanted plane are all within 1 px of it: none changes.
  cv::Mat d = TrueMap();
  for (int y = 0; y < kRows; ++y) {
    for (int x = 0; x < kCols; ++x) d.at<float>(y, x) = std::round(d.at<float>(y, x));
  }
  const cv::Mat rounded = d.clone();
  const PlaneFitSummary summary =
      FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), Sharp(), &d);
  EXPECT_EQ(summary.changed_pixels, 0);
  EXPECT_EQ(cv::norm(d, rounded, cv::NORM_INF), 0.0);
}

TEST(PlaneFitReplaceAll, QuantisedSlantBecomesThePlane) {
  cv::Mat d = TrueMap();
  for (int y = 0; y < kRows; ++y) {
    for (int x = 0; x < kCols; ++x) d.at<float>(y, x) = std::round(d.at<float>(y, x));
  }
  ASSERT_GT(MaxError(d), 0.45);
  PlaneFitOptions options = Sharp();
  options.replace_all = true;
  options.only_farther = false;
  FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), options, &d);
  EXPECT_LT(MaxError(d), 0.1);  // the least-squares plane of the rounded values
}

TEST(PlaneFit, SegmentOnTwoSurfacesIsLeftAlone) {
  // One colour, two depths: no plane holds 90 % of the segment.
  const cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::Mat d(kRows, kCols, CV_32F, cv::Scalar(2.0f));
  d.rowRange(0, kRows / 3).setTo(8.0f);
  const cv::Mat original = d.clone();
  const PlaneFitSummary summary = FitSegmentPlanes(image, cv::Mat(), cv::Mat(), Sharp(), &d);
  EXPECT_EQ(summary.fitted_segments, 0);
  EXPECT_EQ(cv::norm(d, original, cv::NORM_INF), 0.0);
}

TEST(PlaneFit, OnlySupportPixelsDecideThePlane) {
  // Half of the left segment is wrong, but only the correct half supports the fit.
  cv::Mat d = TrueMap();
  d(cv::Rect(0, 0, kSplit, kRows / 2)).setTo(15.0f);
  cv::Mat support(kRows, kCols, CV_8U, cv::Scalar(255));
  support(cv::Rect(0, 0, kSplit, kRows / 2)).setTo(0);
  cv::Mat unsupported = d.clone();
  EXPECT_EQ(FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), Sharp(), &unsupported)
                .fitted_segments,
            1);
  FitSegmentPlanes(TwoRegionImage(), support, cv::Mat(), Sharp(), &d);
  EXPECT_LT(MaxError(d), 1e-3);
}

TEST(PlaneFit, UnknownPixelsStayUnknownAndSmallSupportIsLeftAlone) {
  cv::Mat d = CorruptedMap();
  const float inf = std::numeric_limits<float>::infinity();
  d.at<float>(5, 5) = inf;
  d.at<float>(6, 6) = std::numeric_limits<float>::quiet_NaN();
  cv::Mat copy = d.clone();
  FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), Sharp(), &d);
  EXPECT_EQ(d.at<float>(5, 5), inf);
  EXPECT_TRUE(std::isnan(d.at<float>(6, 6)));
  PlaneFitOptions strict = Sharp();
  strict.min_support_px = kRows * kCols;  // more than any segment holds
  EXPECT_EQ(FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), strict, &copy).changed_pixels,
            0);
}

TEST(PlaneFit, OneThreadEqualsTwo) {
  cv::Mat image(kRows, kCols, CV_8UC3);
  cv::RNG rng(7);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);  // many small segments
  cv::Mat one = CorruptedMap(), two = CorruptedMap();
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  FitSegmentPlanes(image, cv::Mat(), cv::Mat(), Sharp(), &one);
  cv::setNumThreads(2);
  FitSegmentPlanes(image, cv::Mat(), cv::Mat(), Sharp(), &two);
  cv::setNumThreads(threads);
  EXPECT_EQ(cv::norm(one, two, cv::NORM_INF), 0.0);
}

TEST(PlaneFit, BadInputIsRefused) {
  cv::Mat d = TrueMap();
  cv::Mat wrong_type(kRows, kCols, CV_64F, cv::Scalar(1.0));
  EXPECT_THROW(FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), Sharp(), &wrong_type),
               Error);
  cv::Mat small(10, 10, CV_32F, cv::Scalar(1.0f));
  EXPECT_THROW(FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), Sharp(), &small), Error);
  EXPECT_THROW(FitSegmentPlanes(TwoRegionImage(), cv::Mat(3, 3, CV_8U), cv::Mat(), Sharp(), &d),
               Error);
  PlaneFitOptions bad = Sharp();
  bad.min_inlier_fraction = 1.5;
  EXPECT_THROW(FitSegmentPlanes(TwoRegionImage(), cv::Mat(), cv::Mat(), bad, &d), Error);
}

}  // namespace
}  // namespace gcpstereo::optimize
