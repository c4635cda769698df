// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/label_range.h"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "synthetic_scene.h"
#include "test_data.h"

namespace gcpstereo::cost {
namespace {

using gcpstereo::testing::ErrorOf;

GcpSet Gcps(const std::vector<double>& depths, GcpSource source = GcpSource::kLidar) {
  GcpSet set;
  for (double d : depths) set.points.push_back(Gcp{0, 0, d, 0.0, source});
  return set;
}

TEST(LabelRange, GcpPercentilesWithMargin) {
  // 1 … 101 plus an outlier and invalid depths: percentiles by linear interpolation.
  std::vector<double> depths;
  for (int i = 1; i <= 101; ++i) depths.push_back(i);
  depths.push_back(1e6);  // 102 valid values now
  depths.push_back(-3.0);
  depths.push_back(std::nan(""));
  const auto [lo, hi] = DepthRangeFromGcps(Gcps(depths), 10.0, 90.0, 0.0);
  // position p·(n−1) with n = 102: 10.1 → 11.1; 90.9 → 91.9.
  EXPECT_NEAR(lo, 11.1, 1e-9);
  EXPECT_NEAR(hi, 91.9, 1e-9);
  const auto [lo2, hi2] = DepthRangeFromGcps(Gcps({2.0, 4.0}), 0.0, 100.0, 0.25);
  EXPECT_DOUBLE_EQ(lo2, 2.0 / 1.25);
  EXPECT_DOUBLE_EQ(hi2, 4.0 * 1.25);
  EXPECT_EQ(ErrorOf([] {
              DepthRangeFromGcps(Gcps({0.0, -1.0}), 1, 99, 0.1);
            }),
            "automatic label range: none of the 2 GCPs has a finite positive depth");
  EXPECT_EQ(ErrorOf([] { DepthRangeFromGcps(Gcps({1.0}), 50, 50, 0.1); }),
            "labels.auto.gcp_low_percentile, gcp_high_percentile = 50, 50. Violated constraint: "
            "0 <= low < high <= 100");
  EXPECT_EQ(ErrorOf([] { DepthRangeFromGcps(Gcps({1.0}), 1, 99, -0.5); }),
            "labels.auto.margin = -0.5. Violated constraint: 0 <= margin < inf");
}

// Rectified cameras along x (focal f, baseline b per view): reference ray at column u is seen by
// the view one step right for z >= f·b / (u + ½) and by the view one step left for z >= f·b / (W −
// ½ − u); both are unbounded in depth.
TEST(LabelRange, FrustumOverlapOfRectifiedCameras) {
  const int width = 65, height = 9;
  const double f = 100.0, b = 0.3;
  auto view = [&](int index) {
    return View{"v" + std::to_string(index), cv::Mat(),
                RectifiedSequenceCamera(f, 32.0, 4.0, b, index, width, height)};
  };
  const View ref = view(0);
  LabelRangeOptions options;
  auto [near, far] = DepthRangeFromFrustumOverlap(ref, {view(1)}, options);
  EXPECT_NEAR(near, f * b / (width - 0.5), 1e-9);
  EXPECT_TRUE(std::isinf(far));
  options.max_depth = 50.0;
  std::tie(near, far) = DepthRangeFromFrustumOverlap(ref, {view(1), view(-1)}, options);
  EXPECT_NEAR(near, f * b / (width - 0.5), 1e-9);
  EXPECT_EQ(far, 50.0);
  // Seen by both: the nearest depth is on the middle column (u = 32, on the 8-px grid).
  options.min_neighbors = 2;
  std::tie(near, far) = DepthRangeFromFrustumOverlap(ref, {view(1), view(-1)}, options);
  EXPECT_NEAR(near, f * b / 32.5, 1e-9);
  EXPECT_EQ(far, 50.0);
  options.min_neighbors = 3;
  EXPECT_EQ(ErrorOf([&] {
              DepthRangeFromFrustumOverlap(ref, {view(1), view(-1)}, options);
            }),
            "automatic label range: no ray of the reference view 'v0' is seen by 3 neighbour(s) "
            "(labels.auto.min_neighbors); set labels.min and labels.max");
  options = {};
  options.grid_step_px = 0;
  EXPECT_EQ(ErrorOf([&] { options.Check(); }),
            "labels.auto.grid_step_px = 0. Violated constraint: grid_step_px >= 1");
}

// Converging cameras: a bounded frustum overlap; every depth inside is seen, every depth well
// outside is not.
TEST(LabelRange, FrustumOverlapOfConvergingCamerasIsConsistent) {
  using testing::LookAtCamera;
  const Eigen::Vector3d target(0, 0, 4);
  const View ref{"ref", cv::Mat(), LookAtCamera(Eigen::Vector3d::Zero(), target, 80, 64, 48)};
  // The neighbour's axis is 56° from the reference's, more than the 21.8° half field of view of
  // both: no reference ray reaches infinity inside the neighbour's image.
  const View nb{"nb", cv::Mat(), LookAtCamera(Eigen::Vector3d(6, 0, 0), target, 80, 64, 48)};
  LabelRangeOptions options;
  options.grid_step_px = 1;
  const auto [near, far] = DepthRangeFromFrustumOverlap(ref, {nb}, options);
  ASSERT_TRUE(std::isfinite(far));
  ASSERT_LT(near, 4.0);
  ASSERT_GT(far, 4.0);
  // Brute force over rays and depths: the seen set spans [near, far].
  double seen_min = 1e9, seen_max = 0;
  for (int r = 0; r < 48; ++r) {
    for (int c = 0; c < 64; ++c) {
      for (double z = 0.05; z < 200; z *= 1.002) {
        const Eigen::Vector3d X = ref.camera.BackProject(Eigen::Vector2d(c, r), z);
        Eigen::Vector2d px;
        double depth;
        if (nb.camera.Project(X, &px, &depth) && nb.camera.InImage(px)) {
          seen_min = std::min(seen_min, z);
          seen_max = std::max(seen_max, z);
        }
      }
    }
  }
  EXPECT_NEAR(seen_min, near, 0.003 * near);
  EXPECT_NEAR(seen_max, far, 0.003 * far);
}

TEST(LabelRange, MakeLabelSpaceFillsMissingBounds) {
  const View ref{"r", cv::Mat(), RectifiedSequenceCamera(100, 32, 4, 0.3, 0, 65, 9)};
  const std::vector<View> nbs = {
      View{"n", cv::Mat(), RectifiedSequenceCamera(100, 32, 4, 0.3, 1, 65, 9)}};
  LabelRangeSummary summary;
  // Configured range: taken as is.
  LabelSpace s = MakeLabelSpace(LabelSpaceKind::kDepth, 10, 1.0, 5.0, GcpSet{}, ref, nbs, 0.0,
                                false, {}, &summary);
  EXPECT_EQ(summary.source, "config");
  EXPECT_EQ(s.min(), 1.0);
  EXPECT_EQ(s.max(), 5.0);
  // From GCPs, in disparity (numerator 30): depth [2/1.1, 4·1.1] → disparity [0, 30·1.1/2] (the
  // automatic minimum of disparity labels is 0).
  LabelRangeOptions options;
  options.gcp_low_percentile = 0;
  options.gcp_high_percentile = 100;
  s = MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt,
                     Gcps({2.0, 3.0, 4.0}), ref, nbs, 30.0, false, options, &summary);
  EXPECT_EQ(summary.source, "gcps");
  EXPECT_EQ(s.min(), 0.0);
  EXPECT_NEAR(s.max(), 30.0 * 1.1 / 2.0, 1e-9);
  EXPECT_EQ(s.count(), 16);
  // Without a count: one label per pixel, the automatic bound rounded up (16.5 → 17).
  s = MakeLabelSpace(LabelSpaceKind::kDisparity, std::nullopt, std::nullopt, std::nullopt,
                     Gcps({2.0, 3.0, 4.0}), ref, nbs, 30.0, false, options, &summary);
  EXPECT_EQ(s.min(), 0.0);
  EXPECT_EQ(s.max(), 17.0);
  EXPECT_EQ(s.count(), 18);
  EXPECT_EQ(s.step(), 1.0);
  // … and from given bounds, steps of at most one pixel.
  s = MakeLabelSpace(LabelSpaceKind::kDisparity, std::nullopt, 2.0, 12.5, GcpSet{}, ref, nbs, 30.0,
                     false);
  EXPECT_EQ(s.count(), 12);
  EXPECT_LE(s.step(), 1.0);
  EXPECT_EQ(ErrorOf([&] {
              MakeLabelSpace(LabelSpaceKind::kDepth, std::nullopt, 1.0, 5.0, GcpSet{}, ref, nbs,
                             0.0, false);
            }),
            "labels.count = auto. Violated constraint: one label per pixel of disparity needs "
            "labels.space disparity");
  // Min from the config, max from the GCPs (inverse depth).
  s = MakeLabelSpace(LabelSpaceKind::kInverseDepth, 16, 0.1, std::nullopt, Gcps({2.0, 4.0}), ref,
                     nbs, 0.0, false, options, &summary);
  EXPECT_EQ(summary.source, "config+gcps");
  EXPECT_EQ(s.min(), 0.1);
  EXPECT_NEAR(s.max(), 1.1 / 2.0, 1e-9);
  // From the frustum: inverse depth down to 0 (unbounded far).
  s = MakeLabelSpace(LabelSpaceKind::kInverseDepth, 16, std::nullopt, std::nullopt, GcpSet{}, ref,
                     nbs, 0.0, false, {}, &summary);
  EXPECT_EQ(summary.source, "frustum");
  EXPECT_EQ(s.min(), 0.0);
  EXPECT_NEAR(s.max(), 64.5 / 30.0, 1e-9);
  // Depth labels cannot be unbounded.
  EXPECT_EQ(ErrorOf([&] {
              MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt, GcpSet{}, ref,
                             nbs, 0.0, false);
            }),
            "labels.max = auto. Violated constraint: automatic depth range [0.465116, inf] from "
            "the neighbours' frustum overlap is unbounded; set labels.max or "
            "labels.auto.max_depth, or use labels.space inverse_depth");
  options = {};
  options.max_depth = 20.0;
  s = MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt, GcpSet{}, ref, nbs,
                     0.0, false, options);
  EXPECT_NEAR(s.min(), 30.0 / 64.5, 1e-9);
  EXPECT_EQ(s.max(), 20.0);
}

// A rectified pair of random texture: the background at disparity `far_px`, a square at `near_px`
// (left x − right x), `width` × 120 pixels.
std::pair<cv::Mat, cv::Mat> ShiftedPair(int width, int far_px, int near_px) {
  cv::RNG rng(7);
  cv::Mat texture(120, width + near_px, CV_8UC3), square(60, 60 + near_px, CV_8UC3);
  rng.fill(texture, cv::RNG::UNIFORM, 0, 256);
  rng.fill(square, cv::RNG::UNIFORM, 0, 256);
  cv::Mat left = texture.colRange(0, width).clone();
  cv::Mat right(120, width, CV_8UC3);
  // right(x) = left(x + d): the right image sees each point d pixels further left.
  texture.colRange(far_px, far_px + width).copyTo(right);
  square.colRange(0, 60).copyTo(left(cv::Rect(width / 2, 30, 60, 60)));
  square.colRange(0, 60).copyTo(right(cv::Rect(width / 2 - near_px, 30, 60, 60)));
  return {left, right};
}

TEST(LabelRange, MatchedDisparitiesOfARectifiedPair) {
  // Background at 6 px, a square at 40 px; the search covers every disparity below the width.
  for (const int width : {120, 320}) {  // full resolution, and halved above 200 px
    const auto [left, right] = ShiftedPair(width, 6, 40);
    const auto range = DisparityRangeFromMatching(left, right);
    ASSERT_TRUE(range.has_value()) << width;
    EXPECT_NEAR(range->first, 6.0, 2.0) << width;
    EXPECT_NEAR(range->second, 40.0, 2.0) << width;
  }
  // Nothing to match on a textureless pair.
  const cv::Mat flat(120, 320, CV_8UC3, cv::Scalar(90, 90, 90));
  EXPECT_FALSE(DisparityRangeFromMatching(flat, flat).has_value());
  EXPECT_EQ(ErrorOf([&] { DisparityRangeFromMatching(flat, flat.colRange(0, 300).clone()); }),
            "DisparityRangeFromMatching: the images must be non-empty 8-bit grey or BGR images of "
            "one size and type (and the mask CV_8U of their size)");
}

TEST(LabelRange, RectifiedPairRangeSpansMatchesAndGcps) {
  const auto [left, right] = ShiftedPair(320, 6, 40);
  // f = 100, baseline 0.3 per view: disparity = 30 / depth.
  const View ref{"r", left, RectifiedSequenceCamera(100, 160, 60, 0.3, 0, 320, 120)};
  const std::vector<View> nbs = {
      View{"n", right, RectifiedSequenceCamera(100, 160, 60, 0.3, 1, 320, 120)}};
  LabelRangeSummary summary;
  const auto matched = DisparityRangeFromMatching(left, right);
  ASSERT_TRUE(matched.has_value());
  // No GCPs: the matched disparities, widened by the margin (0.1).
  LabelSpace s = MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt,
                                GcpSet{}, ref, nbs, 30.0, true, {}, &summary);
  EXPECT_EQ(summary.source, "matching");
  EXPECT_EQ(s.min(), 0.0);
  EXPECT_NEAR(s.max(), matched->second * 1.1, 1e-9);
  // In depth: the far end from the matched background.
  s = MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt, GcpSet{}, ref, nbs,
                     30.0, true, {}, &summary);
  EXPECT_NEAR(s.min(), 30.0 / matched->second / 1.1, 1e-9);
  EXPECT_NEAR(s.max(), 30.0 / matched->first * 1.1, 1e-9);
  // A background at disparity 0 (the sky) leaves depth unbounded: labels.auto.max_depth caps it.
  {
    const auto [sky_left, sky_right] = ShiftedPair(320, 0, 40);
    const View sky_ref{"r", sky_left, ref.camera};
    const std::vector<View> sky_nbs = {View{"n", sky_right, nbs[0].camera}};
    EXPECT_NE(ErrorOf([&] {
                MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt, GcpSet{},
                               sky_ref, sky_nbs, 30.0, true);
              }).find("is unbounded; set labels.max or labels.auto.max_depth"),
              std::string::npos);
    LabelRangeOptions capped;
    capped.max_depth = 50.0;
    s = MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt, GcpSet{}, sky_ref,
                       sky_nbs, 30.0, true, capped, &summary);
    EXPECT_EQ(summary.source, "matching");
    EXPECT_EQ(s.max(), 50.0);
  }
  // A small patch at disparity 0 (here about 4 % of the pixels) over a background at 6 px: with
  // labels.auto.matching_far_percentile above its share, the far end comes from the background;
  // below it, or at 0, the range stays unbounded.
  {
    auto [patch_left, patch_right] = ShiftedPair(320, 6, 40);
    cv::Mat patch(40, 40, CV_8UC3);
    cv::RNG(11).fill(patch, cv::RNG::UNIFORM, 0, 256);
    patch.copyTo(patch_left(cv::Rect(60, 40, 40, 40)));
    patch.copyTo(patch_right(cv::Rect(60, 40, 40, 40)));
    const View patch_ref{"r", patch_left, ref.camera};
    const std::vector<View> patch_nbs = {View{"n", patch_right, nbs[0].camera}};
    const auto with_zero = DisparityRangeFromMatching(patch_left, patch_right);
    ASSERT_TRUE(with_zero.has_value());
    EXPECT_EQ(with_zero->first, 0.0);
    for (const double percentile : {0.0, 2.0}) {
      LabelRangeOptions options;
      options.matching_far_percentile = percentile;
      EXPECT_NE(ErrorOf([&] {
                  MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt, GcpSet{},
                                 patch_ref, patch_nbs, 30.0, true, options);
                }).find("is unbounded"),
                std::string::npos)
          << percentile;
    }
    LabelRangeOptions options;
    options.matching_far_percentile = 10.0;
    s = MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt, GcpSet{}, patch_ref,
                       patch_nbs, 30.0, true, options, &summary);
    EXPECT_EQ(summary.source, "matching-percentile");
    EXPECT_NEAR(s.max(), 30.0 / 6.0 * 1.1, 0.5);
    // Other label spaces keep the disparity-0 end (depth +inf is a finite label there).
    s = MakeLabelSpace(LabelSpaceKind::kInverseDepth, 16, std::nullopt, std::nullopt, GcpSet{},
                       patch_ref, patch_nbs, 30.0, true, options, &summary);
    EXPECT_EQ(summary.source, "matching");
    EXPECT_EQ(s.min(), 0.0);
    options.matching_far_percentile = 50.0;
    EXPECT_EQ(ErrorOf([&] { options.Check(); }),
              "labels.auto.matching_far_percentile = 50. Violated constraint: 0 <= "
              "matching_far_percentile < 50");
  }
  // GCPs only on the background (depth 5 = disparity 6): the square's disparities still count…
  LabelRangeOptions options;
  options.gcp_low_percentile = 0;
  options.gcp_high_percentile = 100;
  s = MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt,
                     Gcps({5.0, 5.0}, GcpSource::kStereo), ref, nbs, 30.0, true, options, &summary);
  EXPECT_EQ(summary.source, "gcps+matching");
  EXPECT_NEAR(s.max(), matched->second * 1.1, 1e-9);
  // In depth, the far end stays the GCPs' (depth 3, disparity 10; the background is at depth 5).
  s = MakeLabelSpace(LabelSpaceKind::kDepth, 16, std::nullopt, std::nullopt,
                     Gcps({2.0, 3.0}, GcpSource::kStereo), ref, nbs, 30.0, true, options, &summary);
  EXPECT_EQ(summary.source, "gcps+matching");
  EXPECT_NEAR(s.min(), 30.0 / matched->second / 1.1, 1e-9);
  EXPECT_NEAR(s.max(), 3.0 * 1.1, 1e-9);
  // … and a GCP nearer than anything matched widens the range beyond the matches.
  s = MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt,
                     Gcps({5.0, 0.5}, GcpSource::kStereo), ref, nbs, 30.0, true, options, &summary);
  EXPECT_NEAR(s.max(), 60.0 * 1.1, 1e-9);
  // A range sensor's GCPs (here a LiDAR's, on the background only) are the range by themselves.
  s = MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt, Gcps({5.0, 5.0}),
                     ref, nbs, 30.0, true, options, &summary);
  EXPECT_EQ(summary.source, "gcps");
  EXPECT_NEAR(s.max(), 6.0 * 1.1, 1e-9);
  // A textureless pair falls back to the GCPs.
  const cv::Mat flat(120, 320, CV_8UC3, cv::Scalar(90, 90, 90));
  const View flat_ref{"r", flat, ref.camera};
  const std::vector<View> flat_nbs = {View{"n", flat, nbs[0].camera}};
  s = MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt,
                     Gcps({5.0, 2.0}, GcpSource::kStereo), flat_ref, flat_nbs, 30.0, true, options,
                     &summary);
  EXPECT_EQ(summary.source, "gcps");
  EXPECT_NEAR(s.max(), 15.0 * 1.1, 1e-9);
}

// A run builds its label space twice on the same views (provisionally for the stereo GCPs' search,
// then finally): the matched range is computed on the first call and reused on the second.
TEST(LabelRange, MatchedRangeIsComputedOnceWithACache) {
  const auto [left, right] = ShiftedPair(320, 6, 40);
  const View ref{"r", left, RectifiedSequenceCamera(100, 160, 60, 0.3, 0, 320, 120)};
  const std::vector<View> nbs = {
      View{"n", right, RectifiedSequenceCamera(100, 160, 60, 0.3, 1, 320, 120)}};
  const auto matched = DepthRangeFromMatching(ref, nbs, true);
  ASSERT_TRUE(matched.has_value());
  MatchedDepthRange cache;
  LabelRangeSummary summary;
  const LabelSpace first =
      MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt, GcpSet{}, ref, nbs,
                     30.0, true, {}, &summary, &cache);
  EXPECT_TRUE(cache.computed);
  ASSERT_TRUE(cache.depths.has_value());
  EXPECT_EQ(*cache.depths, *matched);
  // The second call takes the cached range and does not match again: a cache holding another
  // range (as if other images had been matched) gives that range.
  cache.depths = std::make_pair(matched->first * 2.0, matched->second);
  const LabelSpace second =
      MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt, GcpSet{}, ref, nbs,
                     30.0, true, {}, &summary, &cache);
  EXPECT_EQ(summary.source, "matching");
  EXPECT_NEAR(second.max(), first.max() / 2.0, 1e-9);
  // A cached "nothing matched" is kept as well: the range falls back as without matches.
  cache.depths.reset();
  MakeLabelSpace(LabelSpaceKind::kDisparity, 16, std::nullopt, std::nullopt,
                 Gcps({5.0, 2.0}, GcpSource::kStereo), ref, nbs, 30.0, true, {}, &summary, &cache);
  EXPECT_EQ(summary.source, "gcps");
}

}  // namespace
}  // namespace gcpstereo::cost
