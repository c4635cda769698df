// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "zncc_sweep.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "cost_internal.h"
#include "gcpstereo/cost/cost_filter.h"
#include "sweep_kernels.h"

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

// The scalar kernels over columns [begin, end); the AVX2 ones finish their rows with these.
void WarpColumns(const GreyImage& image, const WarpRow& row, int begin, int end,
                 std::int32_t* values, std::int32_t* squares, std::int32_t* products,
                 std::uint8_t* inside) {
  const float max_u = static_cast<float>(image.width) - 0.5f;
  const float max_v = static_cast<float>(image.height) - 0.5f;
  const float last_col = static_cast<float>(image.width - 1);
  const float last_row = static_cast<float>(image.height - 1);
  for (int c = begin; c < end; ++c) {
    const float x = static_cast<float>(row.first_col + c);
    const float w = row.aw + row.bw * x;
    const float inv_w = 1.0f / w;
    const float u = (row.ax + row.bx * x) * inv_w;
    const float v = (row.ay + row.by * x) * inv_w;
    const bool front = w > 0.0f;
    // max then min written as _mm256_max_ps / _mm256_min_ps compute them (a NaN gives 0).
    float uc = u > 0.0f ? u : 0.0f;
    float vc = v > 0.0f ? v : 0.0f;
    uc = front ? (uc < last_col ? uc : last_col) : 0.0f;
    vc = front ? (vc < last_row ? vc : last_row) : 0.0f;
    const int x0 = static_cast<int>(uc);
    const int y0 = static_cast<int>(vc);
    const float fu = uc - static_cast<float>(x0);
    const float fv = vc - static_cast<float>(y0);
    const float* p = &image.pixels[static_cast<std::size_t>(y0) * image.stride + x0];
    const float top = p[0] + (p[1] - p[0]) * fu;
    const float bottom = p[image.stride] + (p[image.stride + 1] - p[image.stride]) * fu;
    const float value = front ? top + (bottom - top) * fv : 0.0f;
    // Nearest level (value >= 0; not std::lround, a library call per sample).
    const std::int32_t q = static_cast<std::int32_t>(value * static_cast<float>(kZnccScale) + 0.5f);
    values[c] = q;
    squares[c] = q * q;
    products[c] = row.reference[c] * q;
    inside[c] = (front && u >= -0.5f && u < max_u && v >= -0.5f && v < max_v) ? 1 : 0;
  }
}

std::int64_t ZnccColumns(const ZnccRow& row, int begin, int end, float* sum, float* votes,
                         float* costs) {
  std::int64_t count = 0;
  for (int c = begin; c < end; ++c) {
    const double sn = row.sums[c];
    const double var = (row.n * row.square_sums[c] - sn * sn) + row.floor;
    const double cov = row.n * row.product_sums[c] - row.ref_sum[c] * sn;
    const double rho = cov / std::sqrt(row.ref_var[c] * var);
    double t = 1.0 - rho;
    t = t > 0.0 ? t : 0.0;
    t = t < 1.0 ? t : 1.0;
    if (row.ref_flat != nullptr) {
      const double w = row.ref_flat[c];
      double m = std::abs(row.ref_sum[c] - sn) * row.mean_scale;
      m = m < 1.0 ? m : 1.0;
      t = (1.0 - w) * t + w * m;
    }
    const float cost = row.truncation * static_cast<float>(t);
    if (!row.inside[c]) {
      if (costs != nullptr) costs[c] = kNoVote;
      continue;
    }
    ++count;
    if (costs != nullptr) {
      costs[c] = cost;
    } else {
      sum[c] += cost;
    }
    votes[c] += 1.0f;
  }
  return count;
}

}  // namespace

void WarpRowScalar(const GreyImage& image, const WarpRow& row, std::int32_t* values,
                   std::int32_t* squares, std::int32_t* products, std::uint8_t* inside) {
  WarpColumns(image, row, 0, row.count, values, squares, products, inside);
}

std::int64_t ZnccRowScalar(const ZnccRow& row, float* sum, float* votes, float* costs) {
  return ZnccColumns(row, 0, row.count, sum, votes, costs);
}

#if GCPSTEREO_AVX2_KERNELS

namespace {

// Four columns of ZnccRow in double: min(max(1 − ρ, 0), 1) as floats.
__attribute__((target("avx2"), always_inline)) inline __m128 OneMinusRho4(const ZnccRow& row,
                                                                          int c) {
  const __m256d n = _mm256_set1_pd(row.n);
  auto load = [](const std::int32_t* p) __attribute__((always_inline)) {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  };
  const __m256d sn = _mm256_cvtepi32_pd(load(row.sums + c));
  const __m256d snn = _mm256_cvtepi32_pd(load(row.square_sums + c));
  const __m256d srn = _mm256_cvtepi32_pd(load(row.product_sums + c));
  const __m256d var = _mm256_add_pd(_mm256_sub_pd(_mm256_mul_pd(n, snn), _mm256_mul_pd(sn, sn)),
                                    _mm256_set1_pd(row.floor));
  const __m256d cov =
      _mm256_sub_pd(_mm256_mul_pd(n, srn), _mm256_mul_pd(_mm256_loadu_pd(row.ref_sum + c), sn));
  const __m256d rho =
      _mm256_div_pd(cov, _mm256_sqrt_pd(_mm256_mul_pd(_mm256_loadu_pd(row.ref_var + c), var)));
  const __m256d one = _mm256_set1_pd(1.0);
  __m256d t = _mm256_min_pd(_mm256_max_pd(_mm256_sub_pd(one, rho), _mm256_setzero_pd()), one);
  if (row.ref_flat != nullptr) {
    const __m256d w = _mm256_loadu_pd(row.ref_flat + c);
    const __m256d difference = _mm256_sub_pd(_mm256_loadu_pd(row.ref_sum + c), sn);
    const __m256d magnitude = _mm256_andnot_pd(_mm256_set1_pd(-0.0), difference);
    const __m256d m = _mm256_min_pd(_mm256_mul_pd(magnitude, _mm256_set1_pd(row.mean_scale)), one);
    t = _mm256_add_pd(_mm256_mul_pd(_mm256_sub_pd(one, w), t), _mm256_mul_pd(w, m));
  }
  return _mm256_cvtpd_ps(t);
}

}  // namespace

__attribute__((target("avx2"))) void WarpRowAvx2(const GreyImage& image, const WarpRow& row,
                                                 std::int32_t* values, std::int32_t* squares,
                                                 std::int32_t* products, std::uint8_t* inside) {
  const __m256 max_u = _mm256_set1_ps(static_cast<float>(image.width) - 0.5f);
  const __m256 max_v = _mm256_set1_ps(static_cast<float>(image.height) - 0.5f);
  const __m256 last_col = _mm256_set1_ps(static_cast<float>(image.width - 1));
  const __m256 last_row = _mm256_set1_ps(static_cast<float>(image.height - 1));
  const __m256 minus_half = _mm256_set1_ps(-0.5f);
  const __m256 zero = _mm256_setzero_ps();
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 half = _mm256_set1_ps(0.5f);
  const __m256 scale = _mm256_set1_ps(static_cast<float>(kZnccScale));
  const __m256 ax = _mm256_set1_ps(row.ax), ay = _mm256_set1_ps(row.ay);
  const __m256 aw = _mm256_set1_ps(row.aw), bx = _mm256_set1_ps(row.bx);
  const __m256 by = _mm256_set1_ps(row.by), bw = _mm256_set1_ps(row.bw);
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i stride = _mm256_set1_epi32(image.stride);
  const float* base = image.pixels.data();
  int c = 0;
  for (; c + 8 <= row.count; c += 8) {
    const __m256 x =
        _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(row.first_col + c), lane));
    const __m256 w = _mm256_add_ps(aw, _mm256_mul_ps(bw, x));
    const __m256 inv_w = _mm256_div_ps(one, w);
    const __m256 u = _mm256_mul_ps(_mm256_add_ps(ax, _mm256_mul_ps(bx, x)), inv_w);
    const __m256 v = _mm256_mul_ps(_mm256_add_ps(ay, _mm256_mul_ps(by, x)), inv_w);
    const __m256 front = _mm256_cmp_ps(w, zero, _CMP_GT_OQ);
    const __m256 in =
        _mm256_and_ps(front, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(u, minus_half, _CMP_GE_OQ),
                                                         _mm256_cmp_ps(u, max_u, _CMP_LT_OQ)),
                                           _mm256_and_ps(_mm256_cmp_ps(v, minus_half, _CMP_GE_OQ),
                                                         _mm256_cmp_ps(v, max_v, _CMP_LT_OQ))));
    const __m256 uc = _mm256_and_ps(_mm256_min_ps(_mm256_max_ps(u, zero), last_col), front);
    const __m256 vc = _mm256_and_ps(_mm256_min_ps(_mm256_max_ps(v, zero), last_row), front);
    const __m256i iu = _mm256_cvttps_epi32(uc);
    const __m256i iv = _mm256_cvttps_epi32(vc);
    const __m256 fu = _mm256_sub_ps(uc, _mm256_cvtepi32_ps(iu));
    const __m256 fv = _mm256_sub_ps(vc, _mm256_cvtepi32_ps(iv));
    const __m256i index = _mm256_add_epi32(_mm256_mullo_epi32(iv, stride), iu);
    // Four taps by scalar loads: faster than vgatherdps where the CPU's gather is microcoded.
    alignas(32) std::int32_t at[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(at), index);
    alignas(32) float t00[8], t01[8], t10[8], t11[8];
    for (int j = 0; j < 8; ++j) {
      const float* p = base + at[j];
      t00[j] = p[0];
      t01[j] = p[1];
      t10[j] = p[image.stride];
      t11[j] = p[image.stride + 1];
    }
    const __m256 p00 = _mm256_load_ps(t00);
    const __m256 p01 = _mm256_load_ps(t01);
    const __m256 p10 = _mm256_load_ps(t10);
    const __m256 p11 = _mm256_load_ps(t11);
    const __m256 top = _mm256_add_ps(p00, _mm256_mul_ps(_mm256_sub_ps(p01, p00), fu));
    const __m256 bottom = _mm256_add_ps(p10, _mm256_mul_ps(_mm256_sub_ps(p11, p10), fu));
    const __m256 value =
        _mm256_and_ps(_mm256_add_ps(top, _mm256_mul_ps(_mm256_sub_ps(bottom, top), fv)), front);
    const __m256i q = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(value, scale), half));
    const __m256i ref = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row.reference + c));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(values + c), q);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(squares + c), _mm256_mullo_epi32(q, q));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(products + c), _mm256_mullo_epi32(ref, q));
    const unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(in));
    for (int j = 0; j < 8; ++j) inside[c + j] = static_cast<std::uint8_t>((bits >> j) & 1u);
  }
  WarpColumns(image, row, c, row.count, values, squares, products, inside);
}

__attribute__((target("avx2"))) std::int64_t ZnccRowAvx2(const ZnccRow& row, float* sum,
                                                         float* votes, float* costs) {
  const __m256 truncation = _mm256_set1_ps(row.truncation);
  const __m256 ones = _mm256_set1_ps(1.0f);
  const __m256 infinity = _mm256_set1_ps(kNoVote);
  std::int64_t count = 0;
  int c = 0;
  for (; c + 8 <= row.count; c += 8) {
    const __m128i in_bytes = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(row.inside + c));
    const __m256 in = _mm256_castsi256_ps(
        _mm256_cmpgt_epi32(_mm256_cvtepu8_epi32(in_bytes), _mm256_setzero_si256()));
    const int bits = _mm256_movemask_ps(in);
    if (bits == 0) {
      if (costs != nullptr) _mm256_storeu_ps(costs + c, infinity);
      continue;
    }
    const __m256 cost =
        _mm256_mul_ps(truncation, _mm256_set_m128(OneMinusRho4(row, c + 4), OneMinusRho4(row, c)));
    count += __builtin_popcount(static_cast<unsigned>(bits));
    if (costs != nullptr) {
      _mm256_storeu_ps(costs + c, _mm256_blendv_ps(infinity, cost, in));
    } else {
      _mm256_storeu_ps(sum + c, _mm256_add_ps(_mm256_loadu_ps(sum + c), _mm256_and_ps(cost, in)));
    }
    _mm256_storeu_ps(votes + c, _mm256_add_ps(_mm256_loadu_ps(votes + c), _mm256_and_ps(ones, in)));
  }
  return count + ZnccColumns(row, c, row.count, sum, votes, costs);
}

#else

void WarpRowAvx2(const GreyImage& image, const WarpRow& row, std::int32_t* values,
                 std::int32_t* squares, std::int32_t* products, std::uint8_t* inside) {
  WarpRowScalar(image, row, values, squares, products, inside);
}
std::int64_t ZnccRowAvx2(const ZnccRow& row, float* sum, float* votes, float* costs) {
  return ZnccRowScalar(row, sum, votes, costs);
}

#endif

namespace {

// Σ over the window around every pixel of `roi`, reading the parent matrix beyond the ROI and
// replicating the parent's border: exact (integer running sums).
void WindowSums(const cv::Mat& roi, int window_px, cv::Mat* sums) {
  cv::boxFilter(roi, *sums, CV_32S, cv::Size(window_px, window_px), cv::Point(-1, -1),
                /*normalize=*/false, cv::BORDER_REPLICATE);
}

// Rows of the region processed at a time: the warps, window sums and costs of a strip stay in the
// cache for all neighbours (a whole region's planes per label and neighbour made the sweep wait on
// memory); each strip warps `radius` rows above and below it again.
constexpr int kStripRows = 64;

// Scratch of one thread for a strip of kStripRows region rows of width `width` (the grown region
// `outer` is `outer_width` wide), plus the whole region's aggregation buffers.
struct LabelScratch {
  LabelScratch(int outer_width, int width, int radius, int area, int num_neighbors, bool best_k)
      : strip_values(static_cast<std::size_t>(kStripRows + 2 * radius) * outer_width),
        strip_squares(strip_values.size()),
        strip_products(strip_values.size()),
        inside(strip_values.size()),
        sums(static_cast<std::size_t>(kStripRows) * width),
        square_sums(sums.size()),
        product_sums(sums.size()),
        sum(static_cast<std::size_t>(area)),
        votes(static_cast<std::size_t>(area)),
        per_neighbor(best_k ? static_cast<std::size_t>(area) * num_neighbors : 0) {}
  std::vector<std::int32_t> strip_values, strip_squares, strip_products;  // [row][outer column]
  std::vector<std::uint8_t> inside;  // strip pixels whose centre sample the neighbour sees
  std::vector<std::int32_t> sums, square_sums, product_sums;  // [row][region column]
  std::vector<float> sum, votes;
  std::vector<float> per_neighbor;     // best_k: [neighbour][pixel], +inf = no vote
  std::vector<std::uint16_t> encoded;  // a block's labels, [label][pixel]
};

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
  const cv::Mat ref_value_squares = ref_values.mul(ref_values);
  cv::Mat ref_sums, ref_square_sums;
  WindowSums(ref_values(local), params.window_px, &ref_sums);
  WindowSums(ref_value_squares(local), params.window_px, &ref_square_sums);
  std::vector<double> ref_sum(static_cast<std::size_t>(area));
  std::vector<double> ref_var(static_cast<std::size_t>(area));  // var' + ε
  const bool flat_fallback = params.flat_truncation > 0.0f;
  std::vector<double> ref_flat(flat_fallback ? static_cast<std::size_t>(area) : 0);  // ε' / var
  for (int r = 0; r < region.height; ++r) {
    for (int c = 0; c < region.width; ++c) {
      const double s = ref_sums.at<std::int32_t>(r, c);
      const std::size_t i = static_cast<std::size_t>(r) * region.width + c;
      ref_sum[i] = s;
      ref_var[i] = n * ref_square_sums.at<std::int32_t>(r, c) - s * s + floor;
      if (flat_fallback) ref_flat[i] = floor / ref_var[i];
    }
  }

  CostVolume volume(region, num_labels, truncation);
  const float inv_step = 1.0f / volume.cost_step();
  const float min_votes = static_cast<float>(params.min_voters);
  const bool avx2 = HaveAvx2Kernel();
  std::atomic<std::int64_t> total_votes{0};
  std::atomic<std::int64_t> total_no_data{0};

  // One label: every neighbour's ZNCC, aggregated and encoded into `encoded` (one per pixel).
  auto compute_label = [&](int l, LabelScratch& s, std::uint16_t* encoded) {
    std::fill(s.sum.begin(), s.sum.end(), 0.0f);
    std::fill(s.votes.begin(), s.votes.end(), 0.0f);
    std::int64_t votes = 0;
    WarpRow warp;
    warp.first_col = outer.x;
    warp.count = outer.width;
    ZnccRow row;
    row.count = region.width;
    row.n = n;
    row.floor = floor;
    row.truncation = truncation;
    row.ref_flat = nullptr;
    row.mean_scale = flat_fallback ? 1.0 / (n * kZnccScale * params.flat_truncation) : 0.0;
    for (int y0 = 0; y0 < region.height; y0 += kStripRows) {
      const int y1 = std::min(region.height, y0 + kStripRows);
      // The strip's rows of `outer` with the window's reach (outer-local, clipped to `outer`).
      const int lo = std::max(0, local.y + y0 - radius);
      const int hi = std::min(outer.height, local.y + y1 + radius);
      // Headers over the scratch that end where the strip ends, so that boxFilter replicates
      // the border there (only at an edge of `outer`, which is the image's or `radius` away).
      auto strip = [&](std::vector<std::int32_t>& data) {
        return cv::Mat(hi - lo, outer.width, CV_32S, data.data());
      };
      auto sums = [&](std::vector<std::int32_t>& data) {
        return cv::Mat(y1 - y0, region.width, CV_32S, data.data());
      };
      const cv::Rect in_strip(local.x, local.y + y0 - lo, region.width, y1 - y0);
      for (int nb = 0; nb < num_neighbors; ++nb) {
        const Eigen::Matrix3d& h = homographies[static_cast<std::size_t>(l) * num_neighbors + nb];
        warp.bx = static_cast<float>(h(0, 0));
        warp.by = static_cast<float>(h(1, 0));
        warp.bw = static_cast<float>(h(2, 0));
        for (int r = lo; r < hi; ++r) {
          const int y = outer.y + r;
          warp.ax = static_cast<float>(h(0, 1) * y + h(0, 2));
          warp.ay = static_cast<float>(h(1, 1) * y + h(1, 2));
          warp.aw = static_cast<float>(h(2, 1) * y + h(2, 2));
          warp.reference = ref_values.ptr<std::int32_t>(r);
          const std::size_t at = static_cast<std::size_t>(r - lo) * outer.width;
          (avx2 ? WarpRowAvx2 : WarpRowScalar)(neighbors[nb], warp, &s.strip_values[at],
                                               &s.strip_squares[at], &s.strip_products[at],
                                               &s.inside[at]);
        }
        cv::Mat window_sums = sums(s.sums), window_square_sums = sums(s.square_sums),
                window_product_sums = sums(s.product_sums);
        WindowSums(strip(s.strip_values)(in_strip), params.window_px, &window_sums);
        WindowSums(strip(s.strip_squares)(in_strip), params.window_px, &window_square_sums);
        WindowSums(strip(s.strip_products)(in_strip), params.window_px, &window_product_sums);
        float* costs =
            params.best_k ? &s.per_neighbor[static_cast<std::size_t>(nb) * area] : nullptr;
        for (int r = y0; r < y1; ++r) {
          const std::size_t i = static_cast<std::size_t>(r) * region.width;
          row.sums = window_sums.ptr<std::int32_t>(r - y0);
          row.square_sums = window_square_sums.ptr<std::int32_t>(r - y0);
          row.product_sums = window_product_sums.ptr<std::int32_t>(r - y0);
          row.ref_sum = &ref_sum[i];
          row.ref_var = &ref_var[i];
          row.ref_flat = flat_fallback ? &ref_flat[i] : nullptr;
          row.inside =
              &s.inside[static_cast<std::size_t>(local.y + r - lo) * outer.width + local.x];
          votes += (avx2 ? ZnccRowAvx2 : ZnccRowScalar)(row, params.best_k ? nullptr : &s.sum[i],
                                                        &s.votes[i],
                                                        costs != nullptr ? costs + i : nullptr);
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
  // One scratch per thread, reused by its blocks (allocating it per block cost page faults).
  tbb::enumerable_thread_specific<LabelScratch> scratches(outer.width, region.width, radius, area,
                                                          num_neighbors, params.best_k);
  bool cancelled = false;
  for (int b0 = 0; b0 < num_blocks && !cancelled; b0 += blocks_per_chunk) {
    const int b1 = std::min(num_blocks, b0 + blocks_per_chunk);
    tbb::parallel_for(b0, b1, [&](int block) {
      LabelScratch& scratch = scratches.local();
      const int l0 = block * kBlock;
      const int count = std::min(kBlock, num_labels - l0);
      std::vector<std::uint16_t>& encoded = scratch.encoded;
      encoded.resize(static_cast<std::size_t>(area) * kBlock);
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
