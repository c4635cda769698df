// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// D̂ as a weighted median of the GCPs (propagation.method: weighted_median).
#include <cmath>
#include <limits>
#include <string>

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

// A scan's depth edge a few pixels off the image's: the pixel (4, 4) has the colour of the one GCP
// of value 2 four rows above it, while the five GCPs of value 7 one or two pixels away sit on
// bright pixels. With the colour weight alone (floor 0) the single similar GCP decides; with a
// floor of 0.25 the nearer majority wins, as it does with spatial weights only (floor 1).
TEST(WeightedMedianPropagation, ColourFloorLetsTheNearerMajorityWin) {
  cv::Mat image(9, 9, CV_8UC3, cv::Scalar(40, 40, 40));
  cv::Mat sparse(9, 9, CV_32F, cv::Scalar(kNaN));
  sparse.at<float>(0, 4) = 2.0f;
  for (const cv::Point p :
       {cv::Point(3, 5), cv::Point(4, 5), cv::Point(5, 5), cv::Point(3, 6), cv::Point(5, 6)}) {
    sparse.at<float>(p) = 7.0f;
    image.at<cv::Vec3b>(p) = cv::Vec3b(200, 200, 200);
  }
  PropagationOptions options = Median(4, 3.0, 20.0);
  EXPECT_EQ(Propagate(image, sparse, options).values.at<float>(4, 4), 2.0f);
  options.median_colour_floor = 0.25;
  EXPECT_EQ(Propagate(image, sparse, options).values.at<float>(4, 4), 7.0f);
  options.median_colour_floor = 1.0;
  const cv::Mat spatial_only = Propagate(image, sparse, options).values;
  EXPECT_EQ(spatial_only.at<float>(4, 4), 7.0f);
  // Floor 1 ignores the colours: the same map as an all-grey image.
  const cv::Mat grey(9, 9, CV_8UC3, cv::Scalar(40, 40, 40));
  const cv::Mat no_colour = Propagate(grey, sparse, options).values;
  const cv::Mat both_known = (spatial_only == spatial_only) & (no_colour == no_colour);
  EXPECT_EQ(cv::countNonZero((spatial_only != no_colour) & both_known), 0);
  EXPECT_EQ(cv::countNonZero(both_known), 81);
}

// A pole (value 9, columns 0..4) against a background (value 2), no colour edge: two scan lines
// four rows above and below the pixel (6, 4) cross the edge, and the pixel's own line has
// background GCPs 2..4 px to its right and one pole GCP 3 px to its left. Isotropic weights let
// the nearer background win; with the distance across the edge counted 4 times the pixel follows
// the pole's column above and below it. The same layout transposed (a horizontal edge) gives the
// same value at the transposed pixel: the direction comes from the GCPs, not from the axes.
TEST(WeightedMedianPropagation, EdgeStretchFollowsTheGcpsAlongTheEdge) {
  constexpr int kSize = 13;
  const cv::Mat image(kSize, kSize, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::Mat sparse(kSize, kSize, CV_32F, cv::Scalar(kNaN));
  for (int c = 0; c < kSize; ++c) {
    sparse.at<float>(2, c) = sparse.at<float>(10, c) = c <= 4 ? 9.0f : 2.0f;
  }
  for (int c : {6, 7, 8}) sparse.at<float>(6, c) = 2.0f;
  sparse.at<float>(6, 1) = 9.0f;
  PropagationOptions options = Median(6, 3.0, 20.0);
  EXPECT_EQ(Propagate(image, sparse, options).values.at<float>(6, 4), 2.0f);
  options.median_edge_stretch = 4.0;
  const cv::Mat stretched = Propagate(image, sparse, options).values;
  EXPECT_EQ(stretched.at<float>(6, 4), 9.0f);
  EXPECT_EQ(stretched.at<float>(6, 5), 2.0f);  // a background pixel stays background
  const cv::Mat transposed = Propagate(image, sparse.t(), options).values;
  EXPECT_EQ(transposed.at<float>(4, 6), 9.0f);
  EXPECT_EQ(cv::norm(transposed.t(), stretched, cv::NORM_INF), 0.0);
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
                 "'weighted_median', 'local_plane'");
  }
  EXPECT_THROW(Median(0, 2.0, 20.0).Check(), ConfigError);
  EXPECT_THROW(Median(101, 2.0, 20.0).Check(), ConfigError);
  EXPECT_THROW(Median(4, 0.0, 20.0).Check(), ConfigError);
  EXPECT_THROW(Median(4, 2.0, -1.0).Check(), ConfigError);
  PropagationOptions bad_stretch = Median(4, 2.0, 20.0);
  bad_stretch.median_edge_stretch = 0.5;
  EXPECT_THROW(bad_stretch.Check(), ConfigError);
  for (const double floor : {-0.1, 1.5}) {
    PropagationOptions bad_floor = Median(4, 2.0, 20.0);
    bad_floor.median_colour_floor = floor;
    try {
      bad_floor.Check();
      FAIL() << "expected ConfigError for floor " << floor;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("propagation.median_colour_floor"), std::string::npos);
    }
  }
  const cv::Mat grey(10, 10, CV_8U, cv::Scalar(0));
  EXPECT_THROW(Propagate(grey, cv::Mat(10, 10, CV_32F, cv::Scalar(kNaN)), Median(4, 2.0, 20.0)),
               Error);
}

}  // namespace
}  // namespace gcpstereo::propagation
