// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The plane sweep's scalar and AVX2 row kernels (modules/cost/src/sweep_kernels.h and, for the
// ZNCC sweep, zncc_sweep.h) must produce bit-identical costs, so results do not depend on the CPU.
#include "sweep_kernels.h"

#include "zncc_sweep.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace gcpstereo::cost::internal {
namespace {

TEST(SweepKernels, ScalarAndAvx2AreBitIdentical) {
  if (!HaveAvx2Kernel()) GTEST_SKIP() << "no AVX2 on this CPU: only the scalar kernel runs";
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::uint32_t> byte(0, 255);
  const int width = 53, height = 31;
  std::vector<std::uint32_t> pixels((width + 1) * (height + 1));
  for (auto& p : pixels) p = byte(rng) | (byte(rng) << 8) | (byte(rng) << 16);
  const PackedImage image{pixels.data(), width, height, width + 1};
  const int count = 67;  // not a multiple of 8: the scalar tail runs too
  std::vector<float> ref_b(count), ref_g(count), ref_r(count);
  for (int c = 0; c < count; ++c) {
    ref_b[c] = byte(rng);
    ref_g[c] = byte(rng);
    ref_r[c] = byte(rng);
  }
  std::uniform_real_distribution<float> coef(-1.0f, 1.0f);
  int inside_total = 0;
  for (int trial = 0; trial < 200; ++trial) {
    SweepRow row;
    // Roughly a similarity with perspective: u ≈ 0.9 x + shift, v ≈ row, w ≈ 1 ± small; some
    // trials put the plane behind the camera (w < 0) or the samples partly outside.
    row.bw = 0.01f * coef(rng);
    row.aw = 1.0f + 0.5f * coef(rng) - (trial % 17 == 0 ? 2.0f : 0.0f);
    row.bx = 0.9f + 0.2f * coef(rng);
    row.ax = 30.0f * coef(rng) - 5.0f;
    row.by = 0.05f * coef(rng);
    row.ay = 15.0f + 20.0f * coef(rng);
    row.first_col = trial % 5;
    row.count = count;
    row.ref_b = ref_b.data();
    row.ref_g = ref_g.data();
    row.ref_r = ref_r.data();
    row.truncation = trial % 2 ? 60.0f : 1000.0f;
    for (int mode = 0; mode < 2; ++mode) {
      std::vector<float> sum_a(count, 3.0f), votes_a(count, 1.0f), costs_a(count, -1.0f);
      std::vector<float> sum_b = sum_a, votes_b = votes_a, costs_b = costs_a;
      const bool store = mode == 1;
      const auto na = SweepRowScalar(image, row, store ? nullptr : sum_a.data(), votes_a.data(),
                                     store ? costs_a.data() : nullptr);
      const auto nb = SweepRowAvx2(image, row, store ? nullptr : sum_b.data(), votes_b.data(),
                                   store ? costs_b.data() : nullptr);
      ASSERT_EQ(na, nb) << "trial " << trial;
      inside_total += static_cast<int>(na);
      ASSERT_EQ(0, std::memcmp(sum_a.data(), sum_b.data(), count * sizeof(float))) << trial;
      ASSERT_EQ(0, std::memcmp(votes_a.data(), votes_b.data(), count * sizeof(float))) << trial;
      ASSERT_EQ(0, std::memcmp(costs_a.data(), costs_b.data(), count * sizeof(float))) << trial;
    }
  }
  // Most samples fall inside (the test exercises the arithmetic, not only the bounds).
  EXPECT_GT(inside_total, 200 * 2 * count / 3);
}

TEST(SweepKernels, ScalarKernelMatchesFormula) {
  // 2×1 image, one column: u = 0.25, v = 0 → value = p00 + (p01 − p00)·0.25 per channel.
  std::vector<std::uint32_t> pixels = {0x00102030u, 0x00506070u, 0x00102030u,
                                       0x00102030u, 0x00506070u, 0x00506070u};
  const PackedImage image{pixels.data(), 2, 1, 3};
  const float ref_b[1] = {0x30}, ref_g[1] = {0x20}, ref_r[1] = {0x10};
  SweepRow row{0.25f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 0, 1, ref_b, ref_g, ref_r, 1000.0f};
  float cost = -1.0f;
  ASSERT_EQ(SweepRowScalar(image, row, nullptr, nullptr, &cost), 1);
  // Every channel differs by 0x40 · 0.25 = 16 → cost = 16·√3.
  EXPECT_FLOAT_EQ(cost, 16.0f * std::sqrt(3.0f));
}

TEST(ZnccKernels, WarpScalarAndAvx2AreBitIdentical) {
  if (!HaveAvx2Kernel()) GTEST_SKIP() << "no AVX2 on this CPU: only the scalar kernel runs";
  std::mt19937 rng(11);
  cv::Mat bgr(31, 53, CV_8UC3);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(256));
  const GreyImage image = MakeGreyImage(bgr);
  const int count = 67;  // not a multiple of 8: the scalar tail runs too
  std::uniform_int_distribution<std::int32_t> level(0, 255 * kZnccScale);
  std::vector<std::int32_t> reference(count);
  for (auto& r : reference) r = level(rng);
  std::uniform_real_distribution<float> coef(-1.0f, 1.0f);
  int inside_total = 0, behind_total = 0;
  for (int trial = 0; trial < 300; ++trial) {
    WarpRow row;
    // As the RGB kernel's test: some planes behind the camera (w <= 0), samples partly outside
    // (left, right, above, below: the clamped border taps), and one row through w = 0 exactly.
    row.bw = trial % 29 == 0 ? 0.05f : 0.01f * coef(rng);
    row.aw =
        trial % 29 == 0 ? -0.05f * 7.0f : 1.0f + 0.5f * coef(rng) - (trial % 17 == 0 ? 2.0f : 0.0f);
    row.bx = 0.9f + 0.2f * coef(rng);
    row.ax = 40.0f * coef(rng) - 5.0f;
    row.by = 0.05f * coef(rng);
    row.ay = 15.0f + 30.0f * coef(rng);
    row.first_col = trial % 5;
    row.count = count;
    row.reference = reference.data();
    std::vector<std::int32_t> values_a(count, -1), squares_a(count, -1), products_a(count, -1);
    std::vector<std::uint8_t> inside_a(count, 7);
    auto values_b = values_a, squares_b = squares_a, products_b = products_a;
    auto inside_b = inside_a;
    WarpRowScalar(image, row, values_a.data(), squares_a.data(), products_a.data(),
                  inside_a.data());
    WarpRowAvx2(image, row, values_b.data(), squares_b.data(), products_b.data(), inside_b.data());
    ASSERT_EQ(values_a, values_b) << "trial " << trial;
    ASSERT_EQ(squares_a, squares_b) << "trial " << trial;
    ASSERT_EQ(products_a, products_b) << "trial " << trial;
    ASSERT_EQ(inside_a, inside_b) << "trial " << trial;
    for (int c = 0; c < count; ++c) {
      ASSERT_EQ(squares_a[c], values_a[c] * values_a[c]);
      ASSERT_EQ(products_a[c], reference[c] * values_a[c]);
      inside_total += inside_a[c];
      const float w = row.aw + row.bw * static_cast<float>(row.first_col + c);
      if (!(w > 0.0f)) {
        ASSERT_EQ(values_a[c], 0) << "behind the camera the sample is 0";
        ASSERT_EQ(inside_a[c], 0);
        ++behind_total;
      }
    }
  }
  // Both the inside and the outside paths ran, and some samples lay behind the camera.
  EXPECT_GT(inside_total, 300 * count / 5);
  EXPECT_LT(inside_total, 300 * count);
  EXPECT_GT(behind_total, 0);
}

TEST(ZnccKernels, CostScalarAndAvx2AreBitIdentical) {
  if (!HaveAvx2Kernel()) GTEST_SKIP() << "no AVX2 on this CPU: only the scalar kernel runs";
  std::mt19937 rng(12);
  const int window = 7;
  const double n = window * window;
  const double floor = n * n * kZnccScale * kZnccScale * kZnccVarianceFloor;
  const int count = 61;
  // Window sums of random windows (consistent sums of real samples, so ρ lies in [−1, 1]).
  std::uniform_int_distribution<std::int32_t> level(0, 255 * kZnccScale);
  std::vector<std::int32_t> sums(count), square_sums(count), product_sums(count);
  std::vector<double> ref_sum(count), ref_var(count);
  std::vector<std::uint8_t> inside(count);
  for (int c = 0; c < count; ++c) {
    std::int64_t s = 0, ss = 0, rs = 0, rss = 0, rq = 0;
    const bool flat = c % 9 == 0;  // both windows flat (below the variance floor), other means
    const std::int32_t base = level(rng);
    const std::int32_t other_base = level(rng);
    for (int k = 0; k < window * window; ++k) {
      const std::int32_t q = flat ? base : level(rng);
      // Some windows correlate exactly.
      const std::int32_t r = flat ? other_base : (c % 4 == 0 ? q : level(rng));
      s += q;
      ss += static_cast<std::int64_t>(q) * q;
      rs += r;
      rss += static_cast<std::int64_t>(r) * r;
      rq += static_cast<std::int64_t>(r) * q;
    }
    sums[c] = static_cast<std::int32_t>(s);
    square_sums[c] = static_cast<std::int32_t>(ss);
    product_sums[c] = static_cast<std::int32_t>(rq);
    ref_sum[c] = static_cast<double>(rs);
    ref_var[c] = n * static_cast<double>(rss) - ref_sum[c] * ref_sum[c] + floor;
    inside[c] = c % 7 == 3 ? 0 : 1;
  }
  inside[8] = inside[9] = inside[10] = inside[11] = inside[12] = inside[13] = inside[14] =
      inside[15] = 0;  // one block of eight without a vote
  std::vector<double> ref_flat(count);
  for (int c = 0; c < count; ++c) ref_flat[c] = floor / ref_var[c];
  ZnccRow row;
  row.sums = sums.data();
  row.square_sums = square_sums.data();
  row.product_sums = product_sums.data();
  row.ref_sum = ref_sum.data();
  row.ref_var = ref_var.data();
  row.inside = inside.data();
  row.count = count;
  row.n = n;
  row.floor = floor;
  row.truncation = 60.0f;
  row.mean_scale = 1.0 / (n * kZnccScale * 34.6);
  // Modes: accumulate, store; then both with the flat-window fallback.
  for (int mode = 0; mode < 4; ++mode) {
    const bool store = mode % 2 == 1;
    row.ref_flat = mode >= 2 ? ref_flat.data() : nullptr;
    std::vector<float> sum_a(count, 2.5f), votes_a(count, 1.0f), costs_a(count, -1.0f);
    auto sum_b = sum_a, votes_b = votes_a, costs_b = costs_a;
    const auto na = ZnccRowScalar(row, store ? nullptr : sum_a.data(), votes_a.data(),
                                  store ? costs_a.data() : nullptr);
    const auto nb = ZnccRowAvx2(row, store ? nullptr : sum_b.data(), votes_b.data(),
                                store ? costs_b.data() : nullptr);
    ASSERT_EQ(na, nb);
    ASSERT_EQ(0, std::memcmp(sum_a.data(), sum_b.data(), count * sizeof(float)));
    ASSERT_EQ(0, std::memcmp(votes_a.data(), votes_b.data(), count * sizeof(float)));
    ASSERT_EQ(0, std::memcmp(costs_a.data(), costs_b.data(), count * sizeof(float)));
    if (store && row.ref_flat == nullptr) {
      for (int c = 0; c < count; ++c) {
        if (!inside[c]) {
          EXPECT_TRUE(std::isinf(costs_a[c])) << c;
        } else if (c % 4 == 0 && c % 9 != 0) {
          // Identical windows: cov = var', so ρ = var' / (var' + ε') (1 − ρ ≈ 7e-4 for random
          // windows; exactly 0 for a flat one, whose cost is then τ).
          const double var = n * square_sums[c] - static_cast<double>(sums[c]) * sums[c];
          EXPECT_NEAR(costs_a[c], 60.0 * floor / (var + floor), 1e-4) << c;
        } else {
          EXPECT_GT(costs_a[c], 0.0f) << c;
          EXPECT_LE(costs_a[c], 60.0f) << c;
        }
      }
    }
    if (store && row.ref_flat != nullptr) {
      // (1 − w)·ZNCC + w·|Δμ|/T; in a flat reference window (w = 1) the mean difference alone.
      for (int c = 0; c < count; ++c) {
        if (!inside[c]) continue;
        const double delta = std::abs(ref_sum[c] - sums[c]) / (n * kZnccScale);
        const double w = ref_flat[c];
        if (c % 9 == 0) {
          EXPECT_EQ(w, 1.0) << c;
          EXPECT_NEAR(costs_a[c], 60.0 * std::min(1.0, delta / 34.6), 1e-4) << c;
        } else {
          EXPECT_LT(w, 0.01) << c;
        }
        const double var = n * square_sums[c] - static_cast<double>(sums[c]) * sums[c];
        const double cov = n * product_sums[c] - ref_sum[c] * sums[c];
        const double t = std::clamp(1.0 - cov / std::sqrt(ref_var[c] * (var + floor)), 0.0, 1.0);
        const double expected = 60.0 * ((1.0 - w) * t + w * std::min(1.0, delta / 34.6));
        EXPECT_NEAR(costs_a[c], expected, 1e-4) << c;
      }
    }
  }
}

}  // namespace
}  // namespace gcpstereo::cost::internal
