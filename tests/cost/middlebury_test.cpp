// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Winner-take-all on real Middlebury data (skipped when ../shared/data is absent). WTA without
// aggregation or smoothing is a weak matcher: these tests only bound the error well below chance
// and print the numbers for the report.
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "gcpstereo/cost/birchfield_tomasi.h"
#include "gcpstereo/cost/plane_sweep.h"
#include "gcpstereo/cost/winner_take_all.h"
#include "test_data.h"

namespace gcpstereo::cost {
namespace {

cv::Mat Read(const std::string& path, int flags) {
  cv::Mat m = cv::imread(path, flags);
  if (m.empty()) ADD_FAILURE() << "cannot read " << path;
  return m;
}

struct Bad1 {
  double nonocc = 0.0, all = 0.0;
};

// Middlebury v2 bad-1 (|d − d_gt| > 1) within the official masks; `disparity` CV_32F.
Bad1 Score(const cv::Mat& disparity, const cv::Mat& gt_raw, double gt_scale, const cv::Mat& nonocc,
           const cv::Mat& all) {
  Bad1 out;
  auto rate = [&](const cv::Mat& mask) {
    int counted = 0, bad = 0;
    for (int r = 0; r < disparity.rows; ++r) {
      for (int c = 0; c < disparity.cols; ++c) {
        if (mask.at<std::uint8_t>(r, c) != 255 || gt_raw.at<std::uint8_t>(r, c) == 0) continue;
        ++counted;
        const double gt = gt_raw.at<std::uint8_t>(r, c) / gt_scale;
        const float d = disparity.at<float>(r, c);
        if (!std::isfinite(d) || std::abs(d - gt) > 1.0) ++bad;
      }
    }
    return counted ? 100.0 * bad / counted : 100.0;
  };
  out.nonocc = rate(nonocc);
  out.all = rate(all);
  return out;
}

struct Scene {
  std::string dir, left, right, gt;
  double gt_scale;    // GT disparity = stored value / gt_scale (disparity of the left/right pair)
  int max_disparity;  // labels 0 … max_disparity
  int pair_steps;     // view steps between left and right (disparity per step = d / pair_steps)
  int ref_index;      // view index of `left` in the sequence
  std::vector<std::pair<std::string, int>> sequence;  // (file, view index) neighbours
};

Scene Tsukuba(const std::string& dir) {
  return {dir,
          "scene1.row3.col3.ppm",
          "scene1.row3.col4.ppm",
          "truedisp.row3.col3.pgm",
          16.0,
          15,
          1,
          3,
          {{"scene1.row3.col1.ppm", 1},
           {"scene1.row3.col2.ppm", 2},
           {"scene1.row3.col4.ppm", 4},
           {"scene1.row3.col5.ppm", 5}}};
}

Scene Venus(const std::string& dir) {
  return {dir,
          "im2.ppm",
          "im6.ppm",
          "disp2.pgm",
          8.0,
          19,
          4,
          2,
          {{"im0.ppm", 0},
           {"im1.ppm", 1},
           {"im3.ppm", 3},
           {"im4.ppm", 4},
           {"im5.ppm", 5},
           {"im6.ppm", 6}}};
}

Bad1 RunBirchfieldTomasi(const Scene& s, const std::string& name,
                         const BirchfieldTomasiOptions& options = {},
                         const std::string& what = "BT") {
  const cv::Mat left = Read(s.dir + "/" + s.left, cv::IMREAD_COLOR);
  const cv::Mat right = Read(s.dir + "/" + s.right, cv::IMREAD_COLOR);
  const cv::Mat gt = Read(s.dir + "/" + s.gt, cv::IMREAD_GRAYSCALE);
  const cv::Mat nonocc = Read(s.dir + "/nonocc.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat all = Read(s.dir + "/all.png", cv::IMREAD_GRAYSCALE);
  if (left.empty() || right.empty() || gt.empty() || nonocc.empty() || all.empty()) return {};
  std::vector<double> disparities;
  for (int d = 0; d <= s.max_disparity; ++d) disparities.push_back(d);
  const CostVolume volume = ComputeBirchfieldTomasiCost(
      left, right, disparities, cv::Rect(0, 0, left.cols, left.rows), options);
  cv::Mat wta = WinnerTakeAll(volume);
  cv::Mat disparity;
  wta.convertTo(disparity, CV_32F);  // label = disparity (0 … max)
  disparity.setTo(kInvalidDepth, wta < 0);
  const Bad1 bad = Score(disparity, gt, s.gt_scale, nonocc, all);
  std::cout << "[ measured ] " << name << " " << what << " WTA bad-1: nonocc " << bad.nonocc
            << " %, all " << bad.all << " %\n";
  ::testing::Test::RecordProperty(name + "_" + what + "_wta_bad1_nonocc",
                                  std::to_string(bad.nonocc));
  ::testing::Test::RecordProperty(name + "_" + what + "_wta_bad1_all", std::to_string(bad.all));
  return bad;
}

Bad1 RunPlaneSweep(const Scene& s, const std::string& name, const PlaneSweepOptions& options) {
  const cv::Mat left = Read(s.dir + "/" + s.left, cv::IMREAD_COLOR);
  const cv::Mat gt = Read(s.dir + "/" + s.gt, cv::IMREAD_GRAYSCALE);
  const cv::Mat nonocc = Read(s.dir + "/nonocc.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat all = Read(s.dir + "/all.png", cv::IMREAD_GRAYSCALE);
  if (left.empty() || gt.empty() || nonocc.empty() || all.empty()) return {};
  // Unit focal length and baseline: disparity per step = 1 / z; the GT pair spans pair_steps.
  auto camera = [&](int index) {
    return RectifiedSequenceCamera(1.0, (left.cols - 1) / 2.0, (left.rows - 1) / 2.0, 1.0, index,
                                   left.cols, left.rows);
  };
  const View reference{s.left, left, camera(s.ref_index)};
  std::vector<View> neighbors;
  for (const auto& [file, index] : s.sequence) {
    neighbors.push_back(View{file, Read(s.dir + "/" + file, cv::IMREAD_COLOR), camera(index)});
  }
  const LabelSpace labels(LabelSpaceKind::kDisparity, s.max_disparity + 1, 0.0, s.max_disparity,
                          s.pair_steps);
  const CostVolume volume = ComputePlaneSweepCost(reference, neighbors, labels,
                                                  cv::Rect(0, 0, left.cols, left.rows), options);
  const cv::Mat disparity = LabelsToValue(WinnerTakeAll(volume), labels);
  const Bad1 bad = Score(disparity, gt, s.gt_scale, nonocc, all);
  std::cout << "[ measured ] " << name << " plane-sweep (" << neighbors.size() << " neighbours, "
            << options.aggregation << ", tau " << options.truncation << ") WTA bad-1: nonocc "
            << bad.nonocc << " %, all " << bad.all << " %\n";
  ::testing::Test::RecordProperty(name + "_sweep_" + options.aggregation + "_bad1_all",
                                  std::to_string(bad.all));
  return bad;
}

// Measured (see the cost module's report): pixel-wise WTA of two-view BT is poor — 55 % (tsukuba)
// and 71 % (venus) bad-1 over all pixels with ties sent to the lowest label, 46 % and 69 % with
// ties sent to the middle of the tied labels (WinnerTakeAll today) — because BT is 0 for several
// disparities in smooth areas (ties in 50–70 % of the pixels). Chance level (a uniform random
// label) is 1 − 3/16 ≈ 81 % and 1 − 3/20 = 85 %. The bounds below are sanity bounds between the
// two, catching a wrong disparity sign or scale (which gives ≈ chance), not accuracy targets. The
// multi-view sweep must beat two-view BT clearly.
void CheckScene(const Scene& scene, const std::string& name, double bt_bound_percent) {
  const Bad1 bt = RunBirchfieldTomasi(scene, name);
  EXPECT_LT(bt.all, bt_bound_percent);
  PlaneSweepOptions mean;
  PlaneSweepOptions best;
  best.aggregation = "best_k";
  best.best_k = 2;
  const Bad1 sweep_mean = RunPlaneSweep(scene, name, mean);
  const Bad1 sweep_best = RunPlaneSweep(scene, name, best);
  EXPECT_LT(sweep_mean.all, 0.8 * bt.all);
  EXPECT_LT(sweep_best.all, bt.all);
  // The robust two-view cost of configs/middlebury_stereo.yaml (BT truncated at 60 + 2 · 7×7
  // census Hamming, 3×3 guided filter) must beat pixel BT by far: it is not flat in weak texture.
  BirchfieldTomasiOptions robust;
  robust.truncation = 60;
  robust.census_window_px = 7;
  robust.census_weight = 2;
  robust.window.window_px = 3;
  const Bad1 census = RunBirchfieldTomasi(scene, name, robust, "BT+census+guided3");
  EXPECT_LT(census.nonocc, 0.5 * bt.nonocc);
}

TEST(Middlebury, WtaTsukuba) {
  GCPSTEREO_REQUIRE_SHARED_DATA(dir, "middlebury/tsukuba");
  CheckScene(Tsukuba(dir), "tsukuba", 70.0);
}

TEST(Middlebury, WtaVenus) {
  GCPSTEREO_REQUIRE_SHARED_DATA(dir, "middlebury/venus");
  CheckScene(Venus(dir), "venus", 80.0);
}

}  // namespace
}  // namespace gcpstereo::cost
