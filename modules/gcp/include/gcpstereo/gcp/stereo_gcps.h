// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// GCPs from the stereo images themselves (paper §4.1, "Computing GCPs from stereo images").

#include <string>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/gcp/gcp_sources.h"

namespace gcpstereo::gcp {

// Options of the stereo source. YAML keys gcp.stereo.*.
struct StereoGcpOptions {
  // Largest spread max − min of the three WTA disparities (D_BT, D_NCC, D_AW) of a candidate, px.
  // Paper: "variance smaller than 1 disparity"; we use the stricter "agree within 1 px" of the
  // issue (for three integers, max − min <= 1 implies variance <= 2/9). Valid: [0, 10].
  // Key gcp.stereo.max_spread_px.
  int max_spread_px = 1;
  // Left-right check [9]: |d_L(x) − d_R(x − d_L)| must be <= this, px. Valid: [0, 10].
  // Key gcp.stereo.lr_tolerance_px.
  int lr_tolerance_px = 1;
  // Canny thresholds on the grey image (cv::Canny, L2 gradient, 3×3 Sobel), grey levels; the
  // paper does not give them. Valid: 0 <= low <= high. Keys gcp.stereo.canny_low, canny_high.
  double canny_low = 50.0;
  double canny_high = 150.0;
  // Candidates within this Chebyshev distance of an edge pixel are dropped ("not near any
  // intensity edge"), px. Valid: [0, 20]. Key gcp.stereo.edge_margin_px.
  int edge_margin_px = 1;
  // NCC window (paper: 5×5), odd, px. Valid: odd in [3, 15]. Key gcp.stereo.ncc_window_px.
  int ncc_window_px = 5;
  // Adaptive-weight aggregation (Yoon & Kweon, CVPR 2005 [33]): window side (the paper's value
  // was lost from our copy; Yoon–Kweon use 35), odd, px. Valid: odd in [3, 71].
  // Key gcp.stereo.aw_window_px.
  int aw_window_px = 31;
  // Sample every aw_stride-th pixel of the window (1 = all; 2 = a quarter of the work). Not in the
  // paper: a speed approximation. Valid: [1, 4]. Key gcp.stereo.aw_stride_px.
  int aw_stride_px = 2;
  // γ_c of Yoon–Kweon (CIELab colour distance bandwidth): 5. Valid: > 0. Key gcp.stereo.aw_gamma_c.
  double aw_gamma_c = 5.0;
  // γ_p of Yoon–Kweon (spatial bandwidth, pixels): 17.5. Valid: > 0. Key gcp.stereo.aw_gamma_p.
  double aw_gamma_p = 17.5;
  // Truncation T of the absolute RGB difference (sum over channels) in the AW cost; Yoon–Kweon
  // use 40. Valid: > 0. Key gcp.stereo.aw_truncation.
  double aw_truncation = 40.0;
  // Standard deviation attributed to a stereo GCP's disparity, px (converted to depth sigma by
  // StereoGcpsToGcpSet). Valid: >= 0. Key gcp.stereo.sigma_px.
  double sigma_px = 0.5;

  // --- Reliability tests added to the paper's (not in §4.1; see ExtractStereoGcps) ---
  // Uniqueness of a WTA: u = (c₂ − c₁) / c₂, c₁ the best cost, c₂ the best cost outside ±1 px of
  // the best disparity (NCC: cost = 1 − ncc). u = 0 when no such competitor exists or c₂ = 0.
  // A candidate needs u >= the threshold in each matcher; 0 = test off. Valid: [0, 1).
  // Keys gcp.stereo.min_uniqueness_aw, gcp.stereo.min_uniqueness_ncc, gcp.stereo.min_uniqueness_bt.
  double min_uniqueness_aw = 0.3;
  double min_uniqueness_ncc = 0.3;
  double min_uniqueness_bt = 0.0;
  // Texture test: standard deviation of the grey level (BGR→grey, 0…255) in the
  // texture_window_px² window must be >= this, grey levels; 0 = off. Valid: [0, 128].
  // Key gcp.stereo.min_texture_std.
  double min_texture_std = 0.0;
  // Occlusion (ordering) test against foreground fattening: near a depth discontinuity the
  // windows straddle two surfaces and all matchers extend the nearer one into the background
  // that the other view cannot see; both views fatten alike, so the left-right check passes.
  // A left candidate x with disparity d is dropped when some x' < x on its row has an
  // adaptive-weight WTA d' < d − 1 with x − x' <= (d − d') + occlusion_margin_px, i.e. x lies in
  // (or within the margin of) the band that x' occludes in the right view (mirror for the right
  // view: x' > x). −1 = off. Valid: [−1, 50]. Key gcp.stereo.occlusion_margin_px.
  int occlusion_margin_px = 4;
  // Value given to a GCP: "median" of the three WTAs, or "ncc" (the 5×5 NCC's WTA, measured less
  // biased than the 31×31 adaptive weights on slanted surfaces). Key gcp.stereo.value.
  std::string value = "ncc";
  // Side of the texture test's window, odd, px. Valid: odd in [3, 31].
  // Key gcp.stereo.texture_window_px.
  int texture_window_px = 5;

  // --- Calibrated (non-rectified) views: ExtractCalibratedStereoGcps ---
  // Number of neighbours (the nearest to the reference) each rectified with it and matched.
  // Valid: [1, 20]. Key gcp.stereo.max_neighbors.
  int max_neighbors = 2;
  // A GCP of one pair is kept when at least min_confirmations other pairs' NCC WTA maps have a
  // depth within confirm_radius_px (Chebyshev, reference pixels) whose depth agrees within
  // confirm_sigma · sqrt(σ₁² + σ₂²) (σ from sigma_px). Valid: confirmations in [0, 19] (0 = no
  // check), radius in [0, 10], confirm_sigma > 0. Keys gcp.stereo.min_confirmations,
  // gcp.stereo.confirm_radius_px, gcp.stereo.confirm_sigma.
  int min_confirmations = 1;
  int confirm_radius_px = 1;
  double confirm_sigma = 3.0;
  // Views are matched at this fraction of their resolution and the GCPs mapped back to the
  // reference grid (the adaptive-weight cost grows with the disparity range, so full-resolution
  // matching of a wide-baseline set takes tens of minutes). Valid: (0, 1]. Key
  // gcp.stereo.image_scale.
  double image_scale = 1.0;
  // Calibrated views: each GCP's depth is then searched again with the plane-sweep cost of the
  // processing resolution, between the depths of its match's disparity ± refine_px (pixels of the
  // matching scale; RefineGcpsOnLabels; 0 = off), the cost averaged over a refine_window_px square.
  // Valid: refine_px in [0, 10] (> 0 needs sigma_px > 0), refine_window_px odd in [1, 15]. Keys
  // gcp.stereo.refine_px, gcp.stereo.refine_window_px.
  double refine_px = 1.0;
  int refine_window_px = 5;

  void Check() const;  // throws ConfigError naming the key
};

// What the three matchers say for every pixel of one view (the view is the reference; its
// partner pixel is x − d for the left view and x + d for the right view). Computed once, it can be
// filtered by SelectStereoGcps under several thresholds (parameter sweeps, tests).
struct StereoViewEvidence {
  cv::Mat wta_bt, wta_ncc, wta_aw;  // CV_32S WTA disparities, −1 = no valid disparity
  cv::Mat uniqueness_bt, uniqueness_ncc, uniqueness_aw;  // CV_32F u ∈ [0, 1] (see the options)
  cv::Mat subpixel_aw;  // CV_32F wta_aw refined by a parabola through its cost curve, NaN = none
  cv::Mat texture_std;  // CV_32F grey-level standard deviation in the texture window
  cv::Mat edges;        // CV_8U, 255 = within edge_margin_px of a Canny edge
};
struct StereoPairEvidence {
  StereoViewEvidence left, right;
  double seconds = 0.0;
};

struct StereoGcpResult {
  cv::Mat disparity;  // CV_32F, left view: GCP disparity (px, left x − right x); NaN elsewhere
  cv::Mat wta_bt;     // CV_32S WTA maps of the left view (−1 = no valid disparity)
  cv::Mat wta_ncc;
  cv::Mat wta_aw;
  cv::Mat edges;                // CV_8U, 255 = excluded by the edge test (dilated Canny)
  int num_candidates_left = 0;  // agreeing, away from edges
  int num_candidates_right = 0;
  int num_near_edges_left = 0;  // agreeing but near an edge
  // Left candidates of the paper's tests (agreeing, away from edges) removed by the added tests,
  // in this order (a pixel counts for the first test it fails).
  int num_low_texture_left = 0;
  int num_ambiguous_left = 0;    // failed a uniqueness threshold
  int num_occlusion_left = 0;    // failed the occlusion test
  int num_gcps = 0;              // survivors of the left-right check
  double density_percent = 0.0;  // 100 · num_gcps / pixels
  double seconds = 0.0;
};

// Stereo GCPs (Wang & Yang, CVPR 2011, §4.1) for a rectified pair, integer disparities
// d ∈ [min_disparity_px, max_disparity_px] with left pixel x matching right pixel x − d.
// For each of the left and the right view:
//   D_BT  = WTA of the Birchfield–Tomasi dissimilarity [3] (sum over RGB), no aggregation;
//   D_NCC = WTA (max) of the normalised cross-correlation over a 5×5 RGB patch;
//   D_AW  = WTA of Yoon–Kweon adaptive-support-weight aggregation [33] of truncated AD:
//           C(p, d) = Σ_q w(p,q) w(p̄,q̄) e(q,q̄) / Σ_q w(p,q) w(p̄,q̄),
//           w(p,q) = exp(−(ΔLab_pq / γ_c + ‖p − q‖ / γ_p)), e = min(Σ_RGB |I_L(q) − I_R(q̄)|, T);
//   candidate: max − min of the three <= max_spread_px, and not within edge_margin_px of a Canny
//   edge of that view; its disparity is the median of the three.
// A left candidate becomes a GCP when the right pixel x − d_L is a right candidate with
// |d_L − d_R| <= lr_tolerance_px. Deviations: max_spread instead of the variance; the AW window
// is sub-sampled by aw_stride_px; ties in every WTA go to the smallest disparity; and tests the
// paper does not have, each measured on the 8 Middlebury dev scenes (one default for all; see
// the options): uniqueness of the AW and NCC winners (u >= 0.3), the occlusion (ordering) test
// against foreground fattening (margin 4 px), the GCP value taken from the NCC winner rather
// than the median (the 31×31 AW window is biased on slanted surfaces). Texture and BT-uniqueness
// tests exist but are off by default (measured: no gain). Outliers |d − d_gt| > 1 before → after:
// tsukuba 0.42 → 0.01 %, venus 2.32 → 0.08, Aloe 2.80 → 0.30, Baby1 3.67 → 0.48, Bowling1
// 16.96 → 8.22, Flowerpots 12.75 → 1.28, Midd1 11.07 → 0.74, Rocks1 3.23 → 0.52, at about half
// the density.
// Deterministic (rows are independent; TBB only splits rows). Throws Error on bad inputs.
StereoGcpResult ExtractStereoGcps(const cv::Mat& left_bgr, const cv::Mat& right_bgr,
                                  int min_disparity_px, int max_disparity_px,
                                  const StereoGcpOptions& options,
                                  const ProgressCallback& progress = nullptr);

// The two phases of ExtractStereoGcps: the matchers (expensive) and the tests (cheap). The
// evidence depends on the options' matcher and Canny fields; SelectStereoGcps applies the spread,
// texture, uniqueness and left-right tests. Throws Error on bad inputs (as ExtractStereoGcps) and
// when the evidence maps are missing or of different sizes.
StereoPairEvidence ComputeStereoEvidence(const cv::Mat& left_bgr, const cv::Mat& right_bgr,
                                         int min_disparity_px, int max_disparity_px,
                                         const StereoGcpOptions& options,
                                         const ProgressCallback& progress = nullptr);
StereoGcpResult SelectStereoGcps(const StereoPairEvidence& evidence,
                                 const StereoGcpOptions& options);

// GcpSet of stereo GCPs whose disparity is in the data set's GT convention (the caller rescales
// when the matched pair is not the GT pair): depth = disparity_numerator / d, sigma =
// disparity_numerator · sigma_px / d². Finite d <= 0 (infinite depth) is skipped and counted in
// summary->num_invalid. Source kStereo, raster order. Throws Error on a bad map or numerator.
GcpSet StereoGcpsToGcpSet(const cv::Mat& disparity, double disparity_numerator, double sigma_px,
                          GcpSourceSummary* summary = nullptr);

// Outlier statistics of sparse GCP disparities against ground truth (paper Table 1: |error| > 1).
struct GcpOutlierStats {
  int num_evaluated = 0;  // GCPs with finite ground truth (and inside the mask, if any)
  int num_outliers = 0;   // |d − d_gt| > threshold
  double outlier_percent = 0.0;
};
// sparse: CV_32F, NaN = no GCP; ground_truth: CV_32F, non-finite = unknown; mask: empty or CV_8U
// (non-zero = counted).
GcpOutlierStats ComputeOutlierStats(const cv::Mat& sparse, const cv::Mat& ground_truth,
                                    double threshold = 1.0, const cv::Mat& mask = cv::Mat());

}  // namespace gcpstereo::gcp
