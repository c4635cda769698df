// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core/types.hpp>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/core/labels.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/cost/cost_filter.h"

namespace gcpstereo::cost {

// Options of the multi-view plane-sweep matching cost (Collins 1996, as used by Wang & Yang,
// CVPR 2011, §4.2). YAML keys in brackets.
struct PlaneSweepOptions {
  // τ [cost.truncation]: per-neighbour cost truncation, in RGB grey levels (the Euclidean norm of
  // an RGB difference lies in [0, 441.7]). Truncation keeps one neighbour that sees an occluder or
  // a specularity from dominating the mean. The paper gives no value. Measured with pixel-wise WTA
  // on Middlebury sequences (tsukuba 4 neighbours, venus 6; bad-1 all): τ = 15 / 30 / 45–442 give
  // 22.8 / 21.3 / 21.0–21.2 % (tsukuba) and 45.8 / 43.5 / 42.8–43.1 % (venus), so WTA is flat above
  // ≈45; 60 keeps that accuracy while bounding an occluded neighbour's influence (and fixes the
  // scale the smoothness weight λs is tuned against). Range: τ > 0.
  double truncation = 60.0;
  // [cost.sweep_measure]: the photo-consistency of one neighbour's sample.
  //   "rgb"  — the paper: the truncated RGB difference norm of the pixel alone (below);
  //   "zncc" — exposure-invariant and windowed: ρ, the zero-mean normalised cross-correlation of
  //   the grey levels over a zncc_window_px square around p and around its warps H_{n,l} q (the
  //   plane-swept window), with a variance floor of 4 grey levels² so that a flat window
  //   correlates with nothing; Φ_n = τ · min(1, 1 − ρ) (anti-correlation counts as no match).
  //   Real photographs differ in exposure and white balance between views, which the RGB norm
  //   reads as mismatch; and one pixel's colour is flat in weak texture, where a window is not.
  std::string measure = "rgb";
  // [cost.zncc_window_px]: side of the "zncc" window, in pixels. Range: odd, 3 … 21.
  int zncc_window_px = 7;
  // [cost.zncc_flat_fallback]: "zncc" only. A flat reference window correlates with nothing, so
  // every label costs the same there and the smoothness alone decides; with the fallback the cost
  // moves, as the window flattens, to the difference of the grey-level means of the two windows:
  // Φ_n = τ · [(1 − w) · min(1, 1 − ρ) + w · min(1, |μ_ref − μ_n| / (τ/√3))], w = ε / (σ_ref² +
  // ε) with ε the variance floor (4 grey levels²), so w ≈ 1 below σ ≈ 2 grey levels and ≈ 0 in
  // texture; τ/√3 is the grey difference at which the RGB norm reaches τ. Not exposure-invariant
  // where it acts (flat windows only).
  bool zncc_flat_fallback = false;
  // [cost.aggregation]: how the per-neighbour costs of a pixel and label are combined.
  //   "mean"   — mean over the neighbours that see the sample (the paper);
  //   "best_k" — mean of the best_k smallest of them (occlusion-robust; Kang, Szeliski & Chai
  //   2001).
  std::string aggregation = "mean";
  // k [cost.best_k]: neighbours averaged by "best_k"; with fewer voters, all voters are averaged.
  // Range: best_k >= 1.
  int best_k = 3;
  // [cost.min_voters]: a (pixel, label) needs at least this many neighbours that see the sample,
  // else it gets no data (CostVolume::kNoData). Range: min_voters >= 1.
  int min_voters = 1;
  // [cost.progress_rows]: rows of the region computed between two progress reports (and
  // cancellation checks). Range: >= 1. Has no influence on the result.
  int progress_rows = 16;
  // [cost.sweep_window_px], [cost.sweep_window_filter], [cost.sweep_guided_epsilon]: aggregation
  // of Φ over a window (cost_filter.h); sweep_window_px 1 = pixel-wise (the paper).
  CostFilterOptions window;

  // Throws ConfigError naming the YAML key of the first invalid field.
  void Check() const;
};

// What a plane sweep did (lands in report.json).
struct PlaneSweepSummary {
  std::int64_t samples = 0;        // (pixel, label, neighbour) triples evaluated = region · L · N
  std::int64_t votes = 0;          // samples whose projection fell inside the neighbour image
  std::int64_t no_data_costs = 0;  // (pixel, label) entries left without data
  std::int64_t volume_bytes = 0;   // memory of the returned cost volume
  double seconds = 0.0;            // wall-clock time of the sweep
  bool cancelled = false;  // the progress callback asked to stop; rows not done have no data
};

// The plane-sweep data cost Φ(p, l) of Wang & Yang (CVPR 2011), eq. (2), §4.2:
//
//   Φ(p, l) = A_{n ∈ V(p,l)} min(‖I_ref(p) − I_n(H_{n,l} p)‖₂, τ)
//
// for every pixel p of `region` (a rectangle of the reference image, e.g. a tile plus its margin)
// and every label l of `labels`:
//   - z_l = labels.DepthOfLabel(l) is a fronto-parallel plane of the reference camera (camera z =
//     z_l); z_l = +∞ (disparity / inverse depth 0) is the plane at infinity;
//   - H_{n,l} = K_n (R + t nᵀ / z_l) K_ref⁻¹ with n = (0, 0, 1), R = R_nᵀ R_ref and
//     t = R_nᵀ (C_ref − C_n) (Strecha convention, R camera-to-world) maps reference pixels on the
//     plane to neighbour n's pixels; along a reference row it is x' = (a + b·col)/(c + d·col);
//   - I_n(·) is sampled bilinearly (RGB, grey levels 0…255); ‖·‖₂ is the Euclidean norm of the RGB
//     difference (the paper), truncated at τ = options.truncation; or, with options.measure
//     "zncc", τ · min(1, 1 − ρ) with ρ the windowed ZNCC of the grey levels (see
//     PlaneSweepOptions::measure; the window samples the neighbour at H_{n,l} q for every q of
//     the window, the border replicated; window sums are exact integers, so tiles still agree);
//   - V(p, l): the neighbours whose image contains the projection (Camera::InImage: within half a
//     pixel of the border, sampled with edge replication) and that see the plane in front of them;
//     the others do not vote;
//   - A: options.aggregation, the mean (the paper) or the mean of the best_k smallest costs;
//     |V(p, l)| < options.min_voters → no data (CostVolume::kNoData).
// The returned volume covers `region` with max_cost = τ (16-bit quantisation, step τ / 65534,
// nearest level, see CostVolume). Rows are computed in parallel (TBB); every entry depends only on
// its pixel and label, so the result is identical for any thread count; coordinates come from the
// absolute pixel position, so a tile's costs equal the same pixels' costs in the full image.
// Speed: the inner loop runs 8 columns at a time with AVX2 where the CPU has it (chosen at run
// time; a portable scalar loop otherwise, bit-identical results), and labels are processed in
// blocks of 32 per row before being interleaved into the label-fastest volume. Memory: the volume
// (2 bytes · region pixels · labels) plus ≈4 bytes per neighbour pixel.
// Works unchanged for rectified sequences (RectifiedSequenceCamera) with disparity labels, where
// H reduces to a shift by the label's disparity times the view offset.
// Deviation from the paper: pixels seen by no neighbour get "no data" instead of a cost.
// Optional extension (off by default): options.window > 1 filters each label's slice of Φ with a
// box or guided filter (FilterCostVolume); Φ is then swept on `region` grown by the filter's margin
// (clipped to the image) so that a tile's costs equal the whole image's, and the summary's samples
// and votes count that grown region.
// Throws Error when an image is not CV_8UC3 or does not match its camera's size, when a camera is
// invalid, or when `region` is not inside the reference image; ConfigError for bad options.
CostVolume ComputePlaneSweepCost(const View& reference, const std::vector<View>& neighbors,
                                 const LabelSpace& labels, const cv::Rect& region,
                                 const PlaneSweepOptions& options,
                                 const ProgressCallback& progress = {},
                                 PlaneSweepSummary* summary = nullptr);

// The same costs for several regions at once (each volume equals ComputePlaneSweepCost of its
// region alone); the neighbours' images are prepared once and the regions computed in parallel.
// For many small regions, such as windows around sparse pixels. Throws as above.
std::vector<CostVolume> ComputePlaneSweepCostForRegions(const View& reference,
                                                        const std::vector<View>& neighbors,
                                                        const LabelSpace& labels,
                                                        const std::vector<cv::Rect>& regions,
                                                        const PlaneSweepOptions& options);

}  // namespace gcpstereo::cost
