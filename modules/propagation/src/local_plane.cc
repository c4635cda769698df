// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// D̂ as a robust local plane through the GCPs around each pixel (propagation.method: local_plane).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/core.hpp>

#include "gcpstereo/propagation/propagation.h"
#include "propagation_internal.h"

namespace gcpstereo::propagation {
namespace {

// Reweighting passes after the first weighted least-squares fit.
constexpr int kReweightings = 2;
// Residuals above this share of the window's mean |value| weigh 1/|r| (least absolute deviations),
// below it 1: a robust fit that needs no noise scale of its own.
constexpr double kRelativeHuber = 1e-3;
// Ridge on the two slopes, relative to the total weight times radius²: a window whose GCPs lie on
// a line (one scan line) or at one pixel gets a flat plane through their weighted mean.
constexpr double kSlopeRidge = 1e-3;

struct Sample {
  double value;
  double weight;  // spatial · colour
  double dx, dy;  // offset from the pixel
};

// The value at the window's centre of the plane v = c + a·dx + b·dy fitted to the samples by
// iteratively reweighted least squares (Huber weights, threshold kRelativeHuber · mean |v|).
double FitPlaneAtCentre(const std::vector<Sample>& samples, double radius,
                        std::vector<double>* robust) {
  robust->assign(samples.size(), 1.0);
  double scale = 0.0, total = 0.0;
  for (const Sample& s : samples) {
    scale += s.weight * std::abs(s.value);
    total += s.weight;
  }
  const double huber = std::max(kRelativeHuber * scale / total, 1e-12);
  Eigen::Vector3d plane(0.0, 0.0, 0.0);  // a, b, c
  for (int pass = 0; pass <= kReweightings; ++pass) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    double sum = 0.0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Sample& s = samples[i];
      const double w = s.weight * (*robust)[i];
      const Eigen::Vector3d x(s.dx, s.dy, 1.0);
      normal.noalias() += w * x * x.transpose();
      rhs.noalias() += w * s.value * x;
      sum += w;
    }
    const double ridge = kSlopeRidge * sum * radius * radius;
    normal(0, 0) += ridge;
    normal(1, 1) += ridge;
    plane = normal.ldlt().solve(rhs);
    if (pass == kReweightings) break;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Sample& s = samples[i];
      const double residual = std::abs(s.value - (plane(2) + plane(0) * s.dx + plane(1) * s.dy));
      (*robust)[i] = residual > huber ? huber / residual : 1.0;
    }
  }
  return plane(2);
}

}  // namespace

PropagationResult PropagateByLocalPlanes(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                                         const PropagationOptions& options) {
  internal::CheckPropagationInputs(image_bgr, sparse_values, options);
  const auto start = std::chrono::steady_clock::now();
  const int width = image_bgr.cols, height = image_bgr.rows;
  const int radius = options.plane_radius_px;
  const double inv_2ss = 1.0 / (2.0 * options.plane_sigma_px * options.plane_sigma_px);
  const double inv_2sc = 1.0 / (2.0 * options.plane_sigma_colour * options.plane_sigma_colour);

  PropagationResult result;
  result.solver = "local planes";

  // The GCP columns of every row: a window visits only its GCPs (sparse scans are ≈ 0.4 % of the
  // pixels).
  std::vector<std::vector<int>> gcp_columns(height);
  for (int r = 0; r < height; ++r) {
    const float* row = sparse_values.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      if (std::isfinite(row[c])) gcp_columns[r].push_back(c);
    }
  }
  struct Scratch {
    std::vector<Sample> samples;
    std::vector<double> robust;
  };
  auto estimate = [&](int r, int c, Scratch* scratch) {
    std::vector<Sample>& samples = scratch->samples;
    samples.clear();
    double spatial_total = 0.0;
    const cv::Vec3b& colour = image_bgr.at<cv::Vec3b>(r, c);
    for (int y = std::max(0, r - radius); y <= std::min(height - 1, r + radius); ++y) {
      const int dy = y - r;
      const std::vector<int>& columns = gcp_columns[y];
      const float* values = sparse_values.ptr<float>(y);
      const cv::Vec3b* pixels = image_bgr.ptr<cv::Vec3b>(y);
      for (auto it = std::lower_bound(columns.begin(), columns.end(), c - radius);
           it != columns.end() && *it <= c + radius; ++it) {
        const int x = *it, dx = x - c;
        if (dx * dx + dy * dy > radius * radius) continue;  // a round window
        const double spatial = std::exp(-(dx * dx + dy * dy) * inv_2ss);
        spatial_total += spatial;
        samples.push_back(
            {values[x], spatial * std::exp(-internal::ColourDistance2(pixels[x], colour) * inv_2sc),
             static_cast<double>(dx), static_cast<double>(dy)});
      }
    }
    if (samples.empty()) return std::numeric_limits<float>::quiet_NaN();
    double total = 0.0;
    for (const Sample& s : samples) total += s.weight;
    if (!(total > 1e-12 * spatial_total)) {  // every colour weight underflowed: spatial only
      for (Sample& s : samples) s.weight = std::exp(-(s.dx * s.dx + s.dy * s.dy) * inv_2ss);
    }
    return static_cast<float>(FitPlaneAtCentre(samples, radius, &scratch->robust));
  };
  internal::EstimateNonGcpPixels<Scratch>(sparse_values, estimate, &result);
  result.solve_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace gcpstereo::propagation
