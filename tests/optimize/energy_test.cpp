// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/energy.h"

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/core.hpp>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "test_problems.h"

namespace gcpstereo::optimize {
namespace {

TEST(EnergyOptions, DefaultsAreThePapers) {
  const EnergyOptions options;
  EXPECT_EQ(options.lambda_s, 20.0);
  EXPECT_EQ(options.truncation, 2.0);
  EXPECT_EQ(options.gamma_c, 3.6);
  EXPECT_EQ(options.epsilon, 0.3);
  EXPECT_EQ(options.lambda_r, 8.0);
  EXPECT_EQ(options.gamma_d, 2.0);
  EXPECT_EQ(options.eta, 0.1);
  EXPECT_NO_THROW(options.Check());
}

// The message of the ConfigError that options.Check() throws ("" when it throws none).
std::string CheckMessage(const EnergyOptions& options) {
  try {
    options.Check();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(EnergyOptions, CheckNamesTheKey) {
  EnergyOptions options;
  options.eta = 0.0;
  EXPECT_EQ(CheckMessage(options), "optimizer.eta = 0. Violated constraint: in (0, 1)");
  options = EnergyOptions();
  options.truncation = -1.0;
  EXPECT_EQ(CheckMessage(options), "optimizer.truncation = -1. Violated constraint: > 0");
  options = EnergyOptions();
  options.gcp_confidence = 1.5;
  EXPECT_EQ(CheckMessage(options),
            "optimizer.gcp_confidence = 1.5. Violated constraint: in [0, 1]");
  options = EnergyOptions();
  options.gcp_confidence_radius = 11;
  EXPECT_EQ(CheckMessage(options),
            "optimizer.gcp_confidence_radius = 11. Violated constraint: in [0, 10]");
  options = EnergyOptions();
  options.gcp_spread = -1.0;
  EXPECT_EQ(CheckMessage(options), "optimizer.gcp_spread = -1. Violated constraint: >= 0");
  options = EnergyOptions();
  options.gcp_spread_sigma_px = 0.5;
  EXPECT_EQ(CheckMessage(options),
            "optimizer.gcp_spread_sigma_px = 0.5. Violated constraint: in [1, 50]");
  options = EnergyOptions();
  options.gcp_spread_sigma_colour = -2.0;
  EXPECT_EQ(CheckMessage(options),
            "optimizer.gcp_spread_sigma_colour = -2. Violated constraint: >= 0");
}

TEST(Energy, HandComputedTwoPixels) {
  // 2x1 pixels, 4 labels.
  OwnedMrfProblem owned{CostVolume(cv::Rect(0, 0, 2, 1), 4, 100.0f), cv::Mat(1, 2, CV_8UC3),
                        cv::Mat(1, 2, CV_32F, cv::Scalar(std::nanf("")))};
  for (int l = 0; l < 4; ++l) {
    owned.data.SetCost(0, 0, l, 10.0f * l);
    owned.data.SetCost(0, 1, l, 40.0f - 10.0f * l);
  }
  owned.data.SetNoData(0, 1, 0);  // reads as max_cost = 100
  owned.image.at<cv::Vec3b>(0, 0) = cv::Vec3b(0, 0, 0);
  owned.image.at<cv::Vec3b>(0, 1) = cv::Vec3b(3, 4, 0);  // c_pq = 5
  owned.prior.at<float>(0, 1) = 2.5f;
  EnergyOptions options;  // the hand computation below uses the paper's printed weights
  options.lambda_s = 20.0;
  options.lambda_r = 8.0;
  options.eta = 0.1;
  const MrfProblem problem = owned.View();
  const cv::Mat labels = (cv::Mat_<int>(1, 2) << 1, 0);
  EnergyBreakdown e;
  const double total = ComputeEnergy(problem, labels, options, &e);
  const double step = 100.0 / 65534.0;
  EXPECT_NEAR(e.data, std::round(10.0 / step) * step + 100.0, 1e-3);
  const double w = std::max(std::exp(-5.0 / 3.6), 0.3);
  EXPECT_DOUBLE_EQ(e.smooth, 20.0 * w * 1.0);
  const double psi = -std::log((1 - options.eta) * std::exp(-2.5 / 2.0) + options.eta);
  EXPECT_DOUBLE_EQ(e.gcp, 8.0 * psi);
  EXPECT_EQ(e.num_prior_pixels, 1);
  EXPECT_DOUBLE_EQ(total, e.data + e.smooth + e.gcp);

  // Truncation at T = 2 and the GCP switch.
  const cv::Mat far_labels = (cv::Mat_<int>(1, 2) << 3, 0);
  options.use_gcp_energy = false;
  ComputeEnergy(problem, far_labels, options, &e);
  EXPECT_DOUBLE_EQ(e.smooth, 20.0 * w * 2.0);
  EXPECT_EQ(e.gcp, 0.0);
}

// Eq. (9): ω_p scales the GCP term of its pixel alone; without spread factors PriorWeights is
// 1 − β·c_p.
TEST(Energy, PriorWeightsScaleTheGcpTermOfTheirPixel) {
  OwnedMrfProblem owned{CostVolume(cv::Rect(0, 0, 2, 1), 3, 100.0f), cv::Mat(1, 2, CV_8UC3),
                        cv::Mat(1, 2, CV_32F, cv::Scalar(1.0f))};
  owned.image.setTo(cv::Scalar(7, 7, 7));
  const float costs[2][3] = {{0, 50, 100}, {40, 40, 40}};  // decisive | flat
  for (int c = 0; c < 2; ++c) {
    for (int l = 0; l < 3; ++l) owned.data.SetCost(0, c, l, costs[c][l]);
  }
  EnergyOptions options;
  const cv::Mat labels = (cv::Mat_<int>(1, 2) << 0, 2);
  const double psi0 = GcpPenalty(0, 1.0, options), psi2 = GcpPenalty(2, 1.0, options);
  EnergyBreakdown plain, weighted;
  ComputeEnergy(owned.View(), labels, options, &plain);
  EXPECT_DOUBLE_EQ(plain.gcp, options.lambda_r * (psi0 + psi2));

  EXPECT_TRUE(PriorWeights(owned.data, cv::Mat(), options).empty());  // β = 0: the paper
  options.gcp_confidence = 0.5;
  options.gcp_confidence_radius = 0;  // each pixel's own curve (the default window mixes the two)
  owned.prior_weight = PriorWeights(owned.data, cv::Mat(), options);
  ASSERT_EQ(owned.prior_weight.type(), CV_32F);
  // The peak ratio (cost::PeakRatioConfidence): c = 1 − (0 + 1)/(100 + 1) for the decisive
  // curve (no second minimum: Φ2 = its highest cost; ε = 1 % of max_cost), 0 for the flat one.
  EXPECT_NEAR(owned.prior_weight.at<float>(0, 0), 1.0 - 0.5 * (1.0 - 1.0 / 101.0), 1e-6);
  EXPECT_FLOAT_EQ(owned.prior_weight.at<float>(0, 1), 1.0f);
  ComputeEnergy(owned.View(), labels, options, &weighted);
  EXPECT_NEAR(weighted.gcp, options.lambda_r * (owned.prior_weight.at<float>(0, 0) * psi0 + psi2),
              1e-12);
  EXPECT_EQ(weighted.data, plain.data);
  EXPECT_EQ(weighted.smooth, plain.smooth);

  owned.prior_weight = cv::Mat(1, 3, CV_32F, cv::Scalar(1.0f));
  EXPECT_THROW(owned.View().Validate(), Error);

  // With spread factors ρ_p of eq. (10): ρ_p itself, ρ_p·(1 − β·c_p), and gated
  // 1 − c_p·(1 − ρ_p) (the flat pixel keeps its full weight), times (1 − β·c_p).
  const double c0 = 1.0 - 1.0 / 101.0;
  const cv::Mat spread(1, 2, CV_32F, cv::Scalar(0.4f));
  options.gcp_spread_gated = false;
  options.gcp_confidence = 0.0;
  const cv::Mat same = PriorWeights(owned.data, spread, options);
  EXPECT_EQ(same.data, spread.data);
  options.gcp_confidence = 0.5;
  cv::Mat w = PriorWeights(owned.data, spread, options);
  EXPECT_NEAR(w.at<float>(0, 0), 0.4 * (1.0 - 0.5 * c0), 1e-6);
  EXPECT_NEAR(w.at<float>(0, 1), 0.4, 1e-6);
  options.gcp_spread_gated = true;
  options.gcp_confidence = 0.0;
  w = PriorWeights(owned.data, spread, options);
  EXPECT_NEAR(w.at<float>(0, 0), 1.0 - c0 * 0.6, 1e-6);
  EXPECT_FLOAT_EQ(w.at<float>(0, 1), 1.0f);
  options.gcp_confidence = 0.5;
  w = PriorWeights(owned.data, spread, options);
  EXPECT_NEAR(w.at<float>(0, 0), (1.0 - c0 * 0.6) * (1.0 - 0.5 * c0), 1e-6);
  EXPECT_FLOAT_EQ(w.at<float>(0, 1), 1.0f);
}

// σ_p of eq. (10) at one pixel straight from its definition: the weighted least-squares plane
// (slopes ridged as in GcpPlaneSpread) through the GCPs within 3σw, its weighted RMS residual
// times n/(n − 3); NaN for n <= 3. Colour weights when sigma_colour > 0.
double SpreadByDefinition(const cv::Mat& gcps, const cv::Mat& image, int row, int col, double sigma,
                          double sigma_colour) {
  const int radius = static_cast<int>(std::ceil(3.0 * sigma));
  struct Sample {
    double dx, dy, v, w;
  };
  std::vector<Sample> samples;
  for (int r = 0; r < gcps.rows; ++r) {
    for (int c = 0; c < gcps.cols; ++c) {
      const double v = gcps.at<float>(r, c);
      const int d2 = (r - row) * (r - row) + (c - col) * (c - col);
      if (!std::isfinite(v) || d2 > radius * radius) continue;
      double w = std::exp(-d2 / (2.0 * sigma * sigma));
      if (sigma_colour > 0.0) {
        const cv::Vec3d diff =
            cv::Vec3d(image.at<cv::Vec3b>(r, c)) - cv::Vec3d(image.at<cv::Vec3b>(row, col));
        w *= std::exp(-diff.dot(diff) / (2.0 * sigma_colour * sigma_colour));
      }
      samples.push_back({static_cast<double>(c - col), static_cast<double>(r - row), v, w});
    }
  }
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double sw = 0.0, sw2 = 0.0;
  for (const Sample& q : samples) {
    const Eigen::Vector3d x(q.dx, q.dy, 1.0);
    normal += q.w * x * x.transpose();
    rhs += q.w * q.v * x;
    sw += q.w;
    sw2 += q.w * q.w;
  }
  const double n = sw * sw / sw2;
  if (!(n > 3.0)) return std::nan("");
  const double ridge = 1e-6 * radius * radius * sw;
  normal(0, 0) += ridge;
  normal(1, 1) += ridge;
  const Eigen::Vector3d plane = normal.inverse() * rhs;
  double rss = 0.0;
  for (const Sample& q : samples) {
    const double e = q.v - plane.dot(Eigen::Vector3d(q.dx, q.dy, 1.0));
    rss += q.w * e * e;
  }
  return std::sqrt(rss / sw * n / (n - 3.0));
}

// Eq. (10): GCPs on one slanted plane have no spread (ρ = 1). A depth step between them spreads
// the pixels near it when the weights are spatial only, not when the step lies on a colour edge
// (D̂ follows it there); a wrong GCP among right ones of one colour spreads its neighbourhood.
// Each value equals the definition computed directly.
TEST(Energy, GcpSpreadFollowsTheDefinition) {
  const double sigma = 3.0, sigma_colour = 10.0;
  cv::Mat image(60, 80, CV_8UC3, cv::Scalar(40, 90, 140));
  image.colRange(40, image.cols).setTo(cv::Scalar(120, 60, 30));  // a colour edge at column 40
  cv::Mat gcps(60, 80, CV_32F, cv::Scalar(std::nanf("")));
  for (int r = 1; r < gcps.rows; r += 4) {
    for (int c = 2; c < gcps.cols; c += 4) {
      gcps.at<float>(r, c) = static_cast<float>(10.0 + 0.3 * c - 0.2 * r);
    }
  }
  const cv::Mat plane_spread = GcpPlaneSpread(gcps, cv::Mat(), sigma, 0.0);
  ASSERT_EQ(plane_spread.type(), CV_32F);
  for (int r = 0; r < gcps.rows; r += 7) {
    for (int c = 0; c < gcps.cols; c += 5) {
      // Finite wherever the window holds more than 3 effective GCPs: inside, not in every corner.
      const float s = plane_spread.at<float>(r, c);
      EXPECT_EQ(std::isfinite(s), std::isfinite(SpreadByDefinition(gcps, image, r, c, sigma, 0.0)));
      if (r >= 5 && c >= 5) {
        EXPECT_NEAR(s, 0.0, 1e-3) << r << ", " << c;
      }
    }
  }
  // The right half 20 labels farther: a depth step at column 40, on the colour edge.
  cv::Mat step = gcps.clone();
  step.colRange(40, step.cols) += 20.0;
  // One wrong GCP (+6 labels) in the left half.
  step.at<float>(29, 18) += 6.0f;
  const cv::Mat spatial = GcpPlaneSpread(step, cv::Mat(), sigma, 0.0);
  const cv::Mat coloured = GcpPlaneSpread(step, image, sigma, sigma_colour);
  for (int r = 3; r < gcps.rows - 3; r += 11) {  // 3 … 47: a bottom-corner window is too thin
    for (int c : {0, 13, 18, 31, 38, 40, 41, 47, 52, 79}) {
      for (const auto& [spread, sc] :
           {std::pair{spatial, 0.0}, std::pair{coloured, sigma_colour}}) {
        const double expected = SpreadByDefinition(step, image, r, c, sigma, sc);
        const float s = spread.at<float>(r, c);
        ASSERT_EQ(std::isfinite(s), std::isfinite(expected)) << r << ", " << c;
        if (std::isfinite(expected)) {
          EXPECT_NEAR(s, expected, 1e-4 * (1.0 + expected));
        }
      }
    }
    EXPECT_GT(spatial.at<float>(r, 39), 3.0);         // next to the step
    EXPECT_LT(coloured.at<float>(r, 39), 1e-3) << r;  // …which is on a colour edge
    EXPECT_LT(spatial.at<float>(r, 60), 1e-3);        // 3σw away from it
  }
  EXPECT_GT(coloured.at<float>(29, 19), 0.5);  // next to the wrong GCP
  EXPECT_LT(coloured.at<float>(3, 19), 1e-3);  // 3σw away from it

  EnergyOptions options;
  EXPECT_TRUE(SpreadPriorWeights(step, image, options).empty());  // τ = 0: the paper
  options.gcp_spread = 2.0;
  options.gcp_spread_sigma_px = sigma;
  options.gcp_spread_sigma_colour = 0.0;
  const cv::Mat weights = SpreadPriorWeights(step, cv::Mat(), options);
  ASSERT_EQ(weights.type(), CV_32F);
  const float s = spatial.at<float>(25, 39);
  EXPECT_NEAR(weights.at<float>(25, 39), 1.0 / (1.0 + s * s / 4.0), 1e-6);
  EXPECT_GT(weights.at<float>(25, 60), 0.999f);
  EXPECT_LT(weights.at<float>(25, 39), 0.2f);
  options.gcp_spread_sigma_colour = sigma_colour;
  EXPECT_GT(SpreadPriorWeights(step, image, options).at<float>(25, 39), 0.999f);
  EXPECT_THROW(SpreadPriorWeights(step, cv::Mat(), options), Error);  // colour needs the image
}

// Noise about a plane: σ_p estimates the GCPs' own standard deviation; a window of too few GCPs,
// or a pixel next to one GCP of a sparse set, has no spread and keeps the paper's weight.
TEST(Energy, GcpSpreadOfNoisyGcpsIsTheirNoise) {
  cv::Mat gcps(64, 64, CV_32F, cv::Scalar(std::nanf("")));
  cv::RNG rng(20111);
  for (int r = 0; r < gcps.rows; r += 2) {
    for (int c = 0; c < gcps.cols; c += 2) {
      gcps.at<float>(r, c) = static_cast<float>(50.0 + 0.1 * c + rng.gaussian(0.5));
    }
  }
  const cv::Mat spread = GcpPlaneSpread(gcps, cv::Mat(), 4.0, 0.0);
  std::vector<float> inner;
  for (int r = 16; r < 48; ++r) {
    for (int c = 16; c < 48; ++c) inner.push_back(spread.at<float>(r, c));
  }
  std::nth_element(inner.begin(), inner.begin() + inner.size() / 2, inner.end());
  EXPECT_NEAR(inner[inner.size() / 2], 0.5, 0.05);

  // GCPs one per 16 px, σw 8: next to a GCP its weight dominates the window (n ≤ 3) and D̂ is
  // its own value, so no spread; between GCPs the spread estimates their noise.
  cv::Mat lattice(176, 176, CV_32F, cv::Scalar(std::nanf("")));
  for (int r = 8; r < lattice.rows; r += 16) {
    for (int c = 8; c < lattice.cols; c += 16) {
      lattice.at<float>(r, c) = static_cast<float>(20.0 - 0.05 * r + rng.gaussian(0.5));
    }
  }
  const cv::Mat lattice_spread = GcpPlaneSpread(lattice, cv::Mat(), 8.0, 0.0);
  double between_sum = 0.0;
  int between_count = 0;
  for (int r = 40; r < 136; r += 16) {
    for (int c = 40; c < 136; c += 16) {
      EXPECT_TRUE(std::isnan(lattice_spread.at<float>(r, c))) << r << ", " << c;
      EXPECT_TRUE(std::isnan(lattice_spread.at<float>(r + 2, c + 2))) << r << ", " << c;
      const double between = lattice_spread.at<float>(r + 8, c + 8);
      ASSERT_TRUE(std::isfinite(between)) << r << ", " << c;
      between_sum += between * between;
      ++between_count;
    }
  }
  EXPECT_NEAR(std::sqrt(between_sum / between_count), 0.5, 0.15);

  cv::Mat two(32, 32, CV_32F, cv::Scalar(std::nanf("")));
  two.at<float>(10, 10) = 1.0f;
  two.at<float>(10, 12) = 9.0f;
  EXPECT_TRUE(std::isnan(GcpPlaneSpread(two, cv::Mat(), 4.0, 0.0).at<float>(10, 11)));
  EnergyOptions options;
  options.gcp_spread = 1.0;
  options.gcp_spread_sigma_colour = 0.0;
  EXPECT_EQ(SpreadPriorWeights(two, cv::Mat(), options).at<float>(10, 11), 1.0f);
  EXPECT_THROW(GcpPlaneSpread(cv::Mat(4, 4, CV_64F, cv::Scalar(0.0)), cv::Mat(), 4.0, 0.0), Error);
}

TEST(Energy, GcpPenaltyIsBoundedByMinusLogEta) {
  EnergyOptions options;
  EXPECT_DOUBLE_EQ(GcpPenalty(3.0, 3.0, options), 0.0);
  EXPECT_LT(GcpPenalty(1000.0, 0.0, options), -std::log(options.eta) + 1e-12);
  EXPECT_GT(GcpPenalty(1000.0, 0.0, options), -std::log(options.eta) - 1e-6);
  EXPECT_LT(GcpPenalty(1.0, 0.0, options), GcpPenalty(2.0, 0.0, options));
}

TEST(Energy, RejectsMismatchedInputs) {
  OwnedMrfProblem owned = testing::RandomProblem(4, 3, 3, 1);
  const MrfProblem problem = owned.View();
  try {
    ComputeEnergy(problem, cv::Mat(3, 5, CV_32S, cv::Scalar(0)), EnergyOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "ComputeEnergy: the labelling (5x3) must be CV_32S of the problem's size 4x3");
  }
  try {
    ComputeEnergy(problem, cv::Mat(3, 4, CV_32S, cv::Scalar(3)), EnergyOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "ComputeEnergy: label 3 at (0, 0) outside [0, 3)");
  }
  owned.image = cv::Mat(2, 2, CV_8UC3);
  try {
    ComputeEnergy(owned.View(), cv::Mat(3, 4, CV_32S, cv::Scalar(0)), EnergyOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "MRF problem: the image (2x2) must be CV_8UC3 of the cost volume's region 4x3");
  }
}

TEST(Energy, WinnerTakeAllPicksTheCheapestLabel) {
  const OwnedMrfProblem owned = testing::RandomProblem(5, 4, 7, 3);
  const cv::Mat wta = WinnerTakeAll(owned.data);
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 5; ++col) {
      for (int l = 0; l < 7; ++l) {
        EXPECT_LE(owned.data.Cost(row, col, wta.at<int>(row, col)), owned.data.Cost(row, col, l));
      }
    }
  }
}

}  // namespace
}  // namespace gcpstereo::optimize
