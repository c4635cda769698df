// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/left_right.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "gcpstereo/core/error.h"

namespace gcpstereo::optimize {
namespace {

void Require(bool condition, const char* message) {
  if (!condition) throw Error(message);
}

}  // namespace

cv::Mat LeftRightConsistent(const cv::Mat& left_disparity, const cv::Mat& right_disparity,
                            double max_difference_px) {
  Require(left_disparity.type() == CV_32F && right_disparity.type() == CV_32F,
          "LeftRightConsistent: disparity maps must be CV_32F");
  Require(left_disparity.size() == right_disparity.size(),
          "LeftRightConsistent: the two maps differ in size");
  Require(max_difference_px >= 0.0, "LeftRightConsistent: negative tolerance");
  cv::Mat consistent(left_disparity.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < left_disparity.rows; ++r) {
    const float* left = left_disparity.ptr<float>(r);
    const float* right = right_disparity.ptr<float>(r);
    std::uint8_t* out = consistent.ptr<std::uint8_t>(r);
    for (int c = 0; c < left_disparity.cols; ++c) {
      const float d = left[c];
      if (!std::isfinite(d)) continue;
      const long match = std::lround(c - static_cast<double>(d));
      if (match < 0 || match >= left_disparity.cols) {
        out[c] = 255;  // nothing to check against: kept as the optimisation left it
        continue;
      }
      const float other = right[match];
      if (std::isfinite(other) && std::abs(other - d) <= max_difference_px) out[c] = 255;
    }
  }
  return consistent;
}

cv::Mat LeftRightOccluded(const cv::Mat& left_disparity, const cv::Mat& right_disparity,
                          double max_difference_px) {
  const cv::Mat consistent =
      LeftRightConsistent(left_disparity, right_disparity, max_difference_px);  // checks inputs
  cv::Mat occluded(left_disparity.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < left_disparity.rows; ++r) {
    const float* left = left_disparity.ptr<float>(r);
    const float* right = right_disparity.ptr<float>(r);
    const std::uint8_t* ok = consistent.ptr<std::uint8_t>(r);
    std::uint8_t* out = occluded.ptr<std::uint8_t>(r);
    for (int c = 0; c < left_disparity.cols; ++c) {
      if (ok[c] || !std::isfinite(left[c])) continue;
      const long match = std::lround(c - static_cast<double>(left[c]));
      // Inconsistent pixels always match inside the right image (LeftRightConsistent).
      if (std::isfinite(right[match]) && right[match] > left[c] + max_difference_px) out[c] = 255;
    }
  }
  return occluded;
}

int FillFromBackground(const cv::Mat& consistent, int max_run_px, cv::Mat* values,
                       cv::Mat* disparity) {
  Require(values != nullptr && disparity != nullptr, "FillFromBackground: null output");
  Require(consistent.type() == CV_8U && values->type() == CV_32F && disparity->type() == CV_32F,
          "FillFromBackground: expects a CV_8U mask and CV_32F maps");
  Require(consistent.size() == values->size() && consistent.size() == disparity->size(),
          "FillFromBackground: sizes differ");
  Require(max_run_px >= 0, "FillFromBackground: negative run length");
  int filled = 0;
  const int cols = consistent.cols;
  for (int r = 0; r < consistent.rows; ++r) {
    const std::uint8_t* ok = consistent.ptr<std::uint8_t>(r);
    float* value = values->ptr<float>(r);
    float* disp = disparity->ptr<float>(r);
    // The consistent values are read before any is written: fills never feed other fills.
    int previous = -1;  // last consistent column left of c
    int c = 0;
    while (c < cols) {
      if (ok[c]) {
        previous = c++;
        continue;
      }
      int next = c;
      while (next < cols && !ok[next]) ++next;  // first consistent column at or right of c
      int source = -1;
      if (previous >= 0 && next < cols) {
        source = disp[previous] <= disp[next] ? previous : next;
      } else if (previous >= 0) {
        source = previous;
      } else if (next < cols) {
        source = next;
      }
      if (source >= 0 && next - c <= max_run_px) {
        for (int k = c; k < next; ++k) {
          value[k] = value[source];
          disp[k] = disp[source];
          ++filled;
        }
      }
      c = next;
    }
  }
  return filled;
}

int RestoreGcpConfirmed(const cv::Mat& gcp_disparity, int radius_px, const cv::Mat& values_before,
                        const cv::Mat& disparity_before, cv::Mat* consistent, cv::Mat* values,
                        cv::Mat* disparity) {
  Require(consistent != nullptr && values != nullptr && disparity != nullptr,
          "RestoreGcpConfirmed: null output");
  Require(consistent->type() == CV_8U && gcp_disparity.type() == CV_32F &&
              values_before.type() == CV_32F && disparity_before.type() == CV_32F &&
              values->type() == CV_32F && disparity->type() == CV_32F,
          "RestoreGcpConfirmed: expects a CV_8U mask and CV_32F maps");
  const cv::Size size = consistent->size();
  Require(gcp_disparity.size() == size && values_before.size() == size &&
              disparity_before.size() == size && values->size() == size &&
              disparity->size() == size,
          "RestoreGcpConfirmed: sizes differ");
  Require(radius_px >= 0, "RestoreGcpConfirmed: negative radius");
  const int radius2 = radius_px * radius_px;
  int restored = 0;
  for (int r = 0; r < size.height; ++r) {
    std::uint8_t* ok = consistent->ptr<std::uint8_t>(r);
    for (int c = 0; c < size.width; ++c) {
      if (ok[c]) continue;
      const float before = disparity_before.at<float>(r, c);
      const float after = disparity->at<float>(r, c);
      if (!std::isfinite(before) || before == after) continue;
      // The nearest GCP within the radius.
      int best = radius2 + 1;
      float gcp = std::numeric_limits<float>::quiet_NaN();
      for (int y = std::max(0, r - radius_px); y <= std::min(size.height - 1, r + radius_px); ++y) {
        const float* row = gcp_disparity.ptr<float>(y);
        for (int x = std::max(0, c - radius_px); x <= std::min(size.width - 1, c + radius_px);
             ++x) {
          const int d2 = (y - r) * (y - r) + (x - c) * (x - c);
          if (d2 < best && std::isfinite(row[x])) {
            best = d2;
            gcp = row[x];
          }
        }
      }
      if (!std::isfinite(gcp)) continue;
      if (!std::isfinite(after) || std::abs(gcp - before) < std::abs(gcp - after)) {
        values->at<float>(r, c) = values_before.at<float>(r, c);
        disparity->at<float>(r, c) = before;
        ok[c] = 255;
        ++restored;
      }
    }
  }
  return restored;
}

int WeightedMedianOfFilled(const cv::Mat& image_bgr, const cv::Mat& consistent, int radius_px,
                           double sigma_colour, cv::Mat* values, cv::Mat* disparity) {
  Require(values != nullptr && disparity != nullptr, "WeightedMedianOfFilled: null output");
  Require(image_bgr.type() == CV_8UC3 && consistent.type() == CV_8U && values->type() == CV_32F &&
              disparity->type() == CV_32F,
          "WeightedMedianOfFilled: expects a CV_8UC3 image, a CV_8U mask and CV_32F maps");
  Require(image_bgr.size() == consistent.size() && consistent.size() == values->size() &&
              consistent.size() == disparity->size(),
          "WeightedMedianOfFilled: sizes differ");
  Require(radius_px >= 0 && sigma_colour > 0.0, "WeightedMedianOfFilled: bad radius or sigma");
  const cv::Mat source_values = values->clone(), source_disparity = disparity->clone();
  const double inv_sigma2 = 1.0 / (sigma_colour * sigma_colour * 255.0 * 255.0);
  int changed = 0;
  struct Sample {
    float disparity;
    float weight;
    int row, col;
  };
  std::vector<Sample> samples;
  for (int r = 0; r < consistent.rows; ++r) {
    for (int c = 0; c < consistent.cols; ++c) {
      if (consistent.at<std::uint8_t>(r, c)) continue;
      const cv::Vec3b centre = image_bgr.at<cv::Vec3b>(r, c);
      samples.clear();
      double total = 0.0;
      for (int rr = std::max(0, r - radius_px); rr <= std::min(consistent.rows - 1, r + radius_px);
           ++rr) {
        for (int cc = std::max(0, c - radius_px);
             cc <= std::min(consistent.cols - 1, c + radius_px); ++cc) {
          const float d = source_disparity.at<float>(rr, cc);
          if (!std::isfinite(d)) continue;
          const cv::Vec3b other = image_bgr.at<cv::Vec3b>(rr, cc);
          double distance2 = 0.0;
          for (int k = 0; k < 3; ++k) {
            const double delta = static_cast<double>(centre[k]) - other[k];
            distance2 += delta * delta;
          }
          const float w = static_cast<float>(std::exp(-distance2 * inv_sigma2));
          samples.push_back({d, w, rr, cc});
          total += w;
        }
      }
      if (samples.empty()) continue;
      std::sort(samples.begin(), samples.end(), [](const Sample& a, const Sample& b) {
        return a.disparity < b.disparity ||
               (a.disparity == b.disparity && (a.row < b.row || (a.row == b.row && a.col < b.col)));
      });
      double cumulative = 0.0;
      const Sample* median = &samples.back();
      for (const Sample& s : samples) {
        cumulative += s.weight;
        if (cumulative >= 0.5 * total) {
          median = &s;
          break;
        }
      }
      const float new_value = source_values.at<float>(median->row, median->col);
      if (new_value != values->at<float>(r, c)) ++changed;
      values->at<float>(r, c) = new_value;
      disparity->at<float>(r, c) = median->disparity;
    }
  }
  return changed;
}

}  // namespace gcpstereo::optimize
