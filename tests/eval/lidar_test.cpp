// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/lidar.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::eval {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

TEST(Lidar, RelativeDepthScoreCountsEachPointOnce) {
  cv::Mat depth(4, 4, CV_32F, cv::Scalar(10.0f));
  depth.at<float>(0, 1) = 10.05f;  // 0.5 % off a reference of 10
  depth.at<float>(0, 2) = 10.15f;  // 1.5 %
  depth.at<float>(0, 3) = 9.7f;    // 3 %
  depth.at<float>(1, 0) = 12.0f;   // 20 %
  depth.at<float>(1, 1) = kNan;    // missing
  const std::vector<ReferencePoint> points = {
      {{0.0, 0.0}, 10.0},   // exact
      {{1.2, -0.4}, 10.0},  // nearest pixel (1, 0)
      {{2.0, 0.0}, 10.0},  {{3.0, 0.0}, 10.0}, {{0.0, 1.0}, 10.0},
      {{1.0, 1.0}, 10.0},  {{4.0, 0.0}, 10.0},  // outside
      {{2.0, 2.0}, 0.0},                        // invalid reference
  };
  const RelativeDepthScore score = EvaluateRelativeDepth(depth, points);
  EXPECT_EQ(score.counted, 6);
  EXPECT_EQ(score.outside, 1);
  EXPECT_EQ(score.invalid_reference, 1);
  EXPECT_EQ(score.missing, 1);
  ASSERT_EQ(score.above_percent.size(), 3u);
  EXPECT_NEAR(score.above_percent[0], 100.0 * 4 / 6, 1e-9);  // 1.5, 3, 20 %, missing
  EXPECT_NEAR(score.above_percent[1], 100.0 * 3 / 6, 1e-9);  // 3, 20 %, missing
  EXPECT_NEAR(score.above_percent[2], 100.0 * 2 / 6, 1e-9);  // 20 %, missing
  // Errors 0, 0.5, 1.5, 3, 20, ∞ %: the median is the mean of 1.5 and 3 (float rounding aside).
  EXPECT_NEAR(score.median_percent, 2.25, 1e-4);
  const nlohmann::json j = score.ToJson();
  EXPECT_NEAR(j["above_5_percent"].get<double>(), 100.0 * 2 / 6, 1e-9);
  EXPECT_EQ(j["missing"], 1);

  // More than half missing: the median is infinite, null in JSON.
  cv::Mat none(4, 4, CV_32F, cv::Scalar(kNan));
  const RelativeDepthScore empty = EvaluateRelativeDepth(none, points);
  EXPECT_TRUE(std::isinf(empty.median_percent));
  EXPECT_TRUE(empty.ToJson()["median_relative_error_percent"].is_null());
  EXPECT_EQ(empty.above_percent[0], 100.0);
  EXPECT_THROW(EvaluateRelativeDepth(depth, points, {0.01, 0.0}), ConfigError);
}

TEST(Lidar, CheckerboardSplitCounts) {
  // Every pixel centre of a 32×16 image with 8-px blocks: 4×2 blocks, 4 even and 4 odd.
  std::vector<Eigen::Vector2d> pixels;
  for (int row = 0; row < 16; ++row) {
    for (int col = 0; col < 32; ++col) pixels.emplace_back(col, row);
  }
  const LidarSplit split = CheckerboardSplit(pixels, 8);
  EXPECT_EQ(split.gcp_indices.size(), 256u);
  EXPECT_EQ(split.score_indices.size(), 256u);
  // (0,0) is a GCP square, (8,0) and (0,8) scoring squares, (8,8) GCP.
  EXPECT_EQ(split.gcp_indices.front(), 0);
  EXPECT_EQ(split.score_indices.front(), 8);
  const auto is_gcp = [&](int index) {
    return std::binary_search(split.gcp_indices.begin(), split.gcp_indices.end(), index);
  };
  EXPECT_FALSE(is_gcp(8 * 32 + 0));
  EXPECT_TRUE(is_gcp(8 * 32 + 8));
  EXPECT_TRUE(is_gcp(15 * 32 + 31));  // block (3, 1): even

  // Sub-pixel positions go by their nearest pixel; negative coordinates by floor division.
  const LidarSplit edge =
      CheckerboardSplit({{7.4, 0.0}, {7.6, 0.0}, {-0.6, 0.0}, {-0.4, 0.0}, {0.0, 7.5}}, 8);
  EXPECT_EQ(edge.gcp_indices, (std::vector<int>{0, 3}));
  EXPECT_EQ(edge.score_indices, (std::vector<int>{1, 2, 4}));

  try {
    CheckerboardSplit(pixels, 0);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "eval.lidar.block_px = 0. Violated constraint: block_px >= 1");
  }
}

TEST(Lidar, KittiStyleScores) {
  cv::Mat map(10, 10, CV_32F, cv::Scalar(50.0f));
  map.at<float>(0, 1) = 96.0f;
  map.at<float>(0, 2) = kNan;
  map.at<float>(0, 3) = 0.0f;
  const std::vector<ReferencePoint> points = {
      {{0.0, 0.0}, 50.0},   // exact
      {{0.0, 1.0}, 52.9},   // |e| 2.9: bad-1 only
      {{0.0, 2.0}, 54.0},   // |e| 4 > 3 and > 2.7: bad-3 and bad-1
      {{1.0, 0.0}, 100.0},  // |e| 4 > 3 but < 5: bad-1 only
      {{2.0, 0.0}, 30.0},   // NaN estimate: missing, bad in both
      {{3.0, 0.0}, 30.0},   // 0 estimate: missing, bad in both
      {{10.4, 0.0}, 30.0},  // nearest pixel (10, 0) is outside
      {{-0.4, 0.3}, 50.5},  // nearest pixel (0, 0): inside, |e| 0.5
      {{4.0, 4.0}, 0.0},    // invalid reference
      {{4.0, 5.0}, std::numeric_limits<double>::infinity()},
  };
  const LidarScore s = EvaluateAgainstPoints(map, points);
  EXPECT_EQ(s.outside, 1);
  EXPECT_EQ(s.invalid_reference, 2);
  EXPECT_EQ(s.counted, 7);
  EXPECT_EQ(s.missing, 2);
  EXPECT_EQ(s.bad3_count, 3);
  EXPECT_EQ(s.bad1_count, 5);
  EXPECT_DOUBLE_EQ(s.bad3_percent, 100.0 * 3 / 7);
  EXPECT_DOUBLE_EQ(s.bad1_percent, 100.0 * 5 / 7);
  EXPECT_NEAR(s.mean_abs_error, (0.0 + 2.9 + 4.0 + 4.0 + 0.5) / 5, 1e-12);
  EXPECT_EQ(s.ToJson()["bad3_count"], 3);

  // The map against its own values: 0 % bad.
  std::vector<ReferencePoint> own;
  for (int row = 0; row < 10; ++row) own.push_back({{5.0, static_cast<double>(row)}, 50.0});
  const LidarScore exact = EvaluateAgainstPoints(map, own);
  EXPECT_EQ(exact.counted, 10);
  EXPECT_DOUBLE_EQ(exact.bad3_percent, 0.0);
  EXPECT_DOUBLE_EQ(exact.bad1_percent, 0.0);

  LidarScoreOptions options;
  options.bad_abs_px = 0.0;
  try {
    EvaluateAgainstPoints(map, own, options);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "eval.lidar.bad_abs_px = 0. Violated constraint: bad_abs_px > 0");
  }
  EXPECT_THROW(EvaluateAgainstPoints(cv::Mat(3, 3, CV_8U), own), Error);
}

// Each point is drawn in the colour of its class, by the same definitions as the scores.
TEST(Lidar, RenderPointErrorsColoursByClass) {
  cv::Mat map(20, 40, CV_32F, cv::Scalar(50.0f));
  map.at<float>(10, 30) = kNan;
  const cv::Mat image(20, 40, CV_8UC3, cv::Scalar(100, 100, 100));
  const std::vector<ReferencePoint> points = {
      {{5.0, 10.0}, 50.0},   // good: green
      {{15.0, 10.0}, 52.0},  // bad-1 only: yellow
      {{25.0, 10.0}, 60.0},  // bad-3: red
      {{30.0, 10.0}, 50.0},  // no estimate: magenta
      {{50.0, 10.0}, 50.0},  // outside: not drawn
  };
  const cv::Mat out = RenderPointErrors(image, map, points);
  ASSERT_EQ(out.type(), CV_8UC3);
  EXPECT_EQ(out.at<cv::Vec3b>(10, 5), cv::Vec3b(0, 200, 0));
  EXPECT_EQ(out.at<cv::Vec3b>(10, 15), cv::Vec3b(0, 220, 255));
  EXPECT_EQ(out.at<cv::Vec3b>(10, 25), cv::Vec3b(0, 0, 255));
  EXPECT_EQ(out.at<cv::Vec3b>(10, 30), cv::Vec3b(255, 0, 255));
  EXPECT_EQ(out.at<cv::Vec3b>(2, 2), cv::Vec3b(60, 60, 60));  // the darkened image
  EXPECT_THROW(RenderPointErrors(cv::Mat(5, 5, CV_8UC3), map, points), Error);
}

TEST(Lidar, ProjectPointCloudKeepsTheNearestPointPerPixel) {
  const Camera camera = RectifiedSequenceCamera(10.0, 4.0, 3.0, 0.1, 0, 9, 7);
  PointCloud cloud;
  cloud.points = {
      {0.0f, 0.0f, 2.0f},   // pixel (4, 3), depth 2
      {0.0f, 0.0f, 1.0f},   // same pixel, nearer: wins
      {0.2f, 0.0f, 2.0f},   // pixel (5, 3)
      {0.0f, 0.0f, -1.0f},  // behind
      {5.0f, 0.0f, 1.0f},   // pixel (54, 3): outside
      {0.2f, 0.0f, 2.0f},   // duplicate of index 2: the lower index stays
  };
  const std::vector<ProjectedPoint> kept = ProjectPointCloud(cloud, camera);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept[0].index, 1);
  EXPECT_DOUBLE_EQ(kept[0].depth, 1.0);
  EXPECT_NEAR((kept[0].pixel - Eigen::Vector2d(4.0, 3.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(kept[1].index, 2);
  const std::vector<ProjectedPoint> all =
      ProjectPointCloud(cloud, camera, Eigen::Matrix4d::Identity(), false);
  EXPECT_EQ(all.size(), 4u);

  // A transform into the world frame is applied first.
  Eigen::Matrix4d world_from_cloud = Eigen::Matrix4d::Identity();
  world_from_cloud(2, 3) = 1.0;  // +1 along z
  const std::vector<ProjectedPoint> moved =
      ProjectPointCloud(cloud, camera, world_from_cloud, true);
  ASSERT_FALSE(moved.empty());
  EXPECT_EQ(moved[0].index, 1);
  EXPECT_DOUBLE_EQ(moved[0].depth, 2.0);
}

}  // namespace
}  // namespace gcpstereo::eval
