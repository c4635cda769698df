// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/cost_volume.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "gcpstereo/core/error.h"

namespace gcpstereo {

CostVolume::CostVolume(cv::Rect region, int num_labels, float max_cost, std::uint16_t fill)
    : region_(region), num_labels_(num_labels), max_cost_(max_cost) {
  if (region.width <= 0 || region.height <= 0 || num_labels <= 0 || !(max_cost > 0.0f) ||
      !std::isfinite(max_cost)) {
    std::ostringstream s;
    s << "invalid cost volume: " << region.width << "x" << region.height << " pixels, "
      << num_labels << " labels, max cost " << max_cost;
    throw Error(s.str());
  }
  cost_step_ = max_cost / 65534.0f;
  data_.assign(static_cast<std::size_t>(region.width) * region.height * num_labels, fill);
}

std::uint16_t CostVolume::Encode(float cost) const {
  if (!(cost > 0.0f)) return 0;  // also maps NaN to 0; callers never pass NaN on purpose
  const float q = std::round(cost / cost_step_);
  return static_cast<std::uint16_t>(std::min(q, 65534.0f));
}

void LabelBands::CheckFits(const cv::Size& size, const std::string& what) const {
  if (empty()) return;
  const bool fits = block_px > 0 && lo.type() == CV_32S && hi.type() == CV_32S &&
                    lo.size() == hi.size() &&
                    lo.cols == (size.width + block_px - 1) / block_px &&
                    lo.rows == (size.height + block_px - 1) / block_px;
  if (!fits) {
    std::ostringstream s;
    s << what << ": the label bands (" << lo.cols << "x" << lo.rows << " blocks of " << block_px
      << " px) do not fit the " << size.width << "x" << size.height << " region";
    throw Error(s.str());
  }
}

double LabelBands::Fraction(const cv::Size& size, int num_labels) const {
  if (empty()) return 1.0;
  double inside = 0.0;
  for (int by = 0; by < lo.rows; ++by) {
    const int rows = std::min(block_px, size.height - by * block_px);
    for (int bx = 0; bx < lo.cols; ++bx) {
      const int cols = std::min(block_px, size.width - bx * block_px);
      const int l0 = std::max(lo.at<int>(by, bx), 0);
      const int l1 = std::min(hi.at<int>(by, bx), num_labels - 1);
      if (l0 <= l1) inside += static_cast<double>(rows) * cols * (l1 - l0 + 1);
    }
  }
  return inside / (static_cast<double>(size.area()) * num_labels);
}

}  // namespace gcpstereo
