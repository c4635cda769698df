// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/optimize/energy.h"

namespace gcpstereo::optimize {

// Sub-label refinement of a discrete labelling. 360 depth levels quantise depth more coarsely than
// a laser's sigma; this step moves every label l_p to a continuous x_p = l_p + δ_p.
enum class RefinementMethod {
  kNone,      // x_p = l_p
  kParabola,  // per pixel, the minimum of the parabola through Φ(p, l−1), Φ(p, l), Φ(p, l+1),
              // δ_p in [−0.5, 0.5] (data term only; no change where the parabola is not convex
              // or l is the first/last label)
  kCeres,     // a joint continuous problem solved with Ceres (see RefineSubLabel)
  kIrls,      // the same problem as kCeres, solved by iteratively reweighted least squares
              // (see RefineSubLabel)
};
const char* RefinementMethodName(RefinementMethod method);
// "none", "parabola", "ceres" or "irls"; throws ConfigError naming optimizer.refinement otherwise.
RefinementMethod ParseRefinementMethod(const std::string& name);

struct RefinementOptions {
  // YAML optimizer.refinement.
  RefinementMethod method = RefinementMethod::kIrls;
  // Ceres: maximum Levenberg–Marquardt iterations; IRLS: maximum reweighting steps.
  // YAML optimizer.refinement_iterations. Range: >= 1.
  int max_iterations = 50;
  // Ceres and IRLS: Huber width of the smoothness term, label steps: |x_p − x_q| below it is
  // penalised quadratically, above it linearly like eq. (3). YAML optimizer.refinement_huber.
  // Range: > 0.
  double smoothness_huber = 0.25;
  // Ceres and IRLS: smallest curvature of the local quadratic data model, in cost units per label
  // step² (keeps the problem well posed where Φ is flat or concave around l_p). YAML
  // optimizer.refinement_min_curvature. Range: > 0.
  double min_data_curvature = 1e-3;
  // Ceres threads. YAML optimizer.refinement_threads. Range: >= 1.
  int num_threads = 1;

  void Check() const;
};

struct RefinementSummary {
  RefinementMethod method = RefinementMethod::kNone;
  int pixels = 0;
  int pixels_moved = 0;          // |δ_p| > 1e-3
  double mean_abs_offset = 0.0;  // mean |δ_p|, label steps
  double initial_cost = 0.0;     // objective of kCeres/kIrls before / after (0 for the others)
  double final_cost = 0.0;
  int iterations = 0;
  bool solver_converged = true;     // Ceres reported CONVERGENCE / IRLS met its tolerance
  long long linear_iterations = 0;  // IRLS: conjugate-gradient iterations over all steps
  std::string solver_message;
  double time_seconds = 0.0;
  double build_seconds = 0.0;  // Ceres: building the problem (residual blocks, bounds)
  double solve_seconds = 0.0;  // Ceres: ceres::Solve
};

// Continuous labels (CV_32F) from a discrete labelling (CV_32S) of `problem`.
//
// kCeres minimises over x_p ∈ [l_p − 1, l_p + 1] ∩ [0, L − 1]
//   Σ_p data_weight · ½ a_p (x_p − m_p)²                       (quadratic fit of Φ around l_p:
//        a_p = max(Φ(l−1) − 2Φ(l) + Φ(l+1), min_data_curvature), m_p = l_p − (Φ(l+1) − Φ(l−1))/(2
//        a_p))
// + λs Σ_{p~q, |l_p − l_q| < T} w_pq · huber(x_p − x_q)      (eq. 3 without truncation: pairs the
//        discrete solution put across a discontinuity (|l_p − l_q| >= T) pay the constant λs·w·T
//        for any x in the box, so they are left out)
// + λr Σ_p Ψ̃(x_p, D̂_p)                                        (eq. 7 with |·| smoothed as
//        √(d² + 0.1²) − 0.1 so that it is differentiable)
// with Levenberg–Marquardt and bound constraints, starting from the parabola solution.
//
// kIrls minimises the same objective (the same summary costs, comparable with kCeres's) by
// half-quadratic majorisation, i.e. iteratively reweighted least squares (D. Geman, G. Reynolds,
// PAMI 1992; M. Nikolova, M. Ng, SIAM J. Sci. Comput. 2005): the Huber term and Ψ̃ are concave
// functions of their squared residual, so at the current x each lies below a quadratic that
// touches it there (pair weight λs·w_pq·min(1/δ, 1/|x_p − x_q|), prior weight
// λr·Ψ'(u)/√(d² + 0.1²)). A step minimises the sum of these quadratics and the data quadratics,
// a sparse symmetric positive definite 5-point system, with Eigen's conjugate gradients (Jacobi
// preconditioner, started from the current x), and clips it to the box; it is kept only if the
// objective falls, and the steps stop when it falls by less than 1e-6 of itself (Ceres's default
// function tolerance) or after max_iterations. One unknown per pixel in plain arrays: no
// per-residual objects, so time and memory are a fraction of kCeres's (measured in the
// refinement benchmark and on the KITTI frames; see the README's speed section).
cv::Mat RefineSubLabel(const MrfProblem& problem, const cv::Mat& labels,
                       const EnergyOptions& energy_options, const RefinementOptions& options,
                       RefinementSummary* summary = nullptr);

}  // namespace gcpstereo::optimize
