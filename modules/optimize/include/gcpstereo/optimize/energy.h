// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/cost_volume.h"

namespace gcpstereo::optimize {

// The MRF energy of Wang & Yang, "Global Stereo Matching Leveraged by Sparse Ground Control
// Points", CVPR 2011, eqs. (1)–(4), (7), (8):
//
//   E(D)     = E_data(D) + E_smooth(D) + E_gcp(D)                                          (1)
//   E_data   = data_weight · Σ_p Φ(p, D_p)                                                  (2)
//   E_smooth = λs · Σ_{{p,q} ∈ N4} w_pq · min(|D_p − D_q|, T)                               (3)
//   w_pq     = max(exp(−c_pq / γc), ε),  c_pq = Euclidean distance of p's and q's RGB       (4)
//   E_gcp    = λr · Σ_{p with a prior} ω_p · Ψ(D_p, D̂_p)                                    (8')
//   Ψ(x, y)  = −ln((1 − η) · exp(−|x − y| / γd) + η)                                        (7)
//   ω_p      = (1 − β · c_p) · ρ'_p  (our extension; β = 0, τ = 0: ω_p = 1, eq. 8)          (9)
//   ρ'_p     = ρ_p, or 1 − c_p · (1 − ρ_p) when gated;  ρ_p = 1 / (1 + σ_p² / τ²)            (10)
//
// Units. D_p is a label INDEX (0 … L−1, integer for the discrete solution, fractional after
// sub-label refinement), so |D_p − D_q|, T and γd are in LABEL STEPS for every label space. For
// disparity labels with a step of 1 px this is the paper's disparity unit; for depth labels one
// step is (labels.max − labels.min)/(labels.count − 1) metres (inverse-depth labels: that many
// 1/metres), so T = 2 means "two depth levels", not two metres. Φ is read from the CostVolume in
// its own unit; entries marked CostVolume::kNoData count as max_cost (the worst matching cost: no
// neighbour saw the pixel at that label, so the label is not supported by the images).
// D̂_p (the propagated GCP disparities of Sec. 3.1, "prior") is a continuous label; NaN = none.
//
// Deliberate deviations / interpretations:
//  * Eq. (3) literally sums over p and q ∈ N4(p), i.e. counts every pair twice. We count every
//    unordered 4-neighbour pair once, so the paper's λs read literally is our 2·λs.
//  * `data_weight` makes the scale of Φ relative to λs explicit (default 1: the costs as the cost
//    module produces them — BT summed over RGB, the plane sweep's truncated RGB norm).
//  * η is not legible in the available text of the paper; default 0.1 (Ψ <= −ln η = 2.30).
//  * Eq. (9), a deliberate extension: the paper's λr is one number for every pixel, so the prior
//    pulls as hard where the images have already decided as where they cannot. ω_p lowers it by
//    the pixel's data confidence c_p ∈ [0, 1] (cost::PeakRatioConfidence of the pixel's cost
//    curve: 0 for a flat curve or two equal minima, near 1 for one sharp minimum), by the factor
//    β (`gcp_confidence`). MrfProblem::prior_weight carries ω_p; OptimizeTiled fills it from the
//    tile's costs and the caller's ρ_p (PriorWeights).
//  * Eq. (10), a deliberate extension: D̂_p is only as good as the GCPs around p agree. σ_p is
//    their spread about one plane, label steps: σ_p² = Σ w_q e_q² / Σ w_q · n / (n − 3), e_q the
//    residuals of the weighted least-squares plane v = c + a·dx + b·dy through the GCPs q within
//    3σw of p, w_q = exp(−‖q − p‖² / (2σw²) − ‖I_q − I_p‖² / (2σc²)) (σw =
//    `gcp_spread_sigma_px`, σc = `gcp_spread_sigma_colour`, RGB; σc = 0: no colour term),
//    n = (Σw)² / Σw² the window's effective number of GCPs. The colour
//    term keeps to the pixel's surface as D̂ does, so a depth edge that D̂ follows along a colour
//    edge does not count; GCPs of one colour that disagree — a wrong match among right ones, a
//    depth edge with no colour edge under it — do, and ρ_p lowers the prior's weight by the factor
//    τ (`gcp_spread`, label steps, the spread at which ρ_p = 1/2). Where n ≤ 3 the window cannot
//    judge a plane and ρ_p = 1: too few GCPs, or a pixel next to one GCP of a sparse set (one
//    per 16 px, σw 8: within about 5 px of it), whose weight dominates the window — there D̂
//    is that GCP's own value. (Judging such pixels by the other GCPs instead, with the
//    leverage-corrected Σ w e² / Σ w (1 − h), was measured worse: README, Benchmarks.)
//    Gated (`gcp_spread_gated`), the spread lowers the weight only as far as the pixel's own data
//    are decisive (c_p of eq. 9): where the images cannot decide, a doubtful prior is still the
//    best information there is.
// The defaults are the paper's printed numbers. They are not the best everywhere, and the best
// weights depend on how reliable the GCPs are (tools/benchmark.py; bad-1 nonocc / KITTI held-out
// bad-3):
//  * Middlebury two-view with stereo GCPs (noisy, 0.4–17 % outliers): λs = 40 (the paper's 20 under
//    its double sum), λr = 4, η = 0.5 give tsukuba 1.48 % / venus 0.73 % against 5.13 / 5.69 %
//    with the defaults; configs/middlebury_stereo.yaml sets them.
//  * KITTI with LiDAR GCPs (accurate): those Middlebury weights raise bad-3 on frames 0 / 10 from
//    13.35 / 24.82 % (defaults) to 40.98 / 55.70 %, so they are not the defaults.
struct EnergyOptions {
  // λs, smoothness weight of eq. (3), energy per label step. Range: >= 0.
  double lambda_s = 20.0;
  // T, truncation of the linear smoothness penalty, label steps. Range: > 0.
  double truncation = 2.0;
  // γc, colour bandwidth of eq. (4), in 8-bit RGB units. Range: > 0.
  double gamma_c = 3.6;
  // ε, lower bound of w_pq in eq. (4), dimensionless. Range: [0, 1].
  double epsilon = 0.3;
  // λr, weight of the GCP energy of eq. (8). Range: >= 0.
  double lambda_r = 8.0;
  // γd, sharpness of Ψ in eq. (7), label steps. Range: > 0.
  double gamma_d = 2.0;
  // η, upper-bound control of Ψ in eq. (7) (Ψ <= −ln η), dimensionless. Range: (0, 1).
  double eta = 0.1;
  // Scale applied to every Φ(p, l) read from the cost volume, dimensionless. Range: > 0.
  double data_weight = 1.0;
  // β of eq. (9): how far a pixel's data confidence lowers its GCP weight, ω_p = 1 − β·c_p.
  // 0 = the paper (ω_p = 1); 1 = no prior where one label is certain. Range: [0, 1].
  double gcp_confidence = 0.0;
  // The window radius over which c_p averages the costs before the peak ratio, px (0 = the
  // pixel's own curve). Range: [0, cost::kMaxConfidenceRadius]. Default 2: a 5×5 window.
  int gcp_confidence_radius = 2;
  // τ of eq. (10), label steps: the GCPs' spread about a plane at which their prior's weight
  // halves. 0 = the paper (ρ_p = 1). Range: >= 0.
  double gcp_spread = 0.0;
  // σw of eq. (10), px: the Gaussian window of the spread (it reaches 3σw). Range: [1, 50].
  double gcp_spread_sigma_px = 8.0;
  // σc of eq. (10), RGB grey levels: the colour bandwidth of the spread's weights; 0 (the
  // default) = spatial weights only. Range: >= 0.
  double gcp_spread_sigma_colour = 0.0;
  // Eq. (10) gated by the data confidence c_p of eq. (9) (over gcp_confidence_radius):
  // ρ'_p = 1 − c_p·(1 − ρ_p) instead of ρ_p. Only with gcp_spread > 0. Default true: ungated,
  // the factor lowered the prior where the images are wrong too (KITTI, measured in the README).
  bool gcp_spread_gated = true;
  // false = the paper's baseline D (E_data + E_smooth only); the prior is then ignored.
  bool use_gcp_energy = true;

  // Throws ConfigError naming the YAML key (optimizer.lambda_s, optimizer.truncation,
  // optimizer.gamma_c, optimizer.epsilon, optimizer.lambda_r, optimizer.gamma_d, optimizer.eta,
  // optimizer.data_weight, optimizer.gcp_confidence,
  // optimizer.gcp_confidence_radius, optimizer.gcp_spread, optimizer.gcp_spread_sigma_px,
  // optimizer.gcp_spread_sigma_colour).
  void Check() const;
};

// One MRF instance over a rectangular region of the reference image. Does not own the costs.
struct MrfProblem {
  const CostVolume* data = nullptr;  // Φ(p, l) for the region; required
  cv::Mat image;  // CV_8UC3 (BGR) of the SAME region as `data`, for w_pq; required
  cv::Mat prior;  // CV_32F region-sized continuous label D̂_p, NaN = no prior; may be empty
  // CV_32F region-sized ω_p of eq. (9), in [0, 1]; empty = 1 everywhere (the paper).
  cv::Mat prior_weight;

  int width() const { return data ? data->width() : 0; }
  int height() const { return data ? data->height() : 0; }
  int num_labels() const { return data ? data->num_labels() : 0; }
  // Throws Error when the cost volume is missing or the image/prior/prior weights do not match
  // its region.
  void Validate() const;
  // Whether E_gcp takes part: the GCP energy is on and the problem has a prior. Every consumer
  // (the energy, the candidate labels, the start labelling, the refinement) asks this one question.
  bool UsesPrior(const EnergyOptions& options) const {
    return options.use_gcp_energy && !prior.empty();
  }
  // ω_p at a pixel (1 without prior weights).
  double PriorWeight(int row, int col) const {
    return prior_weight.empty() ? 1.0 : static_cast<double>(prior_weight.ptr<float>(row)[col]);
  }
};

// An MRF problem that owns its costs and images (what a tile's `make_problem` returns).
struct OwnedMrfProblem {
  CostVolume data;
  cv::Mat image;         // CV_8UC3, region-sized
  cv::Mat prior;         // CV_32F, region-sized or empty
  cv::Mat prior_weight;  // CV_32F, region-sized or empty
  // The share of the data term's (pixel, label) entries computed: below 1 when only the labels
  // the solver can read were (CandidateLabelBands).
  double data_computed_share = 1.0;
  MrfProblem View() const { return MrfProblem{&data, image, prior, prior_weight}; }
};

struct EnergyBreakdown {
  double data = 0.0;         // E_data (already multiplied by data_weight)
  double smooth = 0.0;       // E_smooth (with λs)
  double gcp = 0.0;          // E_gcp (with λr)
  int num_prior_pixels = 0;  // pixels with a finite prior (0 when use_gcp_energy is false)
  double total() const { return data + smooth + gcp; }
};

// w_pq of eq. (4) for two BGR colours (without λs).
double PairWeight(const cv::Vec3b& color_p, const cv::Vec3b& color_q, const EnergyOptions& options);
// Ψ(x, y) of eq. (7) (without λr); x, y in label steps.
double GcpPenalty(double label, double prior_label, const EnergyOptions& options);

// Whether PriorWeights reads the data term for these spread factors (the data confidence c_p:
// gcp_confidence > 0, or the spread gated by it); otherwise it returns `spread_weights` as given.
bool PriorWeightsReadData(const cv::Mat& spread_weights, const EnergyOptions& options);
// ω_p of eq. (9) for one problem's costs (CV_32F, region-sized), from the spread factors ρ_p of
// eq. (10) for the same region (CV_32F, or empty for none): (1 − β·c_p)·ρ'_p, c_p
// cost::PeakRatioConfidence over gcp_confidence_radius. Returns `spread_weights` itself when no
// data confidence is asked for (β = 0 and not gated), so an empty Mat for the paper.
cv::Mat PriorWeights(const CostVolume& data, const cv::Mat& spread_weights,
                     const EnergyOptions& options);

// ρ_p of eq. (10) over a whole image from its GCPs (`gcp_labels`: CV_32F, a finite entry is a
// GCP's label, NaN elsewhere) and the image (CV_8UC3 BGR of the same size; may be empty when
// gcp_spread_sigma_colour is 0); CV_32F of the same size in (0, 1]. An empty Mat when τ = 0 (the
// paper: ρ_p = 1). Throws Error for inputs of the wrong type or size.
cv::Mat SpreadPriorWeights(const cv::Mat& gcp_labels, const cv::Mat& image_bgr,
                           const EnergyOptions& options);
// The spread σ_p of eq. (10) itself, label steps (CV_32F; NaN where it cannot judge a plane).
cv::Mat GcpPlaneSpread(const cv::Mat& gcp_labels, const cv::Mat& image_bgr, double sigma_px,
                       double sigma_colour);

// The energy (1) of an integer labelling (CV_32S, region-sized, values in [0, L)), computed
// directly from the definitions above with double sums; independent of the graph-cut code.
// Throws Error for a labelling of the wrong size/type or with labels out of range.
double ComputeEnergy(const MrfProblem& problem, const cv::Mat& labels, const EnergyOptions& options,
                     EnergyBreakdown* breakdown = nullptr);

// Winner-take-all labels for initialising and voting (CV_32S): cost::WinnerTakeAll (argmin_l
// Φ(p, l), ties to the lowest label), with label 0 where no label has data, so that every pixel
// holds a valid label.
cv::Mat WinnerTakeAll(const CostVolume& data);

}  // namespace gcpstereo::optimize
