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
//   E_gcp    = λr · Σ_{p with a prior} Ψ(D_p, D̂_p)                                          (8)
//   Ψ(x, y)  = −ln((1 − η) · exp(−|x − y| / γd) + η)                                        (7)
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
// Deliberate deviations / interpretations (defaults measured with tools/benchmark.py --suite
// table2 on tsukuba, venus and the six 2006 Middlebury sets, two-view BT costs, stereo GCPs,
// refinement off; bad-1 nonocc, mean over the 8 scenes / tsukuba / venus):
//  * Eq. (3) literally sums over p and q ∈ N4(p), i.e. counts every pair twice. We count every
//    unordered 4-neighbour pair once, so the paper's λs = 20 read literally is our λs = 40: the
//    default. (λs = 20 counted once: 19.58 / 5.13 / 5.69 %; λs = 40 with the changes below:
//    17.92 / 1.48 / 0.73 %.)
//  * `data_weight` makes the scale of Φ relative to λs explicit (default 1: the costs as the cost
//    module produces them — BT summed over RGB, the plane sweep's truncated RGB norm).
//  * λr: the printed λr = 8 (16 in our pair-once units) lets a wrong D̂ override correct data
//    (venus 5.50 % at λr = 8 vs 2.20 % at 2, with data_weight 0.5 ≡ λs doubled). Default λr = 4,
//    the measured best relative to the data term at data_weight 1.
//  * η is not legible in the available text of the paper. Default 0.5: Ψ <= −ln η = 0.69, so a
//    wrong prior costs at most λr·0.69 per pixel; with λr as above, η = 0.5 beat η = 0.1 on
//    tsukuba + venus (2.14 / 1.05 % vs 1.82 / 2.34 %). An earlier measurement with a crude prior
//    (ground truth spread over 16×16 blocks) preferred η = 0.1 on venus only.
struct EnergyOptions {
  // λs, smoothness weight of eq. (3), energy per label step. Range: >= 0.
  double lambda_s = 40.0;
  // T, truncation of the linear smoothness penalty, label steps. Range: > 0.
  double truncation = 2.0;
  // γc, colour bandwidth of eq. (4), in 8-bit RGB units. Range: > 0.
  double gamma_c = 3.6;
  // ε, lower bound of w_pq in eq. (4), dimensionless. Range: [0, 1].
  double epsilon = 0.3;
  // λr, weight of the GCP energy of eq. (8). Range: >= 0.
  double lambda_r = 4.0;
  // γd, sharpness of Ψ in eq. (7), label steps. Range: > 0.
  double gamma_d = 2.0;
  // η, upper-bound control of Ψ in eq. (7) (Ψ <= −ln η), dimensionless. Range: (0, 1).
  double eta = 0.5;
  // Scale applied to every Φ(p, l) read from the cost volume, dimensionless. Range: > 0.
  double data_weight = 1.0;
  // false = the paper's baseline D (E_data + E_smooth only); the prior is then ignored.
  bool use_gcp_energy = true;

  // Throws ConfigError naming the YAML key (optimizer.lambda_s, optimizer.truncation,
  // optimizer.gamma_c, optimizer.epsilon, optimizer.lambda_r, optimizer.gamma_d, optimizer.eta,
  // optimizer.data_weight).
  void Check() const;
};

// One MRF instance over a rectangular region of the reference image. Does not own the costs.
struct MrfProblem {
  const CostVolume* data = nullptr;  // Φ(p, l) for the region; required
  cv::Mat image;  // CV_8UC3 (BGR) of the SAME region as `data`, for w_pq; required
  cv::Mat prior;  // CV_32F region-sized continuous label D̂_p, NaN = no prior; may be empty

  int width() const { return data ? data->width() : 0; }
  int height() const { return data ? data->height() : 0; }
  int num_labels() const { return data ? data->num_labels() : 0; }
  // Throws Error when the cost volume is missing or the image/prior do not match its region.
  void Validate() const;
};

// An MRF problem that owns its costs and images (what a tile's `make_problem` returns).
struct OwnedMrfProblem {
  CostVolume data;
  cv::Mat image;  // CV_8UC3, region-sized
  cv::Mat prior;  // CV_32F, region-sized or empty
  MrfProblem View() const { return MrfProblem{&data, image, prior}; }
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
