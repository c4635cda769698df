// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/energy.h"

#include "gcpstereo/cost/winner_take_all.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "gcpstereo/core/error.h"

namespace gcpstereo::optimize {
namespace {

void Require(bool ok, const char* key, double value, const char* constraint) {
  if (!ok) throw ConfigError(ViolatedConstraint(key, FormatNumber(value), constraint));
}

std::string SizeString(const cv::Mat& m) {
  std::ostringstream s;
  s << m.cols << "x" << m.rows;
  return s.str();
}

}  // namespace

void EnergyOptions::Check() const {
  Require(std::isfinite(lambda_s) && lambda_s >= 0.0, "optimizer.lambda_s", lambda_s, ">= 0");
  Require(std::isfinite(truncation) && truncation > 0.0, "optimizer.truncation", truncation, "> 0");
  Require(std::isfinite(gamma_c) && gamma_c > 0.0, "optimizer.gamma_c", gamma_c, "> 0");
  Require(epsilon >= 0.0 && epsilon <= 1.0, "optimizer.epsilon", epsilon, "in [0, 1]");
  Require(std::isfinite(lambda_r) && lambda_r >= 0.0, "optimizer.lambda_r", lambda_r, ">= 0");
  Require(std::isfinite(gamma_d) && gamma_d > 0.0, "optimizer.gamma_d", gamma_d, "> 0");
  Require(eta > 0.0 && eta < 1.0, "optimizer.eta", eta, "in (0, 1)");
  Require(std::isfinite(data_weight) && data_weight > 0.0, "optimizer.data_weight", data_weight,
          "> 0");
  Require(gcp_confidence >= 0.0 && gcp_confidence <= 1.0, "optimizer.gcp_confidence",
          gcp_confidence, "in [0, 1]");
  Require(gcp_confidence_radius >= 0 && gcp_confidence_radius <= cost::kMaxConfidenceRadius,
          "optimizer.gcp_confidence_radius", gcp_confidence_radius, "in [0, 10]");
  static_assert(cost::kMaxConfidenceRadius == 10, "the message above names the bound");
}

void MrfProblem::Validate() const {
  if (data == nullptr || data->empty()) throw Error("MRF problem: the cost volume is missing");
  const std::string region = std::to_string(data->width()) + "x" + std::to_string(data->height());
  if (image.type() != CV_8UC3 || image.cols != data->width() || image.rows != data->height()) {
    throw Error("MRF problem: the image (" + SizeString(image) +
                ") must be CV_8UC3 of the cost volume's region " + region);
  }
  if (!prior.empty() &&
      (prior.type() != CV_32F || prior.cols != data->width() || prior.rows != data->height())) {
    throw Error("MRF problem: the prior (" + SizeString(prior) +
                ") must be empty or CV_32F of the cost volume's region " + region);
  }
  if (!prior_weight.empty() &&
      (prior_weight.type() != CV_32F || prior_weight.cols != data->width() ||
       prior_weight.rows != data->height())) {
    throw Error("MRF problem: the prior weights (" + SizeString(prior_weight) +
                ") must be empty or CV_32F of the cost volume's region " + region);
  }
}

double PairWeight(const cv::Vec3b& color_p, const cv::Vec3b& color_q,
                  const EnergyOptions& options) {
  double sq = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double d = static_cast<double>(color_p[c]) - static_cast<double>(color_q[c]);
    sq += d * d;
  }
  return std::max(std::exp(-std::sqrt(sq) / options.gamma_c), options.epsilon);
}

double GcpPenalty(double label, double prior_label, const EnergyOptions& options) {
  const double eta = options.eta;
  return -std::log((1.0 - eta) * std::exp(-std::abs(label - prior_label) / options.gamma_d) + eta);
}

cv::Mat ConfidencePriorWeights(const CostVolume& data, const EnergyOptions& options) {
  if (options.gcp_confidence <= 0.0) return {};
  cv::Mat weights = cost::PeakRatioConfidence(data, options.gcp_confidence_radius);
  weights.convertTo(weights, CV_32F, -options.gcp_confidence, 1.0);
  return weights;
}

double ComputeEnergy(const MrfProblem& problem, const cv::Mat& labels, const EnergyOptions& options,
                     EnergyBreakdown* breakdown) {
  problem.Validate();
  const int w = problem.width(), h = problem.height(), num_labels = problem.num_labels();
  if (labels.type() != CV_32S || labels.cols != w || labels.rows != h) {
    throw Error("ComputeEnergy: the labelling (" + SizeString(labels) +
                ") must be CV_32S of the problem's size " + std::to_string(w) + "x" +
                std::to_string(h));
  }
  const CostVolume& costs = *problem.data;
  const bool use_prior = options.use_gcp_energy && !problem.prior.empty();
  EnergyBreakdown e;
  for (int row = 0; row < h; ++row) {
    const int* label_row = labels.ptr<int>(row);
    const cv::Vec3b* color_row = problem.image.ptr<cv::Vec3b>(row);
    for (int col = 0; col < w; ++col) {
      const int l = label_row[col];
      if (l < 0 || l >= num_labels) {
        throw Error("ComputeEnergy: label " + std::to_string(l) + " at (" + std::to_string(col) +
                    ", " + std::to_string(row) + ") outside [0, " + std::to_string(num_labels) +
                    ")");
      }
      e.data += options.data_weight * static_cast<double>(costs.Cost(row, col, l));
      // Right and lower neighbours: every unordered 4-neighbour pair once.
      if (col + 1 < w) {
        const double d = std::min<double>(std::abs(l - label_row[col + 1]), options.truncation);
        e.smooth += options.lambda_s * PairWeight(color_row[col], color_row[col + 1], options) * d;
      }
      if (row + 1 < h) {
        const double d =
            std::min<double>(std::abs(l - labels.ptr<int>(row + 1)[col]), options.truncation);
        e.smooth +=
            options.lambda_s *
            PairWeight(color_row[col], problem.image.ptr<cv::Vec3b>(row + 1)[col], options) * d;
      }
      if (use_prior) {
        const float prior = problem.prior.ptr<float>(row)[col];
        if (std::isfinite(prior)) {
          e.gcp += options.lambda_r * problem.PriorWeight(row, col) * GcpPenalty(l, prior, options);
          ++e.num_prior_pixels;
        }
      }
    }
  }
  if (breakdown) *breakdown = e;
  return e.total();
}

cv::Mat WinnerTakeAll(const CostVolume& data) {
  cv::Mat labels = cost::WinnerTakeAll(data);
  labels.setTo(0, labels < 0);
  return labels;
}

}  // namespace gcpstereo::optimize
