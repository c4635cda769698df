// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/refinement.h"

#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/optimize/alpha_expansion.h"
#include "test_problems.h"

namespace gcpstereo::optimize {
namespace {

// A slanted plane whose true label is fractional everywhere; costs are a noisy, truncated
// V-shaped function of |l − truth| (BT-like), i.e. not the parabola the baseline assumes.
struct Plane {
  cv::Mat truth;
  OwnedMrfProblem problem;
};

Plane MakePlane(int width, int height, int num_labels, float noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  Plane plane{cv::Mat(height, width, CV_32F),
              {CostVolume(cv::Rect(0, 0, width, height), num_labels, 100.0f),
               cv::Mat(height, width, CV_8UC3), cv::Mat()}};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float t = 3.3f + 0.071f * x + 0.043f * y;
      plane.truth.at<float>(y, x) = t;
      const int v = std::clamp(static_cast<int>(120 + 20 * gauss(rng)), 0, 255);
      plane.problem.image.at<cv::Vec3b>(y, x) = cv::Vec3b(v, v, v);
      for (int l = 0; l < num_labels; ++l) {
        const float c = 10.0f * std::min(std::abs(l - t), 4.0f) + noise * std::abs(gauss(rng));
        plane.problem.data.SetCost(y, x, l, c);
      }
    }
  }
  return plane;
}

double MeanAbsError(const cv::Mat& labels, const cv::Mat& truth) {
  cv::Mat f;
  labels.convertTo(f, CV_32F);
  return cv::mean(cv::abs(f - truth))[0];
}

TEST(RefineSubLabel, ImprovesAFractionalPlane) {
  const Plane plane = MakePlane(48, 40, 12, 4.0f, 5);
  const MrfProblem problem = plane.problem.View();
  EnergyOptions energy;
  energy.use_gcp_energy = false;
  const ExpansionResult discrete = AlphaExpansion(problem, energy, ExpansionOptions());
  const double discrete_error = MeanAbsError(discrete.labels, plane.truth);

  RefinementOptions parabola_options;
  parabola_options.method = RefinementMethod::kParabola;
  RefinementSummary parabola_summary;
  const cv::Mat parabola =
      RefineSubLabel(problem, discrete.labels, energy, parabola_options, &parabola_summary);
  RefinementOptions ceres_options;
  RefinementSummary ceres_summary;
  const cv::Mat ceres =
      RefineSubLabel(problem, discrete.labels, energy, ceres_options, &ceres_summary);
  const double parabola_error = MeanAbsError(parabola, plane.truth);
  const double ceres_error = MeanAbsError(ceres, plane.truth);
  std::printf(
      "fractional plane, mean |label error|: discrete %.4f, parabola %.4f, ceres %.4f "
      "(%s)\n",
      discrete_error, parabola_error, ceres_error, ceres_summary.solver_message.c_str());
  EXPECT_LT(parabola_error, discrete_error);
  EXPECT_LT(ceres_error, discrete_error);
  EXPECT_GT(parabola_summary.pixels_moved, 0);
  EXPECT_GT(ceres_summary.iterations, 0);
  EXPECT_LE(ceres_summary.final_cost, ceres_summary.initial_cost);
  // Every refined label stays within one step of its discrete label.
  cv::Mat discrete_float;
  discrete.labels.convertTo(discrete_float, CV_32F);
  EXPECT_LE(cv::norm(ceres, discrete_float, cv::NORM_INF), 1.0 + 1e-6);
  EXPECT_LE(cv::norm(parabola, discrete_float, cv::NORM_INF), 0.5 + 1e-6);
}

TEST(RefineSubLabel, PriorPullsTowardsTheGcps) {
  Plane plane = MakePlane(24, 20, 12, 2.0f, 9);
  plane.problem.prior = plane.truth.clone();
  const MrfProblem problem = plane.problem.View();
  EnergyOptions energy;
  const ExpansionResult discrete = AlphaExpansion(problem, energy, ExpansionOptions());
  RefinementOptions options;
  const cv::Mat refined = RefineSubLabel(problem, discrete.labels, energy, options);
  EXPECT_LT(MeanAbsError(refined, plane.truth), MeanAbsError(discrete.labels, plane.truth));
}

// IRLS minimises the objective Ceres minimises: from the same start it must end at Ceres's cost
// or below (up to the tolerance both stop at), inside the same box, with and without a prior
// (the prior makes the problem non-convex: Ψ̃ flattens away from D̂).
TEST(RefineSubLabel, IrlsReachesTheCeresObjective) {
  for (const bool with_prior : {false, true}) {
    Plane plane = MakePlane(40, 32, 12, 4.0f, 11);
    if (with_prior) {
      // A prior on every third pixel, some of it wrong by two labels (outliers Ψ̃ must discount).
      plane.problem.prior = cv::Mat(32, 40, CV_32F, cv::Scalar(std::nanf("")));
      for (int y = 0; y < 32; ++y) {
        for (int x = (y % 3); x < 40; x += 3) {
          plane.problem.prior.at<float>(y, x) =
              plane.truth.at<float>(y, x) + ((x + y) % 7 == 0 ? 2.0f : 0.0f);
        }
      }
    }
    const MrfProblem problem = plane.problem.View();
    EnergyOptions energy;
    energy.use_gcp_energy = with_prior;
    const ExpansionResult discrete = AlphaExpansion(problem, energy, ExpansionOptions());
    RefinementOptions ceres_options;
    ceres_options.method = RefinementMethod::kCeres;
    RefinementOptions irls_options;
    irls_options.method = RefinementMethod::kIrls;
    RefinementSummary ceres_summary, irls_summary;
    const cv::Mat ceres =
        RefineSubLabel(problem, discrete.labels, energy, ceres_options, &ceres_summary);
    const cv::Mat irls =
        RefineSubLabel(problem, discrete.labels, energy, irls_options, &irls_summary);
    std::printf("prior %d: ceres %.6f -> %.6f (%d it), irls %.6f -> %.6f (%s)\n", with_prior,
                ceres_summary.initial_cost, ceres_summary.final_cost, ceres_summary.iterations,
                irls_summary.initial_cost, irls_summary.final_cost,
                irls_summary.solver_message.c_str());
    EXPECT_NEAR(irls_summary.initial_cost, ceres_summary.initial_cost,
                1e-9 * ceres_summary.initial_cost);
    EXPECT_LT(irls_summary.final_cost, irls_summary.initial_cost);
    EXPECT_LE(irls_summary.final_cost, ceres_summary.final_cost * (1.0 + 1e-5));
    EXPECT_TRUE(irls_summary.solver_converged);
    EXPECT_GT(irls_summary.linear_iterations, 0);
    cv::Mat discrete_float;
    discrete.labels.convertTo(discrete_float, CV_32F);
    EXPECT_LE(cv::norm(irls, discrete_float, cv::NORM_INF), 1.0 + 1e-6);
    EXPECT_LT(cv::norm(irls, ceres, cv::NORM_INF), 0.05);
    EXPECT_LT(MeanAbsError(irls, plane.truth), MeanAbsError(discrete.labels, plane.truth));
  }
}

TEST(RefineSubLabel, NoneKeepsTheLabelsAndOptionsAreChecked) {
  const Plane plane = MakePlane(10, 8, 12, 2.0f, 3);
  const cv::Mat labels(8, 10, CV_32S, cv::Scalar(4));
  RefinementOptions options;
  options.method = RefinementMethod::kNone;
  const cv::Mat out = RefineSubLabel(plane.problem.View(), labels, EnergyOptions(), options);
  EXPECT_EQ(cv::norm(out, cv::Mat(8, 10, CV_32F, cv::Scalar(4.0f)), cv::NORM_INF), 0.0);
  options.max_iterations = 0;
  try {
    RefineSubLabel(plane.problem.View(), labels, EnergyOptions(), options);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "optimizer.refinement_iterations = 0. Violated constraint: >= 1");
  }
  EXPECT_THROW(ParseRefinementMethod("cubic"), ConfigError);
  EXPECT_EQ(ParseRefinementMethod("irls"), RefinementMethod::kIrls);
  EXPECT_STREQ(RefinementMethodName(RefinementMethod::kIrls), "irls");
}

}  // namespace
}  // namespace gcpstereo::optimize
