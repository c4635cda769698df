// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// D̂ as a joint-bilateral weighted median of the GCPs (propagation.method: weighted_median).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/propagation/propagation.h"
#include "propagation_internal.h"

namespace gcpstereo::propagation {
namespace {

struct Sample {
  float value;
  double weight;
};

}  // namespace

PropagationResult PropagateByWeightedMedian(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                                            const PropagationOptions& options) {
  internal::CheckPropagationInputs(image_bgr, sparse_values, options);
  const auto start = std::chrono::steady_clock::now();
  const int width = image_bgr.cols, height = image_bgr.rows;
  const int radius = options.median_radius_px;
  const double inv_2ss = 1.0 / (2.0 * options.median_sigma_px * options.median_sigma_px);
  const double inv_2sc = 1.0 / (2.0 * options.median_sigma_colour * options.median_sigma_colour);

  PropagationResult result;
  result.solver = "weighted median";
  for (int r = 0; r < height; ++r) {
    const float* row = sparse_values.ptr<float>(r);
    result.num_gcps +=
        static_cast<int>(std::count_if(row, row + width, [](float v) { return std::isfinite(v); }));
  }
  result.values =
      cv::Mat(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  result.reached = cv::Mat(height, width, CV_8U, cv::Scalar(0));

  // The spatial weights of the window, once.
  std::vector<double> spatial((2 * radius + 1) * (2 * radius + 1));
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      spatial[(dy + radius) * (2 * radius + 1) + dx + radius] =
          std::exp(-(dx * dx + dy * dy) * inv_2ss);
    }
  }
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    std::vector<Sample> samples;
    for (int r = rows.start; r < rows.end; ++r) {
      const cv::Vec3b* image_row = image_bgr.ptr<cv::Vec3b>(r);
      const float* own_row = sparse_values.ptr<float>(r);
      float* out = result.values.ptr<float>(r);
      std::uint8_t* reached = result.reached.ptr<std::uint8_t>(r);
      for (int c = 0; c < width; ++c) {
        if (std::isfinite(own_row[c])) {  // a GCP keeps its value
          out[c] = own_row[c];
          reached[c] = 255;
          continue;
        }
        samples.clear();
        const cv::Vec3b& colour = image_row[c];
        double total = 0.0;
        for (int y = std::max(0, r - radius); y <= std::min(height - 1, r + radius); ++y) {
          const float* values = sparse_values.ptr<float>(y);
          const cv::Vec3b* pixels = image_bgr.ptr<cv::Vec3b>(y);
          const int spatial_row = (y - r + radius) * (2 * radius + 1) + radius;  // dx = 0
          for (int x = std::max(0, c - radius); x <= std::min(width - 1, c + radius); ++x) {
            if (!std::isfinite(values[x])) continue;
            double colour_distance2 = 0.0;
            for (int k = 0; k < 3; ++k) {
              const double d = static_cast<double>(pixels[x][k]) - colour[k];
              colour_distance2 += d * d;
            }
            const double w = spatial[spatial_row + x - c] * std::exp(-colour_distance2 * inv_2sc);
            samples.push_back({values[x], w});
            total += w;
          }
        }
        if (samples.empty()) continue;
        reached[c] = 255;
        if (!(total > 0.0)) {  // every weight underflowed: fall back to equal weights
          for (Sample& s : samples) s.weight = 1.0;
          total = static_cast<double>(samples.size());
        }
        std::stable_sort(samples.begin(), samples.end(),
                         [](const Sample& a, const Sample& b) { return a.value < b.value; });
        double cumulative = 0.0;
        for (const Sample& s : samples) {
          cumulative += s.weight;
          if (cumulative >= 0.5 * total) {
            out[c] = s.value;
            break;
          }
        }
      }
    }
  });

  result.num_unknowns = height * width - result.num_gcps;
  const cv::Mat unreached = result.reached == 0;
  result.num_unreached_pixels = cv::countNonZero(unreached);
  if (result.num_unreached_pixels > 0) {
    cv::Mat components;
    result.num_unreached_regions = cv::connectedComponents(unreached, components, 8, CV_32S) - 1;
  }
  result.solve_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace gcpstereo::propagation
