// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/gcp/stereo_gcps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/propagation/propagation.h"
#include "test_data.h"

namespace gcpstereo::gcp {
namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

// A rectified pair with exact disparity: smooth random texture; background at disparity 3, a
// rectangle at disparity 9. right(x) = left(x + d(x)) for the visible left pixels.
void MakePair(cv::Mat* left, cv::Mat* right, cv::Mat* gt_disparity) {
  const int width = 120, height = 80;
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> value(0, 255);
  cv::Mat texture(height / 2, width / 2 + 20, CV_8UC3);
  for (int y = 0; y < texture.rows; ++y) {
    for (int x = 0; x < texture.cols; ++x) {
      texture.at<cv::Vec3b>(y, x) = cv::Vec3b(value(rng), value(rng), value(rng));
    }
  }
  cv::Mat background;
  cv::resize(texture, background, cv::Size(width + 40, height), 0, 0, cv::INTER_LINEAR);
  cv::Mat foreground_texture;
  cv::flip(background, foreground_texture, -1);
  *gt_disparity = cv::Mat(height, width, CV_32F, cv::Scalar(3.0f));
  const cv::Rect box(45, 20, 40, 40);
  (*gt_disparity)(box).setTo(9.0f);
  *left = cv::Mat(height, width, CV_8UC3);
  *right = cv::Mat(height, width, CV_8UC3);
  // Scene texture is attached to surfaces: background texel u = x_left, foreground texel likewise.
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const bool fg = box.contains(cv::Point(x, y));
      left->at<cv::Vec3b>(y, x) =
          fg ? foreground_texture.at<cv::Vec3b>(y, x) : background.at<cv::Vec3b>(y, x + 20);
    }
    for (int xr = 0; xr < width; ++xr) {
      // Right pixel xr sees the foreground when xr + 9 is inside the box, else the background.
      const bool fg =
          y >= box.y && y < box.y + box.height && xr + 9 >= box.x && xr + 9 < box.x + box.width;
      right->at<cv::Vec3b>(y, xr) = fg ? foreground_texture.at<cv::Vec3b>(y, xr + 9)
                                       : background.at<cv::Vec3b>(y, xr + 3 + 20);
    }
  }
}

TEST(StereoGcpsTest, SyntheticPairGivesCorrectSparseGcps) {
  cv::Mat left, right, gt;
  MakePair(&left, &right, &gt);
  const StereoGcpResult result = ExtractStereoGcps(left, right, 0, 12, StereoGcpOptions());
  const GcpOutlierStats stats = ComputeOutlierStats(result.disparity, gt);
  EXPECT_EQ(stats.num_evaluated, result.num_gcps);
  // Random texture: Canny fires almost everywhere, so the edge test leaves few candidates.
  EXPECT_GT(result.density_percent, 1.0);
  EXPECT_EQ(stats.num_outliers, 0);
  EXPECT_LE(result.num_gcps, result.num_candidates_left);
  std::printf("[ synth    ] density %.2f %%, outliers %d of %d\n", result.density_percent,
              stats.num_outliers, stats.num_evaluated);
  // Depth conversion.
  GcpSourceSummary summary;
  const GcpSet gcps = StereoGcpsToGcpSet(result.disparity, 90.0, 0.5, &summary);
  ASSERT_FALSE(gcps.empty());
  for (const Gcp& g : gcps.points) {
    const float d = result.disparity.at<float>(g.row, g.col);
    EXPECT_DOUBLE_EQ(g.depth, 90.0 / d);
    EXPECT_DOUBLE_EQ(g.sigma, 90.0 * 0.5 / (d * d));
    EXPECT_EQ(g.source, GcpSource::kStereo);
  }
}

// A 29×17 pair for the per-pixel formula tests: `left` a smooth random texture (a 9×6 grid of
// random colours from `seed`, interpolated; `flat` painted grey), right(x) = left(x + shift) plus
// uniform noise in [0, 12) from `noise_seed` (its own generator: not the global RNG's state).
std::pair<cv::Mat, cv::Mat> SmallShiftedPair(unsigned seed, int noise_seed, int shift,
                                             cv::Rect flat = {}) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255);
  cv::Mat small(6, 9, CV_8UC3), left;
  for (auto it = small.begin<cv::Vec3b>(); it != small.end<cv::Vec3b>(); ++it) {
    *it = cv::Vec3b(value(rng), value(rng), value(rng));
  }
  cv::resize(small, left, cv::Size(29, 17), 0, 0, cv::INTER_LINEAR);
  if (!flat.empty()) left(flat).setTo(cv::Scalar(90, 90, 90));
  cv::Mat noise(left.size(), CV_8UC3);
  cv::RNG(noise_seed).fill(noise, cv::RNG::UNIFORM, 0, 12);
  cv::Mat right(left.size(), CV_8UC3);
  for (int y = 0; y < left.rows; ++y) {
    for (int x = 0; x < left.cols; ++x) {
      right.at<cv::Vec3b>(y, x) = left.at<cv::Vec3b>(y, std::min(left.cols - 1, x + shift));
    }
  }
  right += noise;
  return {left, right};
}

// The adaptive-weight evidence against the Yoon–Kweon cost evaluated pixel by pixel and
// disparity by disparity (CIELab weights of both windows, truncated RGB differences, the window
// sampled every aw_stride_px): same WTA, same uniqueness, same parabola vertex, near the image
// borders (where windows leave the image) and in the interior, for strides 1 and 2, in the left
// view (partner x − d) and in the right view (partner x + d). Rows of 29 px: the 16-px blocks of
// the vectorised sums and their scalar tails both take part.
TEST(StereoGcpsTest, AdaptiveWeightEvidenceIsThePerPixelFormula) {
  const std::pair<cv::Mat, cv::Mat> pair = SmallShiftedPair(23, 29, 3);
  const cv::Mat &left = pair.first, &right = pair.second;
  const int dmin = 0, dmax = 6;
  auto lab = [](const cv::Mat& bgr) {
    cv::Mat f, out;
    bgr.convertTo(f, CV_32FC3, 1.0 / 255.0);
    cv::cvtColor(f, out, cv::COLOR_BGR2Lab);
    return out;
  };
  const cv::Mat lab_l = lab(left), lab_r = lab(right);
  for (const int stride : {1, 2}) {
    StereoGcpOptions options;
    options.aw_window_px = 9;
    options.aw_stride_px = stride;
    const StereoPairEvidence evidence = ComputeStereoEvidence(left, right, dmin, dmax, options);
    const int radius = 4, reach = (radius / stride) * stride;
    auto weight = [&](const cv::Mat& image_lab, int y, int x, int dy, int dx) -> float {
      const int qy = y + dy, qx = x + dx;
      if (qy < 0 || qx < 0 || qy >= image_lab.rows || qx >= image_lab.cols) return 0.0f;
      const cv::Vec3f diff = image_lab.at<cv::Vec3f>(qy, qx) - image_lab.at<cv::Vec3f>(y, x);
      return std::exp(-std::sqrt(diff.dot(diff)) * static_cast<float>(1.0 / options.aw_gamma_c)) *
             static_cast<float>(std::exp(-std::hypot(dx, dy) / options.aw_gamma_p));
    };
    // The view's own image is `ref`, its partner `other`; its partner pixel is x − d (left view,
    // sign −1) or x + d (right view, sign +1).
    for (const int sign : {-1, 1}) {
      const StereoViewEvidence& e = sign < 0 ? evidence.left : evidence.right;
      const cv::Mat& ref = sign < 0 ? left : right;
      const cv::Mat& other = sign < 0 ? right : left;
      const cv::Mat& lab_ref = sign < 0 ? lab_l : lab_r;
      const cv::Mat& lab_other = sign < 0 ? lab_r : lab_l;
      int compared = 0;
      for (int y = 0; y < ref.rows; ++y) {
        for (int x = 0; x < ref.cols; ++x) {
          std::vector<double> cost;
          std::vector<int> disparity;
          for (int d = dmin; d <= dmax; ++d) {
            const int xp = x + sign * d;
            if (xp < 0 || xp >= ref.cols) continue;
            double numerator = 0.0, denominator = 0.0;
            for (int dy = -reach; dy <= radius; dy += stride) {
              for (int dx = -reach; dx <= radius; dx += stride) {
                const float w = weight(lab_ref, y, x, dy, dx) * weight(lab_other, y, xp, dy, dx);
                if (w == 0.0f) continue;
                const int qy = y + dy, qx = x + dx, qxp = xp + dx;
                float diff = -1.0f;  // the partner pixel qxp is outside the image
                if (qxp >= 0 && qxp < ref.cols) {
                  const cv::Vec3b a = ref.at<cv::Vec3b>(qy, qx), b = other.at<cv::Vec3b>(qy, qxp);
                  diff = std::min(static_cast<float>(std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) +
                                                     std::abs(a[2] - b[2])),
                                  static_cast<float>(options.aw_truncation));
                }
                numerator += w * diff;
                denominator += w;
              }
            }
            if (denominator <= 0.0) continue;
            cost.push_back(numerator / denominator);
            disparity.push_back(d);
          }
          ASSERT_FALSE(cost.empty());
          const int best =
              static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
          EXPECT_EQ(e.wta_aw.at<int>(y, x), disparity[best])
              << "view " << sign << " stride " << stride << " at " << x << "," << y;
          double second = std::numeric_limits<double>::infinity();
          for (std::size_t i = 0; i < cost.size(); ++i) {
            if (std::abs(disparity[i] - disparity[best]) > 1) second = std::min(second, cost[i]);
          }
          const double u =
              std::isfinite(second) && second > 0.0 ? (second - cost[best]) / second : 0.0;
          EXPECT_NEAR(e.uniqueness_aw.at<float>(y, x), u, 1e-6)
              << "view " << sign << " at " << x << "," << y;
          if (best > 0 && best + 1 < static_cast<int>(cost.size()) &&
              cost[best - 1] - 2.0 * cost[best] + cost[best + 1] > 0.0) {
            const double vertex =
                disparity[best] +
                std::clamp(0.5 * (cost[best - 1] - cost[best + 1]) /
                               (cost[best - 1] - 2.0 * cost[best] + cost[best + 1]),
                           -0.5, 0.5);
            EXPECT_NEAR(e.subpixel_aw.at<float>(y, x), vertex, 1e-5)
                << "view " << sign << " at " << x << "," << y;
          }
          ++compared;
        }
      }
      EXPECT_EQ(compared, ref.rows * ref.cols);
    }
  }
}

// The NCC evidence against the normalised cross-correlation evaluated pixel by pixel and
// disparity by disparity: an n×n RGB patch (rows and columns reflected at the image's borders,
// cv::BORDER_REFLECT_101, as the box filter does), against the target shifted by d (its first
// column repeated where x − d leaves it), flat patches skipped; same WTA (ties to the smaller
// d), same uniqueness, in both views, windows 3 and 5 on a 29×17 pair.
TEST(StereoGcpsTest, NccEvidenceIsThePerPixelFormula) {
  // A flat corner: no correlation there.
  const std::pair<cv::Mat, cv::Mat> pair = SmallShiftedPair(31, 37, 2, cv::Rect(0, 0, 8, 6));
  const cv::Mat &left = pair.first, &right = pair.second;
  const int dmin = 0, dmax = 5;
  for (const int window : {3, 5}) {
    StereoGcpOptions options;
    options.ncc_window_px = window;
    const StereoPairEvidence evidence = ComputeStereoEvidence(left, right, dmin, dmax, options);
    for (const int sign : {-1, 1}) {
      const StereoViewEvidence& e = sign < 0 ? evidence.left : evidence.right;
      // The right view is the left-view formula on the mirrored pair.
      cv::Mat ref = sign < 0 ? left : right, other = sign < 0 ? right : left;
      if (sign > 0) {
        cv::flip(ref, ref, 1);
        cv::flip(other, other, 1);
      }
      const int r = window / 2, width = ref.cols, height = ref.rows;
      const double n = 3.0 * window * window;
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          std::vector<std::pair<double, int>> costs;  // (1 − ncc, d), d ascending
          for (int d = dmin; d <= dmax && x - d >= 0; ++d) {
            double sr = 0, sr2 = 0, st = 0, st2 = 0, srt = 0;
            for (int i = -r; i <= r; ++i) {
              const int qy = cv::borderInterpolate(y + i, height, cv::BORDER_REFLECT_101);
              for (int j = -r; j <= r; ++j) {
                const int qx = cv::borderInterpolate(x + j, width, cv::BORDER_REFLECT_101);
                const cv::Vec3b a = ref.at<cv::Vec3b>(qy, qx);
                const cv::Vec3b b = other.at<cv::Vec3b>(qy, std::max(0, qx - d));
                for (int c = 0; c < 3; ++c) {
                  sr += a[c];
                  sr2 += a[c] * a[c];
                  st += b[c];
                  st2 += b[c] * b[c];
                  srt += a[c] * b[c];
                }
              }
            }
            const double var_r = sr2 - sr * sr / n, var_t = st2 - st * st / n;
            const double denominator = std::sqrt(std::max(0.0, var_r) * std::max(0.0, var_t));
            if (denominator < 1e-6) continue;
            costs.emplace_back(1.0 - (srt - sr * st / n) / denominator, d);
          }
          const int xe = sign < 0 ? x : width - 1 - x;  // the evidence's own column
          if (costs.empty()) {
            EXPECT_EQ(e.wta_ncc.at<int>(y, xe), -1) << "view " << sign << " at " << x << "," << y;
            continue;
          }
          std::size_t best = 0;
          for (std::size_t i = 1; i < costs.size(); ++i) {
            if (costs[i].first < costs[best].first) best = i;
          }
          EXPECT_EQ(e.wta_ncc.at<int>(y, xe), costs[best].second)
              << "view " << sign << " window " << window << " at " << x << "," << y;
          double second = std::numeric_limits<double>::infinity();
          for (const auto& c : costs) {
            if (std::abs(c.second - costs[best].second) > 1) second = std::min(second, c.first);
          }
          const double u = std::isfinite(second) && second > 0.0
                               ? std::max(0.0, (second - costs[best].first) / second)
                               : 0.0;
          EXPECT_NEAR(e.uniqueness_ncc.at<float>(y, xe), u, 1e-6)
              << "view " << sign << " at " << x << "," << y;
        }
      }
    }
  }
}

TEST(StereoGcpsTest, BadInputsThrow) {
  const cv::Mat image(20, 30, CV_8UC3, cv::Scalar(1, 2, 3));
  try {
    ExtractStereoGcps(image, image, 5, 5, StereoGcpOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "ExtractStereoGcps: disparity range [5, 5] must satisfy 0 <= min < "
                 "max < width (30)");
  }
  EXPECT_THROW(ExtractStereoGcps(image, cv::Mat(20, 31, CV_8UC3), 0, 4, StereoGcpOptions()), Error);
  StereoGcpOptions options;
  options.ncc_window_px = 4;
  try {
    options.Check();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(
        e.what(),
        "gcp.stereo.ncc_window_px = 4. Violated constraint: odd, 3 <= ncc_window_px <= 15");
  }
}

TEST(StereoGcpsTest, OutlierStats) {
  cv::Mat sparse = (cv::Mat_<float>(1, 5) << 1.0f, 2.0f, kNaN, 4.0f, 5.0f);
  cv::Mat gt = (cv::Mat_<float>(1, 5) << 1.5f, 3.5f, 3.0f, kInvalidDepth, 5.0f);
  const GcpOutlierStats stats = ComputeOutlierStats(sparse, gt);
  EXPECT_EQ(stats.num_evaluated, 3);
  EXPECT_EQ(stats.num_outliers, 1);
  EXPECT_NEAR(stats.outlier_percent, 100.0 / 3.0, 1e-12);
}

// ---- Real data (Middlebury 2001): paper Table 1 and the D̂ accuracy of §3.1 ----

struct Scene {
  std::string name, left, right, gt;
  double gt_scale;
  int max_disparity;
};

cv::Mat ReadGt(const std::string& path, double scale) {
  const cv::Mat raw = cv::imread(path, cv::IMREAD_GRAYSCALE);
  cv::Mat gt;
  raw.convertTo(gt, CV_32F, 1.0 / scale);
  gt.setTo(kInvalidDepth, raw == 0);
  return gt;
}

// bad-1 % in the mask; unreached (NaN) pixels count as bad unless reached_only.
double BadPercent(const cv::Mat& estimate, const cv::Mat& gt, const cv::Mat& mask,
                  bool reached_only = false) {
  int bad = 0, count = 0;
  for (int y = 0; y < gt.rows; ++y) {
    for (int x = 0; x < gt.cols; ++x) {
      if (!mask.at<uchar>(y, x) || !std::isfinite(gt.at<float>(y, x))) continue;
      if (reached_only && !std::isfinite(estimate.at<float>(y, x))) continue;
      ++count;
      const float e = estimate.at<float>(y, x);
      if (!std::isfinite(e) || std::abs(e - gt.at<float>(y, x)) > 1.0f) ++bad;
    }
  }
  return count ? 100.0 * bad / count : 0.0;
}

class MiddleburyStereoGcpsTest : public ::testing::TestWithParam<Scene> {};

TEST_P(MiddleburyStereoGcpsTest, Table1DensityOutliersAndPropagatedAccuracy) {
  const Scene& scene = GetParam();
  GCPSTEREO_REQUIRE_SHARED_DATA(dir, "middlebury/" + scene.name);
  const cv::Mat left = cv::imread(dir + "/" + scene.left, cv::IMREAD_COLOR);
  const cv::Mat right = cv::imread(dir + "/" + scene.right, cv::IMREAD_COLOR);
  const cv::Mat gt = ReadGt(dir + "/" + scene.gt, scene.gt_scale);
  const cv::Mat nonocc = cv::imread(dir + "/nonocc.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(left.empty() || right.empty() || gt.empty() || nonocc.empty());

  const StereoGcpResult result =
      ExtractStereoGcps(left, right, 0, scene.max_disparity, StereoGcpOptions());
  const GcpOutlierStats stats = ComputeOutlierStats(result.disparity, gt);
  std::printf(
      "[ Table 1  ] %-8s density %.2f %%  outliers %.2f %% (%d of %d)  candidates L %d "
      "R %d  %.1f s\n",
      scene.name.c_str(), result.density_percent, stats.outlier_percent, stats.num_outliers,
      stats.num_evaluated, result.num_candidates_left, result.num_candidates_right, result.seconds);
  EXPECT_LE(stats.outlier_percent, 1.0);  // measured 0.01 % / 0.08 % (issue target: ≤ 2 %)
  EXPECT_GT(result.density_percent, 1.0);

  // D̂ from the stereo GCPs and from ground truth sampled at s = 16 (block centres).
  propagation::PropagationOptions options;
  const propagation::PropagationResult from_stereo =
      propagation::Propagate(left, result.disparity, options);
  cv::Mat sampled(gt.size(), CV_32F, cv::Scalar(kNaN));
  for (int y = 7; y < gt.rows; y += 16) {
    for (int x = 7; x < gt.cols; x += 16) {
      if (std::isfinite(gt.at<float>(y, x))) sampled.at<float>(y, x) = gt.at<float>(y, x);
    }
  }
  const propagation::PropagationResult from_gt = propagation::Propagate(left, sampled, options);
  const double bad_stereo = BadPercent(from_stereo.values, gt, nonocc);
  const double bad_gt = BadPercent(from_gt.values, gt, nonocc);
  std::printf(
      "[ D-hat    ] %-8s bad-1 nonocc: from stereo GCPs %.2f %% (%.2f %% of reached; "
      "unreached %d px), from GT s=16 %.2f %% (%.2f %% of reached; unreached %d px)\n",
      scene.name.c_str(), bad_stereo, BadPercent(from_stereo.values, gt, nonocc, true),
      from_stereo.num_unreached_pixels, bad_gt, BadPercent(from_gt.values, gt, nonocc, true),
      from_gt.num_unreached_pixels);
  // Unreached pixels count as bad above; interpolation must beat a constant guess by far.
  EXPECT_LT(bad_stereo, 50.0);
  EXPECT_LT(bad_gt, 50.0);
}

INSTANTIATE_TEST_SUITE_P(
    Middlebury2001, MiddleburyStereoGcpsTest,
    ::testing::Values(Scene{"tsukuba", "scene1.row3.col3.ppm", "scene1.row3.col4.ppm",
                            "truedisp.row3.col3.pgm", 16.0, 15},
                      Scene{"venus", "im2.ppm", "im6.ppm", "disp2.pgm", 8.0, 19}),
    [](const ::testing::TestParamInfo<Scene>& info) { return info.param.name; });

}  // namespace
}  // namespace gcpstereo::gcp
