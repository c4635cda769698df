// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/birchfield_tomasi.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "cost_internal.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::cost {

void BirchfieldTomasiOptions::Check() const {
  if (!(truncation > 0.0) || !std::isfinite(truncation)) {
    throw ConfigError(ViolatedConstraint("cost.bt_truncation", internal::Str(truncation),
                                         "0 < bt_truncation < inf"));
  }
  if (channels != "sum" && channels != "max") {
    throw ConfigError(ViolatedConstraint("cost.bt_channels", channels, "one of sum, max"));
  }
  if (census_window_px < 1 || census_window_px > 7 || census_window_px % 2 == 0) {
    throw ConfigError(ViolatedConstraint("cost.census_window_px", internal::Str(census_window_px),
                                         "odd and 1 <= census_window_px <= 7"));
  }
  if (!(census_weight >= 0.0) || !std::isfinite(census_weight)) {
    throw ConfigError(ViolatedConstraint("cost.census_weight", internal::Str(census_weight),
                                         "0 <= census_weight < inf"));
  }
  if (census_mask_threshold < 0 || census_mask_threshold > 255) {
    throw ConfigError(ViolatedConstraint("cost.census_mask_threshold",
                                         internal::Str(census_mask_threshold),
                                         "0 <= census_mask_threshold <= 255"));
  }
  window.Check("cost.");
}

namespace {

// Value, minimum and maximum of {I(t − ½), I(t), I(t + ½)} of one channel.
struct Triplet {
  float value, min, max;
};

// One channel of a row, linearly interpolated at a real position, border replicated.
inline float Interpolate(const std::uint8_t* row, int channels, int channel, int width, double t) {
  t = std::clamp(t, 0.0, static_cast<double>(width - 1));
  const int i = std::min(static_cast<int>(t), width - 2 < 0 ? 0 : width - 2);
  const double f = t - i;
  const float a = row[i * channels + channel];
  if (f == 0.0 || width == 1) return a;
  const float b = row[(i + 1) * channels + channel];
  return static_cast<float>(a + (b - a) * f);
}

inline Triplet TripletAt(const std::uint8_t* row, int channels, int channel, int width, double t) {
  const float v = Interpolate(row, channels, channel, width, t);
  const float lo = Interpolate(row, channels, channel, width, t - 0.5);
  const float hi = Interpolate(row, channels, channel, width, t + 0.5);
  return {v, std::min({v, lo, hi}), std::max({v, lo, hi})};
}

// The symmetric BT dissimilarity of one channel.
inline float Dissimilarity(const Triplet& l, const Triplet& r) {
  const float left_to_right = std::max({0.0f, l.value - r.max, r.min - l.value});
  const float right_to_left = std::max({0.0f, r.value - l.max, l.min - r.value});
  return std::min(left_to_right, right_to_left);
}

// A bit string over the side × side window of each pixel of the rows [y0, y0 + rows) and the
// columns [x0, x0 + cols) of a grey image, border replicated, neighbours in raster order without
// the centre: bit i is bit(neighbour i, centre). Words [row − y0][column − x0].
template <typename Bit>
cv::Mat WindowBitsRows(const cv::Mat& grey, int y0, int rows, int x0, int cols, int side, Bit bit) {
  cv::Mat words(rows, cols, CV_64F);  // 64-bit words stored in a CV_64F-sized Mat
  const int h = side / 2;
  std::vector<const std::uint8_t*> window_rows(side);
  for (int r = 0; r < rows; ++r) {
    std::uint64_t* out = words.ptr<std::uint64_t>(r);
    const int y = y0 + r;
    for (int dy = -h; dy <= h; ++dy) {
      window_rows[dy + h] = grey.ptr<std::uint8_t>(std::clamp(y + dy, 0, grey.rows - 1));
    }
    const std::uint8_t* centre_row = grey.ptr<std::uint8_t>(y);
    for (int c = 0; c < cols; ++c) {
      const int x = x0 + c;
      const int centre = centre_row[x];
      std::uint64_t bits = 0;
      const bool inside = x - h >= 0 && x + h < grey.cols;  // no column to replicate
      for (int dy = -h; dy <= h; ++dy) {
        const std::uint8_t* row = window_rows[dy + h];
        for (int dx = -h; dx <= h; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int xx = inside ? x + dx : std::clamp(x + dx, 0, grey.cols - 1);
          bits = (bits << 1) | (bit(row[xx], centre) ? 1u : 0u);
        }
      }
      out[c] = bits;
    }
  }
  return words;
}

// Census transform (Zabih & Woodfill 1994): bit i is set when neighbour i is darker than the
// centre.
cv::Mat CensusRows(const cv::Mat& grey, int y0, int rows, int x0, int cols, int side) {
  return WindowBitsRows(grey, y0, rows, x0, cols, side, [](int n, int c) { return n < c; });
}

// The census mask (census_mask_threshold): bit i is set when neighbour i is within `threshold`
// grey levels of the centre.
cv::Mat CensusMaskRows(const cv::Mat& grey, int y0, int rows, int x0, int cols, int side,
                       int threshold) {
  return WindowBitsRows(grey, y0, rows, x0, cols, side,
                        [threshold](int n, int c) { return std::abs(n - c) <= threshold; });
}

inline int Hamming(std::uint64_t a, std::uint64_t b, std::uint64_t mask) {
  return __builtin_popcountll((a ^ b) & mask);
}

// The pixel-wise costs of one row at integer disparities without a census mask (the common case:
// rectified pairs at whole-pixel disparities), pixel by pixel so that each pixel's entries are
// written in one run. The same float operations in the same order as the general loop in
// PixelCost, so the same bits.
struct IntegerRow {
  const Triplet* left = nullptr;   // the row's triplets, channel-fastest
  const Triplet* right = nullptr;
  // Census words from column census_left_x0 / census_right_x0 on; null without census.
  const std::uint64_t* census_left = nullptr;
  const std::uint64_t* census_right = nullptr;
  int census_left_x0 = 0, census_right_x0 = 0;
  const int* disparities = nullptr;
  // Per pixel of the row, the labels computed (LabelBands): lo[c] … hi[c]; null = all.
  const int* band_lo = nullptr;
  const int* band_hi = nullptr;
  int num_labels = 0, channels = 0, width = 0, x0 = 0, count = 0;
  bool use_max = false;
  float truncation = 0.0f, census_weight = 0.0f, inv_step = 0.0f;
};

#if defined(__GNUC__)
#define GCPSTEREO_INLINE __attribute__((always_inline)) inline
#else
#define GCPSTEREO_INLINE inline
#endif

GCPSTEREO_INLINE void IntegerRowCost(const IntegerRow& row, std::uint16_t* out) {
  const int channels = row.channels;
  for (int c = 0; c < row.count; ++c) {
    const int x = row.x0 + c;
    const Triplet* lt = row.left + x * channels;
    std::uint16_t* entries = out + static_cast<std::size_t>(c) * row.num_labels;
    int lo = 0, hi = row.num_labels - 1;
    if (row.band_lo != nullptr) {
      lo = std::max(row.band_lo[c], 0);
      hi = std::min(row.band_hi[c], row.num_labels - 1);
      for (int l = 0; l < row.num_labels; ++l) {
        if (l >= lo && l <= hi) continue;
        const int xr = x - row.disparities[l];
        entries[l] = xr < 0 || xr > row.width - 1 ? CostVolume::kNoData : internal::kNotComputed;
      }
    }
    for (int l = lo; l <= hi; ++l) {
      const int xr = x - row.disparities[l];
      if (xr < 0 || xr > row.width - 1) {
        entries[l] = CostVolume::kNoData;
        continue;
      }
      const Triplet* rt = row.right + xr * channels;
      float cost = 0.0f;
      for (int ch = 0; ch < channels; ++ch) {
        const float dissimilarity = Dissimilarity(lt[ch], rt[ch]);
        cost = row.use_max ? std::max(cost, dissimilarity) : cost + dissimilarity;
      }
      cost = std::min(cost, row.truncation);
      if (row.census_left != nullptr) {
        const float hamming = static_cast<float>(
            __builtin_popcountll(row.census_left[x - row.census_left_x0] ^
                                 row.census_right[xr - row.census_right_x0]));
        cost += row.census_weight * hamming;
      }
      entries[l] = internal::Quantise(cost, row.inv_step);
    }
  }
}

// Compiled twice on x86-64: with the popcnt instruction (chosen when the CPU has it) and without
// (libgcc's table popcount, a call per Hamming distance). Integer results: the same bits.
#if defined(__GNUC__) && defined(__x86_64__)
__attribute__((target("popcnt"))) void IntegerRowCostPopcnt(const IntegerRow& row,
                                                             std::uint16_t* out) {
  IntegerRowCost(row, out);
}
void IntegerRowCostDispatch(const IntegerRow& row, std::uint16_t* out) {
  static const bool popcnt = __builtin_cpu_supports("popcnt");
  if (popcnt) {
    IntegerRowCostPopcnt(row, out);
  } else {
    IntegerRowCost(row, out);
  }
}
#else
void IntegerRowCostDispatch(const IntegerRow& row, std::uint16_t* out) { IntegerRowCost(row, out); }
#endif

// The pixel-wise cost (BT, plus census when configured) of `region`; with `bands` (over
// `band_region`), only at the labels of the blocks within `margin` pixels of each pixel.
CostVolume PixelCost(const cv::Mat& left, const cv::Mat& right,
                     const std::vector<double>& disparities_px, const cv::Rect& region,
                     const BirchfieldTomasiOptions& options, const LabelBands* bands,
                     const cv::Rect& band_region, int margin) {
  const int channels = left.channels();
  const int width = left.cols;
  const int num_labels = static_cast<int>(disparities_px.size());
  const float truncation = static_cast<float>(options.truncation);
  const bool use_max = options.channels == "max";
  const int census_side = options.census_window_px;
  const bool use_census = census_side > 1;
  const float census_weight = static_cast<float>(options.census_weight);
  const float max_cost =
      truncation + (use_census ? census_weight * (census_side * census_side - 1) : 0.0f);
  CostVolume volume(region, num_labels, max_cost);
  const float inv_step = 1.0f / volume.cost_step();

  // The columns of `right` the disparities reach from the region (with the neighbour of a
  // fractional position): [right_x0, right_x1].
  const auto [d_min, d_max] = std::minmax_element(disparities_px.begin(), disparities_px.end());
  const int right_x0 = static_cast<int>(
      std::clamp(std::floor(region.x - *d_max) - 1.0, 0.0, static_cast<double>(width - 1)));
  const int right_x1 = static_cast<int>(std::clamp(
      std::ceil(region.x + region.width - 1 - *d_min) + 1.0, 0.0, static_cast<double>(width - 1)));
  cv::Mat census_left, census_right, mask_left;
  if (use_census) {
    cv::Mat grey_left = left, grey_right = right;
    if (channels == 3) {
      cv::cvtColor(left, grey_left, cv::COLOR_BGR2GRAY);
      cv::cvtColor(right, grey_right, cv::COLOR_BGR2GRAY);
    }
    census_left =
        CensusRows(grey_left, region.y, region.height, region.x, region.width, census_side);
    census_right = CensusRows(grey_right, region.y, region.height, right_x0,
                              right_x1 - right_x0 + 1, census_side);
    if (options.census_mask_threshold > 0) {
      mask_left = CensusMaskRows(grey_left, region.y, region.height, region.x, region.width,
                                 census_side,
                                 options.census_mask_threshold);
    }
  }
  const int census_bits = census_side * census_side - 1;
  // Whole-pixel disparities and no census mask: IntegerRowCost. A disparity within 1e-9 px of a
  // whole pixel counts as that pixel: the pipeline's labels come back from depth as f·B / depth
  // (2.9999999999999996 for 3), where interpolating gives the whole pixel's costs anyway.
  std::vector<int> integer_disparities;
  if (mask_left.empty()) {
    for (double d : disparities_px) {
      const double whole = std::round(d);
      if (std::abs(d - whole) > 1e-9 || std::abs(whole) > 1e9) break;
      integer_disparities.push_back(static_cast<int>(whole));
    }
    if (integer_disparities.size() != disparities_px.size()) integer_disparities.clear();
  }

  tbb::parallel_for(
      tbb::blocked_range<int>(0, region.height, 1),
      [&](const tbb::blocked_range<int>& range) {
        // Triplets of the whole left / right row, channel-fastest; integer positions only.
        std::vector<Triplet> left_triplets(static_cast<std::size_t>(width) * channels);
        std::vector<Triplet> right_triplets(static_cast<std::size_t>(width) * channels);
        std::vector<int> band_lo(bands != nullptr ? region.width : 0);
        std::vector<int> band_hi(band_lo.size());
        for (int row_local = range.begin(); row_local != range.end(); ++row_local) {
          const int y = region.y + row_local;
          if (bands != nullptr) {
            internal::BandsNear(*bands, band_region, y, region.x, region.width, margin,
                                band_lo.data(), band_hi.data());
          }
          const std::uint8_t* left_row = left.ptr<std::uint8_t>(y);
          const std::uint8_t* right_row = right.ptr<std::uint8_t>(y);
          const std::uint64_t* census_l =
              use_census ? census_left.ptr<std::uint64_t>(row_local) : nullptr;
          const std::uint64_t* census_r =
              use_census ? census_right.ptr<std::uint64_t>(row_local) : nullptr;
          const std::uint64_t* masks =
              mask_left.empty() ? nullptr : mask_left.ptr<std::uint64_t>(row_local);
          // Only the columns the region and its disparities read.
          for (int x = region.x; x < region.x + region.width; ++x) {
            for (int ch = 0; ch < channels; ++ch) {
              left_triplets[x * channels + ch] = TripletAt(left_row, channels, ch, width, x);
            }
          }
          for (int x = right_x0; x <= right_x1; ++x) {
            for (int ch = 0; ch < channels; ++ch) {
              right_triplets[x * channels + ch] = TripletAt(right_row, channels, ch, width, x);
            }
          }
          std::uint16_t* out = volume.MutablePixelData(row_local, 0);
          if (!integer_disparities.empty()) {
            IntegerRow row;
            row.left = left_triplets.data();
            row.right = right_triplets.data();
            row.census_left = census_l;
            row.census_right = census_r;
            row.census_left_x0 = region.x;
            row.census_right_x0 = right_x0;
            row.disparities = integer_disparities.data();
            if (bands != nullptr) {
              row.band_lo = band_lo.data();
              row.band_hi = band_hi.data();
            }
            row.num_labels = num_labels;
            row.channels = channels;
            row.width = width;
            row.x0 = region.x;
            row.count = region.width;
            row.use_max = use_max;
            row.truncation = truncation;
            row.census_weight = census_weight;
            row.inv_step = inv_step;
            IntegerRowCostDispatch(row, out);
            continue;
          }
          for (int l = 0; l < num_labels; ++l) {
            const double d = disparities_px[l];
            const bool integer = d == std::floor(d);
            for (int c = 0; c < region.width; ++c) {
              const int x = region.x + c;
              const double xr = x - d;
              std::uint16_t& entry = out[static_cast<std::size_t>(c) * num_labels + l];
              if (!(xr >= 0.0 && xr <= width - 1)) {
                entry = CostVolume::kNoData;
                continue;
              }
              if (bands != nullptr && (l < band_lo[c] || l > band_hi[c])) {
                entry = internal::kNotComputed;
                continue;
              }
              float cost = 0.0f;
              for (int ch = 0; ch < channels; ++ch) {
                const Triplet& lt = left_triplets[x * channels + ch];
                const Triplet rt = integer ? right_triplets[static_cast<int>(xr) * channels + ch]
                                           : TripletAt(right_row, channels, ch, width, xr);
                const float dissimilarity = Dissimilarity(lt, rt);
                cost = use_max ? std::max(cost, dissimilarity) : cost + dissimilarity;
              }
              cost = std::min(cost, truncation);
              if (use_census) {
                const int x0 = static_cast<int>(std::floor(xr));
                std::uint64_t mask = ~std::uint64_t{0};
                float scale = 1.0f;
                if (masks != nullptr) {
                  const int kept = __builtin_popcountll(masks[x - region.x]);
                  if (4 * kept >= census_bits) {
                    mask = masks[x - region.x];
                    scale = static_cast<float>(census_bits) / static_cast<float>(kept);
                  }
                }
                const std::uint64_t centre = census_l[x - region.x];
                const float hamming0 =
                    static_cast<float>(Hamming(centre, census_r[x0 - right_x0], mask));
                float hamming = hamming0;
                if (!integer) {
                  const float f = static_cast<float>(xr - x0);
                  const float hamming1 = static_cast<float>(
                      Hamming(centre, census_r[std::min(x0 + 1, width - 1) - right_x0], mask));
                  hamming = hamming0 + (hamming1 - hamming0) * f;
                }
                cost += census_weight * scale * hamming;
              }
              entry = internal::Quantise(cost, inv_step);
            }
          }
        }
      },
      tbb::simple_partitioner());
  return volume;
}

}  // namespace

CostVolume ComputeBirchfieldTomasiCost(const cv::Mat& left, const cv::Mat& right,
                                       const std::vector<double>& disparities_px,
                                       const cv::Rect& region,
                                       const BirchfieldTomasiOptions& options,
                                       const LabelBands* bands) {
  options.Check();
  if (left.empty() || (left.type() != CV_8UC3 && left.type() != CV_8UC1)) {
    throw Error("Birchfield-Tomasi cost: the left image must be 8-bit with 1 or 3 channels");
  }
  if (right.type() != left.type() || right.size() != left.size()) {
    std::ostringstream s;
    s << "Birchfield-Tomasi cost: the right image (" << right.cols << "x" << right.rows << ", "
      << right.channels() << " channels) must have the left image's size and type (" << left.cols
      << "x" << left.rows << ", " << left.channels() << " channels)";
    throw Error(s.str());
  }
  if (disparities_px.empty()) throw Error("Birchfield-Tomasi cost: no disparities to evaluate");
  for (double d : disparities_px) {
    if (!std::isfinite(d)) {
      throw Error("Birchfield-Tomasi cost: disparity " + internal::Str(d) + " is not finite");
    }
  }
  if (region.empty() || (region & cv::Rect(0, 0, left.cols, left.rows)) != region) {
    std::ostringstream s;
    s << "Birchfield-Tomasi cost: region " << region.width << "x" << region.height << " at ("
      << region.x << ", " << region.y << ") is empty or not inside the " << left.cols << "x"
      << left.rows << " left image";
    throw Error(s.str());
  }

  if (bands != nullptr && bands->empty()) bands = nullptr;
  if (bands != nullptr) bands->CheckFits(region.size(), "Birchfield-Tomasi cost");
  if (options.window.window_px == 1) {
    return PixelCost(left, right, disparities_px, region, options, bands, region, 0);
  }
  const int margin = options.window.MarginPx();
  const cv::Rect outer = GrowRegion(region, margin, left.size());
  return FilterCostVolume(
      PixelCost(left, right, disparities_px, outer, options, bands, region, margin), left, region,
      options.window, bands);
}

}  // namespace gcpstereo::cost
