// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/energy.h"

#include <cmath>
#include <string>

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

// Eq. (9): ω_p scales the GCP term of its pixel alone; ConfidencePriorWeights is 1 − β·c_p.
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

  EXPECT_TRUE(ConfidencePriorWeights(owned.data, options).empty());  // β = 0: the paper
  options.gcp_confidence = 0.5;
  options.gcp_confidence_radius = 0;  // each pixel's own curve (the default window mixes the two)
  owned.prior_weight = ConfidencePriorWeights(owned.data, options);
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
