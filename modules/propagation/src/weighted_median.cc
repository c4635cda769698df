// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// D̂ as a joint-bilateral weighted median of the GCPs (propagation.method: weighted_median).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "gcpstereo/propagation/propagation.h"
#include "propagation_internal.h"

namespace gcpstereo::propagation {
namespace {

struct Sample {
  float value;
  double weight;
  int dx, dy;     // offset from the pixel
  double colour;  // the colour factor of the weight
};

// Edge-aligned spatial weights (median_edge_stretch k > 1): the weighted least-squares plane
// v = a + b·dx + c·dy through the samples (isotropic spatial weights) gives the direction n of the
// steepest change, across the local depth edge or slope; the distance across it counts k times in
// the squared distance, so the GCPs along the edge (the same side) weigh more than those across
// it. Leaves the weights isotropic when the samples are collinear or the plane is flat.
void StretchAlongEdges(std::vector<Sample>* samples, const std::vector<double>& spatial, int radius,
                       double stretch, double inv_2ss) {
  double sw = 0.0, sx = 0.0, sy = 0.0, sv = 0.0;
  for (const Sample& s : *samples) {
    const double w = spatial[(s.dy + radius) * (2 * radius + 1) + s.dx + radius];
    sw += w;
    sx += w * s.dx;
    sy += w * s.dy;
    sv += w * s.value;
  }
  if (samples->size() < 3 || !(sw > 0.0)) return;
  const double mx = sx / sw, my = sy / sw, mv = sv / sw;
  double cxx = 0.0, cxy = 0.0, cyy = 0.0, cxv = 0.0, cyv = 0.0;
  for (const Sample& s : *samples) {
    const double w = spatial[(s.dy + radius) * (2 * radius + 1) + s.dx + radius];
    const double x = s.dx - mx, y = s.dy - my, v = s.value - mv;
    cxx += w * x * x;
    cxy += w * x * y;
    cyy += w * y * y;
    cxv += w * x * v;
    cyv += w * y * v;
  }
  const double trace = cxx + cyy, det = cxx * cyy - cxy * cxy;
  if (!(trace > 0.0) || !(det > 1e-9 * trace * trace)) return;
  const double b = (cyy * cxv - cxy * cyv) / det, c = (cxx * cyv - cxy * cxv) / det;
  const double g = std::hypot(b, c);
  if (!(g > 0.0) || !std::isfinite(g)) return;
  const double nx = b / g, ny = c / g;
  for (Sample& s : *samples) {
    const double across = s.dx * nx + s.dy * ny, along = s.dy * nx - s.dx * ny;
    s.weight = std::exp(-(along * along + stretch * across * across) * inv_2ss) * s.colour;
  }
}

}  // namespace

PropagationResult PropagateByWeightedMedian(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                                            const PropagationOptions& options) {
  internal::CheckPropagationInputs(image_bgr, sparse_values, options);
  const auto start = std::chrono::steady_clock::now();
  const int width = image_bgr.cols, height = image_bgr.rows;
  const int radius = options.median_radius_px;
  const double inv_2ss = 1.0 / (2.0 * options.median_sigma_px * options.median_sigma_px);
  const double inv_2sc = 1.0 / (2.0 * options.median_sigma_colour * options.median_sigma_colour);
  const double floor = options.median_colour_floor;
  const double stretch = options.median_edge_stretch;

  PropagationResult result;
  result.solver = "weighted median";

  // The spatial weights of the window, once.
  std::vector<double> spatial((2 * radius + 1) * (2 * radius + 1));
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      spatial[(dy + radius) * (2 * radius + 1) + dx + radius] =
          std::exp(-(dx * dx + dy * dy) * inv_2ss);
    }
  }
  // The GCPs' columns per row, in increasing order: a window visits its few GCPs (1–2 % of the
  // pixels of a LiDAR frame) without testing its every pixel, in the same order.
  std::vector<std::vector<int>> gcp_columns(height);
  for (int y = 0; y < height; ++y) {
    const float* values = sparse_values.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      if (std::isfinite(values[x])) gcp_columns[y].push_back(x);
    }
  }
  auto estimate = [&](int r, int c, std::vector<Sample>* scratch) {
    std::vector<Sample>& samples = *scratch;
    samples.clear();
    const cv::Vec3b& colour = image_bgr.at<cv::Vec3b>(r, c);
    for (int y = std::max(0, r - radius); y <= std::min(height - 1, r + radius); ++y) {
      const float* values = sparse_values.ptr<float>(y);
      const cv::Vec3b* pixels = image_bgr.ptr<cv::Vec3b>(y);
      const int spatial_row = (y - r + radius) * (2 * radius + 1) + radius;  // dx = 0
      const std::vector<int>& columns = gcp_columns[y];
      for (auto it = std::lower_bound(columns.begin(), columns.end(), c - radius);
           it != columns.end() && *it <= c + radius; ++it) {
        const int x = *it;
        const double colour_factor =
            floor +
            (1.0 - floor) * std::exp(-internal::ColourDistance2(pixels[x], colour) * inv_2sc);
        samples.push_back(
            {values[x], spatial[spatial_row + x - c] * colour_factor, x - c, y - r, colour_factor});
      }
    }
    if (samples.empty()) return std::numeric_limits<float>::quiet_NaN();
    if (stretch > 1.0) StretchAlongEdges(&samples, spatial, radius, stretch, inv_2ss);
    double total = 0.0;
    for (const Sample& s : samples) total += s.weight;
    if (!(total > 0.0)) {  // every weight underflowed: fall back to equal weights
      for (Sample& s : samples) s.weight = 1.0;
      total = static_cast<double>(samples.size());
    }
    std::stable_sort(samples.begin(), samples.end(),
                     [](const Sample& a, const Sample& b) { return a.value < b.value; });
    double cumulative = 0.0;
    for (const Sample& s : samples) {
      cumulative += s.weight;
      if (cumulative >= 0.5 * total) return s.value;
    }
    return samples.back().value;  // rounding: the total was not quite reached
  };
  internal::EstimateNonGcpPixels<std::vector<Sample>>(sparse_values, estimate, &result);
  result.solve_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace gcpstereo::propagation
