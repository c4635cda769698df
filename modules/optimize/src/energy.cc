// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/energy.h"

#include "gcpstereo/cost/winner_take_all.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/core.hpp>

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
  Require(std::isfinite(gcp_spread) && gcp_spread >= 0.0, "optimizer.gcp_spread", gcp_spread,
          ">= 0");
  Require(gcp_spread_sigma_px >= 1.0 && gcp_spread_sigma_px <= 50.0,
          "optimizer.gcp_spread_sigma_px", gcp_spread_sigma_px, "in [1, 50]");
  Require(std::isfinite(gcp_spread_sigma_colour) && gcp_spread_sigma_colour >= 0.0,
          "optimizer.gcp_spread_sigma_colour", gcp_spread_sigma_colour, ">= 0");
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

bool PriorWeightsReadData(const cv::Mat& spread_weights, const EnergyOptions& options) {
  return options.gcp_confidence > 0.0 || (options.gcp_spread_gated && !spread_weights.empty());
}

cv::Mat PriorWeights(const CostVolume& data, const cv::Mat& spread_weights,
                     const EnergyOptions& options) {
  if (!PriorWeightsReadData(spread_weights, options)) return spread_weights;
  const bool gated = options.gcp_spread_gated && !spread_weights.empty();
  const cv::Mat confidence = cost::PeakRatioConfidence(data, options.gcp_confidence_radius);
  cv::Mat weights;
  if (spread_weights.empty()) {
    weights = cv::Mat(confidence.size(), CV_32F, cv::Scalar(1.0f));
  } else if (gated) {
    weights = 1.0 - confidence.mul(1.0 - spread_weights);  // ρ'_p
  } else {
    weights = spread_weights.clone();
  }
  if (options.gcp_confidence > 0.0) {
    cv::Mat factor;
    confidence.convertTo(factor, CV_32F, -options.gcp_confidence, 1.0);
    weights = weights.mul(factor);
  }
  return weights;
}

cv::Mat GcpPlaneSpread(const cv::Mat& gcp_labels, const cv::Mat& image_bgr, double sigma_px,
                       double sigma_colour) {
  if (gcp_labels.type() != CV_32F) {
    throw Error("GcpPlaneSpread: the GCP labels (" + SizeString(gcp_labels) + ") must be CV_32F");
  }
  if (sigma_colour > 0.0 &&
      (image_bgr.type() != CV_8UC3 || image_bgr.size() != gcp_labels.size())) {
    throw Error("GcpPlaneSpread: the image (" + SizeString(image_bgr) +
                ") must be CV_8UC3 of the GCP map's size " + SizeString(gcp_labels));
  }
  const int width = gcp_labels.cols, height = gcp_labels.rows;
  const int radius = static_cast<int>(std::ceil(3.0 * sigma_px));
  const double inv_2ss = 1.0 / (2.0 * sigma_px * sigma_px);
  const double inv_2sc = sigma_colour > 0.0 ? 1.0 / (2.0 * sigma_colour * sigma_colour) : 0.0;
  // A ridge on the slopes only for windows whose GCPs are collinear (one scan line), where the
  // plane is free to turn about that line; small enough not to bias the residual of any other.
  const double ridge_scale = 1e-6 * radius * radius;
  // The GCP columns of every row: a window visits only its GCPs.
  std::vector<std::vector<int>> gcp_columns(height);
  for (int r = 0; r < height; ++r) {
    const float* row = gcp_labels.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      if (std::isfinite(row[c])) gcp_columns[r].push_back(c);
    }
  }
  cv::Mat spread(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    std::vector<std::array<double, 4>> samples;  // dx, dy, value, weight
    for (int r = rows.start; r < rows.end; ++r) {
      for (int c = 0; c < width; ++c) {
        samples.clear();
        const cv::Vec3b colour = inv_2sc > 0.0 ? image_bgr.at<cv::Vec3b>(r, c) : cv::Vec3b();
        for (int y = std::max(0, r - radius); y <= std::min(height - 1, r + radius); ++y) {
          const int dy = y - r;
          const std::vector<int>& columns = gcp_columns[y];
          const float* values = gcp_labels.ptr<float>(y);
          for (auto it = std::lower_bound(columns.begin(), columns.end(), c - radius);
               it != columns.end() && *it <= c + radius; ++it) {
            const int dx = *it - c;
            if (dx * dx + dy * dy > radius * radius) continue;  // a round window
            double exponent = (dx * dx + dy * dy) * inv_2ss;
            if (inv_2sc > 0.0) {
              const cv::Vec3b& other = image_bgr.at<cv::Vec3b>(y, *it);
              double d2 = 0.0;
              for (int k = 0; k < 3; ++k) {
                const double d = static_cast<double>(other[k]) - colour[k];
                d2 += d * d;
              }
              exponent += d2 * inv_2sc;
            }
            samples.push_back({static_cast<double>(dx), static_cast<double>(dy),
                               static_cast<double>(values[*it]), std::exp(-exponent)});
          }
        }
        double sw = 0.0, sw2 = 0.0;
        Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        for (const auto& q : samples) {
          const Eigen::Vector3d x(q[0], q[1], 1.0);
          normal.noalias() += q[3] * x * x.transpose();
          rhs.noalias() += q[3] * q[2] * x;
          sw += q[3];
          sw2 += q[3] * q[3];
        }
        if (!(sw > 0.0) || !(sw2 > 0.0)) continue;
        // The window's effective number of GCPs; next to one GCP of a sparse set its weight
        // dominates (n ≤ 3), D̂ is that GCP's own value, and the prior keeps its weight.
        const double n = sw * sw / sw2;
        if (n <= 3.0) continue;
        normal(0, 0) += ridge_scale * sw;
        normal(1, 1) += ridge_scale * sw;
        const Eigen::Vector3d plane = normal.ldlt().solve(rhs);
        double rss = 0.0;
        for (const auto& q : samples) {
          const double e = q[2] - plane.dot(Eigen::Vector3d(q[0], q[1], 1.0));
          rss += q[3] * e * e;
        }
        spread.ptr<float>(r)[c] = static_cast<float>(std::sqrt(rss / sw * n / (n - 3.0)));
      }
    }
  });
  return spread;
}

cv::Mat SpreadPriorWeights(const cv::Mat& gcp_labels, const cv::Mat& image_bgr,
                           const EnergyOptions& options) {
  if (options.gcp_spread <= 0.0) return {};
  const cv::Mat spread = GcpPlaneSpread(gcp_labels, image_bgr, options.gcp_spread_sigma_px,
                                        options.gcp_spread_sigma_colour);
  cv::Mat weights(spread.size(), CV_32F);
  const double inv_tau2 = 1.0 / (options.gcp_spread * options.gcp_spread);
  for (int r = 0; r < spread.rows; ++r) {
    const float* s = spread.ptr<float>(r);
    float* w = weights.ptr<float>(r);
    for (int c = 0; c < spread.cols; ++c) {
      w[c] = std::isfinite(s[c]) ? static_cast<float>(1.0 / (1.0 + s[c] * s[c] * inv_tau2)) : 1.0f;
    }
  }
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
  const bool use_prior = problem.UsesPrior(options);
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
