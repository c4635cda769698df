// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/tiling.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "test_problems.h"

namespace gcpstereo::optimize {
namespace {

using testing::Crop;
using testing::MakeScene;

bool BitIdentical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

TEST(TileLayout, PaperLayout) {
  TilingOptions options;  // 2 x 2, 16 px
  const std::vector<cv::Rect> tiles = TileLayout(cv::Size(101, 80), options);
  ASSERT_EQ(tiles.size(), 4u);
  EXPECT_EQ(tiles[0], cv::Rect(0, 0, 50 + 8, 40 + 8));
  EXPECT_EQ(tiles[1], cv::Rect(50 - 8, 0, 101 - 42, 48));
  EXPECT_EQ(tiles[2], cv::Rect(0, 32, 58, 48));
  EXPECT_EQ(tiles[3], cv::Rect(42, 32, 59, 48));
  // Neighbours share exactly overlap_px columns / rows.
  EXPECT_EQ((tiles[0] & tiles[1]).width, 16);
  EXPECT_EQ((tiles[0] & tiles[2]).height, 16);
}

TEST(TileLayout, RejectsBadOptions) {
  TilingOptions options;
  options.blend = "median";
  try {
    TileLayout(cv::Size(100, 100), options);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "optimizer.blend = median. Violated constraint: one of \"mean\", \"feather\"");
  }
  options = TilingOptions();
  options.overlap_px = 40;
  try {
    TileLayout(cv::Size(60, 60), options);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "optimizer.tile_overlap = 40. Violated constraint: <= the smallest tile (30 px "
                 "for 2x2 tiles of 60x60)");
  }
}

class TilingTest : public ::testing::Test {
 protected:
  void SetUp() override { scene_ = MakeScene(72, 56, 16, 31, 7.0f, 0.02); }
  MakeTileProblem Maker() const {
    return [this](const cv::Rect& region) { return Crop(scene_.problem, region); };
  }
  testing::SceneProblem scene_;
};

TEST_F(TilingTest, OneByOneEqualsUntiledBitForBit) {
  ExpansionOptions expansion;
  TilingOptions tiling;
  tiling.rows = tiling.cols = 1;
  const TiledResult tiled =
      OptimizeTiled(scene_.truth.size(), Maker(), EnergyOptions(), expansion, tiling);
  const ExpansionResult untiled = AlphaExpansion(scene_.problem.View(), EnergyOptions(), expansion);
  cv::Mat untiled_float;
  untiled.labels.convertTo(untiled_float, CV_32F);
  EXPECT_TRUE(BitIdentical(tiled.labels, untiled_float));
  ASSERT_EQ(tiled.tiles.size(), 1u);
  EXPECT_EQ(tiled.energy_sum, untiled.breakdown.total());
}

TEST_F(TilingTest, OneByOneWithRefinementEqualsUntiled) {
  ExpansionOptions expansion;
  TilingOptions tiling;
  tiling.rows = tiling.cols = 1;
  RefinementOptions refinement;
  refinement.method = RefinementMethod::kCeres;
  const TiledResult tiled = OptimizeTiled(scene_.truth.size(), Maker(), EnergyOptions(), expansion,
                                          tiling, {}, {}, refinement);
  const ExpansionResult untiled = AlphaExpansion(scene_.problem.View(), EnergyOptions(), expansion);
  const cv::Mat refined =
      RefineSubLabel(scene_.problem.View(), untiled.labels, EnergyOptions(), refinement);
  EXPECT_TRUE(BitIdentical(tiled.labels, refined));
  EXPECT_GT(tiled.tiles[0].refinement.iterations, 0);
}

TEST_F(TilingTest, OneThreadEqualsTwoThreadsBitForBit) {
  for (const char* blend : {"mean", "feather"}) {
    TilingOptions tiling;
    tiling.blend = blend;
    tiling.overlap_px = 8;
    ExpansionOptions one, two;
    one.num_threads = 1;
    two.num_threads = 2;
    const TiledResult a = OptimizeTiled(scene_.truth.size(), Maker(), EnergyOptions(), one, tiling);
    const TiledResult b = OptimizeTiled(scene_.truth.size(), Maker(), EnergyOptions(), two, tiling);
    EXPECT_TRUE(BitIdentical(a.labels, b.labels)) << blend;
    EXPECT_EQ(a.energy_sum, b.energy_sum);
    EXPECT_FALSE(a.cancelled);
  }
}

// Progress advances within tiles (not only when a tile finishes), never goes back, ends at 1,
// and returning false cancels the remaining work.
TEST_F(TilingTest, ProgressAdvancesWithinTilesAndCanCancel) {
  TilingOptions tiling;  // 2 × 2
  ExpansionOptions expansion;
  expansion.num_threads = 1;
  std::vector<double> fractions;
  const TiledResult done = OptimizeTiled(scene_.truth.size(), Maker(), EnergyOptions(), expansion,
                                         tiling, {}, [&](double f) {
                                           fractions.push_back(f);
                                           return true;
                                         });
  EXPECT_FALSE(done.cancelled);
  ASSERT_GT(fractions.size(), 4u * 3u);  // set-up, cycles and hand-over of each of 4 tiles
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  EXPECT_LT(fractions.front(), 0.25);

  int calls = 0;
  const TiledResult stopped =
      OptimizeTiled(scene_.truth.size(), Maker(), EnergyOptions(), expansion, tiling, {},
                    [&](double) { return ++calls < 3; });
  EXPECT_TRUE(stopped.cancelled);
}

TEST_F(TilingTest, MeanBlendAveragesTheTilesInTheOverlaps) {
  TilingOptions tiling;
  tiling.overlap_px = 8;
  const TiledResult tiled =
      OptimizeTiled(scene_.truth.size(), Maker(), EnergyOptions(), ExpansionOptions(), tiling);
  // Recompute the tiles independently and average by hand.
  const std::vector<cv::Rect> layout = TileLayout(scene_.truth.size(), tiling);
  cv::Mat sum(scene_.truth.size(), CV_64F, cv::Scalar(0)), count(sum.size(), CV_64F, cv::Scalar(0));
  for (const cv::Rect& r : layout) {
    const OwnedMrfProblem tile = Crop(scene_.problem, r);
    const ExpansionResult result = AlphaExpansion(tile.View(), EnergyOptions(), ExpansionOptions());
    cv::Mat labels;
    result.labels.convertTo(labels, CV_64F);
    sum(r) += labels;
    count(r) += 1.0;
  }
  cv::Mat expected;
  cv::divide(sum, count, expected);
  expected.convertTo(expected, CV_32F);
  EXPECT_TRUE(BitIdentical(tiled.labels, expected));
  // Seams against the untiled run are small compared with the label range.
  const ExpansionResult untiled =
      AlphaExpansion(scene_.problem.View(), EnergyOptions(), ExpansionOptions());
  const SeamStatistics seams = MeasureSeams(tiled.labels, untiled.labels, tiling);
  EXPECT_GT(seams.overlap_pixels, 0);
  EXPECT_EQ(seams.border_pairs, 72 + 56);
  EXPECT_LT(seams.mean_border_jump_excess, 1.0);
  const SeamStatistics none = MeasureSeams(untiled.labels, untiled.labels, tiling);
  EXPECT_EQ(none.mean_abs_diff_overlap, 0.0);
  EXPECT_EQ(none.mean_border_jump_excess, 0.0);
}

TEST_F(TilingTest, FeatherWeightsSumToOne) {
  // With a constant labelling in every tile the blend must reproduce the constant.
  TilingOptions tiling;
  tiling.blend = "feather";
  tiling.overlap_px = 10;
  const cv::Mat init(scene_.truth.size(), CV_32S, cv::Scalar(3));
  ExpansionOptions options;
  options.max_cycles = 1;
  auto flat = [this](const cv::Rect& region) {
    OwnedMrfProblem p = Crop(scene_.problem, region);
    for (int y = 0; y < region.height; ++y)
      for (int x = 0; x < region.width; ++x)
        for (int l = 0; l < p.data.num_labels(); ++l) p.data.SetCost(y, x, l, l == 3 ? 0.f : 50.f);
    return p;
  };
  const TiledResult tiled =
      OptimizeTiled(scene_.truth.size(), flat, EnergyOptions(), options, tiling, init);
  double min_value = 0, max_value = 0;
  cv::minMaxLoc(tiled.labels, &min_value, &max_value);
  EXPECT_NEAR(min_value, 3.0, 1e-5);
  EXPECT_NEAR(max_value, 3.0, 1e-5);
}

TEST_F(TilingTest, MakeProblemErrorsPropagate) {
  auto broken = [](const cv::Rect&) -> OwnedMrfProblem { throw Error("no costs for this tile"); };
  try {
    OptimizeTiled(scene_.truth.size(), broken, EnergyOptions(), ExpansionOptions(),
                  TilingOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "no costs for this tile");
  }
}

}  // namespace
}  // namespace gcpstereo::optimize
