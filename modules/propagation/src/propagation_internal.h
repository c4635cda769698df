// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Shared by the propagation methods (propagation.cc, weighted_median.cc, local_plane.cc); the
// non-inline functions are defined in propagation.cc.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include <opencv2/core.hpp>

#include "gcpstereo/propagation/propagation.h"

namespace gcpstereo::propagation::internal {

// options.Check(), then: image_bgr a non-empty CV_8UC3, sparse_values CV_32F of its size. Throws
// ConfigError / Error with the messages documented on Propagate.
void CheckPropagationInputs(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                            const PropagationOptions& options);

// The number of finite entries of `sparse_values` (the GCPs).
int CountGcps(const cv::Mat& sparse_values);

// The windowed methods' bookkeeping once `values` and `reached` are filled: unknowns (every
// non-GCP pixel), unreached pixels and their 8-connected regions.
void CountUnreached(PropagationResult* result);

// Squared RGB distance of two pixels, in grey levels².
inline double ColourDistance2(const cv::Vec3b& a, const cv::Vec3b& b) {
  double sum = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double d = static_cast<double>(a[k]) - b[k];
    sum += d * d;
  }
  return sum;
}

// The frame of the windowed methods (weighted median, local planes): fills result->values,
// ->reached and the counts. A GCP pixel keeps its value; every other pixel (r, c) takes
// estimate(r, c, &scratch), NaN when no GCP is within reach (the pixel stays unreached). Rows run
// in parallel with one default-constructed `Scratch` (reused buffers) per range of rows.
template <typename Scratch, typename Estimate>
void EstimateNonGcpPixels(const cv::Mat& sparse_values, const Estimate& estimate,
                          PropagationResult* result) {
  result->num_gcps = CountGcps(sparse_values);
  result->values =
      cv::Mat(sparse_values.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  result->reached = cv::Mat(sparse_values.size(), CV_8U, cv::Scalar(0));
  cv::parallel_for_(cv::Range(0, sparse_values.rows), [&](const cv::Range& rows) {
    Scratch scratch;
    for (int r = rows.start; r < rows.end; ++r) {
      const float* own_row = sparse_values.ptr<float>(r);
      float* out = result->values.ptr<float>(r);
      std::uint8_t* reached = result->reached.ptr<std::uint8_t>(r);
      for (int c = 0; c < sparse_values.cols; ++c) {
        const float value = std::isfinite(own_row[c]) ? own_row[c] : estimate(r, c, &scratch);
        if (std::isnan(value)) continue;
        out[c] = value;
        reached[c] = 255;
      }
    }
  });
  CountUnreached(result);
}

}  // namespace gcpstereo::propagation::internal
