// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The windowed ZNCC photo-consistency of the plane sweep (cost.sweep_measure: zncc); see
// plane_sweep.h for what it computes. Internal to the cost module.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/core/progress.h"

namespace gcpstereo::cost::internal {

// Grey levels are carried as integers in units of 1/kZnccScale grey level, so that every window
// sum is exact in 32-bit integers (for windows up to kMaxZnccWindowPx², 441 · 2040² < 2³¹): the
// sums, and so the costs, do not depend on where a region starts (tiles equal the whole image).
constexpr int kZnccScale = 8;
constexpr int kMaxZnccWindowPx = 21;
// Variance floor ε added to both windows' variances, in grey levels²: a flat window (σ below
// ≈ 2 grey levels, the noise of an 8-bit camera) correlates with nothing, so its cost is high and
// the same for every label instead of following the noise.
constexpr double kZnccVarianceFloor = 4.0;

// A neighbour's grey image (cv::COLOR_BGR2GRAY) as floats with one replicated column on the
// right and one replicated row at the bottom, for bilinear taps.
struct GreyImage {
  std::vector<float> pixels;
  int width = 0;
  int height = 0;
  int stride = 0;  // width + 1
};
GreyImage MakeGreyImage(const cv::Mat& bgr);

// The two inner loops of the ZNCC sweep, each in a portable scalar version and an AVX2 version
// (x86-64, chosen at run time with HaveAvx2Kernel(), sweep_kernels.h) that perform the same IEEE
// operations in the same order, so the costs do not depend on the CPU.
//
// WarpRow: the neighbour's grey level at H (x, y) for x = first_col + c, c < count, as in the RGB
// sweep (sweep_kernels.h: w = aw + bw·x, inv_w = 1/w, u = (ax + bx·x)·inv_w, v = (ay + by·x)·inv_w,
// float arithmetic, no fused multiply-add), sampled bilinearly at u' = min(max(u, 0), width − 1),
// v' likewise (the border replicated; 0 where w <= 0), and stored in units of 1/kZnccScale
// (nearest): values[c] = q = int(value·kZnccScale + ½), squares[c] = q², products[c] =
// reference[c]·q, inside[c] = 1 where w > 0 and −½ <= u < width − ½ and −½ <= v < height − ½.
struct WarpRow {
  float ax, ay, aw, bx, by, bw;
  int first_col;
  int count;
  const std::int32_t* reference;  // the reference row's grey levels ·kZnccScale, `count`
};
void WarpRowScalar(const GreyImage& image, const WarpRow& row, std::int32_t* values,
                   std::int32_t* squares, std::int32_t* products, std::uint8_t* inside);
void WarpRowAvx2(const GreyImage& image, const WarpRow& row, std::int32_t* values,
                 std::int32_t* squares, std::int32_t* products, std::uint8_t* inside);

// ZnccRow: one row of costs from the window sums of the warped values (Σq, Σq², Σr·q) and of the
// reference (Σr and var_r = n·Σr² − (Σr)² + ε'), in double: var = n·Σq² − Σq·Σq + ε', cov = n·Σrq −
// Σr·Σq, ρ = cov / √(var_r·var), cost = τ·float(min(max(1 − ρ, 0), 1)). Where inside[c]: votes[c]
// += 1 and either sum[c] += cost (sum non-null) or costs[c] = cost; elsewhere costs[c] = +inf (costs
// non-null). Returns the number of inside columns.
// With ref_flat (flat-window fallback): t = (1 − w)·t + w·min(1, |Σr − Σq|·mean_scale), w =
// ref_flat[c] = ε'/var_r (≈ 1 in a flat reference window, ≈ 0 in a textured one), before τ·float(t).
struct ZnccRow {
  const std::int32_t* sums;
  const std::int32_t* square_sums;
  const std::int32_t* product_sums;
  const double* ref_sum;
  const double* ref_var;
  const double* ref_flat;  // nullptr: no fallback
  double mean_scale;       // 1 / (n · kZnccScale · T), T the mean difference that costs τ
  const std::uint8_t* inside;
  int count;
  double n;      // pixels in the window
  double floor;  // ε' = n²·kZnccScale²·kZnccVarianceFloor
  float truncation;
};
std::int64_t ZnccRowScalar(const ZnccRow& row, float* sum, float* votes, float* costs);
std::int64_t ZnccRowAvx2(const ZnccRow& row, float* sum, float* votes, float* costs);

struct ZnccSweepParams {
  int window_px = 7;      // odd, 3 … kMaxZnccWindowPx
  float truncation = 60;  // τ: Φ_n = τ · min(1, 1 − ρ)
  bool best_k = false;    // aggregation "best_k" (else the mean)
  int k = 3;              // already ≤ the number of neighbours
  int min_voters = 1;
  int progress_labels = 8;  // labels between two progress reports
  // Flat-window fallback: where the reference window is flat the cost moves to the difference of
  // the window means, truncated at flat_truncation grey levels; 0 = off (pure ZNCC).
  float flat_truncation = 0.0f;
};

struct ZnccSweepCounts {
  std::int64_t votes = 0;
  std::int64_t no_data = 0;
  bool cancelled = false;
};

// The ZNCC costs of `region` of the reference image `reference_bgr` (CV_8UC3) against the
// neighbours, for `homographies` H_{n,l} at index l · neighbours + n (reference pixel → neighbour
// pixel, absolute coordinates).
CostVolume ZnccSweep(const cv::Mat& reference_bgr, const std::vector<GreyImage>& neighbors,
                     const std::vector<Eigen::Matrix3d>& homographies, int num_labels,
                     const cv::Rect& region, const ZnccSweepParams& params,
                     const ProgressCallback& progress, ZnccSweepCounts* counts);

}  // namespace gcpstereo::cost::internal
