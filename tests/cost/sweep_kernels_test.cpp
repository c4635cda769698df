// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The plane sweep's scalar and AVX2 row kernels (modules/cost/src/sweep_kernels.h) must produce
// bit-identical costs, so results do not depend on the CPU.
#include "sweep_kernels.h"

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace gcpstereo::cost::internal
