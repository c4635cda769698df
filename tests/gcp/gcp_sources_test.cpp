// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/gcp/gcp_sources.h"

namespace gcpstereo::gcp {
namespace {

Gcp MakeGcp(int col, int row, double depth, double sigma = 0.1,
            GcpSource source = GcpSource::kLidar) {
  Gcp g;
  g.col = col;
  g.row = row;
  g.depth = depth;
  g.sigma = sigma;
  g.source = source;
  return g;
}

TEST(DownsampleTest, KeepsExactlyOnePerBlockNearestTheCentre) {
  // 37×21 image, s = 8: 5×3 blocks, the last column/row of blocks partial (5 and 5 px).
  const int width = 37, height = 21, s = 8;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> col(0, width - 1), row(0, height - 1);
  GcpSet gcps;
  for (int i = 0; i < 400; ++i) gcps.points.push_back(MakeGcp(col(rng), row(rng), i));
  const GcpSet kept = Downsample(gcps, s, width, height);
  // Brute force: per block, the minimum squared distance to the clipped block centre.
  std::vector<int> per_block(5 * 3, 0);
  for (const Gcp& k : kept.points) {
    const int bx = k.col / s, by = k.row / s;
    ++per_block[by * 5 + bx];
    const double cx = 0.5 * (bx * s + std::min(width, bx * s + s) - 1);
    const double cy = 0.5 * (by * s + std::min(height, by * s + s) - 1);
    const double kept_distance = std::hypot(k.col - cx, k.row - cy);
    const Gcp* first_best = nullptr;
    for (const Gcp& g : gcps.points) {
      if (g.col / s != bx || g.row / s != by) continue;
      const double distance = std::hypot(g.col - cx, g.row - cy);
      EXPECT_GE(distance, kept_distance - 1e-12);
      if (std::abs(distance - kept_distance) < 1e-12 && !first_best) first_best = &g;
    }
    ASSERT_NE(first_best, nullptr);
    EXPECT_EQ(first_best->depth, k.depth) << "tie not broken by input order";
  }
  for (int b = 0; b < 15; ++b) EXPECT_EQ(per_block[b], 1) << "block " << b;
  // Raster order.
  for (size_t i = 1; i < kept.size(); ++i) {
    const Gcp& a = kept.points[i - 1];
    const Gcp& b = kept.points[i];
    EXPECT_TRUE(a.row < b.row || (a.row == b.row && a.col < b.col));
  }
}

TEST(DownsampleTest, TiesPreferSmallerSigmaAndS1KeepsOnePerPixel) {
  GcpSet gcps;
  gcps.points = {MakeGcp(3, 3, 1.0, 0.5), MakeGcp(3, 3, 2.0, 0.1, GcpSource::kStereo),
                 MakeGcp(4, 4, 3.0, 0.1)};
  const GcpSet one = Downsample(gcps, 1, 8, 8);
  ASSERT_EQ(one.size(), 2u);
  EXPECT_EQ(one.points[0].depth, 2.0);  // same pixel: smaller sigma wins
  // s = 8 on an 8×8 image: centre (3.5, 3.5); (3,3) and (4,4) tie, sigma ties between 2.0 and 3.0,
  // then the lower source enum (kLidar) wins.
  const GcpSet block = Downsample(gcps, 8, 8, 8);
  ASSERT_EQ(block.size(), 1u);
  EXPECT_EQ(block.points[0].depth, 3.0);
}

TEST(DownsampleTest, BadArgumentsThrow) {
  GcpSet gcps;
  gcps.points = {MakeGcp(10, 1, 1.0)};
  try {
    Downsample(gcps, 0, 8, 8);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "Downsample: gcp.downsample = 0 must be >= 1");
  }
  try {
    Downsample(gcps, 2, 8, 8);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "Downsample: GCP 0 at (10, 1) lies outside the 8x8 image");
  }
}

TEST(DepthMapGcpsTest, OneGcpPerValidPixel) {
  cv::Mat depth(4, 5, CV_32F, cv::Scalar(0.0f));
  depth.at<float>(1, 2) = 3.5f;
  depth.at<float>(3, 4) = 7.0f;
  depth.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
  depth.at<float>(0, 1) = kInvalidDepth;
  depth.at<float>(2, 2) = -1.0f;
  GcpSourceSummary summary;
  const GcpSet gcps = GcpsFromDepthMap(depth, 0.05, GcpSource::kDepthMap, &summary);
  ASSERT_EQ(gcps.size(), 2u);
  EXPECT_EQ(gcps.points[0].col, 2);
  EXPECT_EQ(gcps.points[0].row, 1);
  EXPECT_DOUBLE_EQ(gcps.points[0].depth, 3.5);
  EXPECT_DOUBLE_EQ(gcps.points[0].sigma, 0.05);
  EXPECT_EQ(gcps.points[1].source, GcpSource::kDepthMap);
  EXPECT_EQ(summary.num_gcps, 2);
  EXPECT_DOUBLE_EQ(summary.density_percent, 10.0);
  EXPECT_THROW(GcpsFromDepthMap(cv::Mat(2, 2, CV_8U), 0.1), Error);
}

TEST(DepthMapGcpsTest, DisparityToDepth) {
  cv::Mat disparity = (cv::Mat_<float>(1, 4) << 2.0f, 0.0f, -1.0f, kInvalidDepth);
  const cv::Mat depth = DisparityToDepth(disparity, 10.0);
  EXPECT_FLOAT_EQ(depth.at<float>(0, 0), 5.0f);
  EXPECT_EQ(depth.at<float>(0, 1), kInvalidDepth);
  EXPECT_EQ(depth.at<float>(0, 2), kInvalidDepth);
  EXPECT_EQ(depth.at<float>(0, 3), kInvalidDepth);
  try {
    DisparityToDepth(disparity, 0.0);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "DisparityToDepth: disparity_numerator = 0 must be > 0");
  }
}

TEST(GcpSourcesTest, MergeAndDensity) {
  GcpSet a, b;
  a.points = {MakeGcp(0, 0, 1.0)};
  b.points = {MakeGcp(1, 0, 2.0), MakeGcp(2, 0, 3.0)};
  const GcpSet merged = MergeGcpSets({a, b});
  ASSERT_EQ(merged.size(), 3u);
  EXPECT_EQ(merged.points[2].depth, 3.0);
  EXPECT_DOUBLE_EQ(DensityPercent(merged, 10, 3), 10.0);
}

}  // namespace
}  // namespace gcpstereo::gcp
