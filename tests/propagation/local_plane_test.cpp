// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// D̂ from robust local planes through the GCPs (propagation.method: local_plane).
#include <cmath>
#include <iostream>
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

PropagationOptions Planes(int radius, double sigma_px, double sigma_colour) {
  PropagationOptions options;
  options.method = "local_plane";
  options.plane_radius_px = radius;
  options.plane_sigma_px = sigma_px;
  options.plane_sigma_colour = sigma_colour;
  return options;
}

// A slanted plane v = 10 + 0.3·x − 0.2·y sampled once per 8 × 8 block (a laser at s = 8) on a
// surface whose colour changes slowly. Between the GCPs the local planes follow it to within 0.1
// (the ridge on the slopes shrinks them a little: it steadies the planes of few, noisy GCPs);
// the membrane of eq. 5 flattens between GCPs and bends towards each, several times as far off.
// Beyond the outermost GCPs the planes extrapolate, less exactly.
TEST(LocalPlanePropagation, ReproducesASparselySampledSlantedPlane) {
  constexpr int kRows = 40, kCols = 56;
  cv::Mat image(kRows, kCols, CV_8UC3);
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) image.at<cv::Vec3b>(r, c) = cv::Vec3b(100 + c, 80 + r, 120);
  }
  cv::Mat truth(kRows, kCols, CV_32F), sparse(kRows, kCols, CV_32F, cv::Scalar(kNaN));
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      truth.at<float>(r, c) = static_cast<float>(10.0 + 0.3 * c - 0.2 * r);
      if (r % 8 == 3 && c % 8 == 5) sparse.at<float>(r, c) = truth.at<float>(r, c);
    }
  }
  const PropagationResult planes = Propagate(image, sparse, Planes(16, 6.0, 10.0));
  EXPECT_EQ(planes.solver, "local planes");
  EXPECT_EQ(planes.num_gcps, 5 * 7);
  EXPECT_EQ(planes.num_unreached_pixels, 0);
  const cv::Rect between(5, 3, 49, 33);  // the GCPs' bounding box
  const double planes_error = cv::norm(planes.values(between), truth(between), cv::NORM_INF);
  EXPECT_LT(planes_error, 0.1);
  EXPECT_LT(cv::norm(planes.values, truth, cv::NORM_INF), 2.0);

  const PropagationResult membrane = Propagate(image, sparse, PropagationOptions());
  const double membrane_error = cv::norm(membrane.values(between), truth(between), cv::NORM_INF);
  std::cout << "[ measured ] max |error| between the GCPs: local planes " << planes_error
            << ", linear system " << membrane_error << "\n";
  EXPECT_GT(membrane_error, 3.0 * planes_error);
}

TEST(LocalPlanePropagation, GcpsKeepTheirValueAndPixelsOutOfReachHaveNone) {
  const cv::Mat image(20, 30, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::Mat sparse(20, 30, CV_32F, cv::Scalar(kNaN));
  sparse.at<float>(5, 5) = 3.0f;
  sparse.at<float>(5, 7) = 9.0f;
  const PropagationResult result = Propagate(image, sparse, Planes(3, 2.0, 20.0));
  EXPECT_EQ(result.values.at<float>(5, 5), 3.0f);
  EXPECT_EQ(result.values.at<float>(5, 7), 9.0f);
  // One GCP in reach: its value (the ridge keeps the plane flat).
  EXPECT_NEAR(result.values.at<float>(5, 2), 3.0f, 1e-5);
  EXPECT_NEAR(result.values.at<float>(5, 10), 9.0f, 1e-5);
  // Both, on one row: the line through them, v = 3 + 3·(c − 5), evaluated between them.
  EXPECT_NEAR(result.values.at<float>(5, 6), 6.0f, 0.05);
  // Round windows of radius 3 around (5, 5) and (5, 7): 29 pixels each, 17 shared.
  EXPECT_EQ(cv::countNonZero(result.reached), 29 + 29 - 17);
  EXPECT_EQ(result.num_unreached_pixels, 20 * 30 - (29 + 29 - 17));
  EXPECT_EQ(result.num_unreached_regions, 1);
  EXPECT_TRUE(std::isnan(result.values.at<float>(15, 25)));
}

// Two surfaces meeting at a colour edge (columns 0..9 dark, value 2 + 0.1·r; columns 10.. bright,
// value 8): the colour weights keep each pixel on its own side's plane, up to the edge (within
// 0.01: the ridge on the slopes biases them by about 1 %; a blend of the sides would be off by
// more than 1).
TEST(LocalPlanePropagation, ColourWeightsKeepEachSideOfAColourEdge) {
  constexpr int kRows = 24, kCols = 24;
  cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar(40, 40, 40));
  image.colRange(10, kCols).setTo(cv::Scalar(200, 200, 200));
  cv::Mat sparse(kRows, kCols, CV_32F, cv::Scalar(kNaN));
  for (int r = 1; r < kRows; r += 4) {
    for (int c = 1; c < kCols; c += 4) {
      sparse.at<float>(r, c) = c < 10 ? 2.0f + 0.1f * r : 8.0f;
    }
  }
  const PropagationResult result = Propagate(image, sparse, Planes(8, 4.0, 10.0));
  for (int r = 2; r < kRows - 2; ++r) {
    EXPECT_NEAR(result.values.at<float>(r, 9), 2.0f + 0.1f * r, 0.01) << r;
    EXPECT_NEAR(result.values.at<float>(r, 10), 8.0f, 0.01) << r;
  }
}

// One wrong GCP among the samples of a plane (no colour to tell it apart) moves the robust fit
// far less than a least-squares plane would (which would move ≈ 1/n of its error).
TEST(LocalPlanePropagation, AnOutlierGcpBarelyMovesTheFit) {
  const cv::Mat image(21, 21, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::Mat sparse(21, 21, CV_32F, cv::Scalar(kNaN));
  for (int r = 2; r < 21; r += 4) {
    for (int c = 2; c < 21; c += 4) sparse.at<float>(r, c) = 5.0f + 0.05f * c;
  }
  sparse.at<float>(10, 10) = 25.0f;  // 20 off the plane
  const PropagationResult result = Propagate(image, sparse, Planes(10, 5.0, 20.0));
  EXPECT_NEAR(result.values.at<float>(10, 11), 5.0f + 0.05f * 11, 0.05);
  EXPECT_NEAR(result.values.at<float>(9, 10), 5.0f + 0.05f * 10, 0.05);
}

TEST(LocalPlanePropagation, OneThreadEqualsTwo) {
  cv::Mat image(60, 80, CV_8UC3);
  cv::RNG rng(5);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  cv::Mat sparse(60, 80, CV_32F, cv::Scalar(kNaN));
  for (int i = 0; i < 120; ++i) {
    sparse.at<float>(rng.uniform(0, 60), rng.uniform(0, 80)) =
        static_cast<float>(rng.uniform(1.0, 20.0));
  }
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const PropagationResult one = Propagate(image, sparse, Planes(12, 5.0, 10.0));
  cv::setNumThreads(2);
  const PropagationResult two = Propagate(image, sparse, Planes(12, 5.0, 10.0));
  cv::setNumThreads(threads);
  const cv::Mat both = (one.values == one.values) & (two.values == two.values);
  EXPECT_EQ(cv::countNonZero(both), cv::countNonZero(one.values == one.values));
  EXPECT_EQ(cv::countNonZero((one.values != two.values) & both), 0);
}

TEST(LocalPlanePropagation, BadOptionsNameTheirKey) {
  const cv::Mat image(8, 8, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Mat sparse(8, 8, CV_32F, cv::Scalar(1.0f));
  auto message = [&](const PropagationOptions& options) {
    try {
      Propagate(image, sparse, options);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(Planes(0, 5.0, 10.0)).find("propagation.plane_radius_px"), std::string::npos);
  EXPECT_NE(message(Planes(101, 5.0, 10.0)).find("propagation.plane_radius_px"), std::string::npos);
  EXPECT_NE(message(Planes(5, 0.0, 10.0)).find("propagation.plane_sigma_px"), std::string::npos);
  EXPECT_NE(message(Planes(5, 5.0, -1.0)).find("propagation.plane_sigma_colour"),
            std::string::npos);
  PropagationOptions unknown;
  unknown.method = "planes";
  EXPECT_NE(message(unknown).find("local_plane"), std::string::npos);
}

}  // namespace
}  // namespace gcpstereo::propagation
