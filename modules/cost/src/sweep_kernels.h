// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The inner loop of the plane sweep: one reference row against one neighbour for one plane.
// Two implementations — portable scalar C++ and AVX2 (x86-64, chosen at run time) — that perform
// the same IEEE float operations in the same order, so they produce bit-identical costs.
#pragma once

#include <cstdint>

// The AVX2 kernels are compiled on x86-64 with GCC or Clang (per function, with the target
// attribute) and chosen at run time (HaveAvx2Kernel); elsewhere only the scalar ones exist.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define GCPSTEREO_AVX2_KERNELS 1
#include <immintrin.h>
#else
#define GCPSTEREO_AVX2_KERNELS 0
#endif

namespace gcpstereo::cost::internal {

// A neighbour image packed as 0x00RRGGBB per pixel (uint8 channels) with one replicated column on
// the right and one replicated row at the bottom, so that the four bilinear taps of every sample
// inside the image are in memory.
struct PackedImage {
  const std::uint32_t* pixels = nullptr;
  int width = 0;  // of the original image
  int height = 0;
  int stride = 0;  // pixels per padded row (width + 1)
};

struct SweepRow {
  // Neighbour pixel of reference pixel (x, y_ref) on the plane: ((ax + bx·x)/(aw + bw·x),
  // (ay + by·x)/(aw + bw·x)), x = first_col + c (absolute column, so that tiles agree bitwise).
  float ax, ay, aw, bx, by, bw;
  int first_col;
  int count;  // columns in the row
  // The reference row's colours as planar floats, `count` each.
  const float* ref_b;
  const float* ref_g;
  const float* ref_r;
  float truncation;  // τ
};

// Mode "accumulate" (mean): sum[c] += cost and votes[c] += 1 for the columns whose sample is inside
// the image. Mode "store" (best_k): costs[c] = cost, or +inf when the neighbour does not see it.
// Either `sum`/`votes` or `costs` is non-null. Returns the number of votes.
//
// Per column (in this order, float arithmetic, no fused multiply-add):
//   w = aw + bw·x; inv_w = 1 / w; u = (ax + bx·x)·inv_w (or −1e30 when w <= 0); v = (ay +
//   by·x)·inv_w inside ⇔ −½ <= u < width − ½ and −½ <= v < height − ½ bilinear per channel from u'
//   = max(u, 0), v' = max(v, 0): top = p00 + (p01 − p00)·fu, bottom likewise, value = top + (bottom
//   − top)·fv d_ch = value_ch − ref_ch; cost = min(sqrt((d_b² + d_g²) + d_r²), τ)
std::int64_t SweepRowScalar(const PackedImage& image, const SweepRow& row, float* sum, float* votes,
                            float* costs);

// True when the AVX2 kernel can run on this CPU (and was compiled in).
bool HaveAvx2Kernel();
std::int64_t SweepRowAvx2(const PackedImage& image, const SweepRow& row, float* sum, float* votes,
                          float* costs);

}  // namespace gcpstereo::cost::internal
