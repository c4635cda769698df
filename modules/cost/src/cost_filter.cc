// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/cost_filter.h"

#include <algorithm>
#include <array>
#include <cmath>
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

namespace {

// Mean of `src` (width × height, row-major) over the (2r+1)² window around each pixel, clipped to
// the grid. Sequential prefix sums in double: the same input gives the same bits. The vertical
// prefix sums are kept as whole rows (row y + 1 = row y + the window sums of image row y), so that
// both passes read and write memory in order and vectorise.
class BoxMean {
 public:
  BoxMean(int width, int height, int radius)
      : width_(width),
        height_(height),
        radius_(radius),
        column_prefix_(static_cast<std::size_t>(width) * (height + 1)),
        row_prefix_(static_cast<std::size_t>(width) + 1),
        x_count_(width) {
    for (int x = 0; x < width_; ++x) {
      x_count_[x] = std::min(x + radius_, width_ - 1) - std::max(x - radius_, 0) + 1;
    }
  }

  void operator()(const double* src, double* dst) {
    const std::size_t w = width_;
    std::fill_n(column_prefix_.begin(), w, 0.0);
    for (int y = 0; y < height_; ++y) {
      // Horizontal window sums of row y, accumulated onto the prefix row above.
      const double* s = src + y * w;
      row_prefix_[0] = 0.0;
      for (int x = 0; x < width_; ++x) row_prefix_[x + 1] = row_prefix_[x] + s[x];
      const double* above = &column_prefix_[y * w];
      double* out = &column_prefix_[(y + 1) * w];
      for (int x = 0; x < width_; ++x) {
        const int lo = std::max(x - radius_, 0), hi = std::min(x + radius_, width_ - 1);
        out[x] = row_prefix_[hi + 1] - row_prefix_[lo];
      }
      for (std::size_t x = 0; x < w; ++x) out[x] += above[x];
    }
    // Vertical window sums, divided by the clipped window's area.
    for (int y = 0; y < height_; ++y) {
      const int lo = std::max(y - radius_, 0), hi = std::min(y + radius_, height_ - 1);
      const double y_count = hi - lo + 1;
      const double* top = &column_prefix_[lo * w];
      const double* bottom = &column_prefix_[(hi + 1) * w];
      double* d = dst + y * w;
      for (std::size_t x = 0; x < w; ++x) d[x] = (bottom[x] - top[x]) / (x_count_[x] * y_count);
    }
  }

 private:
  int width_, height_, radius_;
  std::vector<double> column_prefix_, row_prefix_, x_count_;
};

}  // namespace

CostVolume FilterCostVolume(const CostVolume& raw, const cv::Mat& guide, const cv::Rect& region,
                            const CostFilterOptions& options) {
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
  const int num_labels = raw.num_labels();
  CostVolume out(region, num_labels, raw.max_cost());
  const int ox = region.x - outer.x, oy = region.y - outer.y;
  if (options.window_px == 1) {
    for (int r = 0; r < region.height; ++r) {
      for (int c = 0; c < region.width; ++c) {
        std::copy_n(raw.PixelData(oy + r, ox + c), num_labels, out.MutablePixelData(r, c));
      }
    }
    return out;
  }

  const int width = outer.width, height = outer.height;
  const std::size_t n = static_cast<std::size_t>(width) * height;
  const int radius = (options.window_px - 1) / 2;
  const bool guided = options.filter == "guided";
  const int k = guide.channels();
  const float max_cost = raw.max_cost();
  const float inv_step = 1.0f / out.cost_step();
  const double step = raw.cost_step();

  // Guide statistics shared by all labels: I (k planes in [0, 1]), mean_I and the inverse of
  // Σ + εU per pixel (symmetric: 1 entry for grey, 6 for colour: xx, xy, xz, yy, yz, zz).
  std::vector<std::vector<double>> image(k, std::vector<double>(n));
  std::vector<std::vector<double>> mean_image(k, std::vector<double>(n));
  std::vector<std::vector<double>> inverse(k == 1 ? 1 : 6, std::vector<double>(n));
  if (guided) {
    for (int y = 0; y < height; ++y) {
      const std::uint8_t* g = guide.ptr<std::uint8_t>(outer.y + y) + outer.x * k;
      for (int x = 0; x < width; ++x) {
        for (int ch = 0; ch < k; ++ch) image[ch][y * width + x] = g[x * k + ch] / 255.0;
      }
    }
    BoxMean box(width, height, radius);
    for (int ch = 0; ch < k; ++ch) box(image[ch].data(), mean_image[ch].data());
    std::vector<double> product(n), mean_product(n);
    std::array<std::vector<double>, 6> cov;
    int entry = 0;
    for (int i = 0; i < k; ++i) {
      for (int j = i; j < k; ++j, ++entry) {
        for (std::size_t p = 0; p < n; ++p) product[p] = image[i][p] * image[j][p];
        box(product.data(), mean_product.data());
        cov[entry].resize(n);
        for (std::size_t p = 0; p < n; ++p) {
          cov[entry][p] = mean_product[p] - mean_image[i][p] * mean_image[j][p] +
                          (i == j ? options.guided_epsilon : 0.0);
        }
      }
    }
    for (std::size_t p = 0; p < n; ++p) {
      if (k == 1) {
        inverse[0][p] = 1.0 / cov[0][p];
        continue;
      }
      const double a = cov[0][p], b = cov[1][p], c = cov[2][p], d = cov[3][p], e = cov[4][p],
                   f = cov[5][p];
      // Adjugate of [[a b c] [b d e] [c e f]] over its determinant (positive definite: ε > 0).
      const double ixx = d * f - e * e, ixy = c * e - b * f, ixz = b * e - c * d;
      const double iyy = a * f - c * c, iyz = b * c - a * e, izz = a * d - b * b;
      const double inv_det = 1.0 / (a * ixx + b * ixy + c * ixz);
      inverse[0][p] = ixx * inv_det;
      inverse[1][p] = ixy * inv_det;
      inverse[2][p] = ixz * inv_det;
      inverse[3][p] = iyy * inv_det;
      inverse[4][p] = iyz * inv_det;
      inverse[5][p] = izz * inv_det;
    }
  }

  // The volume stores a pixel's labels together, the filter works on one label's slice: a task
  // takes kChunk consecutive labels, so that copying its slices out of the volume and back reads
  // and writes each pixel's entries in one run instead of one cache line per label.
  constexpr int kChunk = 8;
  const int num_chunks = (num_labels + kChunk - 1) / kChunk;
  const std::size_t region_n = static_cast<std::size_t>(region.width) * region.height;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, num_chunks, 1),
      [&](const tbb::blocked_range<int>& range) {
        BoxMean box(width, height, radius);
        std::vector<double> cost(n), mean_cost(n), result(n), work(n);
        std::vector<std::vector<double>> a(guided ? k : 0, std::vector<double>(n));
        std::vector<double> b(guided ? n : 0);
        // One label's slice `in` (the raw entries, width × height) → its filtered and quantised
        // entries over `region` in `slice_out`.
        auto filter_slice = [&](const std::uint16_t* in, std::uint16_t* slice_out) {
          // The slice, with entries without data replaced by the nearest entry of the row.
          for (int y = 0; y < height; ++y) {
            double* row = &cost[static_cast<std::size_t>(y) * width];
            const std::uint16_t* in_row = in + static_cast<std::size_t>(y) * width;
            int last = -1;
            for (int x = 0; x < width; ++x) {
              const std::uint16_t s = in_row[x];
              if (s == CostVolume::kNoData) continue;
              row[x] = s * step;
              for (int f = last + 1; f < x; ++f) {
                // Nearest: left when closer (ties to the left), else this entry.
                row[f] = (last >= 0 && f - last <= x - f) ? row[last] : row[x];
              }
              last = x;
            }
            for (int f = last + 1; f < width; ++f) row[f] = last >= 0 ? row[last] : max_cost;
          }
          box(cost.data(), mean_cost.data());
          if (!guided) {
            result.swap(mean_cost);
          } else {
            std::array<std::vector<double>, 3> cov_ip;
            for (int ch = 0; ch < k; ++ch) {
              for (std::size_t p = 0; p < n; ++p) work[p] = image[ch][p] * cost[p];
              cov_ip[ch].resize(n);
              box(work.data(), cov_ip[ch].data());
              for (std::size_t p = 0; p < n; ++p) {
                cov_ip[ch][p] -= mean_image[ch][p] * mean_cost[p];
              }
            }
            for (std::size_t p = 0; p < n; ++p) {
              double bp = mean_cost[p];
              if (k == 1) {
                a[0][p] = inverse[0][p] * cov_ip[0][p];
                bp -= a[0][p] * mean_image[0][p];
              } else {
                const double cx = cov_ip[0][p], cy = cov_ip[1][p], cz = cov_ip[2][p];
                a[0][p] = inverse[0][p] * cx + inverse[1][p] * cy + inverse[2][p] * cz;
                a[1][p] = inverse[1][p] * cx + inverse[3][p] * cy + inverse[4][p] * cz;
                a[2][p] = inverse[2][p] * cx + inverse[4][p] * cy + inverse[5][p] * cz;
                bp -= a[0][p] * mean_image[0][p] + a[1][p] * mean_image[1][p] +
                      a[2][p] * mean_image[2][p];
              }
              b[p] = bp;
            }
            box(b.data(), result.data());
            for (int ch = 0; ch < k; ++ch) {
              box(a[ch].data(), work.data());
              for (std::size_t p = 0; p < n; ++p) result[p] += work[p] * image[ch][p];
            }
          }
          for (int r = 0; r < region.height; ++r) {
            for (int c = 0; c < region.width; ++c) {
              const std::size_t p = static_cast<std::size_t>(oy + r) * width + ox + c;
              std::uint16_t& dst = slice_out[static_cast<std::size_t>(r) * region.width + c];
              if (in[p] == CostVolume::kNoData) {
                dst = CostVolume::kNoData;
                continue;
              }
              dst = internal::Quantise(
                  static_cast<float>(std::clamp(result[p], 0.0, static_cast<double>(max_cost))),
                  inv_step);
            }
          }
        };
        std::vector<std::uint16_t> in_slices(kChunk * n), out_slices(kChunk * region_n);
        for (int chunk = range.begin(); chunk != range.end(); ++chunk) {
          const int first = chunk * kChunk, count = std::min(kChunk, num_labels - first);
          for (int y = 0; y < height; ++y) {
            for (int x = 0; x < width; ++x) {
              const std::uint16_t* entries = raw.PixelData(y, x) + first;
              const std::size_t p = static_cast<std::size_t>(y) * width + x;
              for (int j = 0; j < count; ++j) in_slices[j * n + p] = entries[j];
            }
          }
          for (int j = 0; j < count; ++j) {
            filter_slice(&in_slices[j * n], &out_slices[j * region_n]);
          }
          for (int r = 0; r < region.height; ++r) {
            for (int c = 0; c < region.width; ++c) {
              std::uint16_t* entries = out.MutablePixelData(r, c) + first;
              const std::size_t p = static_cast<std::size_t>(r) * region.width + c;
              for (int j = 0; j < count; ++j) entries[j] = out_slices[j * region_n + p];
            }
          }
        }
      },
      tbb::simple_partitioner());
  return out;
}

}  // namespace gcpstereo::cost
