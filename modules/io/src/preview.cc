// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/preview.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::io {
namespace {

constexpr int kMinPreviewRows = 160;

std::string FormatTick(double value) {
  char text[32];
  const double magnitude = std::abs(value);
  if (magnitude != 0.0 && (magnitude >= 1e5 || magnitude < 1e-2)) {
    std::snprintf(text, sizeof(text), "%.2e", value);
  } else if (magnitude >= 100.0) {
    std::snprintf(text, sizeof(text), "%.0f", value);
  } else if (magnitude >= 10.0) {
    std::snprintf(text, sizeof(text), "%.1f", value);
  } else {
    std::snprintf(text, sizeof(text), "%.2f", value);
  }
  return text;
}

// Maps `values` (CV_32F) on [min, max] through `colormap`; `valid(v)` decides which pixels are
// painted (others black). Appends the scale bar.
template <typename ValidFn>
cv::Mat RenderWithScale(const cv::Mat& values, double min, double max, const std::string& unit,
                        int colormap, ValidFn valid) {
  if (values.empty() || values.type() != CV_32FC1) {
    throw Error("preview: expected a non-empty CV_32FC1 map, got type " +
                cv::typeToString(values.type()));
  }
  if (!std::isfinite(min) || !std::isfinite(max) || !(min < max)) {
    throw Error("preview: value range must be finite with min < max, got [" + FormatTick(min) +
                ", " + FormatTick(max) + "]");
  }
  cv::Mat gray(values.size(), CV_8UC1);
  cv::Mat valid_mask(values.size(), CV_8UC1);
  for (int r = 0; r < values.rows; ++r) {
    const float* v = values.ptr<float>(r);
    auto* g = gray.ptr<std::uint8_t>(r);
    auto* m = valid_mask.ptr<std::uint8_t>(r);
    for (int c = 0; c < values.cols; ++c) {
      const bool ok = valid(v[c]);
      m[c] = ok ? 255 : 0;
      const double t = ok ? std::clamp((v[c] - min) / (max - min), 0.0, 1.0) : 0.0;
      g[c] = static_cast<std::uint8_t>(std::lround(t * 255.0));
    }
  }
  cv::Mat colored;
  cv::applyColorMap(gray, colored, colormap);
  colored.setTo(cv::Scalar::all(0), valid_mask == 0);

  // Enlarge tiny maps so that the tick labels stay readable.
  if (colored.rows < kMinPreviewRows) {
    const double factor = std::ceil(static_cast<double>(kMinPreviewRows) / colored.rows);
    cv::resize(colored, colored, cv::Size(), factor, factor, cv::INTER_NEAREST);
  }
  const int rows = colored.rows;
  const double font_scale = std::clamp(rows / 600.0, 0.35, 1.2);
  const int thickness = font_scale > 0.8 ? 2 : 1;
  const int margin = std::max(4, rows / 50);
  const int bar_width = std::max(12, rows / 25);
  int baseline = 0;
  const cv::Size label_size = cv::getTextSize(
      FormatTick(-max) + " " + unit, cv::FONT_HERSHEY_SIMPLEX, font_scale, thickness, &baseline);
  const cv::Size min_label_size = cv::getTextSize(
      FormatTick(-min) + " " + unit, cv::FONT_HERSHEY_SIMPLEX, font_scale, thickness, &baseline);
  const int text_width = std::max(label_size.width, min_label_size.width);
  const int panel_width = margin + bar_width + margin + text_width + margin;
  cv::Mat panel(rows, panel_width, CV_8UC3, cv::Scalar(255, 255, 255));

  // The bar: top = max, bottom = min.
  const int bar_top = margin + label_size.height;
  const int bar_bottom = rows - margin - label_size.height;
  const int bar_height = std::max(2, bar_bottom - bar_top);
  cv::Mat ramp(bar_height, 1, CV_8UC1);
  for (int r = 0; r < bar_height; ++r) {
    ramp.at<std::uint8_t>(r) =
        static_cast<std::uint8_t>(std::lround(255.0 * (bar_height - 1 - r) / (bar_height - 1)));
  }
  cv::Mat ramp_colored;
  cv::applyColorMap(ramp, ramp_colored, colormap);
  cv::resize(ramp_colored, ramp_colored, cv::Size(bar_width, bar_height), 0, 0, cv::INTER_NEAREST);
  ramp_colored.copyTo(panel(cv::Rect(margin, bar_top, bar_width, bar_height)));
  cv::rectangle(panel, cv::Rect(margin, bar_top, bar_width, bar_height), cv::Scalar(0, 0, 0), 1);

  const int num_ticks = std::clamp(bar_height / (3 * label_size.height), 2, 6);
  for (int i = 0; i < num_ticks; ++i) {
    const double fraction = static_cast<double>(i) / (num_ticks - 1);  // 0 = bottom (min)
    const int y = bar_top + static_cast<int>(std::lround((1.0 - fraction) * (bar_height - 1)));
    const double value = min + fraction * (max - min);
    cv::line(panel, cv::Point(margin + bar_width, y), cv::Point(margin + bar_width + margin / 2, y),
             cv::Scalar(0, 0, 0), 1);
    const std::string label = FormatTick(value) + " " + unit;
    cv::putText(panel, label, cv::Point(margin + bar_width + margin, y + label_size.height / 2),
                cv::FONT_HERSHEY_SIMPLEX, font_scale, cv::Scalar(0, 0, 0), thickness, cv::LINE_AA);
  }
  cv::Mat out;
  cv::hconcat(colored, panel, out);
  return out;
}

}  // namespace

cv::Mat RenderDepthPreview(const cv::Mat& depth, double min, double max,
                           const std::string& unit_label) {
  return RenderWithScale(depth, min, max, unit_label, cv::COLORMAP_TURBO,
                         [](float v) { return std::isfinite(v) && v > 0.0f; });
}

cv::Mat RenderErrorPreview(const cv::Mat& abs_error, double max_error,
                           const std::string& unit_label) {
  return RenderWithScale(abs_error, 0.0, max_error, unit_label, cv::COLORMAP_INFERNO,
                         [](float v) { return std::isfinite(v); });
}

bool RobustValueRange(const cv::Mat& depth, double* min, double* max) {
  std::vector<float> values;
  if (!depth.empty() && depth.type() == CV_32FC1) {
    values.reserve(depth.total());
    for (int r = 0; r < depth.rows; ++r) {
      const float* v = depth.ptr<float>(r);
      for (int c = 0; c < depth.cols; ++c) {
        if (std::isfinite(v[c]) && v[c] > 0.0f) values.push_back(v[c]);
      }
    }
  }
  if (values.empty()) {
    *min = 0.0;
    *max = 1.0;
    return false;
  }
  const auto lo = values.begin() + static_cast<std::ptrdiff_t>(0.01 * (values.size() - 1));
  std::nth_element(values.begin(), lo, values.end());
  *min = *lo;
  const auto hi = values.begin() + static_cast<std::ptrdiff_t>(0.99 * (values.size() - 1));
  std::nth_element(values.begin(), hi, values.end());
  *max = *hi;
  if (!(*min < *max)) {
    const double center = *min;
    const double half = std::max(1e-6, std::abs(center) * 1e-3);
    *min = center - half;
    *max = center + half;
  }
  return true;
}

}  // namespace gcpstereo::io
