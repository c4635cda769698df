// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/plane_sweep.h"

#include <cmath>
#include <cstring>
#include <iostream>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/cost/winner_take_all.h"
#include "synthetic_scene.h"

namespace gcpstereo::cost {
namespace {

using testing::LookAtCamera;
using testing::Scene;

constexpr int kWidth = 160;
constexpr int kHeight = 120;
constexpr double kFocalPx = 180.0;

struct SceneViews {
  Scene scene;
  View reference;
  cv::Mat depth;  // ground-truth depth of the reference
  std::vector<View> neighbors;
};

const std::vector<Eigen::Vector3d> kSpreadCenters = {
    {0.5, 0.0, 0.0}, {-0.5, 0.05, 0.1}, {0.05, 0.4, -0.1}, {-0.05, -0.4, 0.0}};

SceneViews MakeSceneViews(const std::vector<Eigen::Vector3d>& centers = kSpreadCenters) {
  SceneViews s;
  const Eigen::Vector3d target(0.0, 0.0, 5.0);
  s.reference = s.scene.Render(
      "ref",
      LookAtCamera(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1), kFocalPx, kWidth, kHeight),
      &s.depth);
  for (std::size_t i = 0; i < centers.size(); ++i) {
    s.neighbors.push_back(s.scene.Render(
        "nb" + std::to_string(i), LookAtCamera(centers[i], target, kFocalPx, kWidth, kHeight)));
  }
  return s;
}

// Pixels whose GT point every neighbour that has it in its image also sees (no occlusion), and that
// at least two neighbours see. `occluded_twice`: pixels hidden from at least two neighbours and
// seen by at least two.
cv::Mat UnoccludedMask(const SceneViews& s, cv::Mat* occluded_twice) {
  cv::Mat mask(kHeight, kWidth, CV_8U, cv::Scalar(0));
  *occluded_twice = cv::Mat(kHeight, kWidth, CV_8U, cv::Scalar(0));
  for (int row = 0; row < kHeight; ++row) {
    for (int col = 0; col < kWidth; ++col) {
      const float z = s.depth.at<float>(row, col);
      if (!IsValidDepth(z)) continue;
      const Eigen::Vector3d p = s.reference.camera.BackProject(Eigen::Vector2d(col, row), z);
      int seen = 0, occluded = 0;
      for (const View& nb : s.neighbors) {
        Eigen::Vector2d pixel;
        double depth;
        if (!nb.camera.Project(p, &pixel, &depth) || !nb.camera.InImage(pixel)) continue;
        if (s.scene.Visible(nb.camera, p)) {
          ++seen;
        } else {
          ++occluded;
        }
      }
      if (occluded == 0 && seen >= 2) mask.at<std::uint8_t>(row, col) = 255;
      if (occluded >= 2 && seen >= 2) occluded_twice->at<std::uint8_t>(row, col) = 255;
    }
  }
  return mask;
}

struct Accuracy {
  int counted = 0;
  int within_one_label = 0;
  double Fraction() const { return counted ? static_cast<double>(within_one_label) / counted : 0; }
};

Accuracy ScoreWta(const cv::Mat& wta, const cv::Mat& depth, const cv::Mat& mask,
                  const LabelSpace& labels) {
  Accuracy a;
  for (int row = 0; row < wta.rows; ++row) {
    for (int col = 0; col < wta.cols; ++col) {
      if (!mask.at<std::uint8_t>(row, col)) continue;
      ++a.counted;
      const int label = wta.at<int>(row, col);
      const double gt_label = labels.LabelOfDepth(depth.at<float>(row, col));
      if (label >= 0 && std::abs(label - gt_label) <= 1.0) ++a.within_one_label;
    }
  }
  return a;
}

TEST(PlaneSweep, WtaRecoversSyntheticDepthWithinOneLabel) {
  const SceneViews s = MakeSceneViews();
  cv::Mat occluded;
  const cv::Mat mask = UnoccludedMask(s, &occluded);
  ASSERT_GT(cv::countNonZero(mask), kWidth * kHeight / 2);
  // The paper's label kind (equal steps in depth) and inverse depth; both ≈ 0.3–0.9 px per label.
  for (const LabelSpace& labels :
       {LabelSpace(LabelSpaceKind::kDepth, 41, 3.0, 7.0),
        LabelSpace(LabelSpaceKind::kInverseDepth, 41, 1.0 / 7.0, 1.0 / 3.0)}) {
    PlaneSweepSummary summary;
    const CostVolume volume =
        ComputePlaneSweepCost(s.reference, s.neighbors, labels, cv::Rect(0, 0, kWidth, kHeight),
                              PlaneSweepOptions{}, {}, &summary);
    EXPECT_EQ(summary.samples, static_cast<std::int64_t>(kWidth) * kHeight * 41 * 4);
    EXPECT_GT(summary.votes, summary.samples / 2);
    EXPECT_LE(summary.votes, summary.samples);
    EXPECT_FALSE(summary.cancelled);
    const Accuracy a = ScoreWta(WinnerTakeAll(volume), s.depth, mask, labels);
    RecordProperty(std::string("within_one_label_") + LabelSpaceKindName(labels.kind()),
                   std::to_string(a.Fraction()));
    std::cout << "[ measured ] synthetic WTA within one label ("
              << LabelSpaceKindName(labels.kind()) << " labels): " << 100.0 * a.Fraction()
              << " % of " << a.counted << " unoccluded pixels\n";
    EXPECT_GT(a.Fraction(), 0.95) << LabelSpaceKindName(labels.kind()) << ": " << a.within_one_label
                                  << " of " << a.counted;
  }
}

// Two neighbours on each side of the reference: near the rectangle's vertical edges a background
// pixel is hidden from both neighbours of one side. The mean then averages two truncated (bad)
// costs into the true label; the mean of the best k = 2 uses the two clean views.
TEST(PlaneSweep, BestKIsMoreRobustToOcclusionThanMean) {
  const SceneViews s =
      MakeSceneViews({{0.5, 0.0, 0.0}, {0.42, 0.12, 0.0}, {-0.5, 0.0, 0.0}, {-0.42, -0.12, 0.0}});
  cv::Mat occluded;
  UnoccludedMask(s, &occluded);
  ASSERT_GT(cv::countNonZero(occluded), 100);
  const LabelSpace labels(LabelSpaceKind::kInverseDepth, 41, 1.0 / 7.0, 1.0 / 3.0);
  const cv::Rect all(0, 0, kWidth, kHeight);
  PlaneSweepOptions mean_options;
  PlaneSweepOptions best_options;
  best_options.aggregation = "best_k";
  best_options.best_k = 2;
  const Accuracy mean = ScoreWta(
      WinnerTakeAll(ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, mean_options)),
      s.depth, occluded, labels);
  const Accuracy best = ScoreWta(
      WinnerTakeAll(ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, best_options)),
      s.depth, occluded, labels);
  std::cout << "[ measured ] pixels hidden from two neighbours, WTA within one label: mean "
            << 100.0 * mean.Fraction() << " %, best_k(2) " << 100.0 * best.Fraction() << " % of "
            << best.counted << "\n";
  EXPECT_GT(best.Fraction(), mean.Fraction() + 0.05)
      << "best_k " << best.within_one_label << " / mean " << mean.within_one_label << " of "
      << best.counted << " pixels occluded in two neighbours";
}

TEST(PlaneSweep, TileEqualsCropOfFullVolume) {
  const SceneViews s = MakeSceneViews();
  const LabelSpace labels(LabelSpaceKind::kDepth, 12, 3.0, 7.0);
  const CostVolume full =
      ComputePlaneSweepCost(s.reference, s.neighbors, labels, cv::Rect(0, 0, kWidth, kHeight), {});
  const cv::Rect tile(37, 21, 50, 40);
  const CostVolume part = ComputePlaneSweepCost(s.reference, s.neighbors, labels, tile, {});
  ASSERT_EQ(part.region(), tile);
  ASSERT_EQ(part.memory_bytes(), static_cast<std::size_t>(50 * 40 * 12 * 2));
  for (int row = 0; row < tile.height; ++row) {
    for (int col = 0; col < tile.width; ++col) {
      for (int l = 0; l < 12; ++l) {
        ASSERT_EQ(part.PixelData(row, col)[l], full.PixelData(row + tile.y, col + tile.x)[l]);
      }
    }
  }
}

// The batch form (several regions, one preparation) gives each region the bytes of a sweep of
// that region alone, pixel-wise and with a window filter (whose regions are grown and cropped).
TEST(PlaneSweep, RegionBatchEqualsOneSweepPerRegion) {
  const SceneViews s = MakeSceneViews();
  const LabelSpace labels(LabelSpaceKind::kDepth, 12, 3.0, 7.0);
  const std::vector<cv::Rect> regions = {cv::Rect(0, 0, 5, 5), cv::Rect(77, 40, 5, 5),
                                         cv::Rect(155, 115, 5, 5), cv::Rect(10, 60, 31, 2)};
  for (const int window_px : {1, 5}) {
    PlaneSweepOptions options;
    options.window.window_px = window_px;
    const std::vector<CostVolume> batch =
        ComputePlaneSweepCostForRegions(s.reference, s.neighbors, labels, regions, options);
    ASSERT_EQ(batch.size(), regions.size());
    for (size_t i = 0; i < regions.size(); ++i) {
      const CostVolume one =
          ComputePlaneSweepCost(s.reference, s.neighbors, labels, regions[i], options);
      ASSERT_EQ(batch[i].region(), regions[i]);
      ASSERT_EQ(batch[i].memory_bytes(), one.memory_bytes());
      EXPECT_EQ(0, std::memcmp(batch[i].PixelData(0, 0), one.PixelData(0, 0), one.memory_bytes()))
          << "region " << i << ", window " << window_px;
    }
  }
  EXPECT_TRUE(ComputePlaneSweepCostForRegions(s.reference, s.neighbors, labels, {}, {}).empty());
  EXPECT_THROW(ComputePlaneSweepCostForRegions(s.reference, s.neighbors, labels,
                                               {cv::Rect(150, 0, 20, 5)}, {}),
               Error);
}

TEST(PlaneSweep, SameBytesForAnyThreadCount) {
  const SceneViews s = MakeSceneViews();
  const LabelSpace labels(LabelSpaceKind::kDepth, 16, 3.0, 7.0);
  PlaneSweepOptions options;
  options.aggregation = "best_k";
  options.best_k = 2;
  options.progress_rows = 5;
  const cv::Rect all(0, 0, kWidth, kHeight);
  const CostVolume parallel = ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, options);
  CostVolume serial;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, options);
  }
  const std::size_t n = static_cast<std::size_t>(kWidth) * kHeight * 16;
  EXPECT_EQ(0, std::memcmp(parallel.PixelData(0, 0), serial.PixelData(0, 0), n * 2));
}

// A rectified sequence of random-colour images (focal 100 px, baseline 0.2 per view step): the
// reference at index 2 and the neighbours at `indices`, drawn in that order from `seed`.
constexpr double kSequenceFocal = 100.0;
constexpr double kSequenceBaseline = 0.2;
struct RandomSequence {
  View reference;
  std::vector<View> neighbors;
};
RandomSequence MakeRandomSequence(int width, int height, unsigned seed,
                                  const std::vector<int>& indices) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255);
  auto view = [&](int index) {
    cv::Mat image(height, width, CV_8UC3);
    for (int r = 0; r < height; ++r)
      for (int c = 0; c < width; ++c)
        image.at<cv::Vec3b>(r, c) = cv::Vec3b(value(rng), value(rng), value(rng));
    return View{"v" + std::to_string(index), image,
                RectifiedSequenceCamera(kSequenceFocal, (width - 1) / 2.0, (height - 1) / 2.0,
                                        kSequenceBaseline, index, width, height)};
  };
  RandomSequence out;
  out.reference = view(2);
  for (const int index : indices) out.neighbors.push_back(view(index));
  return out;
}

// Rectified sequence with disparity labels: the sweep must equal a direct shift x − k·d.
TEST(PlaneSweep, RectifiedSequenceEqualsDirectShift) {
  const int width = 40, height = 7;
  const RandomSequence sequence = MakeRandomSequence(width, height, 7, {3, 1, 4});
  const View& reference = sequence.reference;
  const std::vector<View>& neighbors = sequence.neighbors;
  const double focal = kSequenceFocal, baseline = kSequenceBaseline;
  // Disparity per view step: numerator = focal · baseline.
  const LabelSpace labels(LabelSpaceKind::kDisparity, 6, 0.0, 5.0, focal * baseline);
  PlaneSweepOptions options;
  options.truncation = 300.0;
  const CostVolume volume =
      ComputePlaneSweepCost(reference, neighbors, labels, cv::Rect(0, 0, width, height), options);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      for (int l = 0; l < 6; ++l) {
        double sum = 0.0;
        int voters = 0;
        for (const View& nb : neighbors) {
          const int steps =
              static_cast<int>(std::lround(nb.camera.center_world.x() / baseline)) - 2;
          const int x = col - steps * l;  // label value l px per step
          if (x < 0 || x >= width) continue;
          const cv::Vec3b a = reference.image.at<cv::Vec3b>(row, col);
          const cv::Vec3b b = nb.image.at<cv::Vec3b>(row, x);
          double d2 = 0.0;
          for (int ch = 0; ch < 3; ++ch) d2 += (a[ch] - b[ch]) * (a[ch] - b[ch]);
          sum += std::min(std::sqrt(d2), options.truncation);
          ++voters;
        }
        if (voters == 0) {
          ASSERT_FALSE(volume.HasData(row, col, l)) << row << " " << col << " " << l;
        } else {
          ASSERT_TRUE(volume.HasData(row, col, l)) << row << " " << col << " " << l;
          ASSERT_NEAR(volume.Cost(row, col, l), sum / voters, 0.5 * volume.cost_step() + 1e-3)
              << row << " " << col << " " << l;
        }
      }
    }
  }
}

TEST(PlaneSweep, FractionalShiftIsBilinear) {
  // One neighbour, one step to the right, disparity 0.25 px: cost = ‖I_ref(x) − lerp‖.
  const int width = 12, height = 3;
  cv::Mat ref(height, width, CV_8UC3), nb(height, width, CV_8UC3);
  for (int c = 0; c < width; ++c) {
    for (int r = 0; r < height; ++r) {
      ref.at<cv::Vec3b>(r, c) = cv::Vec3b(10 * c, 200 - 7 * c, (c * c) % 97);
      nb.at<cv::Vec3b>(r, c) = cv::Vec3b(10 * c + 3, 190 - 7 * c, (3 * c) % 50);
    }
  }
  const View reference{"r", ref, RectifiedSequenceCamera(50.0, 5.5, 1.0, 1.0, 0, width, height)};
  const View neighbor{"n", nb, RectifiedSequenceCamera(50.0, 5.5, 1.0, 1.0, 1, width, height)};
  const LabelSpace labels(LabelSpaceKind::kDisparity, 2, 0.25, 1.25, 50.0);
  PlaneSweepOptions options;
  options.truncation = 400.0;
  const CostVolume volume =
      ComputePlaneSweepCost(reference, {neighbor}, labels, cv::Rect(0, 0, width, height), options);
  for (int c = 1; c < width; ++c) {
    const double x = c - 0.25;
    const int i = static_cast<int>(std::floor(x));
    const double f = x - i;
    double d2 = 0.0;
    for (int ch = 0; ch < 3; ++ch) {
      const double v = (1 - f) * nb.at<cv::Vec3b>(1, i)[ch] + f * nb.at<cv::Vec3b>(1, i + 1)[ch];
      d2 += (ref.at<cv::Vec3b>(1, c)[ch] - v) * (ref.at<cv::Vec3b>(1, c)[ch] - v);
    }
    EXPECT_NEAR(volume.Cost(1, c, 0), std::sqrt(d2), 0.5 * volume.cost_step() + 1e-3) << c;
  }
  // x − 0.25 = −0.25 at column 0 is still inside the image (half-pixel border, edge replicated).
  EXPECT_TRUE(volume.HasData(1, 0, 0));
  // x − 1.25 = −1.25 at column 0 is outside; −0.25 at column 1 is inside.
  EXPECT_FALSE(volume.HasData(1, 0, 1));
  EXPECT_TRUE(volume.HasData(1, 1, 1));
}

TEST(PlaneSweep, MinVotersAndNoData) {
  const SceneViews s = MakeSceneViews();
  const LabelSpace labels(LabelSpaceKind::kDepth, 8, 3.0, 7.0);
  PlaneSweepOptions options;
  options.min_voters = 5;  // more than the 4 neighbours: nothing has data
  PlaneSweepSummary summary;
  const CostVolume volume = ComputePlaneSweepCost(s.reference, s.neighbors, labels,
                                                  cv::Rect(0, 0, 20, 10), options, {}, &summary);
  EXPECT_EQ(summary.no_data_costs, 20 * 10 * 8);
  EXPECT_EQ(WinnerTakeAll(volume).at<int>(3, 3), -1);
}

TEST(PlaneSweep, ProgressIsReportedAndCanCancel) {
  const SceneViews s = MakeSceneViews();
  const LabelSpace labels(LabelSpaceKind::kDepth, 4, 3.0, 7.0);
  PlaneSweepOptions options;
  options.progress_rows = 10;
  std::vector<double> fractions;
  PlaneSweepSummary summary;
  const CostVolume volume = ComputePlaneSweepCost(
      s.reference, s.neighbors, labels, cv::Rect(0, 0, kWidth, kHeight), options,
      [&](double f) {
        fractions.push_back(f);
        return fractions.size() < 3;
      },
      &summary);
  ASSERT_EQ(fractions.size(), 3u);
  EXPECT_DOUBLE_EQ(fractions[0], 10.0 / kHeight);
  EXPECT_DOUBLE_EQ(fractions[2], 30.0 / kHeight);
  EXPECT_TRUE(summary.cancelled);
  EXPECT_TRUE(volume.HasData(29, 80, 0));
  EXPECT_FALSE(volume.HasData(30, 80, 0));
  EXPECT_EQ(
      summary.no_data_costs, static_cast<std::int64_t>(kHeight - 30) * kWidth * 4 + [&] {
        std::int64_t n = 0;
        for (int r = 0; r < 30; ++r)
          for (int c = 0; c < kWidth; ++c)
            for (int l = 0; l < 4; ++l) n += !volume.HasData(r, c, l);
        return n;
      }());
}

TEST(PlaneSweepOptions, CheckNamesTheKey) {
  auto message = [](const PlaneSweepOptions& o) {
    try {
      o.Check();
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  PlaneSweepOptions o;
  EXPECT_EQ(message(o), "no error");
  o.truncation = 0.0;
  EXPECT_EQ(message(o), "cost.truncation = 0. Violated constraint: 0 < truncation < inf");
  o = {};
  o.aggregation = "median";
  EXPECT_EQ(message(o), "cost.aggregation = median. Violated constraint: one of mean, best_k");
  o = {};
  o.best_k = 0;
  EXPECT_EQ(message(o), "cost.best_k = 0. Violated constraint: best_k >= 1");
  o = {};
  o.min_voters = -1;
  EXPECT_EQ(message(o), "cost.min_voters = -1. Violated constraint: min_voters >= 1");
  o = {};
  o.measure = "census";
  EXPECT_EQ(message(o), "cost.sweep_measure = census. Violated constraint: one of rgb, zncc");
  o = {};
  o.zncc_window_px = 8;
  EXPECT_EQ(message(o),
            "cost.zncc_window_px = 8. Violated constraint: odd, 3 <= zncc_window_px <= 21");
  o.zncc_window_px = 23;
  EXPECT_EQ(message(o),
            "cost.zncc_window_px = 23. Violated constraint: odd, 3 <= zncc_window_px <= 21");
}

TEST(PlaneSweep, BadInputsAreReported) {
  const SceneViews s = MakeSceneViews();
  const LabelSpace labels(LabelSpaceKind::kDepth, 4, 3.0, 7.0);
  auto message = [&](const View& ref, const std::vector<View>& nbs, cv::Rect region) {
    try {
      ComputePlaneSweepCost(ref, nbs, labels, region, {});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const cv::Rect all(0, 0, kWidth, kHeight);
  EXPECT_EQ(message(s.reference, {}, all), "plane sweep: no neighbour views to match against");
  EXPECT_EQ(message(s.reference, s.neighbors, cv::Rect(150, 0, 20, 10)),
            "plane sweep: region 20x10 at (150, 0) is empty or not inside the 160x120 reference "
            "image 'ref'");
  View grey = s.neighbors[1];
  cv::cvtColor(grey.image, grey.image, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(message(s.reference, {s.neighbors[0], grey}, all),
            "neighbour view 'nb1': the plane sweep needs an 8-bit 3-channel (BGR) image");
  View small = s.neighbors[0];
  small.image = small.image(cv::Rect(0, 0, 100, 100)).clone();
  EXPECT_EQ(message(s.reference, {small}, all),
            "neighbour view 'nb0': image is 100x100 but its camera is 160x120");
}

// cost.sweep_measure: zncc against a brute-force ZNCC on a rectified sequence with integer
// disparities (the warp is then an exact shift): window sums in double, the reference's border
// replicated, the neighbour sampled at the clamped shifted column, ε = 4 grey levels² per sample.
// The sweep's costs against ZNCC computed directly from the definition (plane_sweep.h), with or
// without the flat-window fallback.
void ExpectEqualsDirectZncc(bool flat_fallback) {
  const int width = 40, height = 12, window = 5;
  const RandomSequence sequence = MakeRandomSequence(width, height, 11, {3, 1});
  const View& reference = sequence.reference;
  const std::vector<View>& neighbors = sequence.neighbors;
  const double focal = kSequenceFocal, baseline = kSequenceBaseline;
  const LabelSpace labels(LabelSpaceKind::kDisparity, 4, 0.0, 3.0, focal * baseline);
  PlaneSweepOptions options;
  options.measure = "zncc";
  options.zncc_window_px = window;
  options.zncc_flat_fallback = flat_fallback;
  const CostVolume volume =
      ComputePlaneSweepCost(reference, neighbors, labels, cv::Rect(0, 0, width, height), options);
  auto grey = [](const cv::Mat& bgr) {
    cv::Mat g;
    cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
    return g;
  };
  const cv::Mat ref_grey = grey(reference.image);
  auto clamp = [](int v, int hi) { return std::min(std::max(v, 0), hi - 1); };
  int checked = 0;
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      for (int l = 0; l < 4; ++l) {
        double sum = 0.0;
        int voters = 0;
        for (const View& nb : neighbors) {
          const int steps =
              static_cast<int>(std::lround(nb.camera.center_world.x() / baseline)) - 2;
          if (col - steps * l < 0 || col - steps * l >= width) continue;
          const cv::Mat nb_grey = grey(nb.image);
          double sr = 0, sn = 0, srr = 0, snn = 0, srn = 0;
          for (int dy = -window / 2; dy <= window / 2; ++dy) {
            for (int dx = -window / 2; dx <= window / 2; ++dx) {
              const int y = clamp(row + dy, height);
              const int x = clamp(col + dx, width);
              const double a = ref_grey.at<std::uint8_t>(y, x);
              const double b = nb_grey.at<std::uint8_t>(y, clamp(x - steps * l, width));
              sr += a, sn += b, srr += a * a, snn += b * b, srn += a * b;
            }
          }
          const double n = window * window;
          const double var_r = srr / n - (sr / n) * (sr / n);
          const double var_n = snn / n - (sn / n) * (sn / n);
          const double rho = (srn / n - (sr / n) * (sn / n)) / std::sqrt((var_r + 4) * (var_n + 4));
          double t = std::min(1.0, std::max(0.0, 1.0 - rho));
          if (flat_fallback) {
            const double w = 4.0 / (var_r + 4.0);
            const double mean_difference = std::abs(sr - sn) / n;
            t = (1.0 - w) * t + w * std::min(1.0, mean_difference * std::sqrt(3.0) /
                                                       options.truncation);
          }
          sum += options.truncation * t;
          ++voters;
        }
        if (voters == 0) {
          ASSERT_FALSE(volume.HasData(row, col, l)) << row << " " << col << " " << l;
        } else {
          ASSERT_TRUE(volume.HasData(row, col, l)) << row << " " << col << " " << l;
          ASSERT_NEAR(volume.Cost(row, col, l), sum / voters, 0.5 * volume.cost_step() + 1e-4)
              << row << " " << col << " " << l;
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, width * height * 3);
}

TEST(PlaneSweepZncc, EqualsDirectZncc) { ExpectEqualsDirectZncc(false); }
TEST(PlaneSweepZncc, FlatFallbackEqualsItsDefinition) { ExpectEqualsDirectZncc(true); }

// The neighbours photographed with other exposures (gain and offset per view): the RGB norm reads
// the change as mismatch, ZNCC does not see it.
TEST(PlaneSweepZncc, RecoversDepthUnderExposureChange) {
  SceneViews s = MakeSceneViews();
  const double gains[] = {0.6, 1.35, 0.8, 1.2};
  const double offsets[] = {30.0, -25.0, -10.0, 15.0};
  for (std::size_t i = 0; i < s.neighbors.size(); ++i) {
    s.neighbors[i].image.convertTo(s.neighbors[i].image, CV_8UC3, gains[i], offsets[i]);
  }
  cv::Mat occluded;
  const cv::Mat mask = UnoccludedMask(s, &occluded);
  const LabelSpace labels(LabelSpaceKind::kInverseDepth, 41, 1.0 / 7.0, 1.0 / 3.0);
  const cv::Rect all(0, 0, kWidth, kHeight);
  PlaneSweepOptions rgb;
  PlaneSweepOptions zncc;
  zncc.measure = "zncc";
  const Accuracy a_rgb =
      ScoreWta(WinnerTakeAll(ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, rgb)),
               s.depth, mask, labels);
  const Accuracy a_zncc =
      ScoreWta(WinnerTakeAll(ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, zncc)),
               s.depth, mask, labels);
  std::cout << "[ measured ] neighbours with other exposures, WTA within one label: rgb "
            << 100.0 * a_rgb.Fraction() << " %, zncc " << 100.0 * a_zncc.Fraction() << " % of "
            << a_zncc.counted << " unoccluded pixels\n";
  EXPECT_GT(a_zncc.Fraction(), 0.9);
  EXPECT_GT(a_zncc.Fraction(), a_rgb.Fraction() + 0.2);
}

// Window sums are exact integers: a tile's ZNCC costs are the whole image's, bit for bit, and the
// thread count does not matter (best_k aggregation, a cancelled-free progress in small chunks).
TEST(PlaneSweepZncc, TileAndThreadCountDoNotChangeTheBytes) {
  const SceneViews s = MakeSceneViews();
  const LabelSpace labels(LabelSpaceKind::kDepth, 20, 3.0, 7.0);
  PlaneSweepOptions options;
  options.measure = "zncc";
  options.zncc_window_px = 9;
  options.aggregation = "best_k";
  options.best_k = 2;
  const cv::Rect all(0, 0, kWidth, kHeight);
  int reports = 0;
  const CostVolume full = ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, options,
                                                [&](double) { return ++reports > 0; });
  EXPECT_EQ(reports, 3);  // 20 labels in blocks of 8
  for (const cv::Rect& tile :
       {cv::Rect(37, 21, 50, 40), cv::Rect(0, 0, 30, 17), cv::Rect(140, 100, 20, 20)}) {
    const CostVolume part = ComputePlaneSweepCost(s.reference, s.neighbors, labels, tile, options);
    for (int row = 0; row < tile.height; ++row) {
      for (int col = 0; col < tile.width; ++col) {
        ASSERT_EQ(0, std::memcmp(part.PixelData(row, col),
                                 full.PixelData(row + tile.y, col + tile.x), 20 * 2))
            << tile << " " << row << " " << col;
      }
    }
  }
  CostVolume serial;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = ComputePlaneSweepCost(s.reference, s.neighbors, labels, all, options);
  }
  EXPECT_EQ(0, std::memcmp(full.PixelData(0, 0), serial.PixelData(0, 0), full.memory_bytes()));
}

}  // namespace
}  // namespace gcpstereo::cost
