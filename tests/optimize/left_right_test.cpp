// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Left-right check and background fill on a one-row step scene whose true maps are known.
#include "gcpstereo/optimize/left_right.h"

#include <cmath>
#include <cstdint>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::optimize {
namespace {

// A foreground at disparity 5 over a background at disparity 2, on rows of 60 pixels. In the left
// view the foreground covers columns [20, 40), in the right view [15, 35). The left columns
// [17, 20) are background that the right camera does not see (the foreground hides it there).
constexpr int kCols = 60, kRows = 3;
constexpr float kFore = 5.0f, kBack = 2.0f;

cv::Mat TrueLeft() {
  cv::Mat d(kRows, kCols, CV_32F, cv::Scalar(kBack));
  d.colRange(20, 40).setTo(kFore);
  return d;
}
cv::Mat TrueRight() {
  cv::Mat d(kRows, kCols, CV_32F, cv::Scalar(kBack));
  d.colRange(15, 35).setTo(kFore);
  return d;
}
std::vector<int> InconsistentColumns(const cv::Mat& consistent, int row) {
  std::vector<int> cols;
  for (int c = 0; c < consistent.cols; ++c) {
    if (!consistent.at<std::uint8_t>(row, c)) cols.push_back(c);
  }
  return cols;
}

TEST(LeftRightCheck, TrueMapsFailOnlyWhereTheRightCameraCannotSee) {
  const cv::Mat consistent = LeftRightConsistent(TrueLeft(), TrueRight(), 0.5);
  // 17–19 are the half-occluded band. Columns 0 and 1 match outside the right image: unchecked.
  const std::vector<int> expected{17, 18, 19};
  for (int r = 0; r < kRows; ++r) EXPECT_EQ(InconsistentColumns(consistent, r), expected);
}

TEST(LeftRightCheck, FatteningIsDetectedAndFilledFromTheBackground) {
  cv::Mat left = TrueLeft();
  left.colRange(16, 20).setTo(kFore);  // the foreground spills 4 px over its left edge
  const cv::Mat consistent = LeftRightConsistent(left, TrueRight(), 1.0);
  EXPECT_EQ(InconsistentColumns(consistent, 0), (std::vector<int>{16, 17, 18, 19}));

  cv::Mat values = left * 10.0f;  // e.g. labels: any map that travels with the disparity
  const int filled = FillFromBackground(consistent, kCols, &values, &left);
  EXPECT_EQ(filled, kRows * 4);
  // Every pixel of the row is now the truth: the band takes the background side (2, not 5).
  EXPECT_EQ(cv::norm(left, TrueLeft(), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(values, TrueLeft() * 10.0f, cv::NORM_INF), 0.0);
}

TEST(LeftRightCheck, OccludedPixelsAreToldFromMismatches) {
  // The true band 17–19 is hidden from the right camera by the foreground: occluded.
  cv::Mat left = TrueLeft();
  left.at<float>(0, 45) = 8.0f;  // a mismatch: the right map at its match is background
  const cv::Mat occluded = LeftRightOccluded(left, TrueRight(), 0.5);
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      EXPECT_EQ(occluded.at<std::uint8_t>(r, c), c >= 17 && c < 20 ? 255 : 0) << r << "," << c;
    }
  }
  // Fattening over the band: the foreground value matches background in the right view, so
  // those pixels are mismatches, not occlusions.
  left.colRange(16, 20).setTo(kFore);
  EXPECT_EQ(cv::countNonZero(LeftRightOccluded(left, TrueRight(), 1.0)), 0);
}

TEST(LeftRightCheck, ToleranceAndUnknownValues) {
  cv::Mat right = TrueRight();
  right += 0.75f;  // every right value off by 0.75 px
  EXPECT_EQ(cv::countNonZero(LeftRightConsistent(TrueLeft(), right, 0.5)), kRows * 2);  // border
  EXPECT_EQ(cv::countNonZero(LeftRightConsistent(TrueLeft(), right, 1.0)), kRows * (kCols - 3));

  cv::Mat left = TrueLeft();
  left.at<float>(1, 30) = std::numeric_limits<float>::quiet_NaN();
  left.at<float>(1, 31) = std::numeric_limits<float>::infinity();
  const cv::Mat consistent = LeftRightConsistent(left, TrueRight(), 0.5);
  EXPECT_EQ(consistent.at<std::uint8_t>(1, 30), 0);
  EXPECT_EQ(consistent.at<std::uint8_t>(1, 31), 0);
  EXPECT_EQ(consistent.at<std::uint8_t>(0, 30), 255);
}

TEST(LeftRightCheck, RunsLongerThanTheBoundAreKept) {
  cv::Mat disparity(1, 20, CV_32F, cv::Scalar(3.0f));
  disparity.colRange(2, 5).setTo(9.0f);   // run of 3
  disparity.colRange(8, 16).setTo(7.0f);  // run of 8
  disparity.at<float>(0, 19) = 1.0f;
  cv::Mat consistent(1, 20, CV_8U, cv::Scalar(255));
  consistent.colRange(2, 5).setTo(0);
  consistent.colRange(8, 16).setTo(0);
  cv::Mat values = disparity.clone();
  EXPECT_EQ(FillFromBackground(consistent, 4, &values, &disparity), 3);
  for (int c = 2; c < 5; ++c) EXPECT_EQ(disparity.at<float>(0, c), 3.0f);
  for (int c = 8; c < 16; ++c) EXPECT_EQ(disparity.at<float>(0, c), 7.0f);  // untouched

  // The smaller of the two neighbours wins, whichever side it is on.
  cv::Mat d2(1, 6, CV_32F, cv::Scalar(0));
  d2.at<float>(0, 0) = 8.0f;
  d2.at<float>(0, 5) = 4.0f;
  cv::Mat mask(1, 6, CV_8U, cv::Scalar(0));
  mask.at<std::uint8_t>(0, 0) = mask.at<std::uint8_t>(0, 5) = 255;
  cv::Mat v2 = d2.clone();
  EXPECT_EQ(FillFromBackground(mask, 10, &v2, &d2), 4);
  for (int c = 1; c < 5; ++c) EXPECT_EQ(v2.at<float>(0, c), 4.0f);

  // At the image border the one neighbour there gives the value.
  cv::Mat d3(1, 6, CV_32F, cv::Scalar(6.0f));
  d3.at<float>(0, 2) = 1.5f;
  cv::Mat border(1, 6, CV_8U, cv::Scalar(255));
  border.colRange(0, 2).setTo(0);
  cv::Mat v3 = d3.clone();
  EXPECT_EQ(FillFromBackground(border, 10, &v3, &d3), 2);
  EXPECT_EQ(v3.at<float>(0, 0), 1.5f);
  EXPECT_EQ(v3.at<float>(0, 1), 1.5f);

  // A row without any consistent pixel has nothing to copy.
  cv::Mat none(1, 6, CV_8U, cv::Scalar(0));
  EXPECT_EQ(FillFromBackground(none, 10, &v2, &d2), 0);
}

// The row fill ends where the consistent pixels end; the colour-weighted median moves the filled
// edge onto the image's colour edge.
TEST(LeftRightCheck, WeightedMedianPutsTheFilledEdgeOnTheColourEdge) {
  constexpr int kSize = 24;
  cv::Mat image(kSize, kSize, CV_8UC3, cv::Scalar(40, 40, 40));
  image.colRange(12, kSize).setTo(cv::Scalar(200, 180, 160));  // colour edge at column 12
  // Truth: disparity 3 left of the edge, 8 right of it. The fill gave 8 from column 9 on.
  cv::Mat disparity(kSize, kSize, CV_32F, cv::Scalar(3.0f));
  disparity.colRange(9, kSize).setTo(8.0f);
  cv::Mat consistent(kSize, kSize, CV_8U, cv::Scalar(255));
  consistent.colRange(8, 14).setTo(0);  // the filled band
  cv::Mat values = disparity * 2.0f;
  const int changed = WeightedMedianOfFilled(image, consistent, 6, 0.1, &values, &disparity);
  EXPECT_EQ(changed, kSize * 3);  // columns 9, 10, 11
  for (int r = 0; r < kSize; ++r) {
    for (int c = 0; c < kSize; ++c) {
      const float expected = c < 12 ? 3.0f : 8.0f;
      ASSERT_EQ(disparity.at<float>(r, c), expected) << r << "," << c;
      ASSERT_EQ(values.at<float>(r, c), 2.0f * expected) << r << "," << c;
    }
  }
}

// A pole 3 px wide at disparity 9 that the right view lost: the check flags it and the fill puts
// the background there; a GCP on the pole within the radius brings it back. In a fattened band,
// GCPs on the background confirm the fill.
TEST(LeftRightCheck, GcpsOnThinForegroundUndoTheFill) {
  const cv::Mat nan(kRows, kCols, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  cv::Mat left(kRows, kCols, CV_32F, cv::Scalar(kBack));
  left.colRange(30, 33).setTo(9.0f);
  const cv::Mat right(kRows, kCols, CV_32F, cv::Scalar(kBack));  // no pole
  cv::Mat consistent = LeftRightConsistent(left, right, 1.0);
  EXPECT_EQ(InconsistentColumns(consistent, 0), (std::vector<int>{30, 31, 32}));
  const cv::Mat left_before = left.clone(), values_before = left * 10.0f;
  cv::Mat values = values_before.clone();
  ASSERT_EQ(FillFromBackground(consistent, kCols, &values, &left), kRows * 3);

  cv::Mat gcps = nan.clone();
  gcps.at<float>(1, 31) = 9.2f;   // on the pole
  gcps.at<float>(1, 26) = kBack;  // background, 4 px left of the pole
  // Radius 0 only reaches the GCP's own pixel.
  {
    cv::Mat l = left.clone(), v = values.clone(), m = consistent.clone();
    EXPECT_EQ(RestoreGcpConfirmed(gcps, 0, values_before, left_before, &m, &v, &l), 1);
    EXPECT_EQ(l.at<float>(1, 31), 9.0f);
    EXPECT_EQ(l.at<float>(1, 30), kBack);
  }
  // Radius 4: every pole pixel of the three rows has the pole GCP as its nearest (column 30 of
  // row 1 is 1 px from it and 4 px from the background GCP).
  const int restored =
      RestoreGcpConfirmed(gcps, 4, values_before, left_before, &consistent, &values, &left);
  EXPECT_EQ(restored, kRows * 3);
  EXPECT_EQ(cv::norm(left, left_before, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(values, values_before, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::countNonZero(consistent), kRows * kCols);  // restored pixels count as checked

  // Fattening 4 px over the left edge of a real foreground: a background GCP in the band keeps
  // the fill, the foreground GCP beyond the edge is farther away.
  cv::Mat fat = TrueLeft();
  fat.colRange(16, 20).setTo(kFore);
  cv::Mat mask = LeftRightConsistent(fat, TrueRight(), 1.0);
  const cv::Mat fat_before = fat.clone();
  cv::Mat fat_values = fat.clone();
  FillFromBackground(mask, kCols, &fat_values, &fat);
  cv::Mat band_gcps = nan.clone();
  for (int r = 0; r < kRows; ++r) {
    band_gcps.at<float>(r, 17) = kBack + 0.3f;  // in the band: 0–2 px from its pixels
    band_gcps.at<float>(r, 22) = kFore;         // on the foreground: 3–6 px from them
  }
  EXPECT_EQ(RestoreGcpConfirmed(band_gcps, 8, fat_before, fat_before, &mask, &fat_values, &fat), 0);
  EXPECT_EQ(cv::norm(fat, TrueLeft(), cv::NORM_INF), 0.0);
  // Without the background GCP the foreground one is the nearest, and the fattening comes back:
  // the rule trusts the measurement, so GCPs must be visible in the reference view.
  band_gcps.col(17).setTo(std::numeric_limits<float>::quiet_NaN());
  EXPECT_EQ(RestoreGcpConfirmed(band_gcps, 8, fat_before, fat_before, &mask, &fat_values, &fat),
            kRows * 4);
  EXPECT_EQ(fat.at<float>(0, 16), kFore);
}

TEST(LeftRightCheck, BadInputThrows) {
  const cv::Mat left = TrueLeft();
  EXPECT_THROW(LeftRightConsistent(left, cv::Mat(2, 2, CV_32F), 1.0), Error);
  EXPECT_THROW(LeftRightConsistent(left, TrueRight(), -1.0), Error);
  cv::Mat as_int;
  left.convertTo(as_int, CV_32S);
  EXPECT_THROW(LeftRightConsistent(as_int, TrueRight(), 1.0), Error);
  cv::Mat values = left.clone(), disparity = left.clone();
  EXPECT_THROW(FillFromBackground(cv::Mat(kRows, kCols, CV_32F), 4, &values, &disparity), Error);
  EXPECT_THROW(FillFromBackground(cv::Mat(kRows, kCols, CV_8U), -1, &values, &disparity), Error);
  const cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar::all(0));
  const cv::Mat mask(kRows, kCols, CV_8U, cv::Scalar(0));
  EXPECT_THROW(WeightedMedianOfFilled(image, mask, 2, 0.0, &values, &disparity), Error);
  EXPECT_THROW(WeightedMedianOfFilled(image, mask, -1, 0.1, &values, &disparity), Error);
  EXPECT_THROW(
      WeightedMedianOfFilled(cv::Mat(kRows, kCols, CV_8U), mask, 2, 0.1, &values, &disparity),
      Error);
  cv::Mat m = mask.clone();
  EXPECT_THROW(RestoreGcpConfirmed(left, -1, left, left, &m, &values, &disparity), Error);
  EXPECT_THROW(RestoreGcpConfirmed(cv::Mat(2, 2, CV_32F), 2, left, left, &m, &values, &disparity),
               Error);
  EXPECT_THROW(RestoreGcpConfirmed(left, 2, left, left, nullptr, &values, &disparity), Error);
}

}  // namespace
}  // namespace gcpstereo::optimize
