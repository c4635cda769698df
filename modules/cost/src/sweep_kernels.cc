// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "sweep_kernels.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gcpstereo::cost::internal {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// The scalar kernel over columns [begin, end).
std::int64_t SweepColumns(const PackedImage& image, const SweepRow& row, int begin, int end,
                          float* sum, float* votes, float* costs) {
  const float u_max = static_cast<float>(image.width) - 0.5f;
  const float v_max = static_cast<float>(image.height) - 0.5f;
  std::int64_t vote_count = 0;
  for (int c = begin; c < end; ++c) {
    const float x = static_cast<float>(row.first_col + c);
    const float w = row.aw + row.bw * x;
    const float inv_w = 1.0f / w;
    const float u = w > 0.0f ? (row.ax + row.bx * x) * inv_w : -1e30f;
    const float v = (row.ay + row.by * x) * inv_w;
    if (!(u >= -0.5f && u < u_max && v >= -0.5f && v < v_max)) {
      if (costs) costs[c] = kInfinity;
      continue;
    }
    const float uc = std::max(u, 0.0f);
    const float vc = std::max(v, 0.0f);
    const int iu = static_cast<int>(uc);
    const int iv = static_cast<int>(vc);
    const float fu = uc - static_cast<float>(iu);
    const float fv = vc - static_cast<float>(iv);
    const std::uint32_t* p = image.pixels + static_cast<std::ptrdiff_t>(iv) * image.stride + iu;
    const std::uint32_t p00 = p[0], p01 = p[1], p10 = p[image.stride], p11 = p[image.stride + 1];
    const float* refs[3] = {row.ref_b, row.ref_g, row.ref_r};
    float d[3];
    for (int ch = 0; ch < 3; ++ch) {
      const int shift = 8 * ch;
      const float a = static_cast<float>(static_cast<int>((p00 >> shift) & 0xFFu));
      const float b = static_cast<float>(static_cast<int>((p01 >> shift) & 0xFFu));
      const float e = static_cast<float>(static_cast<int>((p10 >> shift) & 0xFFu));
      const float f = static_cast<float>(static_cast<int>((p11 >> shift) & 0xFFu));
      const float top = a + (b - a) * fu;
      const float bottom = e + (f - e) * fu;
      const float value = top + (bottom - top) * fv;
      d[ch] = value - refs[ch][c];
    }
    const float cost =
        std::min(std::sqrt((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2]), row.truncation);
    ++vote_count;
    if (costs) {
      costs[c] = cost;
    } else {
      sum[c] += cost;
      votes[c] += 1.0f;
    }
  }
  return vote_count;
}

}  // namespace

std::int64_t SweepRowScalar(const PackedImage& image, const SweepRow& row, float* sum, float* votes,
                            float* costs) {
  return SweepColumns(image, row, 0, row.count, sum, votes, costs);
}

#if GCPSTEREO_AVX2_KERNELS

bool HaveAvx2Kernel() {
  static const bool have = __builtin_cpu_supports("avx2");
  return have;
}

// One 8-bit channel of eight packed pixels as floats.
__attribute__((target("avx2"), always_inline)) inline __m256 Channel(__m256i pixels, __m128i shift,
                                                                     __m256i byte_mask) {
  return _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srl_epi32(pixels, shift), byte_mask));
}

__attribute__((target("avx2"))) std::int64_t SweepRowAvx2(const PackedImage& image,
                                                          const SweepRow& row, float* sum,
                                                          float* votes, float* costs) {
  const __m256 u_max = _mm256_set1_ps(static_cast<float>(image.width) - 0.5f);
  const __m256 v_max = _mm256_set1_ps(static_cast<float>(image.height) - 0.5f);
  const __m256 minus_half = _mm256_set1_ps(-0.5f);
  const __m256 zero = _mm256_setzero_ps();
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 far_out = _mm256_set1_ps(-1e30f);
  const __m256 infinity = _mm256_set1_ps(kInfinity);
  const __m256 ax = _mm256_set1_ps(row.ax), ay = _mm256_set1_ps(row.ay);
  const __m256 aw = _mm256_set1_ps(row.aw), bx = _mm256_set1_ps(row.bx);
  const __m256 by = _mm256_set1_ps(row.by), bw = _mm256_set1_ps(row.bw);
  const __m256 truncation = _mm256_set1_ps(row.truncation);
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i stride = _mm256_set1_epi32(image.stride);
  const __m256i byte_mask = _mm256_set1_epi32(0xFF);
  const int* base = reinterpret_cast<const int*>(image.pixels);
  std::int64_t vote_count = 0;
  int c = 0;
  for (; c + 8 <= row.count; c += 8) {
    const __m256 x =
        _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(row.first_col + c), lane));
    const __m256 w = _mm256_add_ps(aw, _mm256_mul_ps(bw, x));
    const __m256 inv_w = _mm256_div_ps(one, w);
    const __m256 in_front = _mm256_cmp_ps(w, zero, _CMP_GT_OQ);
    const __m256 u = _mm256_blendv_ps(
        far_out, _mm256_mul_ps(_mm256_add_ps(ax, _mm256_mul_ps(bx, x)), inv_w), in_front);
    const __m256 v = _mm256_mul_ps(_mm256_add_ps(ay, _mm256_mul_ps(by, x)), inv_w);
    const __m256 inside = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(u, minus_half, _CMP_GE_OQ),
                                                      _mm256_cmp_ps(u, u_max, _CMP_LT_OQ)),
                                        _mm256_and_ps(_mm256_cmp_ps(v, minus_half, _CMP_GE_OQ),
                                                      _mm256_cmp_ps(v, v_max, _CMP_LT_OQ)));
    const int inside_bits = _mm256_movemask_ps(inside);
    if (inside_bits == 0) {
      if (costs) _mm256_storeu_ps(costs + c, infinity);
      continue;
    }
    // Lanes outside the image sample pixel (0, 0) (harmless) and are masked out below.
    const __m256 uc = _mm256_and_ps(_mm256_max_ps(u, zero), inside);
    const __m256 vc = _mm256_and_ps(_mm256_max_ps(v, zero), inside);
    const __m256i iu = _mm256_cvttps_epi32(uc);
    const __m256i iv = _mm256_cvttps_epi32(vc);
    const __m256 fu = _mm256_sub_ps(uc, _mm256_cvtepi32_ps(iu));
    const __m256 fv = _mm256_sub_ps(vc, _mm256_cvtepi32_ps(iv));
    const __m256i index = _mm256_add_epi32(_mm256_mullo_epi32(iv, stride), iu);
    const __m256i p00 = _mm256_i32gather_epi32(base, index, 4);
    const __m256i p01 = _mm256_i32gather_epi32(base + 1, index, 4);
    const __m256i p10 = _mm256_i32gather_epi32(base + image.stride, index, 4);
    const __m256i p11 = _mm256_i32gather_epi32(base + image.stride + 1, index, 4);
    const float* refs[3] = {row.ref_b + c, row.ref_g + c, row.ref_r + c};
    __m256 d2 = zero;
    for (int ch = 0; ch < 3; ++ch) {
      const __m128i shift = _mm_cvtsi32_si128(8 * ch);
      const __m256 a = Channel(p00, shift, byte_mask), b = Channel(p01, shift, byte_mask);
      const __m256 e = Channel(p10, shift, byte_mask), f = Channel(p11, shift, byte_mask);
      const __m256 top = _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), fu));
      const __m256 bottom = _mm256_add_ps(e, _mm256_mul_ps(_mm256_sub_ps(f, e), fu));
      const __m256 value = _mm256_add_ps(top, _mm256_mul_ps(_mm256_sub_ps(bottom, top), fv));
      const __m256 d = _mm256_sub_ps(value, _mm256_loadu_ps(refs[ch]));
      // ((d_b² + d_g²) + d_r²), as in the scalar kernel (0 + d_b² is exact).
      d2 = _mm256_add_ps(d2, _mm256_mul_ps(d, d));
    }
    const __m256 cost = _mm256_min_ps(_mm256_sqrt_ps(d2), truncation);
    vote_count += __builtin_popcount(static_cast<unsigned>(inside_bits));
    if (costs) {
      _mm256_storeu_ps(costs + c, _mm256_blendv_ps(infinity, cost, inside));
    } else {
      _mm256_storeu_ps(sum + c,
                       _mm256_add_ps(_mm256_loadu_ps(sum + c), _mm256_and_ps(cost, inside)));
      _mm256_storeu_ps(votes + c,
                       _mm256_add_ps(_mm256_loadu_ps(votes + c), _mm256_and_ps(one, inside)));
    }
  }
  return vote_count + SweepColumns(image, row, c, row.count, sum, votes, costs);
}

#else

bool HaveAvx2Kernel() { return false; }
std::int64_t SweepRowAvx2(const PackedImage& image, const SweepRow& row, float* sum, float* votes,
                          float* costs) {
  return SweepRowScalar(image, row, sum, votes, costs);
}

#endif

}  // namespace gcpstereo::cost::internal
