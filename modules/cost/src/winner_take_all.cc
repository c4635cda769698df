// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/winner_take_all.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::cost {

cv::Mat WinnerTakeAll(const CostVolume& volume) {
  if (volume.empty()) throw Error("winner-take-all: the cost volume is empty");
  cv::Mat labels(volume.height(), volume.width(), CV_32S);
  const int num_labels = volume.num_labels();
  tbb::parallel_for(tbb::blocked_range<int>(0, volume.height()),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int row = range.begin(); row != range.end(); ++row) {
                        int* out = labels.ptr<int>(row);
                        for (int col = 0; col < volume.width(); ++col) {
                          const std::uint16_t* costs = volume.PixelData(row, col);
                          // kNoData (65535) is above every stored cost, so it never wins.
                          std::uint16_t best = CostVolume::kNoData;
                          int ties = 0;
                          for (int l = 0; l < num_labels; ++l) {
                            if (costs[l] < best) {
                              best = costs[l];
                              ties = 1;
                            } else if (costs[l] == best) {
                              ++ties;
                            }
                          }
                          // The middle one of the tied labels (lower middle for an even count).
                          int best_label = -1;
                          if (best != CostVolume::kNoData) {
                            const int wanted = (ties - 1) / 2;
                            for (int l = 0, seen = 0; l < num_labels; ++l) {
                              if (costs[l] == best && seen++ == wanted) {
                                best_label = l;
                                break;
                              }
                            }
                          }
                          out[col] = best_label;
                        }
                      }
                    });
  return labels;
}

namespace {

// c = 1 − (Φ1 + ε) / (Φ2 + ε) of one cost curve (see PeakRatioConfidence).
double PeakRatio(const std::vector<double>& curve, double epsilon) {
  const int num_labels = static_cast<int>(curve.size());
  int best = 0;
  double highest = curve[0];
  for (int l = 1; l < num_labels; ++l) {
    if (curve[l] < curve[best]) best = l;
    highest = std::max(highest, curve[l]);
  }
  // The first label of a plateau is its one local minimum: strictly below the left neighbour,
  // no higher than the right one.
  double second = highest;
  for (int l = 0; l < num_labels; ++l) {
    if (l == best) continue;
    const double v = curve[l];
    if ((l == 0 || v < curve[l - 1]) && (l + 1 == num_labels || v <= curve[l + 1])) {
      second = std::min(second, v);
    }
  }
  return 1.0 - (curve[best] + epsilon) / (second + epsilon);
}

}  // namespace

cv::Mat PeakRatioConfidence(const CostVolume& volume, int radius) {
  if (volume.empty()) throw Error("peak-ratio confidence: the cost volume is empty");
  if (radius < 0 || radius > kMaxConfidenceRadius) {
    throw Error("peak-ratio confidence: the window radius " + std::to_string(radius) +
                " is outside [0, " + std::to_string(kMaxConfidenceRadius) + "]");
  }
  const int width = volume.width();
  const int height = volume.height();
  const int num_labels = volume.num_labels();
  cv::Mat confidence(height, width, CV_32F);
  // In stored units (the fixed-point steps of max_cost): kNoData reads as max_cost.
  constexpr std::int32_t kFullScale = CostVolume::kNoData - 1;
  constexpr double kEpsilon = 0.01 * kFullScale;
  auto cost = [&](int row, int col, int l) {
    return std::min<std::int32_t>(volume.PixelData(row, col)[l], kFullScale);
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
    // column_sums[col · L + l]: Σ of label l's cost over the window's rows at column col,
    // slid down the rows (exact in int32: at most 21² costs of < 2^16 each).
    std::vector<std::int32_t> column_sums(static_cast<std::size_t>(width) * num_labels, 0);
    auto add_row = [&](int row, int sign) {
      if (row < 0 || row >= height) return;
      for (int col = 0; col < width; ++col) {
        std::int32_t* sums = &column_sums[static_cast<std::size_t>(col) * num_labels];
        for (int l = 0; l < num_labels; ++l) sums[l] += sign * cost(row, col, l);
      }
    };
    for (int row = range.begin() - radius; row < range.begin() + radius; ++row) add_row(row, 1);
    std::vector<std::int64_t> window(num_labels);
    std::vector<double> curve(num_labels);
    for (int row = range.begin(); row != range.end(); ++row) {
      add_row(row + radius, 1);
      const int rows_in = std::min(height - 1, row + radius) - std::max(0, row - radius) + 1;
      std::fill(window.begin(), window.end(), 0);
      for (int col = 0; col <= std::min(radius, width - 1); ++col) {
        for (int l = 0; l < num_labels; ++l) {
          window[l] += column_sums[static_cast<std::size_t>(col) * num_labels + l];
        }
      }
      float* out = confidence.ptr<float>(row);
      for (int col = 0; col < width; ++col) {
        if (col > 0) {  // slide the window one column right
          const int enter = col + radius;
          const int leave = col - radius - 1;
          for (int l = 0; l < num_labels; ++l) {
            if (enter < width) {
              window[l] += column_sums[static_cast<std::size_t>(enter) * num_labels + l];
            }
            if (leave >= 0) {
              window[l] -= column_sums[static_cast<std::size_t>(leave) * num_labels + l];
            }
          }
        }
        const std::uint16_t* own = volume.PixelData(row, col);
        if (std::all_of(own, own + num_labels,
                        [](std::uint16_t c) { return c == CostVolume::kNoData; })) {
          out[col] = 0.0f;
          continue;
        }
        const int cols_in = std::min(width - 1, col + radius) - std::max(0, col - radius) + 1;
        const double count = static_cast<double>(rows_in) * cols_in;
        for (int l = 0; l < num_labels; ++l) curve[l] = window[l] / count;
        out[col] = static_cast<float>(PeakRatio(curve, kEpsilon));
      }
      add_row(row - radius, -1);
    }
  });
  return confidence;
}

namespace {

// Applies `value_of(label)` to every valid label of a CV_32S or CV_32F map.
template <typename ValueOf>
cv::Mat MapLabels(const cv::Mat& label_map, int count, const char* what, ValueOf&& value_of) {
  if (label_map.type() != CV_32S && label_map.type() != CV_32F) {
    throw Error(std::string(what) + ": the label map must be CV_32S or CV_32F");
  }
  cv::Mat out(label_map.size(), CV_32F);
  for (int row = 0; row < label_map.rows; ++row) {
    float* dst = out.ptr<float>(row);
    for (int col = 0; col < label_map.cols; ++col) {
      const double label = label_map.type() == CV_32S
                               ? static_cast<double>(label_map.at<int>(row, col))
                               : static_cast<double>(label_map.at<float>(row, col));
      if (!(label >= 0.0 && label <= count - 1)) {
        dst[col] = kInvalidDepth;
        continue;
      }
      const double v = value_of(label);
      dst[col] = std::isfinite(v) ? static_cast<float>(v) : kInvalidDepth;
    }
  }
  return out;
}

}  // namespace

cv::Mat LabelsToDepth(const cv::Mat& label_map, const LabelSpace& labels) {
  return MapLabels(label_map, labels.count(), "LabelsToDepth",
                   [&](double l) { return labels.DepthOfLabel(l); });
}

cv::Mat LabelsToValue(const cv::Mat& label_map, const LabelSpace& labels) {
  return MapLabels(label_map, labels.count(), "LabelsToValue",
                   [&](double l) { return labels.ValueOfLabel(l); });
}

}  // namespace gcpstereo::cost
