// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/cost_volume.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "gcpstereo/core/error.h"

namespace gcpstereo {

CostVolume::CostVolume(cv::Rect region, int num_labels, float max_cost)
    : region_(region), num_labels_(num_labels), max_cost_(max_cost) {
  if (region.width <= 0 || region.height <= 0 || num_labels <= 0 || !(max_cost > 0.0f) ||
      !std::isfinite(max_cost)) {
    std::ostringstream s;
    s << "invalid cost volume: " << region.width << "x" << region.height << " pixels, "
      << num_labels << " labels, max cost " << max_cost;
    throw Error(s.str());
  }
  cost_step_ = max_cost / 65534.0f;
  data_.assign(static_cast<std::size_t>(region.width) * region.height * num_labels, kNoData);
}

std::uint16_t CostVolume::Encode(float cost) const {
  if (!(cost > 0.0f)) return 0;  // also maps NaN to 0; callers never pass NaN on purpose
  const float q = std::round(cost / cost_step_);
  return static_cast<std::uint16_t>(std::min(q, 65534.0f));
}

}  // namespace gcpstereo
