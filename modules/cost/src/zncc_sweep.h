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

struct ZnccSweepParams {
  int window_px = 7;      // odd, 3 … kMaxZnccWindowPx
  float truncation = 60;  // τ: Φ_n = τ · min(1, 1 − ρ)
  bool best_k = false;    // aggregation "best_k" (else the mean)
  int k = 3;              // already ≤ the number of neighbours
  int min_voters = 1;
  int progress_labels = 8;  // labels between two progress reports
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
