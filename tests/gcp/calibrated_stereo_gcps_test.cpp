// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The added reliability tests of the stereo source (hand-made evidence) and the calibrated
// (non-rectified) source on the tiny synthetic scene.
#include "gcpstereo/gcp/calibrated_stereo_gcps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/gcp/stereo_gcps.h"
#include "gcpstereo/synth/generator.h"

namespace gcpstereo::gcp {
namespace {

// Evidence of a fronto-parallel pair at disparity d everywhere (both views), every test passing:
// uniqueness 0.5, texture 20 grey levels, no edges.
StereoViewEvidence UniformEvidence(int width, int height, int d) {
  StereoViewEvidence e;
  e.wta_bt = cv::Mat(height, width, CV_32S, cv::Scalar(d));
  e.wta_ncc = e.wta_bt.clone();
  e.wta_aw = e.wta_bt.clone();
  e.uniqueness_bt = cv::Mat(height, width, CV_32F, cv::Scalar(0.5f));
  e.uniqueness_ncc = e.uniqueness_bt.clone();
  e.uniqueness_aw = e.uniqueness_bt.clone();
  e.subpixel_aw = cv::Mat(height, width, CV_32F, cv::Scalar(static_cast<float>(d)));
  e.texture_std = cv::Mat(height, width, CV_32F, cv::Scalar(20.0f));
  e.edges = cv::Mat(height, width, CV_8U, cv::Scalar(0));
  return e;
}

StereoPairEvidence UniformPair(int width, int height, int d) {
  StereoPairEvidence pair;
  pair.left = UniformEvidence(width, height, d);
  pair.right = UniformEvidence(width, height, d);
  return pair;
}

bool IsGcp(const StereoGcpResult& r, int y, int x) {
  return std::isfinite(r.disparity.at<float>(y, x));
}

TEST(StereoGcpFiltersTest, UniformEvidencePassesWherePartnerExists) {
  const StereoPairEvidence pair = UniformPair(20, 3, 4);
  const StereoGcpResult r = SelectStereoGcps(pair, StereoGcpOptions());
  // Left pixels x < 4 have no right partner; the rest pass.
  EXPECT_EQ(r.num_gcps, 3 * 16);
  EXPECT_FALSE(IsGcp(r, 1, 3));
  EXPECT_TRUE(IsGcp(r, 1, 4));
  EXPECT_FLOAT_EQ(r.disparity.at<float>(1, 10), 4.0f);
}

TEST(StereoGcpFiltersTest, UniquenessRejectsAmbiguousWinners) {
  StereoPairEvidence pair = UniformPair(20, 3, 4);
  pair.left.uniqueness_aw.at<float>(1, 10) = 0.29f;  // default threshold 0.3
  pair.left.uniqueness_ncc.at<float>(1, 11) = 0.1f;
  pair.left.uniqueness_bt.at<float>(1, 12) = 0.0f;  // BT test off by default
  pair.right.uniqueness_aw.at<float>(0, 9) = 0.0f;  // partner of left (0, 13)
  StereoGcpOptions options;
  const StereoGcpResult r = SelectStereoGcps(pair, options);
  EXPECT_FALSE(IsGcp(r, 1, 10));
  EXPECT_FALSE(IsGcp(r, 1, 11));
  EXPECT_TRUE(IsGcp(r, 1, 12));
  EXPECT_FALSE(IsGcp(r, 0, 13));  // the right view's candidate failed: no left-right match
  EXPECT_EQ(r.num_ambiguous_left, 2);
  options.min_uniqueness_bt = 0.2;
  EXPECT_FALSE(IsGcp(SelectStereoGcps(pair, options), 1, 12));
  options = StereoGcpOptions();
  options.min_uniqueness_aw = options.min_uniqueness_ncc = 0.0;
  const StereoGcpResult off = SelectStereoGcps(pair, options);
  EXPECT_TRUE(IsGcp(off, 1, 10));
  EXPECT_TRUE(IsGcp(off, 1, 11));
}

TEST(StereoGcpFiltersTest, TextureTestRejectsFlatWindows) {
  StereoPairEvidence pair = UniformPair(20, 3, 4);
  pair.left.texture_std.at<float>(2, 8) = 2.0f;
  StereoGcpOptions options;  // default: test off
  EXPECT_TRUE(IsGcp(SelectStereoGcps(pair, options), 2, 8));
  options.min_texture_std = 3.0;
  const StereoGcpResult r = SelectStereoGcps(pair, options);
  EXPECT_FALSE(IsGcp(r, 2, 8));
  EXPECT_TRUE(IsGcp(r, 2, 9));
  EXPECT_EQ(r.num_low_texture_left, 1);
}

TEST(StereoGcpFiltersTest, OcclusionTestRejectsTheFattenedBand) {
  // Left view: background d = 2 for x < 20, foreground d = 8 from x = 20. The background band
  // [20 − 6, 20) is occluded in the right view; a matcher that fattened the foreground over it
  // reports 8 there, which the left-right check cannot catch. Here the AW map's boundary is at
  // 16 (4 px fattened): pixels 16..(15 + 6 + margin) are in the band of x' = 15.
  const int width = 40;
  StereoPairEvidence pair = UniformPair(width, 1, 2);
  for (cv::Mat* m : {&pair.left.wta_bt, &pair.left.wta_ncc, &pair.left.wta_aw}) {
    for (int x = 16; x < width; ++x) m->at<int>(0, x) = 8;
  }
  for (cv::Mat* m : {&pair.right.wta_bt, &pair.right.wta_ncc, &pair.right.wta_aw}) {
    for (int x = 8; x < width; ++x) m->at<int>(0, x) = 8;
  }
  StereoGcpOptions options;
  options.occlusion_margin_px = -1;
  const StereoGcpResult off = SelectStereoGcps(pair, options);
  EXPECT_TRUE(IsGcp(off, 0, 16));
  options.occlusion_margin_px = 0;
  const StereoGcpResult on = SelectStereoGcps(pair, options);
  // x − 15 <= 8 − 2 + 0  ⇔  x <= 21.
  for (int x = 16; x <= 21; ++x) EXPECT_FALSE(IsGcp(on, 0, x)) << x;
  EXPECT_TRUE(IsGcp(on, 0, 22));
  // The background x = 15 is not in a band (it fails the left-right check instead: its right
  // partner 13 belongs to the fattened foreground of the right view).
  EXPECT_EQ(on.num_occlusion_left, 6);
  options.occlusion_margin_px = 3;
  const StereoGcpResult wide = SelectStereoGcps(pair, options);
  EXPECT_FALSE(IsGcp(wide, 0, 24));
  EXPECT_TRUE(IsGcp(wide, 0, 25));
}

TEST(StereoGcpFiltersTest, ValueIsNccOrMedian) {
  StereoPairEvidence pair = UniformPair(20, 1, 4);
  pair.left.wta_ncc.at<int>(0, 10) = 5;
  pair.left.wta_aw.at<int>(0, 10) = 5;
  pair.left.wta_bt.at<int>(0, 11) = 5;
  pair.left.wta_ncc.at<int>(0, 12) = 5;
  StereoGcpOptions options;
  options.occlusion_margin_px = -1;
  options.value = "median";
  StereoGcpResult r = SelectStereoGcps(pair, options);
  EXPECT_FLOAT_EQ(r.disparity.at<float>(0, 10), 5.0f);
  EXPECT_FLOAT_EQ(r.disparity.at<float>(0, 11), 4.0f);
  options.value = "ncc";
  r = SelectStereoGcps(pair, options);
  EXPECT_FLOAT_EQ(r.disparity.at<float>(0, 11), 4.0f);
  EXPECT_FLOAT_EQ(r.disparity.at<float>(0, 12), 5.0f);
}

TEST(StereoGcpFiltersTest, BadOptionsAndEvidence) {
  StereoGcpOptions options;
  options.min_uniqueness_aw = 1.0;
  try {
    options.Check();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "gcp.stereo.min_uniqueness_aw = 1. Violated constraint: 0 <= min_uniqueness_aw "
                 "< 1");
  }
  options = StereoGcpOptions();
  options.value = "mean";
  EXPECT_THROW(options.Check(), ConfigError);
  options = StereoGcpOptions();
  options.occlusion_margin_px = -2;
  EXPECT_THROW(options.Check(), ConfigError);
  StereoPairEvidence pair = UniformPair(20, 3, 4);
  pair.right.texture_std = cv::Mat();
  try {
    SelectStereoGcps(pair, StereoGcpOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "SelectStereoGcps: evidence maps are missing or of different sizes");
  }
}

// ---- The calibrated source on the tiny synthetic scene ----

class CalibratedStereoGcpsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    synth::SynthOptions options;
    options.preset = "tiny";
    options.seed = 7;
    scene_ = new synth::SyntheticScene(synth::GenerateScene(options));
  }
  static void TearDownTestSuite() {
    delete scene_;
    scene_ = nullptr;
  }
  static synth::SyntheticScene* scene_;
};
synth::SyntheticScene* CalibratedStereoGcpsTest::scene_ = nullptr;

TEST_F(CalibratedStereoGcpsTest, GcpsAreAccurateAndProjectWhereTheyShould) {
  const View& reference = scene_->views[scene_->reference_index];
  const cv::Mat& gt = scene_->depth[scene_->reference_index];
  std::vector<View> neighbors;
  std::vector<int> neighbor_index;
  for (size_t i = 0; i < scene_->views.size(); ++i) {
    if (static_cast<int>(i) == scene_->reference_index) continue;
    neighbors.push_back(scene_->views[i]);
    neighbor_index.push_back(static_cast<int>(i));
  }
  double z_min = std::numeric_limits<double>::infinity(), z_max = 0.0;
  for (int r = 0; r < gt.rows; ++r) {
    for (int c = 0; c < gt.cols; ++c) {
      const float z = gt.at<float>(r, c);
      if (!std::isfinite(z)) continue;
      z_min = std::min<double>(z_min, z);
      z_max = std::max<double>(z_max, z);
    }
  }
  StereoGcpOptions options;
  const CalibratedStereoGcpResult result =
      ExtractCalibratedStereoGcps(reference, neighbors, z_min, z_max, options);
  ASSERT_EQ(result.pairs.size(), 2u);
  for (const auto& p : result.pairs) {
    std::printf(
        "[ calib    ] pair %s: B %.3f f %.1f %s d %d..%d matches %d projected %d "
        "confirmed %d\n",
        p.neighbor.c_str(), p.baseline, p.focal_px, p.mirrored ? "mirrored" : "",
        p.min_disparity_px, p.max_disparity_px, p.num_matches, p.num_projected, p.num_confirmed);
    EXPECT_GT(p.num_matches, 0);
  }
  // Outlier: |z − z_gt| > the depth of 1 px of rectified disparity = σ_z / sigma_px.
  int evaluated = 0, outliers = 0, neighbor_checked = 0, neighbor_bad = 0;
  const View& nearest = *std::find_if(neighbors.begin(), neighbors.end(), [&](const View& v) {
    return v.name == result.pairs[0].neighbor;
  });
  const int nearest_index = neighbor_index[static_cast<size_t>(&nearest - neighbors.data())];
  for (const Gcp& g : result.gcps.points) {
    EXPECT_EQ(g.source, GcpSource::kStereo);
    const float z_gt = gt.at<float>(g.row, g.col);
    if (!std::isfinite(z_gt)) continue;
    ++evaluated;
    const double one_px = g.sigma / options.sigma_px;
    if (std::abs(g.depth - z_gt) > one_px) ++outliers;
    // The GCP's 3D point seen from the nearest neighbour lands on that view's surface.
    const Eigen::Vector3d world =
        reference.camera.BackProject(Eigen::Vector2d(g.col, g.row), g.depth);
    Eigen::Vector2d pixel;
    double depth_nb = 0.0;
    if (!nearest.camera.Project(world, &pixel, &depth_nb)) continue;
    const int c = static_cast<int>(std::lround(pixel.x())),
              r = static_cast<int>(std::lround(pixel.y()));
    if (c < 0 || r < 0 || c >= nearest.camera.width || r >= nearest.camera.height) continue;
    const float z_nb = scene_->depth[nearest_index].at<float>(r, c);
    if (!std::isfinite(z_nb)) continue;
    ++neighbor_checked;
    // A point in front of the neighbour's surface floats in free space (behind it: occluded in
    // that view, fine). Rounding to the reference pixel moves the point by up to half a pixel:
    // allow 2 px' depth.
    if (depth_nb < z_nb - 2.0 * one_px) ++neighbor_bad;
  }
  const double outlier_percent = evaluated ? 100.0 * outliers / evaluated : 100.0;
  std::printf(
      "[ calib    ] tiny: %d GCPs (%.2f %%), outliers %.2f %% (%d of %d), in the "
      "nearest neighbour off its surface %d of %d, %.1f s\n",
      result.summary.num_gcps, result.summary.density_percent, outlier_percent, outliers, evaluated,
      neighbor_bad, neighbor_checked, result.seconds);
  // Tiny (160×107) images leave the 31×31 adaptive-weight matcher few unambiguous pixels; the
  // density is reported, not tuned (measured 0.76 %).
  EXPECT_GT(result.summary.density_percent, 0.3);
  EXPECT_LE(outlier_percent, 2.0);
  EXPECT_GT(neighbor_checked, evaluated / 2);
  EXPECT_LE(neighbor_bad, std::max(1, neighbor_checked / 50));
  EXPECT_EQ(result.summary.num_gcps, static_cast<int>(result.gcps.size()));
  EXPECT_GT(result.summary.num_inconsistent, 0);  // the cross-pair check did reject some

  // Without the confirmation more GCPs, never fewer.
  options.min_confirmations = 0;
  const CalibratedStereoGcpResult unconfirmed =
      ExtractCalibratedStereoGcps(reference, neighbors, z_min, z_max, options);
  EXPECT_GE(unconfirmed.summary.num_gcps, result.summary.num_gcps);
}

// The `small` scene (640×427) and its stereo GCPs matched at a quarter of its resolution, made
// once for the tests below.
class QuarterScaleGcpsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    synth::SynthOptions synth_options;
    synth_options.preset = "small";
    synth_options.seed = 7;
    scene_ = new synth::SyntheticScene(synth::GenerateScene(synth_options));
    const View& reference = scene_->views[scene_->reference_index];
    const cv::Mat& gt = scene_->depth[scene_->reference_index];
    neighbors_ = new std::vector<View>();
    for (size_t i = 0; i < scene_->views.size(); ++i) {
      if (static_cast<int>(i) != scene_->reference_index) neighbors_->push_back(scene_->views[i]);
    }
    cv::minMaxLoc(gt, &z_min_, &z_max_, nullptr, nullptr, gt < 1e30f);
    options_.image_scale = 0.25;
    result_ = new CalibratedStereoGcpResult(
        ExtractCalibratedStereoGcps(reference, *neighbors_, z_min_, z_max_, options_));
  }
  static void TearDownTestSuite() {
    delete scene_;
    delete neighbors_;
    delete result_;
    scene_ = nullptr;
    neighbors_ = nullptr;
    result_ = nullptr;
  }
  static synth::SyntheticScene* scene_;
  static std::vector<View>* neighbors_;
  static CalibratedStereoGcpResult* result_;
  static StereoGcpOptions options_;
  static double z_min_, z_max_;
};
synth::SyntheticScene* QuarterScaleGcpsTest::scene_ = nullptr;
std::vector<View>* QuarterScaleGcpsTest::neighbors_ = nullptr;
CalibratedStereoGcpResult* QuarterScaleGcpsTest::result_ = nullptr;
StereoGcpOptions QuarterScaleGcpsTest::options_;
double QuarterScaleGcpsTest::z_min_ = 0.0;
double QuarterScaleGcpsTest::z_max_ = 0.0;

// gcp.stereo.image_scale: the GCPs land on the full-resolution grid with depths that agree with
// the full-resolution truth.
TEST_F(QuarterScaleGcpsTest, GcpsLandOnTheFullGrid) {
  const cv::Mat& gt = scene_->depth[scene_->reference_index];
  const CalibratedStereoGcpResult& result = *result_;
  const StereoGcpOptions& options = options_;
  int evaluated = 0, outliers = 0;
  for (const Gcp& g : result.gcps.points) {
    ASSERT_TRUE(g.col >= 0 && g.row >= 0 && g.col < gt.cols && g.row < gt.rows);
    // A quarter-resolution pixel covers 4×4 reference pixels: compare with the nearest truth in
    // that footprint (depth edges move by up to 2 px).
    double best = std::numeric_limits<double>::infinity();
    for (int r = std::max(0, g.row - 2); r <= std::min(gt.rows - 1, g.row + 2); ++r) {
      for (int c = std::max(0, g.col - 2); c <= std::min(gt.cols - 1, g.col + 2); ++c) {
        const float z = gt.at<float>(r, c);
        if (std::isfinite(z)) best = std::min(best, std::abs(g.depth - z));
      }
    }
    if (!std::isfinite(best)) continue;
    ++evaluated;
    if (best > g.sigma / options.sigma_px) ++outliers;  // > 1 px of disparity at the match scale
  }
  std::printf("[ calib    ] small at 1/4: %d GCPs (%.3f %% of the full grid), outliers %d of %d\n",
              result.summary.num_gcps, result.summary.density_percent, outliers, evaluated);
  EXPECT_EQ(result.summary.num_gcps, static_cast<int>(result.gcps.size()));
  EXPECT_GT(evaluated, 20);
  EXPECT_LE(outliers, std::max(1, evaluated / 50));
}

// gcp.stereo.refine_px: the quarter-resolution matches, searched again within ±1 px of their
// disparity on the full resolution's plane-sweep cost over 360 depth labels, land within a label
// of the truth far more often; GCPs of other sources pass unchanged, in their place.
TEST_F(QuarterScaleGcpsTest, RefinementMovesMatchesOntoTheirLabel) {
  const View& reference = scene_->views[scene_->reference_index];
  const cv::Mat& gt = scene_->depth[scene_->reference_index];
  const std::vector<View>& neighbors = *neighbors_;
  const StereoGcpOptions& options = options_;
  const GcpSet& gcps = result_->gcps;
  ASSERT_GT(gcps.size(), 20u);
  const LabelSpace labels(LabelSpaceKind::kDepth, 360, z_min_, z_max_);
  // Within one label of the truth (returned) and beyond 5 labels (*far, percent).
  auto score = [&](const GcpSet& set, double* far) {
    int good = 0, counted = 0, bad = 0;
    for (const Gcp& g : set.points) {
      if (g.source != GcpSource::kStereo) continue;
      const float z = gt.at<float>(g.row, g.col);
      if (!std::isfinite(z)) continue;
      ++counted;
      const double e = std::abs(labels.LabelOfDepth(g.depth) - labels.LabelOfDepth(z));
      good += e <= 1.0 ? 1 : 0;
      bad += e > 5.0 ? 1 : 0;
    }
    *far = counted ? 100.0 * bad / counted : 0.0;
    return counted ? 100.0 * good / counted : 0.0;
  };
  // A LiDAR GCP rides along untouched.
  Gcp lidar = gcps.points.front();
  lidar.source = GcpSource::kLidar;
  lidar.depth = labels.DepthOfLabel(100.25);
  GcpSet input = gcps;
  input.points.insert(input.points.begin() + static_cast<long>(gcps.size() / 2), lidar);

  GcpRefinementSummary summary;
  const GcpSet refined = RefineGcpsOnLabels(input, reference, neighbors, labels, 1.0,
                                            options.sigma_px, 5, {}, &summary);
  double far_before = 0.0, far_after = 0.0;
  const double before = score(gcps, &far_before), after = score(refined, &far_after);
  std::printf(
      "[ refine   ] small at 1/4, 360 labels: within 1 label %.1f %% -> %.1f %% (beyond 5: %.1f "
      "-> %.1f %%); %d of %d refined, %d at the edge, %d without data, mean shift %.2f, %.3f s\n",
      before, after, far_before, far_after, summary.refined, summary.input, summary.dropped_at_edge,
      summary.dropped_no_data, summary.mean_shift_labels, summary.seconds);
  EXPECT_EQ(summary.input, static_cast<int>(gcps.size()));
  EXPECT_EQ(summary.refined + summary.dropped_at_edge + summary.dropped_no_data, summary.input);
  EXPECT_EQ(static_cast<int>(refined.size()), summary.refined + 1);
  EXPECT_GT(summary.refined, static_cast<int>(gcps.size()) * 3 / 4);
  EXPECT_GT(after, before + 20.0);
  EXPECT_GT(after, 90.0);
  EXPECT_LT(far_after, far_before / 4.0);
  // The LiDAR GCP is unchanged and keeps its place among the refined ones.
  const auto it = std::find_if(refined.points.begin(), refined.points.end(),
                               [](const Gcp& g) { return g.source == GcpSource::kLidar; });
  ASSERT_NE(it, refined.points.end());
  EXPECT_EQ(it->depth, lidar.depth);
  EXPECT_EQ(it->sigma, lidar.sigma);
  EXPECT_EQ(it->col, lidar.col);
  for (auto g = refined.points.begin(); g != refined.points.end(); ++g) {
    if (g == it) continue;
    // Raster order of the input is kept around it.
    const bool before_it = g < it;
    EXPECT_EQ(before_it,
              std::make_pair(g->row, g->col) < std::make_pair(gcps.points[gcps.size() / 2].row,
                                                              gcps.points[gcps.size() / 2].col));
  }
  EXPECT_THROW(RefineGcpsOnLabels(input, reference, neighbors, labels, 0.0, 0.5, 5, {}), Error);
  EXPECT_THROW(RefineGcpsOnLabels(input, reference, neighbors, labels, 1.0, 0.0, 5, {}), Error);
  EXPECT_THROW(RefineGcpsOnLabels(input, reference, neighbors, labels, 1.0, 0.5, 4, {}), Error);
}

TEST_F(CalibratedStereoGcpsTest, BadInputsThrow) {
  const View& reference = scene_->views[scene_->reference_index];
  const View& other = scene_->views[(scene_->reference_index + 1) % scene_->views.size()];
  const StereoGcpOptions options;
  try {
    ExtractCalibratedStereoGcps(reference, {}, 1.0, 10.0, options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "ExtractCalibratedStereoGcps: no neighbour view");
  }
  try {
    ExtractCalibratedStereoGcps(reference, {other}, 5.0, 2.0, options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "ExtractCalibratedStereoGcps: depth range [5, 2] must satisfy 0 < min < max < "
                 "inf");
  }
  View same = reference;
  same.name = "copy";
  try {
    ExtractCalibratedStereoGcps(reference, {same}, 1.0, 10.0, options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "ExtractCalibratedStereoGcps: view 'copy' has the reference's camera centre (no "
                 "baseline)");
  }
  View small = other;
  small.image = cv::Mat(10, 10, CV_8UC3);
  EXPECT_THROW(ExtractCalibratedStereoGcps(reference, {small}, 1.0, 10.0, options), Error);
}

}  // namespace
}  // namespace gcpstereo::gcp
