// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// D̂ as a weighted median of the GCPs (propagation.method: weighted_median).
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/propagation/propagation.h"

namespace gcpstereo::propagation {
namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

PropagationOptions Median(int radius, double sigma_px, double sigma_colour) {
  PropagationOptions options;
  options.method = "weighted_median";
  options.median_radius_px = radius;
  options.median_sigma_px = sigma_px;
  options.median_sigma_colour = sigma_colour;
  return options;
}

TEST(WeightedMedianPropagation, GcpsKeepTheirValueAndPixelsOutOfReachHaveNone) {
  const cv::Mat image(20, 30, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::Mat sparse(20, 30, CV_32F, cv::Scalar(kNaN));
  sparse.at<float>(5, 5) = 3.0f;
  sparse.at<float>(5, 7) = 9.0f;
  const PropagationResult result = Propagate(image, sparse, Median(3, 2.0, 20.0));
  EXPECT_EQ(result.solver, "weighted median");
  EXPECT_EQ(result.num_gcps, 2);
  EXPECT_EQ(result.values.at<float>(5, 5), 3.0f);
  EXPECT_EQ(result.values.at<float>(5, 7), 9.0f);
  EXPECT_EQ(result.values.at<float>(5, 4), 3.0f);   // nearer to the first GCP
  EXPECT_EQ(result.values.at<float>(5, 10), 9.0f);  // only the second one in reach
  // Reached: rows 2..8, columns 2..10 (Chebyshev distance <= 3 from a GCP): 7 x 9 pixels.
  EXPECT_EQ(result.num_unreached_pixels, 20 * 30 - 7 * 9);
  EXPECT_EQ(result.num_unreached_regions, 1);
  EXPECT_EQ(cv::countNonZero(result.reached), 7 * 9);
  EXPECT_TRUE(std::isnan(result.values.at<float>(15, 25)));
  EXPECT_EQ(result.reached.at<std::uint8_t>(15, 25), 0);
}

// A foreground stripe (value 9 over 2) with no colour edge under it, as when a LiDAR scan sees a
// pole a few pixels away from where the image shows it, sampled every 3 px with the stripe's edges
// half-way between GCP columns: the median reproduces it exactly (the Gaussian weights are
// separable, so each pixel follows its nearer GCP column), the linear system of eq. 5 blends it.
TEST(WeightedMedianPropagation, KeepsAStripeThatTheLinearSystemBlends) {
  constexpr int kRows = 24, kCols = 30;
  const cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar(70, 80, 90));
  cv::Mat truth(kRows, kCols, CV_32F, cv::Scalar(2.0f));
  truth.colRange(11, 17).setTo(9.0f);
  cv::Mat sparse(kRows, kCols, CV_32F, cv::Scalar(kNaN));
  for (int r = 0; r < kRows; r += 3) {
    for (int c = 0; c < kCols; c += 3) sparse.at<float>(r, c) = truth.at<float>(r, c);
  }
  const PropagationResult median = Propagate(image, sparse, Median(5, 2.0, 20.0));
  EXPECT_EQ(median.num_unreached_pixels, 0);
  EXPECT_EQ(cv::norm(median.values, truth, cv::NORM_INF), 0.0);

  PropagationOptions linear;  // the paper's method, defaults
  const PropagationResult blended = Propagate(image, sparse, linear);
  int between = 0;
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      const float v = blended.values.at<float>(r, c);
      between += v > 2.5f && v < 8.5f;
    }
  }
  EXPECT_GT(between, kRows);  // at least a column's worth of invented values
}

// Pixel column 9 is dark like the GCPs on the left (value 2, column 6, 3 px away) and unlike the
// bright GCPs on the right (value 7, column 11, 2 px away): the colour weights decide for the left;
// without them the nearer right side wins.
TEST(WeightedMedianPropagation, ColourWeightsKeepTheSideOfTheColourEdge) {
  cv::Mat image(9, 16, CV_8UC3, cv::Scalar(40, 40, 40));
  image.colRange(10, 16).setTo(cv::Scalar(200, 200, 200));
  cv::Mat sparse(9, 16, CV_32F, cv::Scalar(kNaN));
  sparse.col(6).setTo(2.0f);
  sparse.col(11).setTo(7.0f);
  const PropagationResult with_colour = Propagate(image, sparse, Median(5, 3.0, 20.0));
  const PropagationResult without = Propagate(image, sparse, Median(5, 3.0, 1e6));
  for (int r = 0; r < 9; ++r) {
    EXPECT_EQ(with_colour.values.at<float>(r, 9), 2.0f) << r;
    EXPECT_EQ(without.values.at<float>(r, 9), 7.0f) << r;
    EXPECT_EQ(with_colour.values.at<float>(r, 10), 7.0f) << r;
  }
}

// A ramp 0.5·column sampled every 2 px: away from the borders, where the window is symmetric, the
// median is the value at the pixel or one of the two GCP columns around it (error <= 0.5).
TEST(WeightedMedianPropagation, RampIsKeptWithinHalfAGcpStep) {
  constexpr int kRows = 20, kCols = 40, kRadius = 4;
  const cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar(128, 128, 128));
  cv::Mat sparse(kRows, kCols, CV_32F, cv::Scalar(kNaN));
  for (int r = 0; r < kRows; r += 2) {
    for (int c = 0; c < kCols; c += 2) sparse.at<float>(r, c) = 0.5f * c;
  }
  const PropagationResult result = Propagate(image, sparse, Median(kRadius, 2.0, 20.0));
  for (int r = kRadius; r < kRows - kRadius; ++r) {
    for (int c = kRadius; c < kCols - kRadius; ++c) {
      ASSERT_LE(std::abs(result.values.at<float>(r, c) - 0.5f * c), 0.5f) << r << "," << c;
    }
  }
}

TEST(WeightedMedianPropagation, SameResultWithOneOrTwoThreads) {
  cv::Mat image(60, 80, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::Mat sparse(60, 80, CV_32F, cv::Scalar(kNaN));
  cv::RNG rng(7);
  for (int k = 0; k < 300; ++k) {
    sparse.at<float>(rng.uniform(0, 60), rng.uniform(0, 80)) = rng.uniform(0.f, 50.f);
  }
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const PropagationResult one = Propagate(image, sparse, Median(6, 3.0, 25.0));
  cv::setNumThreads(2);
  const PropagationResult two = Propagate(image, sparse, Median(6, 3.0, 25.0));
  cv::setNumThreads(threads);
  const cv::Mat both_known = (one.values == one.values) & (two.values == two.values);
  EXPECT_EQ(cv::countNonZero((one.values != two.values) & both_known), 0);
  EXPECT_EQ(cv::countNonZero(both_known), cv::countNonZero(one.reached));
  EXPECT_EQ(cv::countNonZero(one.reached != two.reached), 0);
}

TEST(WeightedMedianPropagation, OptionsCheckNamesTheKey) {
  PropagationOptions options;
  options.method = "kriging";
  try {
    options.Check();
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "propagation.method = 'kriging'. Violated constraint: one of 'linear_system', "
                 "'weighted_median'");
  }
  EXPECT_THROW(Median(0, 2.0, 20.0).Check(), ConfigError);
  EXPECT_THROW(Median(101, 2.0, 20.0).Check(), ConfigError);
  EXPECT_THROW(Median(4, 0.0, 20.0).Check(), ConfigError);
  EXPECT_THROW(Median(4, 2.0, -1.0).Check(), ConfigError);
  const cv::Mat grey(10, 10, CV_8U, cv::Scalar(0));
  EXPECT_THROW(Propagate(grey, cv::Mat(10, 10, CV_32F, cv::Scalar(kNaN)), Median(4, 2.0, 20.0)),
               Error);
}

}  // namespace
}  // namespace gcpstereo::propagation
