// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "zncc_sweep.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "cost_internal.h"
#include "gcpstereo/cost/cost_filter.h"

namespace gcpstereo::cost::internal {

GreyImage MakeGreyImage(const cv::Mat& bgr) {
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  GreyImage out;
  out.width = grey.cols;
  out.height = grey.rows;
  out.stride = grey.cols + 1;
  out.pixels.resize(static_cast<std::size_t>(out.stride) * (grey.rows + 1));
  for (int row = 0; row <= grey.rows; ++row) {
    const std::uint8_t* src = grey.ptr<std::uint8_t>(std::min(row, grey.rows - 1));
    float* dst = &out.pixels[static_cast<std::size_t>(row) * out.stride];
    for (int col = 0; col <= grey.cols; ++col) dst[col] = src[std::min(col, grey.cols - 1)];
  }
  return out;
}

namespace {

constexpr float kNoVote = std::numeric_limits<float>::infinity();

// Σ over the window around every pixel, the border replicated: exact (integer running sums).
cv::Mat WindowSums(const cv::Mat& values, int window_px) {
  cv::Mat sums;
  cv::boxFilter(values, sums, CV_32S, cv::Size(window_px, window_px), cv::Point(-1, -1),
                /*normalize=*/false, cv::BORDER_REPLICATE);
  return sums;
}

// Scratch of one label task, sized to the grown region `outer`.
struct LabelScratch {
  LabelScratch(const cv::Size& outer, int area, int num_neighbors, bool best_k)
      : warped(outer, CV_32S),
        squares(outer, CV_32S),
        products(outer, CV_32S),
        inside(static_cast<std::size_t>(area)),
        sum(static_cast<std::size_t>(area)),
        votes(static_cast<std::size_t>(area)),
        per_neighbor(best_k ? static_cast<std::size_t>(area) * num_neighbors : 0) {}
  cv::Mat warped, squares, products;
  std::vector<std::uint8_t> inside;  // region pixels whose centre sample the neighbour sees
  std::vector<float> sum, votes;
  std::vector<float> per_neighbor;  // best_k: [neighbour][pixel], +inf = no vote
};

// Samples the neighbour's grey image at H p for every pixel p of `outer` (absolute coordinates,
// in units of 1/kZnccScale grey level, bilinear, the border replicated) and marks the pixels of
// `region` whose sample lies inside the image on the plane's front side (the RGB sweep's rule,
// sweep_kernels.h).
std::int64_t Warp(const GreyImage& image, const Eigen::Matrix3d& h, const cv::Rect& outer,
                  const cv::Rect& region, LabelScratch* s) {
  const float max_u = static_cast<float>(image.width) - 0.5f;
  const float max_v = static_cast<float>(image.height) - 0.5f;
  const float last_col = static_cast<float>(image.width - 1);
  const float last_row = static_cast<float>(image.height - 1);
  std::int64_t votes = 0;
  for (int r = 0; r < outer.height; ++r) {
    const int y = outer.y + r;
    const float ax = static_cast<float>(h(0, 1) * y + h(0, 2));
    const float ay = static_cast<float>(h(1, 1) * y + h(1, 2));
    const float aw = static_cast<float>(h(2, 1) * y + h(2, 2));
    const float bx = static_cast<float>(h(0, 0));
    const float by = static_cast<float>(h(1, 0));
    const float bw = static_cast<float>(h(2, 0));
    std::int32_t* out = s->warped.ptr<std::int32_t>(r);
    const bool region_row = y >= region.y && y < region.y + region.height;
    std::uint8_t* inside =
        region_row ? &s->inside[static_cast<std::size_t>(y - region.y) * region.width] : nullptr;
    for (int c = 0; c < outer.width; ++c) {
      const int x = outer.x + c;
      const float w = aw + bw * static_cast<float>(x);
      bool in = false;
      float value = 0.0f;
      if (w > 0.0f) {
        const float inv_w = 1.0f / w;
        const float u = (ax + bx * static_cast<float>(x)) * inv_w;
        const float v = (ay + by * static_cast<float>(x)) * inv_w;
        in = u >= -0.5f && u < max_u && v >= -0.5f && v < max_v;
        const float uc = std::clamp(u, 0.0f, last_col);
        const float vc = std::clamp(v, 0.0f, last_row);
        const int x0 = static_cast<int>(uc);
        const int y0 = static_cast<int>(vc);
        const float fu = uc - static_cast<float>(x0);
        const float fv = vc - static_cast<float>(y0);
        const float* p = &image.pixels[static_cast<std::size_t>(y0) * image.stride + x0];
        const float top = p[0] + (p[1] - p[0]) * fu;
        const float bottom = p[image.stride] + (p[image.stride + 1] - p[image.stride]) * fu;
        value = top + (bottom - top) * fv;
      }
      // Nearest level (value >= 0; not std::lround, a library call per sample).
      out[c] = static_cast<std::int32_t>(value * static_cast<float>(kZnccScale) + 0.5f);
      if (inside != nullptr && x >= region.x && x < region.x + region.width) {
        inside[x - region.x] = in ? 1 : 0;
        votes += in ? 1 : 0;
      }
    }
  }
  return votes;
}

}  // namespace

CostVolume ZnccSweep(const cv::Mat& reference_bgr, const std::vector<GreyImage>& neighbors,
                     const std::vector<Eigen::Matrix3d>& homographies, int num_labels,
                     const cv::Rect& region, const ZnccSweepParams& params,
                     const ProgressCallback& progress, ZnccSweepCounts* counts) {
  const int radius = params.window_px / 2;
  const cv::Rect outer = GrowRegion(region, radius, reference_bgr.size());
  const cv::Rect local(region.x - outer.x, region.y - outer.y, region.width, region.height);
  const int area = region.area();
  const int num_neighbors = static_cast<int>(neighbors.size());
  const double n = static_cast<double>(params.window_px) * params.window_px;
  // var' = n·Σx² − (Σx)² = n²·σ²·kZnccScale², so the floor ε scales alike.
  const double floor = n * n * kZnccScale * kZnccScale * kZnccVarianceFloor;
  const float truncation = params.truncation;

  // The reference's window sums, once.
  cv::Mat ref_grey;
  cv::cvtColor(reference_bgr(outer), ref_grey, cv::COLOR_BGR2GRAY);
  cv::Mat ref_values;
  ref_grey.convertTo(ref_values, CV_32S, kZnccScale);
  const cv::Mat ref_sums = WindowSums(ref_values, params.window_px)(local);
  const cv::Mat ref_square_sums = WindowSums(ref_values.mul(ref_values), params.window_px)(local);
  std::vector<double> ref_sum(static_cast<std::size_t>(area));
  std::vector<double> ref_var(static_cast<std::size_t>(area));  // var' + ε
  for (int r = 0; r < region.height; ++r) {
    for (int c = 0; c < region.width; ++c) {
      const double s = ref_sums.at<std::int32_t>(r, c);
      const std::size_t i = static_cast<std::size_t>(r) * region.width + c;
      ref_sum[i] = s;
      ref_var[i] = n * ref_square_sums.at<std::int32_t>(r, c) - s * s + floor;
    }
  }

  CostVolume volume(region, num_labels, truncation);
  const float inv_step = 1.0f / volume.cost_step();
  const float min_votes = static_cast<float>(params.min_voters);
  std::atomic<std::int64_t> total_votes{0};
  std::atomic<std::int64_t> total_no_data{0};

  // One label: every neighbour's ZNCC, aggregated and encoded into `encoded` (one per pixel).
  auto compute_label = [&](int l, LabelScratch& s, std::uint16_t* encoded) {
    std::fill(s.sum.begin(), s.sum.end(), 0.0f);
    std::fill(s.votes.begin(), s.votes.end(), 0.0f);
    std::int64_t votes = 0;
    for (int nb = 0; nb < num_neighbors; ++nb) {
      votes += Warp(neighbors[nb], homographies[static_cast<std::size_t>(l) * num_neighbors + nb],
                    outer, region, &s);
      cv::multiply(s.warped, s.warped, s.squares);
      cv::multiply(ref_values, s.warped, s.products);
      const cv::Mat sums = WindowSums(s.warped, params.window_px)(local);
      const cv::Mat square_sums = WindowSums(s.squares, params.window_px)(local);
      const cv::Mat product_sums = WindowSums(s.products, params.window_px)(local);
      float* costs = params.best_k ? &s.per_neighbor[static_cast<std::size_t>(nb) * area] : nullptr;
      for (int r = 0; r < region.height; ++r) {
        const std::int32_t* sn = sums.ptr<std::int32_t>(r);
        const std::int32_t* snn = square_sums.ptr<std::int32_t>(r);
        const std::int32_t* srn = product_sums.ptr<std::int32_t>(r);
        for (int c = 0; c < region.width; ++c) {
          const std::size_t i = static_cast<std::size_t>(r) * region.width + c;
          if (!s.inside[i]) {
            if (costs != nullptr) costs[i] = kNoVote;
            continue;
          }
          const double var_n = n * snn[c] - static_cast<double>(sn[c]) * sn[c] + floor;
          const double cov = n * srn[c] - ref_sum[i] * sn[c];
          const double rho = cov / std::sqrt(ref_var[i] * var_n);
          const float cost = truncation * static_cast<float>(std::clamp(1.0 - rho, 0.0, 1.0));
          if (costs != nullptr) {
            costs[i] = cost;
          } else {
            s.sum[i] += cost;
          }
          s.votes[i] += 1.0f;
        }
      }
    }
    if (params.best_k) {
      MeanOfBestK(s.per_neighbor, num_neighbors, area, params.k, s.votes.data(), s.sum.data());
    }
    std::int64_t no_data = 0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(area); ++i) {
      const bool has_data = s.votes[i] >= min_votes;
      const float value = params.best_k ? s.sum[i] : (has_data ? s.sum[i] / s.votes[i] : 0.0f);
      no_data += has_data ? 0 : 1;
      encoded[i] = has_data ? Quantise(value, inv_step) : CostVolume::kNoData;
    }
    total_votes += votes;
    total_no_data += no_data;
  };

  // Labels in blocks of kBlock per task (encoded per label, then interleaved into the
  // label-fastest volume); blocks in parallel, progress between chunks of blocks.
  constexpr int kBlock = 8;
  const int num_blocks = (num_labels + kBlock - 1) / kBlock;
  const int blocks_per_chunk = std::max(1, params.progress_labels / kBlock);
  bool cancelled = false;
  for (int b0 = 0; b0 < num_blocks && !cancelled; b0 += blocks_per_chunk) {
    const int b1 = std::min(num_blocks, b0 + blocks_per_chunk);
    tbb::parallel_for(b0, b1, [&](int block) {
      LabelScratch scratch(outer.size(), area, num_neighbors, params.best_k);
      const int l0 = block * kBlock;
      const int count = std::min(kBlock, num_labels - l0);
      std::vector<std::uint16_t> encoded(static_cast<std::size_t>(area) * count);
      for (int j = 0; j < count; ++j) {
        compute_label(l0 + j, scratch, &encoded[static_cast<std::size_t>(j) * area]);
      }
      for (int r = 0; r < region.height; ++r) {
        for (int c = 0; c < region.width; ++c) {
          const std::size_t i = static_cast<std::size_t>(r) * region.width + c;
          std::uint16_t* dst = volume.MutablePixelData(r, c) + l0;
          for (int j = 0; j < count; ++j) dst[j] = encoded[static_cast<std::size_t>(j) * area + i];
        }
      }
    });
    const int labels_done = std::min(num_labels, b1 * kBlock);
    if (progress && !progress(static_cast<double>(labels_done) / num_labels) &&
        labels_done < num_labels) {
      cancelled = true;
      for (int r = 0; r < region.height; ++r) {
        for (int c = 0; c < region.width; ++c) {
          std::uint16_t* dst = volume.MutablePixelData(r, c);
          std::fill(dst + labels_done, dst + num_labels, CostVolume::kNoData);
        }
      }
      total_no_data += static_cast<std::int64_t>(area) * (num_labels - labels_done);
    }
  }
  if (counts != nullptr) {
    counts->votes = total_votes.load();
    counts->no_data = total_no_data.load();
    counts->cancelled = cancelled;
  }
  return volume;
}

}  // namespace gcpstereo::cost::internal
