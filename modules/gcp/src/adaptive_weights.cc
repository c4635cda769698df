// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Yoon–Kweon adaptive support weights for both views of a rectified pair.
//
// C(p, d) = Σ_k w_ref,k(p) · w_tgt,k(p̄) · e_k(p, d) / Σ_k w_ref,k(p) · w_tgt,k(p̄), the offsets k of
// the (sub-sampled) window. Every support weight w_k(p) = exp(−ΔLab/γ_c)·exp(−‖k‖/γ_p) of a row
// serves both views (the left view's reference weights are the right view's target weights and
// back), and so does every truncated difference e, so both are computed once. Each sum adds its
// offsets in a fixed order: the left view in window order, the right view in the mirrored order,
// which is the order the same formula would take on the mirrored images, so the right view's
// costs are bit for bit those of the formula run on the mirrored pair.
#include "adaptive_weights.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/huge_page_allocator.h"

namespace gcpstereo::gcp::internal {

float UniquenessOfCurve(const double* cost, const bool* valid, int count, int best) {
  double c2 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < count; ++i) {
    if (valid[i] && std::abs(i - best) > 1) c2 = std::min(c2, cost[i]);
  }
  if (!std::isfinite(c2) || c2 <= 0.0) return 0.0f;
  return static_cast<float>(std::max(0.0, (c2 - cost[best]) / c2));
}

namespace {

// One window offset of one disparity along `count` pixels: w = a[j] · b[j], num[j] += w · e[j],
// den[j] += w. Compiled twice on x86-64, the AVX2 copy chosen when the CPU has it: both do the
// same float products and double sums per element, so they give the same bits.
#if defined(__GNUC__) && defined(__x86_64__)
__attribute__((target_clones("avx2", "default")))
#endif
void AccumulateOffset(const float* a, const float* b, const float* e, double* num, double* den,
                      int count) {
  for (int j = 0; j < count; ++j) {
    const float w = a[j] * b[j];  // 0 when a window pixel is outside its image
    num[j] += w * e[j];
    den[j] += w;
  }
}

// The window sums of `count` consecutive pixels j of one disparity, from 0, adding the offsets k
// in `order`: row k of the weights a and b starts at k · stride, of the differences e at
// e_offset[k]. Offset by offset along the row, which streams through memory.
struct WindowSums {
  const float* a;
  const float* b;
  std::ptrdiff_t stride;
  const float* e;
  const std::ptrdiff_t* e_offset;
  const int* order;
  int num_k;
};

void SumWindows(const WindowSums& s, int count, double* num, double* den) {
  std::fill(num, num + count, 0.0);
  std::fill(den, den + count, 0.0);
  for (int o = 0; o < s.num_k; ++o) {
    const int k = s.order[o];
    AccumulateOffset(s.a + k * s.stride, s.b + k * s.stride, s.e + s.e_offset[k], num, den, count);
  }
}

cv::Mat ToLab(const cv::Mat& bgr) {
  cv::Mat bgr32, lab;
  bgr.convertTo(bgr32, CV_32FC3, 1.0 / 255.0);
  cv::cvtColor(bgr32, lab, cv::COLOR_BGR2Lab);
  return lab;
}

// The WTA, uniqueness and parabola vertex of pixel x's cost curve (costs[i · width + x]), written
// at column x of the given rows.
void FinishPixel(const double* costs, const bool* has_cost, int width, int x, int num_d, int dmin,
                 double* curve, bool* valid, int* wta, float* uniqueness, float* subpixel) {
  double best = std::numeric_limits<double>::infinity();
  int best_i = -1;
  for (int i = 0; i < num_d; ++i) {
    valid[i] = has_cost[static_cast<std::size_t>(i) * width + x];
    if (!valid[i]) continue;
    const double cost = costs[static_cast<std::size_t>(i) * width + x];
    curve[i] = cost;
    if (cost < best) {
      best = cost;
      best_i = i;
    }
  }
  if (best_i < 0) return;
  wta[x] = dmin + best_i;
  uniqueness[x] = UniquenessOfCurve(curve, valid, num_d, best_i);
  // Parabola through the costs at best − 1, best, best + 1 (vertex offset in [−½, ½]).
  float refined = static_cast<float>(dmin + best_i);
  if (best_i > 0 && best_i + 1 < num_d && valid[best_i - 1] && valid[best_i + 1]) {
    const double c_minus = curve[best_i - 1], c0 = curve[best_i], c_plus = curve[best_i + 1];
    const double curvature = c_minus - 2.0 * c0 + c_plus;
    if (curvature > 0.0) {
      refined += static_cast<float>(std::clamp(0.5 * (c_minus - c_plus) / curvature, -0.5, 0.5));
    }
  }
  subpixel[x] = refined;
}

}  // namespace

void AdaptiveWeightEvidence(const cv::Mat& left_bgr, const cv::Mat& right_bgr, int dmin, int dmax,
                            const StereoGcpOptions& options, StereoViewEvidence* left,
                            StereoViewEvidence* right) {
  const int width = left_bgr.cols;
  const int height = left_bgr.rows;
  const int num_d = dmax - dmin + 1;
  cv::Mat lab[2];
  lab[0] = ToLab(left_bgr);
  lab[1] = ToLab(right_bgr);

  // The window offsets, row by row, each row's columns ascending; the mirrored order takes each
  // row's columns descending (the column offsets are symmetric: −reach … reach).
  struct Offset {
    int dy, dx;
    float spatial;  // exp(−‖Δp‖ / γ_p)
  };
  std::vector<Offset> offsets;
  const int radius = options.aw_window_px / 2;
  const int stride = options.aw_stride_px;
  const int reach = (radius / stride) * stride;  // the largest |dy| and |dx| of the window
  const int side = 2 * (reach / stride) + 1;
  for (int dy = -reach; dy <= reach; dy += stride) {
    for (int dx = -reach; dx <= reach; dx += stride) {
      offsets.push_back(
          {dy, dx, static_cast<float>(std::exp(-std::hypot(dx, dy) / options.aw_gamma_p))});
    }
  }
  const int num_k = static_cast<int>(offsets.size());
  std::vector<int> order_left(num_k), order_right(num_k);
  for (int k = 0; k < num_k; ++k) {
    order_left[k] = k;
    order_right[k] = (k / side) * side + (side - 1 - k % side);
  }
  const float inv_gamma_c = static_cast<float>(1.0 / options.aw_gamma_c);

  // Truncated absolute differences e(x, d) = min(Σ_RGB |L(x) − R(x − d)|, T): image row r holds
  // the rows of every disparity (row r + reach, then disparity i, then image column c at c +
  // reach), so that the rows a window of image rows reads lie together. A border of zeros (−1
  // inside the image where x − d leaves it): a window reaching outside either image reads a
  // value there that its zero weight cancels.
  const int plane_width = width + 2 * reach;
  const std::ptrdiff_t row_stride = static_cast<std::ptrdiff_t>(num_d) * plane_width;
  // Tens of MB written whole at once: huge pages (core/huge_page_allocator.h).
  std::vector<float, HugePageAllocator<float>> tad(
      static_cast<std::size_t>(height + 2 * reach) * row_stride, 0.0f);
  const float truncation = static_cast<float>(options.aw_truncation);
  tbb::parallel_for(0, num_d, [&](int i) {
    const int d = dmin + i;
    for (int y = 0; y < height; ++y) {
      float* out =
          &tad[(y + reach) * row_stride + static_cast<std::ptrdiff_t>(i) * plane_width + reach];
      const cv::Vec3b* l = left_bgr.ptr<cv::Vec3b>(y);
      const cv::Vec3b* r = right_bgr.ptr<cv::Vec3b>(y);
      std::fill(out, out + std::min(width, std::max(0, d)), -1.0f);
      for (int x = std::max(0, d); x < width; ++x) {
        const int xr = x - d;
        const float e =
            static_cast<float>(std::abs(l[x][0] - r[xr][0]) + std::abs(l[x][1] - r[xr][1]) +
                               std::abs(l[x][2] - r[xr][2]));
        out[x] = std::min(e, truncation);
      }
    }
  });

  for (StereoViewEvidence* e : {left, right}) {
    e->wta_aw = cv::Mat(height, width, CV_32S, cv::Scalar(-1));
    e->uniqueness_aw = cv::Mat(height, width, CV_32F, cv::Scalar(0.0f));
    e->subpixel_aw =
        cv::Mat(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    // Support weights of a row, offset-major (w[k · width + x]), of the left and the right image:
    // for one disparity and offset the pixels of the row are consecutive in the weights of both
    // images and in the differences, so the innermost loop runs along the row (and vectorises).
    const std::ptrdiff_t row_length = width;
    std::vector<float> weights[2] = {std::vector<float>(num_k * row_length),
                                     std::vector<float>(num_k * row_length)};
    const float* w[2] = {weights[0].data(), weights[1].data()};
    std::vector<std::ptrdiff_t> e_offset(num_k);
    const std::size_t volume = static_cast<std::size_t>(num_d) * width;
    std::vector<double> costs[2] = {std::vector<double>(volume), std::vector<double>(volume)};
    std::unique_ptr<bool[]> has_cost[2] = {std::unique_ptr<bool[]>(new bool[volume]),
                                           std::unique_ptr<bool[]>(new bool[volume])};
    std::vector<double> numerator(width), denominator(width);
    std::vector<double> curve(num_d);
    std::unique_ptr<bool[]> valid(new bool[num_d]);
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int v = 0; v < 2; ++v) {
        const cv::Vec3f* centre = lab[v].ptr<cv::Vec3f>(y);
        for (int k = 0; k < num_k; ++k) {
          float* out = &weights[v][k * row_length];
          const int qy = y + offsets[k].dy;
          if (qy < 0 || qy >= height) {
            std::fill(out, out + width, 0.0f);
            continue;
          }
          const cv::Vec3f* q = lab[v].ptr<cv::Vec3f>(qy);
          for (int x = 0; x < width; ++x) {
            const int qx = x + offsets[k].dx;
            float weight = 0.0f;
            if (qx >= 0 && qx < width) {
              const cv::Vec3f diff = q[qx] - centre[x];
              weight = std::exp(-std::sqrt(diff.dot(diff)) * inv_gamma_c) * offsets[k].spatial;
            }
            out[x] = weight;
          }
        }
      }
      for (int k = 0; k < num_k; ++k) {
        e_offset[k] = (y + reach + offsets[k].dy) * row_stride + reach + offsets[k].dx;
      }
      std::fill(has_cost[0].get(), has_cost[0].get() + volume, false);
      std::fill(has_cost[1].get(), has_cost[1].get() + volume, false);
      for (int i = 0; i < num_d; ++i) {
        const int d = dmin + i;
        const int count = width - d;  // pixels whose partner lies in the other image
        if (count <= 0) continue;
        const float* e = &tad[static_cast<std::size_t>(i) * plane_width] + d;
        // Left pixel x = d + j against right pixel j; right pixel j against left pixel d + j.
        const WindowSums sums[2] = {
            {w[0] + d, w[1], row_length, e, e_offset.data(), order_left.data(), num_k},
            {w[1], w[0] + d, row_length, e, e_offset.data(), order_right.data(), num_k}};
        for (int v = 0; v < 2; ++v) {
          SumWindows(sums[v], count, numerator.data(), denominator.data());
          const int first = v == 0 ? d : 0;
          double* cost_row = &costs[v][static_cast<std::size_t>(i) * width + first];
          bool* has_row = &has_cost[v][static_cast<std::size_t>(i) * width + first];
          for (int j = 0; j < count; ++j) {
            has_row[j] = denominator[j] > 0.0;
            if (has_row[j]) cost_row[j] = numerator[j] / denominator[j];
          }
        }
      }
      for (int v = 0; v < 2; ++v) {
        StereoViewEvidence* out = v == 0 ? left : right;
        int* wta = out->wta_aw.ptr<int>(y);
        float* uniqueness = out->uniqueness_aw.ptr<float>(y);
        float* subpixel = out->subpixel_aw.ptr<float>(y);
        for (int x = 0; x < width; ++x) {
          FinishPixel(costs[v].data(), has_cost[v].get(), width, x, num_d, dmin, curve.data(),
                      valid.get(), wta, uniqueness, subpixel);
        }
      }
    }
  });
}

}  // namespace gcpstereo::gcp::internal
