// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include "gcpstereo/core/huge_page_allocator.h"

namespace gcpstereo {

// Matching costs Φ(p, l) of every label at every pixel of a rectangular region of the reference
// image (a tile plus its margin, or the whole image).
// Storage: 16-bit fixed point, cost = stored · cost_step() with cost_step() = max_cost / 65534;
// costs are clamped to [0, max_cost]. The value 65535 marks "no data" (no neighbour saw the
// pixel at that label) and reads back as `max_cost`. Quantisation error ≤ cost_step()/2.
// Layout: label fastest, index ((row · width) + col) · num_labels + label, so one pixel's costs
// are contiguous.
class CostVolume {
 public:
  CostVolume() = default;
  // `region` is the area of the reference image covered (x, y = its top-left pixel). Every entry
  // starts as `fill` (a stored value: kNoData, or a cost step a caller writes around).
  CostVolume(cv::Rect region, int num_labels, float max_cost, std::uint16_t fill = kNoData);

  const cv::Rect& region() const { return region_; }
  int width() const { return region_.width; }
  int height() const { return region_.height; }
  int num_labels() const { return num_labels_; }
  float max_cost() const { return max_cost_; }
  float cost_step() const { return cost_step_; }
  bool empty() const { return data_.empty(); }
  std::size_t memory_bytes() const { return data_.size() * sizeof(std::uint16_t); }

  static constexpr std::uint16_t kNoData = 65535;

  // Local coordinates: 0 <= row < height(), 0 <= col < width().
  float Cost(int row, int col, int label) const { return Decode(data_[Index(row, col, label)]); }
  void SetCost(int row, int col, int label, float cost) {
    data_[Index(row, col, label)] = Encode(cost);
  }
  void SetNoData(int row, int col, int label) { data_[Index(row, col, label)] = kNoData; }
  bool HasData(int row, int col, int label) const {
    return data_[Index(row, col, label)] != kNoData;
  }
  const std::uint16_t* PixelData(int row, int col) const { return &data_[Index(row, col, 0)]; }
  std::uint16_t* MutablePixelData(int row, int col) { return &data_[Index(row, col, 0)]; }

  std::uint16_t Encode(float cost) const;
  float Decode(std::uint16_t stored) const {
    return stored == kNoData ? max_cost_ : static_cast<float>(stored) * cost_step_;
  }

 private:
  std::size_t Index(int row, int col, int label) const {
    return (static_cast<std::size_t>(row) * region_.width + col) * num_labels_ + label;
  }

  cv::Rect region_;
  int num_labels_ = 0;
  float max_cost_ = 0.0f;
  float cost_step_ = 0.0f;
  // Written whole as soon as it is allocated: huge pages (huge_page_allocator.h).
  std::vector<std::uint16_t, HugePageAllocator<std::uint16_t>> data_;
};

// The labels a caller will read of a cost volume, per square block of the volume's region: block
// (bx, by) covers the region's pixels [bx·block_px, (bx + 1)·block_px) × [by·block_px, (by + 1)·
// block_px) (clipped), and its labels are lo(by, bx) … hi(by, bx), inclusive (lo > hi: none). A
// volume computed with bands holds, inside them, exactly the entries of the full computation, and
// outside them the largest cost — 65534 steps, or kNoData, which reads as the largest cost too —
// not computed, as if the label were hopeless there. Empty bands (no
// blocks) = every label everywhere. α-expansion over candidate labels (optimize::
// CandidateLabelBands) knows its labels before the volume exists; most of a LiDAR frame's volume
// is then never needed.
struct LabelBands {
  int block_px = 0;
  cv::Mat lo, hi;  // CV_32S, ceil(height / block_px) × ceil(width / block_px)
  bool empty() const { return lo.empty(); }
  // Throws Error unless the bands are empty or fit a region of `size` (block_px > 0, both CV_32S
  // of the block grid's size).
  void CheckFits(const cv::Size& size, const std::string& what) const;
  // The share of the region's (pixel, label) entries inside the bands, for num_labels labels.
  double Fraction(const cv::Size& size, int num_labels) const;
};

}  // namespace gcpstereo
