// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/winner_take_all.h"

#include <cmath>

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
