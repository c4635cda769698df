// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/middlebury.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::eval {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

TEST(Middlebury, GroundTruthAgainstItselfHasNoBadPixels) {
  const cv::Mat gt(10, 20, CV_32F, cv::Scalar(5.0f));
  const MiddleburyResult r = EvaluateDisparity(gt, gt, {});
  EXPECT_FALSE(r.nonocc.available);
  EXPECT_FALSE(r.disc.available);
  ASSERT_TRUE(r.all.available);
  EXPECT_EQ(r.all.counted, 200);
  for (double p : r.all.bad_percent) EXPECT_DOUBLE_EQ(p, 0.0);
  EXPECT_DOUBLE_EQ(r.all.mean_abs_error_px, 0.0);
  EXPECT_DOUBLE_EQ(r.all.rms_error_px, 0.0);
}

// 20×10 GT of 5 px with a known set of wrong pixels.
struct KnownErrors {
  cv::Mat gt = cv::Mat(10, 20, CV_32F, cv::Scalar(5.0f));
  cv::Mat disparity = gt.clone();
  KnownErrors() {
    for (int i = 0; i < 7; ++i) disparity.at<float>(1, i) = 5.75f;  // bad at 0.5 only
    for (int i = 0; i < 3; ++i) disparity.at<float>(2, i) = 3.5f;   // bad at 0.5 and 1
    for (int i = 0; i < 2; ++i) disparity.at<float>(3, i) = 7.0f;   // |e| = 2: not > 2
    disparity.at<float>(4, 0) = kNan;                               // bad everywhere
    disparity.at<float>(4, 1) = kInf;                               // bad everywhere
    disparity.at<float>(4, 2) = -1.0f;                              // |e| = 6: bad everywhere
  }
};

TEST(Middlebury, KnownWrongPixelsGiveTheirShare) {
  KnownErrors k;
  const MiddleburyResult r = EvaluateDisparity(k.disparity, k.gt, {});
  const BadPixelStats& all = r.all;
  EXPECT_EQ(all.counted, 200);
  EXPECT_EQ(all.missing, 2);
  ASSERT_EQ(all.bad_count.size(), 3u);
  EXPECT_EQ(all.bad_count[0], 7 + 3 + 2 + 3);  // > 0.5
  EXPECT_EQ(all.bad_count[1], 3 + 2 + 3);      // > 1
  EXPECT_EQ(all.bad_count[2], 3);              // > 2 (|e| = 2 is not bad)
  EXPECT_DOUBLE_EQ(all.BadPercent(0.5), 100.0 * 15 / 200);
  EXPECT_DOUBLE_EQ(all.BadPercent(1.0), 100.0 * 8 / 200);
  EXPECT_DOUBLE_EQ(all.BadPercent(2.0), 100.0 * 3 / 200);
  EXPECT_THROW(all.BadPercent(3.0), Error);
  // Mean/RMS over the 198 finite estimates.
  const double sum_abs = 7 * 0.75 + 3 * 1.5 + 2 * 2.0 + 6.0;
  const double sum_sq = 7 * 0.5625 + 3 * 2.25 + 2 * 4.0 + 36.0;
  EXPECT_NEAR(all.mean_abs_error_px, sum_abs / 198, 1e-12);
  EXPECT_NEAR(all.rms_error_px, std::sqrt(sum_sq / 198), 1e-12);
  const nlohmann::json j = r.ToJson();
  EXPECT_EQ(j["all"]["bad_count"][1], 8);
  EXPECT_EQ(j["nonocc"]["available"], false);
}

TEST(Middlebury, MasksBordersAndUnknownGroundTruth) {
  KnownErrors k;
  k.gt.at<float>(2, 0) = kInf;  // unknown GT under a bad pixel: not counted
  k.gt.at<float>(2, 1) = 0.0f;  // the files' 0 = unknown as well
  MiddleburyMasks masks;
  masks.nonocc = cv::Mat(10, 20, CV_8U, cv::Scalar(255));
  masks.nonocc.row(1).setTo(0);  // hide the seven 0.75 errors
  masks.all = cv::Mat(10, 20, CV_8U, cv::Scalar(255));
  masks.disc = cv::Mat(10, 20, CV_8U, cv::Scalar(128));  // 128 = non-occluded, not near a disc.
  masks.disc.row(4).setTo(255);
  const MiddleburyResult r = EvaluateDisparity(k.disparity, k.gt, masks);
  EXPECT_EQ(r.all.counted, 198);
  EXPECT_EQ(r.all.bad_count[0], 7 + 1 + 2 + 3);
  EXPECT_EQ(r.nonocc.counted, 178);
  EXPECT_EQ(r.nonocc.bad_count[0], 1 + 2 + 3);
  EXPECT_EQ(r.nonocc.bad_count[2], 3);
  EXPECT_EQ(r.disc.counted, 20);
  EXPECT_EQ(r.disc.bad_count[2], 3);
  EXPECT_DOUBLE_EQ(r.disc.BadPercent(2.0), 15.0);

  // A 2-pixel border removes rows 0, 1, 8, 9 and columns 0, 1, 18, 19: of the wrong pixels only
  // (row 2, col 2: |e| = 1.5) and (row 4, col 2: |e| = 6) remain.
  MiddleburyOptions options;
  options.border_px = 2;
  const MiddleburyResult b = EvaluateDisparity(k.disparity, k.gt, masks, options);
  EXPECT_EQ(b.all.counted, 6 * 16);
  EXPECT_EQ(b.all.bad_count[0], 2);
  EXPECT_EQ(b.all.bad_count[2], 1);
  EXPECT_EQ(b.all.missing, 0);
}

TEST(Middlebury, OptionChecksNameTheKey) {
  const cv::Mat gt(4, 4, CV_32F, cv::Scalar(1.0f));
  MiddleburyOptions options;
  options.thresholds_px = {1.0, 0.5};
  try {
    EvaluateDisparity(gt, gt, {}, options);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "eval.middlebury.thresholds_px[1] = 0.5. Violated constraint: finite, > 0 and "
                 "strictly ascending");
  }
  options = {};
  options.border_px = -1;
  EXPECT_THROW(EvaluateDisparity(gt, gt, {}, options), ConfigError);
  MiddleburyMasks masks;
  masks.nonocc = cv::Mat(3, 4, CV_8U, cv::Scalar(255));
  try {
    EvaluateDisparity(gt, gt, masks);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "nonocc mask is 4x3 but the disparity estimate is 4x4");
  }
  DeriveMasksOptions derive;
  derive.disc_width_px = 8;
  try {
    DeriveMasks(gt, gt, derive);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "eval.masks.disc_width_px = 8. Violated constraint: disc_width_px odd and >= 1");
  }
}

// Two fronto-parallel planes: background disparity 2, a full-height foreground strip of
// disparity 6 over columns [20, 30) of a 50×12 image. The right GT is the forward warp of the left
// one (x_r = x − d, larger disparity wins).
struct TwoPlanes {
  static constexpr int kWidth = 50, kHeight = 12;
  cv::Mat left = cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(2.0f));
  cv::Mat right = cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(0.0f));
  TwoPlanes() {
    left.colRange(20, 30).setTo(6.0f);
    for (int row = 0; row < kHeight; ++row) {
      for (int x = 0; x < kWidth; ++x) {
        const float d = left.at<float>(row, x);
        const int xr = x - static_cast<int>(d);
        if (xr >= 0 && d > right.at<float>(row, xr)) right.at<float>(row, xr) = d;
      }
    }
  }
};

TEST(Middlebury, DerivedMasksOfTwoPlanes) {
  TwoPlanes s;
  const MiddleburyMasks m = DeriveMasks(s.left, s.right);
  ASSERT_FALSE(m.nonocc.empty());
  // Occluded: background columns 0, 1 (leave the right image) and 16…19 (hidden behind the strip,
  // which covers right columns 14…23).
  for (int x = 0; x < TwoPlanes::kWidth; ++x) {
    const bool occluded = x < 2 || (x >= 16 && x < 20);
    for (int row = 0; row < TwoPlanes::kHeight; ++row) {
      EXPECT_EQ(m.all.at<std::uint8_t>(row, x), 255);
      EXPECT_EQ(m.nonocc.at<std::uint8_t>(row, x), occluded ? 0 : 255) << "x = " << x;
      // Jumps between columns 19|20 and 29|30, dilated by 9×9 → columns 15…34, within nonocc.
      const std::uint8_t disc = occluded ? 0 : (x >= 15 && x <= 34 ? 255 : 128);
      EXPECT_EQ(m.disc.at<std::uint8_t>(row, x), disc) << "x = " << x;
    }
  }
  // A border and unknown GT leave the masks; no right GT → no nonocc.
  DeriveMasksOptions options;
  options.border_px = 3;
  cv::Mat left = s.left.clone();
  left.at<float>(5, 40) = kInf;
  const MiddleburyMasks b = DeriveMasks(left, cv::Mat(), options);
  EXPECT_TRUE(b.nonocc.empty());
  EXPECT_EQ(cv::countNonZero(b.all), (TwoPlanes::kWidth - 6) * (TwoPlanes::kHeight - 6) - 1);
  EXPECT_EQ(b.all.at<std::uint8_t>(5, 40), 0);
  EXPECT_EQ(b.disc.at<std::uint8_t>(5, 20), 255);
  EXPECT_EQ(b.disc.at<std::uint8_t>(5, 10), 128);
  EXPECT_EQ(b.disc.at<std::uint8_t>(1, 20), 0);

  // The derived masks drive the evaluation: an estimate that is wrong only in the occlusions is
  // perfect in nonocc and 12·6 / 600 bad in all.
  cv::Mat estimate = s.left.clone();
  for (int row = 0; row < TwoPlanes::kHeight; ++row) {
    for (int x : {0, 1, 16, 17, 18, 19}) estimate.at<float>(row, x) = 6.0f;
  }
  const MiddleburyResult r = EvaluateDisparity(estimate, s.left, m);
  EXPECT_DOUBLE_EQ(r.nonocc.BadPercent(1.0), 0.0);
  EXPECT_DOUBLE_EQ(r.all.BadPercent(1.0), 100.0 * 72 / 600);
  EXPECT_EQ(r.disc.counted, TwoPlanes::kHeight * (34 - 15 + 1 - 4));
}

TEST(Middlebury, ErrorMapColours) {
  KnownErrors k;
  cv::Mat mask(10, 20, CV_8U, cv::Scalar(255));
  mask.at<std::uint8_t>(9, 19) = 0;
  const cv::Mat map = RenderDisparityErrorMap(k.disparity, k.gt, mask, 1.0);
  ASSERT_EQ(map.type(), CV_8UC3);
  EXPECT_EQ(map.at<cv::Vec3b>(2, 0), cv::Vec3b(0, 0, 255));      // bad: red
  EXPECT_EQ(map.at<cv::Vec3b>(1, 0), cv::Vec3b(255, 255, 255));  // 0.75 good: grey = 5.75/5 clip
  EXPECT_EQ(map.at<cv::Vec3b>(4, 0), cv::Vec3b(0, 255, 255));    // no estimate: yellow
  EXPECT_EQ(map.at<cv::Vec3b>(5, 5), cv::Vec3b(255, 255, 255));  // exact: grey of 5/5
  EXPECT_EQ(map.at<cv::Vec3b>(9, 19), cv::Vec3b(85, 85, 85));    // excluded: dimmed
}

}  // namespace
}  // namespace gcpstereo::eval
