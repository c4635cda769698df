// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/cost_filter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cost_internal.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::cost {

void CostFilterOptions::Check(const std::string& key_prefix) const {
  if (window_px < 1 || window_px > 101 || window_px % 2 == 0) {
    throw ConfigError(ViolatedConstraint(key_prefix + "window_px", internal::Str(window_px),
                                         "odd and 1 <= window_px <= 101"));
  }
  if (filter != "box" && filter != "guided") {
    throw ConfigError(
        ViolatedConstraint(key_prefix + "window_filter", filter, "one of box, guided"));
  }
  if (!(guided_epsilon > 0.0) || !std::isfinite(guided_epsilon)) {
    throw ConfigError(ViolatedConstraint(
        key_prefix + "guided_epsilon", internal::Str(guided_epsilon), "0 < guided_epsilon < inf"));
  }
}

int CostFilterOptions::MarginPx() const {
  const int radius = (window_px - 1) / 2;
  return filter == "guided" ? 2 * radius : radius;
}

cv::Rect GrowRegion(const cv::Rect& region, int margin_px, const cv::Size& image_size) {
  const cv::Rect grown(region.x - margin_px, region.y - margin_px, region.width + 2 * margin_px,
                       region.height + 2 * margin_px);
  return grown & cv::Rect(0, 0, image_size.width, image_size.height);
}

namespace internal {

void BandsNear(const LabelBands& bands, const cv::Rect& band_region, int y, int x0, int n,
               int margin, int* lo, int* hi) {
  std::fill(lo, lo + n, std::numeric_limits<int>::max());
  std::fill(hi, hi + n, std::numeric_limits<int>::min());
  const int block = bands.block_px;
  const int ry0 = std::max(y - margin - band_region.y, 0);
  const int ry1 = std::min(y + margin - band_region.y, band_region.height - 1);
  if (ry0 > ry1) return;
  // The hull over the block rows in reach, per block column, then over the block columns.
  const int num_bx = bands.lo.cols;
  std::vector<int> column_lo(num_bx, std::numeric_limits<int>::max());
  std::vector<int> column_hi(num_bx, std::numeric_limits<int>::min());
  for (int by = ry0 / block; by <= ry1 / block; ++by) {
    const int* l = bands.lo.ptr<int>(by);
    const int* h = bands.hi.ptr<int>(by);
    for (int bx = 0; bx < num_bx; ++bx) {
      if (l[bx] > h[bx]) continue;
      column_lo[bx] = std::min(column_lo[bx], l[bx]);
      column_hi[bx] = std::max(column_hi[bx], h[bx]);
    }
  }
  for (int c = 0; c < n; ++c) {
    const int rx0 = std::max(x0 + c - margin - band_region.x, 0);
    const int rx1 = std::min(x0 + c + margin - band_region.x, band_region.width - 1);
    for (int bx = rx0 / block; rx0 <= rx1 && bx <= rx1 / block; ++bx) {
      lo[c] = std::min(lo[c], column_lo[bx]);
      hi[c] = std::max(hi[c], column_hi[bx]);
    }
  }
}

}  // namespace internal

namespace {

#if defined(__GNUC__) && defined(__x86_64__)
#define GCPSTEREO_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define GCPSTEREO_AVX2_CLONE
#endif
// Lambdas inside a cloned function are not cloned with it: inlined, they take the clone's target.
#if defined(__GNUC__)
#define GCPSTEREO_INLINE __attribute__((always_inline))
#else
#define GCPSTEREO_INLINE
#endif

// Labels filtered together: a pixel's kLanes entries sit side by side (one AVX2 register of
// doubles), so every step below is one vector operation per pixel.
constexpr int kLanes = 4;
// The coefficients a, b of the guided filter are summed as integer multiples of 2^-20 (rounded to
// nearest; at most 5e-7 off, against a cost step of max_cost / 65534): integers far below 2^53
// add exactly in double, so running window sums give the same bits whatever row or column they
// start from. A tile's result is then bit for bit the same pixels' result on the whole image.
constexpr double kCoefficientScale = 1048576.0;  // 2^20
// Four lanes of doubles (GCC's vector extension: one AVX2 register, two SSE2 ones), kept in
// std::vector<double> buffers (LaneBuffer): aligned like a double and allowed to alias it, as
// GCC's own unaligned AVX type is (a std::vector of the plain 32-byte aligned vector type was
// handed a 16-byte aligned buffer here and faulted).
using Lanes = double __attribute__((vector_size(kLanes * sizeof(double)), aligned(sizeof(double)),
                                    may_alias));

// `size` Lanes, zeroed.
class LaneBuffer {
 public:
  explicit LaneBuffer(std::size_t size) : data_(size * kLanes, 0.0) {}
  Lanes* data() { return reinterpret_cast<Lanes*>(data_.data()); }
  const Lanes* data() const { return reinterpret_cast<const Lanes*>(data_.data()); }
  Lanes& operator[](std::size_t i) { return data()[i]; }

 private:
  std::vector<double> data_;
};
using FloatLanes = float __attribute__((vector_size(kLanes * sizeof(float))));
using IntLanes = std::int32_t __attribute__((vector_size(kLanes * sizeof(std::int32_t))));
using ShortLanes = std::uint16_t __attribute__((vector_size(kLanes * sizeof(std::uint16_t))));

// Window sums along one row of `width` elements (doubles, or Lanes lane by lane): out[x] = Σ
// in[x'] over x' ∈ [x − r, x + r] ∩ [0, width), as a running sum. Exact (and so the same bits for
// any start) when the inputs are integers whose window sums stay below 2^53.
template <typename T>
inline void RowWindowSums(const T* in, int width, int radius, T* out) {
  T acc = {};
  for (int x = 0; x < std::min(radius, width); ++x) acc += in[x];
  // x < first: nothing leaves the window yet; x >= last: nothing enters it any more.
  const int first = std::min(width, radius + 1), last = std::max(first, width - radius);
  for (int x = 0; x < first; ++x) {
    if (x + radius < width) acc += in[x + radius];
    out[x] = acc;
  }
  // One addition on the running sum per pixel (the difference does not wait for it); exact, so
  // the same as adding and then subtracting.
  for (int x = first; x < last; ++x) {
    acc += in[x + radius] - in[x - radius - 1];
    out[x] = acc;
  }
  for (int x = last; x < width; ++x) {
    acc -= in[x - radius - 1];
    out[x] = acc;
  }
}

// Exact window sums of a width × height plane of integers held in doubles (running sums along
// the rows, then down the columns).
void PlaneWindowSums(const double* in, int width, int height, int radius, double* out) {
  const std::size_t w = width;
  std::vector<double> rows(w * height);
  for (int y = 0; y < height; ++y) RowWindowSums(in + y * w, width, radius, &rows[y * w]);
  std::vector<double> acc(w, 0.0);
  for (int y = 0; y < std::min(radius, height); ++y) {
    for (std::size_t x = 0; x < w; ++x) acc[x] += rows[y * w + x];
  }
  for (int y = 0; y < height; ++y) {
    if (y + radius < height) {
      for (std::size_t x = 0; x < w; ++x) acc[x] += rows[(y + radius) * w + x];
    }
    if (y - radius - 1 >= 0) {
      for (std::size_t x = 0; x < w; ++x) acc[x] -= rows[(y - radius - 1) * w + x];
    }
    std::copy(acc.begin(), acc.end(), out + y * w);
  }
}

// Number of pixels of [i − r, i + r] ∩ [0, n).
inline int ClippedCount(int i, int radius, int n) {
  return std::min(i + radius, n - 1) - std::max(i - radius, 0) + 1;
}

// What every label's filter shares: the guide over the outer region R (grey levels 0–255 per
// channel; I = level / 255), its window means mean_I and the inverse of Σ + εU per pixel
// (symmetric: 1 entry for grey, 6 for colour: xx, xy, xz, yy, yz, zz), all from exact integer
// window sums.
struct GuideStatistics {
  int width = 0, height = 0, channels = 0;
  // Kept small, as every 4 labels read them again: levels in bytes, the window statistics in
  // single precision (their rounding, 6e-8 relative, moves a filtered cost by ~1e-4 of a grey
  // level at most, under a tenth of a cost step; the same bits wherever the region starts).
  std::vector<std::vector<std::uint8_t>> level;
  std::vector<std::vector<float>> mean_image, inverse;
  std::vector<int> x_count;  // pixels of the window at column x
};

GuideStatistics ComputeGuideStatistics(const cv::Mat& guide, const cv::Rect& outer, int radius,
                                       bool guided, double epsilon) {
  GuideStatistics g;
  g.width = outer.width;
  g.height = outer.height;
  g.channels = guide.channels();
  const int w = g.width, h = g.height, k = g.channels;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  g.x_count.resize(w);
  for (int x = 0; x < w; ++x) g.x_count[x] = ClippedCount(x, radius, w);
  if (!guided) return g;
  g.level.assign(k, std::vector<std::uint8_t>(n));
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = guide.ptr<std::uint8_t>(outer.y + y) + outer.x * k;
    for (int x = 0; x < w; ++x) {
      for (int ch = 0; ch < k; ++ch) {
        g.level[ch][y * w + x] = row[x * k + ch];
      }
    }
  }
  std::vector<double> sums(n), product(n), mean_image(n * k);
  auto area = [&](std::size_t p) {
    return static_cast<double>(g.x_count[p % w]) * ClippedCount(static_cast<int>(p / w), radius, h);
  };
  g.mean_image.assign(k, std::vector<float>(n));
  for (int ch = 0; ch < k; ++ch) {
    for (std::size_t p = 0; p < n; ++p) product[p] = g.level[ch][p];
    PlaneWindowSums(product.data(), w, h, radius, sums.data());
    for (std::size_t p = 0; p < n; ++p) {
      mean_image[ch * n + p] = sums[p] / (255.0 * area(p));
      g.mean_image[ch][p] = static_cast<float>(mean_image[ch * n + p]);
    }
  }
  std::array<std::vector<double>, 6> cov;
  int entry = 0;
  for (int i = 0; i < k; ++i) {
    for (int j = i; j < k; ++j, ++entry) {
      for (std::size_t p = 0; p < n; ++p) {
        product[p] = static_cast<double>(g.level[i][p]) * g.level[j][p];
      }
      PlaneWindowSums(product.data(), w, h, radius, sums.data());
      cov[entry].resize(n);
      for (std::size_t p = 0; p < n; ++p) {
        cov[entry][p] = sums[p] / (255.0 * 255.0 * area(p)) -
                        mean_image[i * n + p] * mean_image[j * n + p] + (i == j ? epsilon : 0.0);
      }
    }
  }
  g.inverse.assign(k == 1 ? 1 : 6, std::vector<float>(n));
  for (std::size_t p = 0; p < n; ++p) {
    if (k == 1) {
      g.inverse[0][p] = static_cast<float>(1.0 / cov[0][p]);
      continue;
    }
    const double a = cov[0][p], b = cov[1][p], c = cov[2][p], d = cov[3][p], e = cov[4][p],
                 f = cov[5][p];
    // Adjugate of [[a b c] [b d e] [c e f]] over its determinant (positive definite: ε > 0).
    const double ixx = d * f - e * e, ixy = c * e - b * f, ixz = b * e - c * d;
    const double iyy = a * f - c * c, iyz = b * c - a * e, izz = a * d - b * b;
    const double inv_det = 1.0 / (a * ixx + b * ixy + c * ixz);
    g.inverse[0][p] = static_cast<float>(ixx * inv_det);
    g.inverse[1][p] = static_cast<float>(ixy * inv_det);
    g.inverse[2][p] = static_cast<float>(ixz * inv_det);
    g.inverse[3][p] = static_cast<float>(iyy * inv_det);
    g.inverse[4][p] = static_cast<float>(iyz * inv_det);
    g.inverse[5][p] = static_cast<float>(izz * inv_det);
  }
  return g;
}

// Running window sums down the rows of a stream of rows of `size` Lanes: Row(y) takes row y's
// horizontal window sums (rows in order), Add(y) / Drop(y) / Slide add it to or remove it from
// sums().
// Keeps the last 2r + 2 rows, all a vertical running sum needs.
class RowRing {
 public:
  RowRing(int radius, std::size_t size)
      : slots_(2 * radius + 2), size_(size), rows_(slots_ * size), sums_(size) {}
  Lanes* Row(int y) { return rows_.data() + (y % slots_) * size_; }
  void Add(int y) {
    const Lanes* row = Row(y);
    Lanes* sums = sums_.data();
    for (std::size_t i = 0; i < size_; ++i) sums[i] += row[i];
  }
  void Drop(int y) {
    const Lanes* row = Row(y);
    Lanes* sums = sums_.data();
    for (std::size_t i = 0; i < size_; ++i) sums[i] -= row[i];
  }
  // Add(entering) and Drop(leaving) in one pass (exact sums: the same result).
  void Slide(int entering, int leaving) {
    const Lanes* in = Row(entering);
    const Lanes* out = Row(leaving);
    Lanes* sums = sums_.data();
    for (std::size_t i = 0; i < size_; ++i) sums[i] += in[i] - out[i];
  }
  const Lanes* sums() const { return sums_.data(); }

 private:
  int slots_;
  std::size_t size_;
  LaneBuffer rows_, sums_;
};

struct ChunkJob {
  const CostVolume* raw = nullptr;
  const GuideStatistics* guide = nullptr;
  cv::Rect region;  // in the outer region's coordinates
  int radius = 0;
  bool guided = false;
  double step = 0.0;  // the cost volume's cost step
  double max_cost = 0.0;
  float inv_step = 0.0f;
};

// Filters labels [first, first + count) (count ≤ kLanes) of job.raw at the columns
// [x0, x1) of the region, streaming down the rows: stage 1 sums the raw costs s (in steps) and
// g_c · s (g_c the guide's levels) over the window; stage 2 turns them into the guided filter's
// a, b per pixel (He et al., eqs. 13–14) and sums those over the window; stage 3 writes
// q = mean a · I + mean b. Works on the columns [x0 − 2r, x1 + 2r) only, and holds 2r + 2 rows of
// each stage: a strip of ~128 columns keeps all of it in a core's L2 cache. The sums being exact,
// strips give the bits of the whole row.
// Only the rows [y_begin, y_end) of the outer region stream (see below). `in` holds the chunk's
// raw entries over the span's columns from outer row in_row0 on, kLanes per pixel ([row −
// in_row0][column][lane], the span's width per row); `out` receives its filtered entries over the
// strip from region row out_row0 on, kLanes per pixel ([region row − out_row0][column − x0]
// [lane]).
GCPSTEREO_AVX2_CLONE void FilterChunk(const ChunkJob& job, int first, int count, int x0, int x1,
                                      int y_begin, int y_end, const std::uint16_t* in,
                                      int in_row0, std::uint16_t* out, int out_row0) {
  const CostVolume& raw = *job.raw;
  const GuideStatistics& g = *job.guide;
  const int h = g.height, r = job.radius, k = g.channels;
  // The span of columns worked on: [sx, sx + w) in the outer region.
  const int sx = std::max(x0 - 2 * r, 0), w = std::min(x1 + 2 * r, g.width) - sx;
  const int nq = job.guided ? 1 + k : 1;  // stage-1 quantities: s, then g_c · s
  RowRing ring1(r, nq * w), ring2(r, job.guided ? (k + 1) * w : 0);
  LaneBuffer input(nq * w), coefficients(job.guided ? (k + 1) * w : 0);
  const double max_steps = 65534.0;  // a row without data: max_cost
  const cv::Rect& region = job.region;

  // Stage 1, row y: the raw entries, with entries without data replaced by the nearest entry of
  // the row with data (ties to the left), and their products with the guide's levels.
  auto push_input = [&](int y) GCPSTEREO_INLINE {
    Lanes* s = input.data();
    bool complete = count == kLanes;
    for (int x = 0; x < w && complete; ++x) {
      const std::uint16_t* e = in + (static_cast<std::size_t>(y - in_row0) * w + x) * kLanes;
      complete = e[0] != CostVolume::kNoData && e[1] != CostVolume::kNoData &&
                 e[2] != CostVolume::kNoData && e[3] != CostVolume::kNoData;
      s[x] = Lanes{static_cast<double>(e[0]), static_cast<double>(e[1]),
                   static_cast<double>(e[2]), static_cast<double>(e[3])};
    }
    if (!complete) {
      // Entries without data take the nearest entry with data of the row (ties to the left),
      // which may lie outside the span: only then is the volume searched beyond it.
      for (int j = 0; j < kLanes; ++j) {
        if (j >= count) {
          for (int x = 0; x < w; ++x) s[x][j] = 0.0;
          continue;
        }
        auto entry = [&](int x) {
          return in[(static_cast<std::size_t>(y - in_row0) * w + x) * kLanes + j];
        };
        for (int x = 0; x < w;) {
          if (entry(x) != CostVolume::kNoData) {
            s[x][j] = entry(x);
            ++x;
            continue;
          }
          const int a = x;
          while (x < w && entry(x) == CostVolume::kNoData) ++x;
          // The run [a, x) of the span; its neighbours with data at columns left, right of R.
          int left = -1, right = -1;
          double left_value = 0.0, right_value = 0.0;
          if (a > 0) {
            left = sx + a - 1;
            left_value = entry(a - 1);
          } else {
            for (int c = sx - 1; c >= 0 && left < 0; --c) {
              const std::uint16_t v = raw.PixelData(y, c)[first + j];
              if (v != CostVolume::kNoData) left = c, left_value = v;
            }
          }
          if (x < w) {
            right = sx + x;
            right_value = entry(x);
          } else {
            for (int c = sx + w; c < g.width && right < 0; ++c) {
              const std::uint16_t v = raw.PixelData(y, c)[first + j];
              if (v != CostVolume::kNoData) right = c, right_value = v;
            }
          }
          for (int f = a; f < x; ++f) {
            const int column = sx + f;
            if (left >= 0 && (right < 0 || column - left <= right - column)) {
              s[f][j] = left_value;
            } else {
              s[f][j] = right >= 0 ? right_value : max_steps;
            }
          }
        }
      }
    }
    for (int ch = 0; ch < nq - 1; ++ch) {
      const std::uint8_t* level = &g.level[ch][static_cast<std::size_t>(y) * g.width + sx];
      Lanes* q = input.data() + (1 + ch) * w;
      for (int x = 0; x < w; ++x) q[x] = static_cast<double>(level[x]) * s[x];
    }
    Lanes* row = ring1.Row(y);
    for (int q = 0; q < nq; ++q) RowWindowSums(input.data() + q * w, w, r, row + q * w);
  };

  // Writes the filtered costs of row y (outer coordinates) from window means at its columns.
  auto write_row = [&](int y, auto&& mean_at) GCPSTEREO_INLINE {
    if (y < region.y || y >= region.y + region.height) return;
    for (int x = x0; x < x1; ++x) {
      Lanes q;
      mean_at(x, q);
      // internal::Quantise of the cost clamped to [0, max_cost], lane by lane.
      q = q > 0.0 ? q : 0.0;
      q = q < job.max_cost ? q : job.max_cost;
      FloatLanes levels = __builtin_convertvector(q, FloatLanes) * job.inv_step + 0.5f;
      levels = levels < 65534.0f ? levels : 65534.0f;
      const IntLanes quantised = __builtin_convertvector(levels, IntLanes);
      const std::uint16_t* entries =
          in + (static_cast<std::size_t>(y - in_row0) * w + x - sx) * kLanes;
      std::uint16_t* dst =
          out + (static_cast<std::size_t>(y - region.y - out_row0) * (x1 - x0) + x - x0) * kLanes;
      // All kLanes lanes (those past `count` are never copied back): no data stays no data.
      ShortLanes raw_entries;
      std::memcpy(&raw_entries, entries, sizeof(raw_entries));
      const ShortLanes filtered = __builtin_convertvector(quantised, ShortLanes);
      const ShortLanes result = raw_entries == CostVolume::kNoData ? raw_entries : filtered;
      std::memcpy(dst, &result, sizeof(result));
    }
  };

  // Stage 2, row y (its stage-1 window sums complete): a, b of every pixel, then their window sums.
  auto push_coefficients = [&](int y) GCPSTEREO_INLINE {
    const int y_count = ClippedCount(y, r, h);
    const Lanes* sums = ring1.sums();
    const std::size_t row0 = static_cast<std::size_t>(y) * g.width + sx;
    const double level_step = job.step / 255.0;
    // Adding and subtracting 1.5 · 2^52 rounds a value of magnitude below 2^51 to an integer (to
    // nearest, ties to even) in any SIMD width.
    constexpr double kMagic = 6755399441055744.0;
    for (int x = 0; x < w; ++x) {
      const double norm = 1.0 / (static_cast<double>(g.x_count[sx + x]) * y_count);
      const std::size_t p = row0 + x;
      const Lanes mean_cost = sums[x] * (job.step * norm);
      Lanes b = mean_cost;
      if (k == 1) {
        const double mean_i = g.mean_image[0][p];
        const Lanes cov = sums[w + x] * (level_step * norm) - mean_i * mean_cost;
        const Lanes a = static_cast<double>(g.inverse[0][p]) * cov;
        b -= a * mean_i;
        coefficients[x] = (a * kCoefficientScale + kMagic) - kMagic;
      } else {
        double inv[6];
        for (int e = 0; e < 6; ++e) inv[e] = g.inverse[e][p];
        const double mx = g.mean_image[0][p], my = g.mean_image[1][p], mz = g.mean_image[2][p];
        const Lanes cx = sums[w + x] * (level_step * norm) - mx * mean_cost;
        const Lanes cy = sums[2 * w + x] * (level_step * norm) - my * mean_cost;
        const Lanes cz = sums[3 * w + x] * (level_step * norm) - mz * mean_cost;
        const Lanes a0 = inv[0] * cx + inv[1] * cy + inv[2] * cz;
        const Lanes a1 = inv[1] * cx + inv[3] * cy + inv[4] * cz;
        const Lanes a2 = inv[2] * cx + inv[4] * cy + inv[5] * cz;
        b -= a0 * mx + a1 * my + a2 * mz;
        coefficients[x] = (a0 * kCoefficientScale + kMagic) - kMagic;
        coefficients[w + x] = (a1 * kCoefficientScale + kMagic) - kMagic;
        coefficients[2 * w + x] = (a2 * kCoefficientScale + kMagic) - kMagic;
      }
      coefficients[k * w + x] = (b * kCoefficientScale + kMagic) - kMagic;
    }
    Lanes* row = ring2.Row(y);
    for (int q = 0; q <= k; ++q) RowWindowSums(coefficients.data() + q * w, w, r, row + q * w);
  };

  // Stage 3, row y (its stage-2 window sums complete): q = mean a · I + mean b.
  auto write_guided = [&](int y) GCPSTEREO_INLINE {
    const int y_count = ClippedCount(y, r, h);
    const Lanes* sums = ring2.sums();
    const std::size_t row0 = static_cast<std::size_t>(y) * g.width;
    write_row(y, [&](int x, Lanes& q) GCPSTEREO_INLINE {
      const double norm = 1.0 / (static_cast<double>(g.x_count[x]) * y_count * kCoefficientScale);
      const int i = x - sx;
      Lanes v = sums[k * w + i];
      for (int ch = 0; ch < k; ++ch) {
        v += sums[ch * w + i] * (g.level[ch][row0 + x] / 255.0);
      }
      q = v * norm;
    });
  };

  auto write_box = [&](int y) GCPSTEREO_INLINE {
    const int y_count = ClippedCount(y, r, h);
    const Lanes* sums = ring1.sums();
    write_row(y, [&](int x, Lanes& q) GCPSTEREO_INLINE {
      const double norm = 1.0 / (static_cast<double>(g.x_count[x]) * y_count);
      q = sums[x - sx] * (job.step * norm);
    });
  };

  // Row y of stage 1 is complete once rows up to y + r are in; stage 2's row y − r once stage 1's
  // row y is. Only the rows [y_begin, y_end) stream: the windows are clipped to them, so the rows
  // within the filter's margin of a cut end come out wrong and are not asked for (the window's
  // pixel counts are those of the whole region, so every other row is exact).
  const int lo = y_begin, hi = y_end;
  int next_input = lo;
  for (int y = lo; y < hi; ++y) {
    // Stage 1's window for row y: rows [y − r, y + r]; row y + r enters as row y − r − 1 leaves.
    for (; next_input <= std::min(y + r, hi - 1); ++next_input) {
      push_input(next_input);
      if (next_input < y + r || y - r - 1 < lo) ring1.Add(next_input);
    }
    if (y - r - 1 >= lo) {
      if (y + r < hi) {
        ring1.Slide(y + r, y - r - 1);
      } else {
        ring1.Drop(y - r - 1);
      }
    }
    if (!job.guided) {
      write_box(y);
      continue;
    }
    push_coefficients(y);
    // Stage 2's window for row y3 = y − r: rows [y − 2r, y]; row y enters as y − 2r − 1 leaves.
    const int y3 = y - r;
    if (y3 - r - 1 >= lo) {
      ring2.Slide(y, y3 - r - 1);
    } else {
      ring2.Add(y);
    }
    if (y3 >= lo) write_guided(y3);
  }
  if (job.guided) {
    for (int y3 = std::max(hi - r, lo); y3 < hi; ++y3) {
      if (y3 - r - 1 >= lo) ring2.Drop(y3 - r - 1);
      write_guided(y3);
    }
  }
}

}  // namespace

CostVolume FilterCostVolume(const CostVolume& raw, const cv::Mat& guide, const cv::Rect& region,
                            const CostFilterOptions& options, const LabelBands* bands) {
  options.Check();
  const cv::Rect outer = raw.region();
  if (raw.empty() || region.empty() || (region & outer) != region) {
    std::ostringstream s;
    s << "cost filter: region " << region.width << "x" << region.height << " at (" << region.x
      << ", " << region.y << ") is empty or not inside the cost volume's region " << outer.width
      << "x" << outer.height << " at (" << outer.x << ", " << outer.y << ")";
    throw Error(s.str());
  }
  if (guide.empty() || (guide.type() != CV_8UC3 && guide.type() != CV_8UC1) ||
      (outer & cv::Rect(0, 0, guide.cols, guide.rows)) != outer) {
    throw Error(
        "cost filter: the guide image must be 8-bit with 1 or 3 channels and contain the cost "
        "volume's region");
  }
  if (bands != nullptr && bands->empty()) bands = nullptr;
  if (bands != nullptr) bands->CheckFits(region.size(), "cost filter");
  const int num_labels = raw.num_labels();
  // With bands, the entries outside them are kNotComputed from the start: the filter writes only
  // the bands.
  CostVolume out(region, num_labels, raw.max_cost(),
                 bands != nullptr ? internal::kNotComputed : CostVolume::kNoData);
  const int ox = region.x - outer.x, oy = region.y - outer.y;
  // The band of the block of region pixel (row, col).
  auto band_of = [&](int row, int col, int* lo, int* hi) {
    if (bands == nullptr) {
      *lo = 0, *hi = num_labels - 1;
      return;
    }
    *lo = bands->lo.at<int>(row / bands->block_px, col / bands->block_px);
    *hi = bands->hi.at<int>(row / bands->block_px, col / bands->block_px);
  };
  if (options.window_px == 1) {
    for (int r = 0; r < region.height; ++r) {
      for (int c = 0; c < region.width; ++c) {
        int lo = 0, hi = 0;
        band_of(r, c, &lo, &hi);
        lo = std::max(lo, 0);
        hi = std::min(hi, num_labels - 1);
        if (lo > hi) continue;  // outside the bands: kNotComputed since `out` was made
        const std::uint16_t* entries = raw.PixelData(oy + r, ox + c);
        std::copy(entries + lo, entries + hi + 1, out.MutablePixelData(r, c) + lo);
      }
    }
    return out;
  }

  ChunkJob job;
  job.raw = &raw;
  job.radius = (options.window_px - 1) / 2;
  job.guided = options.filter == "guided";
  const GuideStatistics statistics =
      ComputeGuideStatistics(guide, outer, job.radius, job.guided, options.guided_epsilon);
  job.guide = &statistics;
  job.region = cv::Rect(ox, oy, region.width, region.height);
  job.step = raw.cost_step();
  job.max_cost = raw.max_cost();
  job.inv_step = 1.0f / out.cost_step();
  // Tasks: a strip of up to kStripPx columns of the region × kGroup labels (one 64-byte cache line
  // of a pixel's entries). A task copies its entries out of the volume into one plane per 4 labels
  // first, and back at the end, so that the volume is read and written a whole cache line at a
  // time rather than 8 bytes of every line by each of 8 chunks.
  constexpr int kStripPx = 128, kGroup = 8 * kLanes;
  const int num_groups = (num_labels + kGroup - 1) / kGroup;
  const int num_strips = (region.width + kStripPx - 1) / kStripPx;
  const int h = outer.height, r = job.radius;
  const int margin = options.MarginPx();
  // The rows of the outer region that labels [first, first + count) need over the region's columns
  // [c0, c1): those of the blocks whose bands hold any of them, grown by the margin; every row
  // without bands, none (begin = end) when no block holds them.
  auto rows_needed = [&](int first, int count, int c0, int c1, int* begin, int* end) {
    if (bands == nullptr) {
      *begin = 0, *end = h;
      return;
    }
    const int block = bands->block_px;
    int first_row = -1, last_row = -1;
    for (int by = 0; by < bands->lo.rows; ++by) {
      const int* lo = bands->lo.ptr<int>(by);
      const int* hi = bands->hi.ptr<int>(by);
      bool needed = false;
      for (int bx = c0 / block; bx <= (c1 - 1) / block && !needed; ++bx) {
        needed = lo[bx] <= hi[bx] && lo[bx] < first + count && hi[bx] >= first;
      }
      if (needed) {
        if (first_row < 0) first_row = by * block;
        last_row = std::min((by + 1) * block, region.height);
      }
    }
    if (first_row < 0) {
      *begin = *end = 0;
      return;
    }
    *begin = std::max(oy + first_row - margin, 0);
    *end = std::min(oy + last_row + margin, h);
  };
  tbb::parallel_for(
      tbb::blocked_range<int>(0, num_groups * num_strips, 1),
      [&](const tbb::blocked_range<int>& range) {
        for (int task = range.begin(); task != range.end(); ++task) {
          const int group_first = (task / num_strips) * kGroup, strip = task % num_strips;
          const int group_count = std::min(kGroup, num_labels - group_first);
          const int num_chunks = (group_count + kLanes - 1) / kLanes;
          const int x0 = job.region.x + strip * kStripPx;
          const int x1 = std::min(x0 + kStripPx, job.region.x + job.region.width);
          const int sx = std::max(x0 - 2 * r, 0), w = std::min(x1 + 2 * r, outer.width) - sx;
          std::vector<int> chunk_begin(num_chunks), chunk_end(num_chunks);
          int copy_begin = h, copy_end = 0;  // the outer rows any chunk streams
          for (int c = 0; c < num_chunks; ++c) {
            const int first = group_first + c * kLanes;
            rows_needed(first, std::min(kLanes, num_labels - first), x0 - job.region.x,
                        x1 - job.region.x, &chunk_begin[c], &chunk_end[c]);
            if (chunk_begin[c] < chunk_end[c]) {
              copy_begin = std::min(copy_begin, chunk_begin[c]);
              copy_end = std::max(copy_end, chunk_end[c]);
            }
          }
          if (copy_begin >= copy_end) copy_begin = copy_end = 0;
          // The region rows those give: [out_begin, out_end).
          const int out_begin = std::clamp(copy_begin - oy, 0, region.height);
          const int out_end = std::clamp(copy_end - oy, out_begin, region.height);
          const std::size_t in_plane = static_cast<std::size_t>(copy_end - copy_begin) * w * kLanes;
          const std::size_t out_plane =
              static_cast<std::size_t>(out_end - out_begin) * (x1 - x0) * kLanes;
          // Every entry of `filtered` that is read back is written by FilterChunk (a pixel's band
          // labels lie in chunks whose rows cover it): no initialisation.
          std::vector<std::uint16_t> in(num_chunks * in_plane, 0);
          std::unique_ptr<std::uint16_t[]> filtered(new std::uint16_t[num_chunks * out_plane]);
          // Each chunk reads only its own rows [chunk_begin, chunk_end) of `in` (FilterChunk):
          // a row's entries are copied to the chunks that stream it, kLanes labels at a time.
          const int full_chunks = group_count / kLanes;
          std::vector<char> streams(num_chunks);
          for (int y = copy_begin; y < copy_end; ++y) {
            for (int c = 0; c < num_chunks; ++c) {
              streams[c] = chunk_begin[c] <= y && y < chunk_end[c];
            }
            const std::size_t row = static_cast<std::size_t>(y - copy_begin) * w;
            for (int x = 0; x < w; ++x) {
              const std::uint16_t* entries = raw.PixelData(y, sx + x) + group_first;
              std::uint16_t* lanes = &in[(row + x) * kLanes];
              for (int c = 0; c < full_chunks; ++c) {
                if (streams[c]) {
                  std::memcpy(lanes + c * in_plane, entries + c * kLanes, sizeof(*lanes) * kLanes);
                }
              }
              if (full_chunks < num_chunks && streams[full_chunks]) {
                for (int i = full_chunks * kLanes; i < group_count; ++i) {
                  lanes[full_chunks * in_plane + i % kLanes] = entries[i];
                }
              }
            }
          }
          for (int c = 0; c < num_chunks; ++c) {
            if (chunk_begin[c] >= chunk_end[c]) continue;
            const int first = group_first + c * kLanes;
            FilterChunk(job, first, std::min(kLanes, num_labels - first), x0, x1, chunk_begin[c],
                        chunk_end[c], &in[c * in_plane], copy_begin, &filtered[c * out_plane],
                        out_begin);
          }
          const int group_last = group_first + group_count - 1;
          for (int y = 0; y < region.height; ++y) {
            for (int x = x0; x < x1; ++x) {
              std::uint16_t* entries = out.MutablePixelData(y, x - job.region.x) + group_first;
              int lo = 0, hi = 0;
              band_of(y, x - job.region.x, &lo, &hi);
              lo = std::max(lo, group_first);
              hi = std::min(hi, group_last);
              if (lo > hi) continue;  // outside the bands: kNotComputed since `out` was made
              const std::size_t p =
                  (static_cast<std::size_t>(y - out_begin) * (x1 - x0) + x - x0) * kLanes;
              for (int l = lo; l <= hi; ++l) {
                const int i = l - group_first;
                entries[i] = filtered[(i / kLanes) * out_plane + p + i % kLanes];
              }
            }
          }
        }
      },
      tbb::simple_partitioner());
  return out;
}

}  // namespace gcpstereo::cost
