// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/refinement.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <sstream>
#include <unordered_map>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"

namespace gcpstereo::optimize {
namespace {

constexpr double kPriorSmoothing = 0.1;  // label steps; |d| ≈ √(d² + κ²) − κ in Ψ̃

// r = √(dw·a)·(x − m): ½r² is the local quadratic model of data_weight·Φ.
class QuadraticData final : public ceres::SizedCostFunction<1, 1> {
 public:
  QuadraticData(double sqrt_curvature, double minimum)
      : sqrt_curvature_(sqrt_curvature), minimum_(minimum) {}
  bool Evaluate(double const* const* x, double* residual, double** jacobians) const override {
    residual[0] = sqrt_curvature_ * (x[0][0] - minimum_);
    if (jacobians && jacobians[0]) jacobians[0][0] = sqrt_curvature_;
    return true;
  }

 private:
  double sqrt_curvature_, minimum_;
};

// r = x_p − x_q (the loss function carries λs·w_pq and the Huber shape).
class Difference final : public ceres::SizedCostFunction<1, 1, 1> {
 public:
  bool Evaluate(double const* const* x, double* residual, double** jacobians) const override {
    residual[0] = x[0][0] - x[1][0];
    if (jacobians) {
      if (jacobians[0]) jacobians[0][0] = 1.0;
      if (jacobians[1]) jacobians[1][0] = -1.0;
    }
    return true;
  }
};

// The GCP term λr·Ψ̃(d) of a pixel as a function of d = x − D̂, with Ψ̃ eq. (7) with |d| smoothed as
// u = √(d² + κ²) − κ. As a residual r = sign(d)·√(2 λr Ψ̃(d)), so that ½r² = λr Ψ̃(d) and r is
// smooth at d = 0.
struct GcpTerm {
  double lambda_r, gamma_d, eta;
  // `weight` = ω_p of eq. (9): the term of one pixel is λr·ω_p·Ψ̃.
  explicit GcpTerm(const EnergyOptions& options, double weight = 1.0)
      : lambda_r(options.lambda_r * weight), gamma_d(options.gamma_d), eta(options.eta) {}
  // λr·Ψ̃(d).
  double Penalty(double d) const {
    const double u = std::sqrt(d * d + kPriorSmoothing * kPriorSmoothing) - kPriorSmoothing;
    return lambda_r * std::max(-std::log((1.0 - eta) * std::exp(-u / gamma_d) + eta), 0.0);
  }
  // Ψ̃ is a concave function of d², so λr·Ψ̃(d) <= const + ½·ω·d² with equality at d (the
  // half-quadratic majoriser): ω = λr·Ψ'(u)/√(d² + κ²), Ψ'(u) = e/(γd·(e + η)).
  double MajorizerWeight(double d) const {
    const double root = std::sqrt(d * d + kPriorSmoothing * kPriorSmoothing);
    const double e = (1.0 - eta) * std::exp(-(root - kPriorSmoothing) / gamma_d);
    return lambda_r * e / (gamma_d * (e + eta)) / root;
  }
  // The residual r at d and (when jacobian != nullptr) dr/dd = λr·Ψ̃'(d)/r.
  void Evaluate(double d, double* residual, double* jacobian) const {
    if (std::abs(d) < 1e-9) {
      const double slope = std::sqrt(lambda_r * (1.0 - eta) / (gamma_d * kPriorSmoothing));
      *residual = slope * d;
      if (jacobian) *jacobian = slope;
      return;
    }
    const double r = std::copysign(std::sqrt(2.0 * Penalty(d)), d);
    *residual = r;
    // λr·Ψ̃'(d) = ω·d with the majoriser's weight ω.
    if (jacobian) *jacobian = r != 0.0 ? MajorizerWeight(d) * d / r : 0.0;
  }
};

// A pixel with a prior: the QuadraticData residual and the GcpTerm residual in one block (one
// residual block fewer per prior pixel for Ceres to carry; the objective is the same sum).
class QuadraticDataAndGcp final : public ceres::SizedCostFunction<2, 1> {
 public:
  QuadraticDataAndGcp(double sqrt_curvature, double minimum, double prior, double prior_weight,
                      const EnergyOptions& options)
      : sqrt_curvature_(sqrt_curvature),
        minimum_(minimum),
        prior_(prior),
        gcp_(options, prior_weight) {}
  bool Evaluate(double const* const* x, double* residual, double** jacobians) const override {
    double* jacobian = jacobians ? jacobians[0] : nullptr;
    residual[0] = sqrt_curvature_ * (x[0][0] - minimum_);
    if (jacobian) jacobian[0] = sqrt_curvature_;
    gcp_.Evaluate(x[0][0] - prior_, &residual[1], jacobian ? &jacobian[1] : nullptr);
    return true;
  }

 private:
  double sqrt_curvature_, minimum_, prior_;
  GcpTerm gcp_;
};

// Parabola offset in [−0.5, 0.5] and its curvature; false when not convex / at the label range end.
bool ParabolaFit(const CostVolume& costs, int row, int col, int label, double* offset,
                 double* curvature, double* slope) {
  if (label <= 0 || label + 1 >= costs.num_labels()) return false;
  const double cm = costs.Cost(row, col, label - 1), c0 = costs.Cost(row, col, label),
               cp = costs.Cost(row, col, label + 1);
  *curvature = cm - 2.0 * c0 + cp;
  *slope = 0.5 * (cp - cm);
  if (!(*curvature > 0.0)) return false;
  *offset = std::clamp(-*slope / *curvature, -0.5, 0.5);
  return true;
}

// The continuous problem of kCeres/kIrls in plain arrays, one unknown per pixel (row-major).
struct GridProblem {
  std::vector<double> sqrt_curvature;  // √(data_weight·a_p)
  std::vector<double> minimum;         // m_p
  std::vector<double> lower, upper;    // the box [l_p − 1, l_p + 1] ∩ [0, L − 1]
  std::vector<double> prior;           // D̂_p, NaN = none (or the prior is not used)
  std::vector<double> prior_weight;    // ω_p of eq. (9) where the prior is finite
  struct Pair {
    int p, q;
    double weight;  // λs·w_pq
  };
  std::vector<Pair> pairs;  // 4-neighbour pairs with |l_p − l_q| < T and a positive weight
};

GridProblem MakeGridProblem(const MrfProblem& problem, const cv::Mat& labels,
                            const EnergyOptions& energy_options, const RefinementOptions& options) {
  const int w = problem.width(), h = problem.height(), num_labels = problem.num_labels();
  const std::size_t n = static_cast<std::size_t>(w) * h;
  GridProblem g;
  g.sqrt_curvature.resize(n);
  g.minimum.resize(n);
  g.lower.resize(n);
  g.upper.resize(n);
  g.prior.assign(n, std::numeric_limits<double>::quiet_NaN());
  g.prior_weight.assign(n, 1.0);
  g.pairs.reserve(2 * n);
  const bool use_prior = problem.UsesPrior(energy_options) && energy_options.lambda_r > 0.0;
  for (int row = 0; row < h; ++row) {
    const int* label_row = labels.ptr<int>(row);
    const cv::Vec3b* image_row = problem.image.ptr<cv::Vec3b>(row);
    for (int col = 0; col < w; ++col) {
      const int p = row * w + col;
      const int l = label_row[col];
      double offset = 0.0, curvature = 0.0, slope = 0.0;
      double minimum = l;
      if (l > 0 && l + 1 < num_labels) {
        ParabolaFit(*problem.data, row, col, l, &offset, &curvature, &slope);
        curvature = std::max(curvature, options.min_data_curvature);
        minimum = l - slope / curvature;
      } else {
        curvature = options.min_data_curvature;
      }
      g.sqrt_curvature[p] = std::sqrt(energy_options.data_weight * curvature);
      g.minimum[p] = minimum;
      g.lower[p] = std::max(0, l - 1);
      g.upper[p] = std::min(num_labels - 1, l + 1);
      if (use_prior) {
        const float prior = problem.prior.ptr<float>(row)[col];
        const double weight = problem.PriorWeight(row, col);
        // ω_p = 0: no term at all (the weighted term would be 0 with a 0/0 Jacobian).
        if (std::isfinite(prior) && weight > 0.0) {
          g.prior[p] = prior;
          g.prior_weight[p] = weight;
        }
      }
      auto add_pair = [&](int q, int lq, const cv::Vec3b& cq) {
        if (std::abs(l - lq) >= energy_options.truncation) return;
        const double weight =
            energy_options.lambda_s * PairWeight(image_row[col], cq, energy_options);
        if (weight > 0.0) g.pairs.push_back({p, q, weight});
      };
      if (col + 1 < w) add_pair(p + 1, label_row[col + 1], image_row[col + 1]);
      if (row + 1 < h) {
        add_pair(p + w, labels.ptr<int>(row + 1)[col], problem.image.ptr<cv::Vec3b>(row + 1)[col]);
      }
    }
  }
  return g;
}

void SolveWithCeres(const GridProblem& grid, const EnergyOptions& energy_options,
                    const RefinementOptions& options, const Timer& timer, std::vector<double>* x,
                    RefinementSummary* s) {
  // Cost functions outlive the problem (declared first), in deques (one allocation per chunk,
  // stable addresses); the shared Difference is added many times, so the problem must not own
  // them.
  std::deque<QuadraticData> data_terms;
  std::deque<QuadraticDataAndGcp> data_gcp_terms;
  Difference difference;
  std::unordered_map<double, std::unique_ptr<ceres::LossFunction>> pair_losses;
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  // Losses are shared too: w_pq takes few distinct values (max(exp(−c/γc), ε) with c the
  // distance of two 8-bit colours is the floor ε for all but the closest colours), so one
  // ScaledLoss per distinct weight instead of two allocations per pair.
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  // Every block below is built from the labelling's own pixels (valid pointers, one parameter
  // each, no duplicate): Ceres's per-call checks of that cost time for a million blocks.
  problem_options.disable_all_safety_checks = true;
  ceres::Problem ceres_problem(problem_options);
  for (std::size_t p = 0; p < x->size(); ++p) {
    double* xp = &(*x)[p];
    if (std::isfinite(grid.prior[p])) {
      ceres_problem.AddResidualBlock(
          &data_gcp_terms.emplace_back(grid.sqrt_curvature[p], grid.minimum[p], grid.prior[p],
                                       grid.prior_weight[p], energy_options),
          nullptr, xp);
    } else {
      ceres_problem.AddResidualBlock(
          &data_terms.emplace_back(grid.sqrt_curvature[p], grid.minimum[p]), nullptr, xp);
    }
    ceres_problem.SetParameterLowerBound(xp, 0, grid.lower[p]);
    ceres_problem.SetParameterUpperBound(xp, 0, grid.upper[p]);
  }
  // ½·scale·huber(r²) ≈ weight·|r| for |r| >> δ: scale = weight / δ.
  const double delta = options.smoothness_huber;
  for (const GridProblem::Pair& pair : grid.pairs) {
    std::unique_ptr<ceres::LossFunction>& loss = pair_losses[pair.weight];
    if (!loss) {
      loss = std::make_unique<ceres::ScaledLoss>(new ceres::HuberLoss(delta), pair.weight / delta,
                                                 ceres::TAKE_OWNERSHIP);
    }
    ceres_problem.AddResidualBlock(&difference, loss.get(), &(*x)[pair.p], &(*x)[pair.q]);
  }
  ceres::Solver::Options solver_options;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = options.num_threads;
  // Conjugate gradients on the normal equations with a Jacobi preconditioner, not a sparse
  // Cholesky factorisation: the problem is a 2D grid (one unknown per pixel, 4-neighbour pairs)
  // whose normal matrix is diagonally dominant where the data or the prior is curved, so CG
  // converges in few steps, and the factor's fill-in (the nested-dissection separators of a grid)
  // costs time and memory. Measured (safety checks off in both) on fountain-P11 view 0005
  // (configs/fountain_p11.yaml, four 776x520 tiles): the same final Ceres cost to 6 digits in
  // every tile (1.40090e8, 1.18869e8, 2.79608e8, 1.81789e8), 4.0–5.5 s per tile instead
  // of 6.5–10.1 s, peak memory of the run 2602 → 2428 MB; KITTI frame 10
  // (kitti_lidar.yaml): 4.0–4.5 s per tile instead of 5.3–5.4 s, peak 1244 → 1058 MB, held-out
  // bad-3 unchanged (2.08 %).
  solver_options.linear_solver_type = ceres::CGNR;
  solver_options.preconditioner_type = ceres::JACOBI;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary ceres_summary;
  s->build_seconds = timer.ElapsedSeconds();
  ceres::Solve(solver_options, &ceres_problem, &ceres_summary);
  s->solve_seconds = timer.ElapsedSeconds() - s->build_seconds;
  s->initial_cost = ceres_summary.initial_cost;
  s->final_cost = ceres_summary.final_cost;
  s->iterations = static_cast<int>(ceres_summary.iterations.size());
  s->solver_converged = ceres_summary.termination_type == ceres::CONVERGENCE;
  s->solver_message = ceres_summary.BriefReport();
}

// The objective ½Σ‖residual‖² (with the pair losses) that Ceres reports as its cost.
double GridObjective(const GridProblem& grid, const EnergyOptions& energy_options, double delta,
                     const std::vector<double>& x) {
  const GcpTerm gcp(energy_options);
  double total = 0.0;
  for (std::size_t p = 0; p < x.size(); ++p) {
    const double r = grid.sqrt_curvature[p] * (x[p] - grid.minimum[p]);
    total += 0.5 * r * r;
    if (std::isfinite(grid.prior[p])) {
      total += grid.prior_weight[p] * gcp.Penalty(x[p] - grid.prior[p]);
    }
  }
  for (const GridProblem::Pair& pair : grid.pairs) {
    const double r = std::abs(x[pair.p] - x[pair.q]);
    // Ceres: ½·(weight/δ)·ρ(r²), ρ(s) = s for s <= δ², 2δ√s − δ² above.
    total += r <= delta ? 0.5 * pair.weight / delta * r * r : pair.weight * (r - 0.5 * delta);
  }
  return total;
}

void SolveWithIrls(const GridProblem& grid, const EnergyOptions& energy_options,
                   const RefinementOptions& options, const Timer& timer, std::vector<double>* x,
                   RefinementSummary* s) {
  const int n = static_cast<int>(x->size());
  const double delta = options.smoothness_huber;
  const GcpTerm gcp(energy_options);
  // Fixed sparsity (diagonal + both halves of every pair), values refilled at each step.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(n) + 2 * grid.pairs.size());
  for (int p = 0; p < n; ++p) triplets.emplace_back(p, p, 1.0);
  for (const GridProblem::Pair& pair : grid.pairs) {
    triplets.emplace_back(pair.p, pair.q, -1.0);
    triplets.emplace_back(pair.q, pair.p, -1.0);
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> matrix(n, n);
  matrix.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};
  matrix.makeCompressed();
  // Where each pair's two off-diagonal entries and every diagonal entry sit in the value array.
  std::vector<int> diagonal(n);
  std::vector<std::pair<int, int>> off_diagonal(grid.pairs.size());
  {
    const int* outer = matrix.outerIndexPtr();
    const int* inner = matrix.innerIndexPtr();
    auto find = [&](int row, int col) {
      return static_cast<int>(std::lower_bound(inner + outer[row], inner + outer[row + 1], col) -
                              inner);
    };
    for (int p = 0; p < n; ++p) diagonal[p] = find(p, p);
    for (std::size_t i = 0; i < grid.pairs.size(); ++i) {
      off_diagonal[i] = {find(grid.pairs[i].p, grid.pairs[i].q),
                         find(grid.pairs[i].q, grid.pairs[i].p)};
    }
  }
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double, Eigen::RowMajor>,
                           Eigen::Lower | Eigen::Upper>
      cg;
  // Relative residual of each step's system. Measured on KITTI frame 10 (two tiles) and the
  // synthetic fountain's view 0005 (four): 1e-6 takes 565–626 CG iterations per KITTI tile, 1e-5
  // 58–377 with the final objective within 3e-7 of 1e-6's (and of Ceres's), 1e-4 10–44 but
  // 4e-6 above it; the accuracy of all three is the same to 0.15 points (within-3σ 86.82–86.95 %,
  // KITTI bad-3 identical), so the objective decides: 1e-5.
  cg.setTolerance(1e-5);
  cg.setMaxIterations(500);
  Eigen::VectorXd rhs(n), solution(n);
  std::vector<double> candidate(n);
  for (int p = 0; p < n; ++p) (*x)[p] = std::clamp((*x)[p], grid.lower[p], grid.upper[p]);
  double cost = GridObjective(grid, energy_options, delta, *x);
  s->initial_cost = cost;
  s->build_seconds = timer.ElapsedSeconds();
  s->solver_converged = false;
  double* values = matrix.valuePtr();
  for (int step = 0; step < options.max_iterations; ++step) {
    // The majorising quadratics at x: data a_p, prior and pair weights from the current residuals.
    for (int p = 0; p < n; ++p) {
      const double a = grid.sqrt_curvature[p] * grid.sqrt_curvature[p];
      double diag = a, b = a * grid.minimum[p];
      if (std::isfinite(grid.prior[p])) {
        const double weight = grid.prior_weight[p] * gcp.MajorizerWeight((*x)[p] - grid.prior[p]);
        diag += weight;
        b += weight * grid.prior[p];
      }
      values[diagonal[p]] = diag;
      rhs[p] = b;
    }
    for (std::size_t i = 0; i < grid.pairs.size(); ++i) {
      const GridProblem::Pair& pair = grid.pairs[i];
      const double r = std::abs((*x)[pair.p] - (*x)[pair.q]);
      const double weight = pair.weight / std::max(delta, r);
      values[diagonal[pair.p]] += weight;
      values[diagonal[pair.q]] += weight;
      values[off_diagonal[i].first] = -weight;
      values[off_diagonal[i].second] = -weight;
    }
    cg.compute(matrix);
    solution = cg.solveWithGuess(rhs, Eigen::Map<const Eigen::VectorXd>(x->data(), n));
    s->linear_iterations += cg.iterations();
    for (int p = 0; p < n; ++p) {
      candidate[p] = std::clamp(solution[p], grid.lower[p], grid.upper[p]);
    }
    const double candidate_cost = GridObjective(grid, energy_options, delta, candidate);
    s->iterations = step + 1;
    if (!(candidate_cost < cost)) {  // the clipped step did not help: x is (near) a fixed point
      s->solver_converged = true;
      break;
    }
    const double decrease = cost - candidate_cost;
    x->swap(candidate);
    cost = candidate_cost;
    if (decrease <= 1e-6 * cost) {
      s->solver_converged = true;
      break;
    }
  }
  s->final_cost = cost;
  s->solve_seconds = timer.ElapsedSeconds() - s->build_seconds;
  std::ostringstream message;
  message.precision(7);
  message << "IRLS: " << s->iterations << " steps, " << s->linear_iterations
          << " CG iterations, cost " << s->initial_cost << " -> " << s->final_cost
          << (s->solver_converged ? " (converged)" : " (step limit)");
  s->solver_message = message.str();
}

}  // namespace

const char* RefinementMethodName(RefinementMethod method) {
  switch (method) {
    case RefinementMethod::kNone:
      return "none";
    case RefinementMethod::kParabola:
      return "parabola";
    case RefinementMethod::kCeres:
      return "ceres";
    case RefinementMethod::kIrls:
      return "irls";
  }
  return "?";
}

RefinementMethod ParseRefinementMethod(const std::string& name) {
  if (name == "none") return RefinementMethod::kNone;
  if (name == "parabola") return RefinementMethod::kParabola;
  if (name == "ceres") return RefinementMethod::kCeres;
  if (name == "irls") return RefinementMethod::kIrls;
  throw ConfigError(ViolatedConstraint("optimizer.refinement", name,
                                       "one of \"none\", \"parabola\", \"ceres\", \"irls\""));
}

void RefinementOptions::Check() const {
  if (max_iterations < 1) {
    throw ConfigError(ViolatedConstraint("optimizer.refinement_iterations",
                                         std::to_string(max_iterations), ">= 1"));
  }
  if (!(smoothness_huber > 0.0) || !std::isfinite(smoothness_huber)) {
    throw ConfigError(
        ViolatedConstraint("optimizer.refinement_huber", FormatNumber(smoothness_huber), "> 0"));
  }
  if (!(min_data_curvature > 0.0) || !std::isfinite(min_data_curvature)) {
    throw ConfigError(ViolatedConstraint("optimizer.refinement_min_curvature",
                                         FormatNumber(min_data_curvature), "> 0"));
  }
  if (num_threads < 1) {
    throw ConfigError(
        ViolatedConstraint("optimizer.refinement_threads", std::to_string(num_threads), ">= 1"));
  }
}

cv::Mat RefineSubLabel(const MrfProblem& problem, const cv::Mat& labels,
                       const EnergyOptions& energy_options, const RefinementOptions& options,
                       RefinementSummary* summary) {
  const Timer timer;
  problem.Validate();
  energy_options.Check();
  options.Check();
  const int w = problem.width(), h = problem.height(), num_labels = problem.num_labels();
  if (labels.type() != CV_32S || labels.cols != w || labels.rows != h) {
    throw Error("RefineSubLabel: the labelling must be CV_32S of the problem's size " +
                std::to_string(w) + "x" + std::to_string(h));
  }
  const CostVolume& costs = *problem.data;
  RefinementSummary s;
  s.method = options.method;
  s.pixels = w * h;

  // Parabola solution (the result of kParabola and the start of kCeres).
  std::vector<double> x(static_cast<std::size_t>(w) * h);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const int l = labels.ptr<int>(row)[col];
      if (l < 0 || l >= num_labels) {
        throw Error("RefineSubLabel: label " + std::to_string(l) + " at (" + std::to_string(col) +
                    ", " + std::to_string(row) + ") outside [0, " + std::to_string(num_labels) +
                    ")");
      }
      double offset = 0.0, curvature = 0.0, slope = 0.0;
      if (options.method != RefinementMethod::kNone &&
          ParabolaFit(costs, row, col, l, &offset, &curvature, &slope)) {
        x[row * w + col] = l + offset;
      } else {
        x[row * w + col] = l;
      }
    }
  }

  if (options.method == RefinementMethod::kCeres || options.method == RefinementMethod::kIrls) {
    const GridProblem grid = MakeGridProblem(problem, labels, energy_options, options);
    if (options.method == RefinementMethod::kCeres) {
      SolveWithCeres(grid, energy_options, options, timer, &x, &s);
    } else {
      SolveWithIrls(grid, energy_options, options, timer, &x, &s);
    }
  }

  cv::Mat out(h, w, CV_32F);
  double offset_sum = 0.0;
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const double value = x[row * w + col];
      const double offset = value - labels.ptr<int>(row)[col];
      offset_sum += std::abs(offset);
      if (std::abs(offset) > 1e-3) ++s.pixels_moved;
      out.ptr<float>(row)[col] = static_cast<float>(value);
    }
  }
  s.mean_abs_offset = s.pixels > 0 ? offset_sum / s.pixels : 0.0;
  s.time_seconds = timer.ElapsedSeconds();
  if (summary) *summary = s;
  return out;
}

}  // namespace gcpstereo::optimize
