// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Helpers shared by the cost module's sources (not installed).
#pragma once

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core/types.hpp>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/cost/cost_filter.h"

namespace gcpstereo::cost::internal {

template <typename T>
std::string Str(const T& value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

// The CostVolume encoding of a cost in [0, max_cost]: nearest quantisation level (ties up),
// inv_step = 1 / CostVolume::cost_step(). Equal to CostVolume::Encode up to float rounding of the
// product; inlined because the sweeps encode hundreds of millions of costs.
inline std::uint16_t Quantise(float cost, float inv_step) {
  const float q = cost * inv_step + 0.5f;
  if (!(q > 0.0f)) return 0;
  return q >= 65534.0f ? std::uint16_t{65534} : static_cast<std::uint16_t>(q);
}

// LabelBands' value of an entry outside the bands that has data: the largest cost.
constexpr std::uint16_t kNotComputed = 65534;

// The hull of the labels of `bands` (over `band_region`, image coordinates) within `margin` pixels
// (Chebyshev distance) of each pixel of image row y, columns [x0, x0 + n): lo[c] … hi[c], lo > hi
// where no block is that near.
void BandsNear(const LabelBands& bands, const cv::Rect& band_region, int y, int x0, int n,
               int margin, int* lo, int* hi);

// The best_k aggregation of the plane sweep (RGB and ZNCC): per_neighbor holds the costs of
// `width` entries for each neighbour ([neighbour][entry], +inf = the neighbour does not see it) and
// is sorted in place per entry; out[i] = the mean of the min(k, votes[i]) smallest, 0 without
// votes.
void MeanOfBestK(std::vector<float>& per_neighbor, int num_neighbors, int width, int k,
                 const float* votes, float* out);

}  // namespace gcpstereo::cost::internal
