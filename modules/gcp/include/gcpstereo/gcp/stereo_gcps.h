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

  void Check() const;  // throws ConfigError naming the key
};

struct StereoGcpResult {
  cv::Mat disparity;  // CV_32F, left view: GCP disparity (px, left x − right x); NaN elsewhere
  cv::Mat wta_bt;     // CV_32S WTA maps of the left view (−1 = no valid disparity)
  cv::Mat wta_ncc;
  cv::Mat wta_aw;
  cv::Mat edges;                // CV_8U, 255 = excluded by the edge test (dilated Canny)
  int num_candidates_left = 0;  // agreeing, away from edges
  int num_candidates_right = 0;
  int num_near_edges_left = 0;   // agreeing but near an edge
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
// is sub-sampled by aw_stride_px; ties in every WTA go to the smallest disparity.
// Deterministic (rows are independent; TBB only splits rows). Throws Error on bad inputs.
StereoGcpResult ExtractStereoGcps(const cv::Mat& left_bgr, const cv::Mat& right_bgr,
                                  int min_disparity_px, int max_disparity_px,
                                  const StereoGcpOptions& options,
                                  const ProgressCallback& progress = nullptr);

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
