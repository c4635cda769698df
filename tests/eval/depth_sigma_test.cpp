// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/depth_sigma.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::eval {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// A 12×8 scene: gt depth 10, sigma 0.25 (both exactly representable).
struct Scene {
  cv::Mat gt = cv::Mat(8, 12, CV_32F, cv::Scalar(10.0f));
  cv::Mat sigma = cv::Mat(8, 12, CV_32F, cv::Scalar(0.25f));
};

TEST(DepthSigma, ConstantTwoSigmaOffset) {
  Scene s;
  const cv::Mat depth = s.gt + 0.5f;  // exactly 2σ everywhere
  const SigmaHistogram h = EvaluateDepthSigma(depth, s.gt, s.sigma);
  EXPECT_EQ(h.counted, 96);
  EXPECT_EQ(h.missing, 0);
  EXPECT_EQ(h.gt_unknown, 0);
  EXPECT_DOUBLE_EQ(h.WithinPercent(1), 0.0);
  for (int n = 2; n <= 10; ++n) EXPECT_DOUBLE_EQ(h.WithinPercent(n), 100.0) << n;
  EXPECT_DOUBLE_EQ(h.BinPercent(2), 100.0);
  EXPECT_DOUBLE_EQ(h.BinPercent(1), 0.0);
  EXPECT_DOUBLE_EQ(h.BinPercent(3), 0.0);
  EXPECT_DOUBLE_EQ(h.mean_abs_error, 0.5);
  EXPECT_DOUBLE_EQ(h.rms_error, 0.5);
  EXPECT_DOUBLE_EQ(h.median_error_sigma, 2.0);
  // Negative offsets count the same.
  const SigmaHistogram below = EvaluateDepthSigma(s.gt - 0.5f, s.gt, s.sigma);
  EXPECT_DOUBLE_EQ(below.WithinPercent(1), 0.0);
  EXPECT_DOUBLE_EQ(below.WithinPercent(2), 100.0);
}

TEST(DepthSigma, GroundTruthAgainstItselfIsAllWithinOneSigma) {
  Scene s;
  const SigmaHistogram h = EvaluateDepthSigma(s.gt, s.gt, s.sigma);
  EXPECT_DOUBLE_EQ(h.WithinPercent(1), 100.0);
  EXPECT_DOUBLE_EQ(h.MissingPercent(), 0.0);
  EXPECT_DOUBLE_EQ(h.mean_abs_error, 0.0);
}

TEST(DepthSigma, KnownMixWithMissingAndUnknownGroundTruth) {
  // One row of 14 pixels, every case once.
  const float gt_values[] = {10, 10, 10, 10, 10, 10, 10, 10, 10, 10, 10, kInf, 0, 10};
  const float sigma_values[] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0};
  const float depth_values[] = {10, 10.5f, 11, 8.5f, 13, 20, 20.5f, kNan, kInf, -1, 0, 10, 10, 10};
  cv::Mat gt(1, 14, CV_32F), sigma(1, 14, CV_32F), depth(1, 14, CV_32F);
  for (int i = 0; i < 14; ++i) {
    gt.at<float>(0, i) = gt_values[i];
    sigma.at<float>(0, i) = sigma_values[i];
    depth.at<float>(0, i) = depth_values[i];
  }
  const SigmaHistogram h = EvaluateDepthSigma(depth, gt, sigma);
  // Pixels 11 (gt inf), 12 (gt 0) and 13 (sigma 0) have no usable GT.
  EXPECT_EQ(h.gt_unknown, 3);
  EXPECT_EQ(h.counted, 11);
  // NaN, +inf, −1 and 0 are missing: in the denominator, never within.
  EXPECT_EQ(h.missing, 4);
  // e = 0, 0.5, 1 → bin 1; 1.5 → bin 2; 3 → bin 3; 10 → bin 10; 10.5 → beyond.
  EXPECT_EQ(h.bin_count[0], 3);
  EXPECT_EQ(h.bin_count[1], 1);
  EXPECT_EQ(h.bin_count[2], 1);
  EXPECT_EQ(h.bin_count[9], 1);
  EXPECT_EQ(h.beyond_10, 1);
  EXPECT_EQ(h.within_count[0], 3);
  EXPECT_EQ(h.within_count[2], 5);
  EXPECT_EQ(h.within_count[9], 6);
  EXPECT_DOUBLE_EQ(h.WithinPercent(1), 100.0 * 3 / 11);
  EXPECT_DOUBLE_EQ(h.MissingPercent(), 100.0 * 4 / 11);
  EXPECT_DOUBLE_EQ(h.Beyond10Percent(), 100.0 * 1 / 11);
  EXPECT_DOUBLE_EQ(h.mean_abs_error, (0 + 0.5 + 1 + 1.5 + 3 + 10 + 10.5) / 7.0);
  EXPECT_DOUBLE_EQ(h.median_error_sigma, 1.5);
  // Shares add up to 100 %.
  double total = h.MissingPercent() + h.Beyond10Percent();
  for (int n = 1; n <= 10; ++n) total += h.BinPercent(n);
  EXPECT_NEAR(total, 100.0, 1e-12);

  const nlohmann::json j = h.ToJson();
  EXPECT_EQ(j["counted"], 11);
  EXPECT_EQ(j["missing"], 4);
  EXPECT_DOUBLE_EQ(j["within_n_sigma_percent"][0].get<double>(), 100.0 * 3 / 11);
}

TEST(DepthSigma, MaskRestrictsCountedPixels) {
  Scene s;
  cv::Mat depth = s.gt.clone();
  depth(cv::Rect(0, 0, 6, 8)).setTo(kNan);  // left half missing
  cv::Mat mask(8, 12, CV_8U, cv::Scalar(0));
  mask(cv::Rect(4, 0, 8, 8)).setTo(255);  // 2 missing columns + 6 good columns
  const SigmaHistogram h = EvaluateDepthSigma(depth, s.gt, s.sigma, mask);
  EXPECT_EQ(h.counted, 64);
  EXPECT_EQ(h.missing, 16);
  EXPECT_DOUBLE_EQ(h.WithinPercent(1), 75.0);
  EXPECT_DOUBLE_EQ(h.MissingPercent(), 25.0);
}

TEST(DepthSigma, NoCountedPixelsGivesZeroShares) {
  Scene s;
  const cv::Mat gt(8, 12, CV_32F, cv::Scalar(kInf));
  const SigmaHistogram h = EvaluateDepthSigma(s.gt, gt, s.sigma);
  EXPECT_EQ(h.counted, 0);
  EXPECT_EQ(h.gt_unknown, 96);
  EXPECT_DOUBLE_EQ(h.WithinPercent(10), 0.0);
}

TEST(DepthSigma, BadInputsNameTheProblem) {
  Scene s;
  try {
    EvaluateDepthSigma(cv::Mat(8, 10, CV_32F, cv::Scalar(1)), s.gt, s.sigma);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "ground-truth depth is 12x8 but the depth estimate is 10x8");
  }
  try {
    EvaluateDepthSigma(cv::Mat(8, 12, CV_64F, cv::Scalar(1)), s.gt, s.sigma);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_EQ(
        std::string(e.what()).rfind("depth estimate: expected a single-channel CV_32F map", 0), 0u)
        << e.what();
  }
  try {
    EvaluateDepthSigma(s.gt, s.gt, s.sigma, cv::Mat(8, 12, CV_32F));
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("evaluation mask: expected a single-channel CV_8U", 0),
              0u)
        << e.what();
  }
  const SigmaHistogram h;
  EXPECT_THROW(h.WithinPercent(0), Error);
  EXPECT_THROW(h.BinPercent(11), Error);
}

TEST(DepthSigma, HistogramFigureDrawsTheBarsWhereTheSharesAre) {
  Scene s;
  SigmaHistogramPlotOptions options;
  const SigmaHistogram h = EvaluateDepthSigma(s.gt + 0.5f, s.gt, s.sigma);  // all in bin 2
  const cv::Mat image = RenderSigmaHistogram({{"offset", h}}, options);
  ASSERT_EQ(image.type(), CV_8UC3);
  ASSERT_EQ(image.cols, options.width_px);
  ASSERT_EQ(image.rows, options.height_px);
  // Layout (see RenderSigmaHistogram): plot area x in [60, width − 20), 12 groups; the bottom of
  // the plot at height − 60. Sample just above the axis in the middle of groups 1 and 2.
  const double group_w = (options.width_px - 80) / 12.0;
  const int y = options.height_px - 60 - 5;
  const cv::Vec3b bin1 = image.at<cv::Vec3b>(y, static_cast<int>(60 + 0.5 * group_w));
  const cv::Vec3b bin2 = image.at<cv::Vec3b>(y, static_cast<int>(60 + 1.5 * group_w));
  EXPECT_EQ(bin1, cv::Vec3b(255, 255, 255));
  EXPECT_EQ(bin2, cv::Vec3b(200, 120, 30));  // first series colour
  // A bar of 100 % reaches the top of the plot (y axis 0 … 100 %).
  EXPECT_EQ(image.at<cv::Vec3b>(40 + 2, static_cast<int>(60 + 1.5 * group_w)),
            cv::Vec3b(200, 120, 30));

  // Two series side by side; empty input and a tiny image are refused.
  const SigmaHistogram exact = EvaluateDepthSigma(s.gt, s.gt, s.sigma);
  EXPECT_NO_THROW(RenderSigmaHistogram({{"offset", h}, {"exact", exact}}));
  EXPECT_THROW(RenderSigmaHistogram({}), Error);
  options.width_px = 100;
  try {
    RenderSigmaHistogram({{"offset", h}}, options);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "eval.histogram.width_px = 100. Violated constraint: width_px >= 320");
  }
}

TEST(DepthSigma, ErrorMapColours) {
  Scene s;
  cv::Mat depth = s.gt.clone();
  depth.at<float>(0, 0) = kNan;          // missing → magenta
  depth.at<float>(0, 2) = 10.0f + 5.0f;  // 20σ → clipped to the colour of max_sigma
  cv::Mat gt = s.gt.clone();
  gt.at<float>(0, 1) = kInf;  // unknown GT → black
  const cv::Mat map = RenderDepthErrorMap(depth, gt, s.sigma);
  ASSERT_EQ(map.type(), CV_8UC3);
  cv::Mat zero(1, 1, CV_8U, cv::Scalar(0)), full(1, 1, CV_8U, cv::Scalar(255)), c0, c255;
  cv::applyColorMap(zero, c0, cv::COLORMAP_TURBO);
  cv::applyColorMap(full, c255, cv::COLORMAP_TURBO);
  EXPECT_EQ(map.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 0, 255));
  EXPECT_EQ(map.at<cv::Vec3b>(0, 1), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(map.at<cv::Vec3b>(0, 2), c255.at<cv::Vec3b>(0, 0));
  EXPECT_EQ(map.at<cv::Vec3b>(3, 3), c0.at<cv::Vec3b>(0, 0));
  EXPECT_THROW(RenderDepthErrorMap(depth, gt, s.sigma, cv::Mat(), 0.0), Error);
}

}  // namespace
}  // namespace gcpstereo::eval
