// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include <opencv2/core/mat.hpp>

namespace gcpstereo::propagation {

// Options of the adaptive propagation (paper §3.1, eq. 5). YAML keys propagation.*.
struct PropagationOptions {
  // How D̂ is computed from the GCPs. Key propagation.method.
  //   "linear_system": the paper's eq. 5 (Propagate below), a smooth interpolation: every pixel
  //     is the affinity-weighted mean of its neighbours, so where a depth edge has no colour edge
  //     under it, or the GCPs' edge is a few pixels off the image's, D̂ blends the two sides.
  //   "weighted_median": each pixel takes the weighted median of the GCPs within median_radius_px
  //     (PropagateByWeightedMedian). Not in the paper. A median never invents a value between two
  //     surfaces, so thin foreground and depth edges measured by dense GCPs (a LiDAR scan) stay
  //     where the GCPs put them; pixels without a GCP in their window get no prior. Measured on
  //     the KITTI frames in configs/kitti_lidar.yaml.
  //   "local_plane": each pixel takes the value at its own position of a robust plane fitted to
  //     the GCPs within plane_radius_px (PropagateByLocalPlanes). Not in the paper. Where the GCPs
  //     are sparse (a laser downsampled by 16: one per 16 × 16 px), a slanted surface between them
  //     is a plane, not the membrane of eq. 5 (which flattens between GCPs and bends towards each);
  //     the caller passes a quantity that is affine over a scene plane (disparity, inverse depth).
  //     Pixels without a GCP within the radius get no prior.
  std::string method = "linear_system";
  // weighted_median: window half-size, spatial and colour bandwidths of the weights
  // w = exp(−d² / (2 σs²) − ‖I_p − I_q‖² / (2 σc²)), d in px, I in RGB grey levels (0…255).
  // Valid: radius in [1, 100], both sigmas > 0. Keys propagation.median_radius_px,
  // propagation.median_sigma_px, propagation.median_sigma_colour.
  int median_radius_px = 10;
  double median_sigma_px = 4.0;
  double median_sigma_colour = 20.0;
  // weighted_median: the share of its spatial weight a GCP keeps however different its colour,
  // w = exp(−d² / (2 σs²)) · (φ + (1 − φ) · exp(−‖I_p − I_q‖² / (2 σc²))). With φ = 0 (the
  // default, the weights above) one GCP of similar colour outweighs many nearer ones of another
  // colour; where a scan's depth edges lie a few pixels off the image's (KITTI: poles, roof
  // edges), the colour then picks the wrong side. φ = 1: spatial weights only. Valid: [0, 1].
  // Key propagation.median_colour_floor.
  double median_colour_floor = 0.0;
  // weighted_median: k ≥ 1, how many times the distance across the local depth edge counts in the
  // squared distance of the spatial weight: d² = along² + k·across², the direction from the
  // weighted least-squares plane through the window's GCPs (see PropagateByWeightedMedian). A
  // pixel then follows the GCPs along the edge — a pole's column above and below it, a roof's
  // scan line beside it — rather than the nearest GCP across it. 1 (the default): isotropic.
  // Valid: [1, 100]. Key propagation.median_edge_stretch.
  double median_edge_stretch = 1.0;
  // local_plane: radius of the round window of GCPs, spatial and colour bandwidths of the weights
  // w = exp(−d² / (2 σs²) − ‖I_p − I_q‖² / (2 σc²)) (d in px, I in RGB grey levels). Defaults
  // measured on the synthetic fountain (laser GCPs at s = 16; configs/synthetic_fountain.yaml).
  // Valid: radius in [1, 100], both sigmas > 0. Keys propagation.plane_radius_px,
  // propagation.plane_sigma_px, propagation.plane_sigma_colour.
  int plane_radius_px = 24;
  double plane_sigma_px = 8.0;
  double plane_sigma_colour = 10.0;
  // γ of eq. 5 (the colour bandwidth of w_pq = max(exp(−‖I_p − I_q‖₂ / γ), ε)), in RGB grey levels
  // (0…255 per channel). Paper: 1.25 (its colour unit is not stated); in 8-bit units that makes
  // the affinities nearly binary. Default 4, measured (tools/benchmark.py --suite table2, D̂ from
  // stereo GCPs, bad-1 nonocc): tsukuba 10.7 → 6.5 %, venus 10.1 → 7.45 % for γ = 1.25 → 4
  // (γ = 10 or 25 worse; Aloe slightly worse at 4). Valid: > 0. Key propagation.gamma.
  double gamma = 4.0;
  // ε of eq. 5, the lower bound of w_pq. Paper: 0 ("edge-preserving interpolation"). Valid: [0, 1).
  // Key propagation.epsilon.
  double epsilon = 0.0;
  // Affinities below this value (after the ε floor) are treated as exactly 0, i.e. no link.
  // Not in the paper: with ε = 0, w = exp(−‖ΔRGB‖/1.25) reaches 1e-150 across strong edges, and a
  // region tied to the rest only by such links makes the system numerically singular (its values
  // would be rounding noise). Cutting them turns the region into an honest "unreached" region.
  // Dropping a link of weight < 1e-8 moves a solution by at most ~1e-8 relative. Valid: [0, 1e-3].
  // Default 0 (no cut: the paper's system reaches every pixel): with γ = 4 no link underflows in
  // practice, and cutting at 1e-8 left thousands of small unreached islands (text strokes) with
  // no prior: 8.6 % of venus, 4.9 % of tsukuba at γ = 1.25. Key propagation.min_weight.
  double min_weight = 0.0;
  // Sparse direct solver: "umfpack" (LU of eq. 5 as written, as in the paper) or "cholmod"
  // (Cholesky of the equivalent symmetric positive definite form: every non-GCP row of eq. 5 times
  // Σ_q w_pq is a row of the weighted graph Laplacian, and the GCP unknowns are eliminated — the
  // same solution, see propagation.cc). Key propagation.solver. Default CHOLMOD: the two agree
  // to 1e-6 (tests), and on fountain-P11 at 1536×1024 (1.57 M unknowns) CHOLMOD solved in 9.0 s
  // against UMFPACK's 16.3 s, with 1.7 GB peak instead of 2.5 GB.
  std::string solver = "cholmod";
  // Fill-reducing elimination order: "nested_dissection" (geometric nested dissection of the pixel
  // grid, computed here in O(n)) or "amd" (the backend's own approximate minimum degree). Same
  // solution, different speed (see tools/benchmarks/propagation_benchmark.cpp). Not in the paper.
  // Key propagation.ordering.
  std::string ordering = "nested_dissection";

  // Throws ConfigError naming the YAML key, value and violated bound.
  void Check() const;
};

struct PropagationResult {
  cv::Mat values;    // CV_32F dense D̂; GCP pixels hold their value exactly; NaN where unreached
  cv::Mat reached;   // CV_8U, 255 where some GCP reaches the pixel through links w_pq > 0
  int num_gcps = 0;  // finite entries of sparse_values
  int num_unknowns = 0;           // size of the solved linear system
  int num_unreached_pixels = 0;   // pixels in connected regions that contain no GCP (NaN)
  int num_unreached_regions = 0;  // number of such regions (8-connected over links w_pq > 0)
  double setup_seconds = 0.0;     // weights, regions and matrix assembly
  double solve_seconds = 0.0;     // factorisation and solve
  double residual = 0.0;  // max_p |x_p − Σ_q α_pq x_q| over solved non-GCP pixels (eq. 5)
  std::string solver;     // the backend that was used ("umfpack (fallback: …)" when CHOLMOD
                          // failed numerically and UMFPACK solved the system instead)
};

// Adaptive disparity propagation (Wang & Yang, CVPR 2011, §3.1, eq. 5).
//
// Minimises J(D̂) = Σ_p (D̂_p − Σ_{q∈N8(p)} α_pq D̂_q)² subject to D̂_p = G_p at the GCPs, with
//   w_pq = max(exp(−‖I_p − I_q‖₂ / γ), ε)   (γ = options.gamma, ε = options.epsilon),
//   α_pq = w_pq / Σ_{q'∈N8(p)} w_pq'         (normalised per row),
// by solving the sparse system A x = b of the paper: A_pp = 1; A_pq = −α_pq and b_p = 0 for a
// non-GCP p; identity row and b_p = G_p for a GCP.
//
// image_bgr: CV_8UC3 reference image (I; BGR order — the distance is the same as in RGB).
// sparse_values: CV_32F of the same size; a finite entry is a GCP value (whatever the caller
// propagates: disparities, continuous labels, depths); NaN (any non-finite) = no GCP.
//
// Deliberate deviations, all documented on the options: links w < min_weight are cut; pixels in
// 8-connected regions (over the remaining links) that contain no GCP are found by a traversal
// before solving, removed from the system (otherwise it is singular) and reported as NaN /
// num_unreached_*. Throws Error on bad inputs and when the solver fails.
//
// options.method = "weighted_median" dispatches to PropagateByWeightedMedian, "local_plane" to
// PropagateByLocalPlanes.
PropagationResult Propagate(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                            const PropagationOptions& options);

// D̂ as a joint-bilateral weighted median of the GCPs (options.method "weighted_median"): pixel p
// takes the value v of a GCP q within the (2r+1)² window (r = median_radius_px) at which the
// cumulative weight of the window's GCPs, sorted by value, first reaches half of their total,
// w_q = exp(−‖p − q‖² / (2 σs²)) · (φ + (1 − φ) · exp(−‖I_p − I_q‖² / (2 σc²))), φ =
// median_colour_floor; ties in value keep the raster order. With median_edge_stretch k > 1 the
// spatial factor becomes exp(−(a² + k·n²) / (2 σs²)), n and a the offset's components across and
// along the gradient of the least-squares plane through the window's GCPs weighted by the
// isotropic spatial factor (isotropic when those GCPs are collinear or their plane is flat).
// GCP pixels hold their own value. Pixels with no GCP in their window are NaN and counted as
// unreached (regions: 8-connected). Same inputs, outputs and errors as Propagate; `solver` is
// "weighted median", `num_unknowns` the number of pixels computed, residual 0.
PropagationResult PropagateByWeightedMedian(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                                            const PropagationOptions& options);

// D̂ from local planes (options.method "local_plane"): pixel p takes c of the plane
// v = c + a·dx + b·dy (dx, dy the offset from p) fitted to the GCPs q with ‖q − p‖ ≤ r
// (r = plane_radius_px), weighted by w_q = exp(−‖q − p‖² / (2 σs²) − ‖I_p − I_q‖² / (2 σc²))
// (spatial weights alone when every colour weight underflows), by iteratively reweighted least
// squares: two Huber reweightings with the threshold 1e-3 · the window's weighted mean |v|, so
// that a GCP on another surface pulls like an L1 residual, and a ridge of 1e-3 · Σw · r² on the
// slopes (a window of collinear GCPs gets a flat plane). GCP pixels hold their own value; pixels
// with no GCP within r are NaN and counted as unreached (regions: 8-connected). Same inputs,
// outputs and errors as Propagate; `solver` is "local planes", `num_unknowns` the number of
// non-GCP pixels, residual 0.
PropagationResult PropagateByLocalPlanes(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                                         const PropagationOptions& options);

}  // namespace gcpstereo::propagation
