// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/cost_volume.h"

namespace gcpstereo::cost {

// Window aggregation of a cost volume (a deliberate deviation from Wang & Yang, whose data term is
// pixel-wise): each label's cost slice is averaged over a window, either uniformly ("box") or with
// the edge-preserving guided filter of He, Sun & Tang (ECCV 2010 / PAMI 2013) guided by the
// reference colour image, as in Hosni et al., "Fast cost-volume filtering for visual correspondence
// and beyond" (CVPR 2011 / PAMI 2013). The pixel-wise cost is nearly flat in weak texture; the
// window lends it the texture of the neighbourhood, and the guided filter keeps depth edges where
// the image has colour edges.
// The YAML keys are `<prefix>window_px`, `<prefix>window_filter`, `<prefix>guided_epsilon`, with
// prefix "cost." for the rectified-pair (Birchfield–Tomasi) cost and "cost.sweep_" for the plane
// sweep.
struct CostFilterOptions {
  // [window_px]: side of the square window, in pixels (radius r = (window_px − 1) / 2); 1 = no
  // aggregation (the paper's pixel-wise cost). Range: odd, 1 ≤ window_px ≤ 101.
  int window_px = 1;
  // [window_filter]: "guided" (He et al.'s guided filter with the reference colour image as guide:
  // edge-preserving) or "box" (plain window mean).
  std::string filter = "guided";
  // ε [guided_epsilon]: regularisation of the guided filter, for guide intensities scaled to
  // [0, 1] (He et al. and Hosni et al. use 1e-4 for stereo); larger = closer to the box mean.
  // Range: ε > 0.
  double guided_epsilon = 1e-4;

  // Throws ConfigError naming `<key_prefix>window_px` etc. for the first invalid field.
  void Check(const std::string& key_prefix = "cost.") const;
  // Pixels of context the filter needs around a region: 0 (window 1), r (box), 2r (guided).
  int MarginPx() const;
};

// Filters `raw`, a volume covering a region R ⊇ `region` of the reference image, and returns the
// volume of `region`. `guide` is the full reference image (CV_8UC3 BGR or CV_8UC1) in whose
// coordinates both regions lie. Each label's slice is filtered independently:
//   box:    q(p) = mean_{W(p)} c
//   guided: q(p) = mean_{W(p)} a · I(p) + mean_{W(p)} b, with per window k (I a 3-vector in [0, 1])
//           a_k = (Σ_k + ε U)⁻¹ cov_k(I, c),  b_k = mean_k c − a_kᵀ mean_k I   (He et al., eq.
//           13–14)
// where W(p) is the r-window around p clipped to R (pass R = region + MarginPx() clipped to the
// image, and windows are those of the whole image: then a tile's result equals the same pixels'
// result on the whole image). Entries of `raw` without data are replaced, for the filter only, by
// the nearest entry with data in the same row of R (the image border is the only place the
// rectified pair has no data, so the replacement is the border's cost); a row of R without any
// data uses max_cost. Entries of `region` that have no data in `raw` stay without data. The
// filtered cost is clamped to [0, raw.max_cost()] (the guided filter may overshoot) and quantised
// like `raw` (same max_cost). Labels are filtered in parallel (TBB), 4 labels a task side by side
// in SIMD lanes, streaming down the rows (2r + 2 rows of window sums held, not whole slices).
// Window sums are running sums of integers held in doubles — the stored costs in steps, their
// products with the guide's 8-bit levels, and a and b in multiples of 2^-20 (rounded; at most
// 5e-7 off) — so they are exact: the result depends neither on the thread count nor on where the
// region starts (a tile is bit for bit a crop of the whole image), and the AVX2 and SSE2 builds
// give the same bits.
// (Not cv::ximgproc::guidedFilter: its colour path inverts Σ + εU in single precision, and where
// the three channels are nearly equal — grey surfaces — Σ is nearly singular: on a 0 → 80 cost
// step at a grey 40 → 200 edge, window 7, ε 1e-4, it is up to 0.61 off against 0.02 here.)
// Throws Error when `region` is not inside raw.region() or the guide does not contain raw.region().
// With `bands` (over `region`; see LabelBands), only the entries in them are filtered — `raw` needs
// to hold the entries within MarginPx() of a block's pixels at the block's labels (others may be
// anything but kNoData where there is data, and must be kNoData where there is none) — and the
// rest are set to the largest cost (65534 steps).
CostVolume FilterCostVolume(const CostVolume& raw, const cv::Mat& guide, const cv::Rect& region,
                            const CostFilterOptions& options, const LabelBands* bands = nullptr);

// `region` grown by `margin_px` on every side and clipped to an image of `image_size`.
cv::Rect GrowRegion(const cv::Rect& region, int margin_px, const cv::Size& image_size);

}  // namespace gcpstereo::cost
