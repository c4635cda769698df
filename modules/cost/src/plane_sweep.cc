// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/plane_sweep.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/LU>
#include <opencv2/core.hpp>

#include "cost_internal.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"
#include "sweep_kernels.h"
#include "zncc_sweep.h"

namespace gcpstereo::cost {

void PlaneSweepOptions::Check() const {
  if (!(truncation > 0.0) || !std::isfinite(truncation)) {
    throw ConfigError(
        ViolatedConstraint("cost.truncation", internal::Str(truncation), "0 < truncation < inf"));
  }
  if (measure != "rgb" && measure != "zncc") {
    throw ConfigError(ViolatedConstraint("cost.sweep_measure", measure, "one of rgb, zncc"));
  }
  if (zncc_window_px < 3 || zncc_window_px > internal::kMaxZnccWindowPx ||
      zncc_window_px % 2 == 0) {
    throw ConfigError(ViolatedConstraint("cost.zncc_window_px", internal::Str(zncc_window_px),
                                         "odd, 3 <= zncc_window_px <= 21"));
  }
  if (aggregation != "mean" && aggregation != "best_k") {
    throw ConfigError(ViolatedConstraint("cost.aggregation", aggregation, "one of mean, best_k"));
  }
  if (best_k < 1) {
    throw ConfigError(ViolatedConstraint("cost.best_k", internal::Str(best_k), "best_k >= 1"));
  }
  if (min_voters < 1) {
    throw ConfigError(
        ViolatedConstraint("cost.min_voters", internal::Str(min_voters), "min_voters >= 1"));
  }
  if (progress_rows < 1) {
    throw ConfigError(ViolatedConstraint("cost.progress_rows", internal::Str(progress_rows),
                                         "progress_rows >= 1"));
  }
  window.Check("cost.sweep_");
}

namespace internal {

// (cost_internal.h) Sorts the per-neighbour costs of every column ascending (+inf = no vote
// sorts last) with an odd–even transposition network over the neighbour arrays (min/max per
// column vectorise), then averages the first min(k, votes) of them.
void MeanOfBestK(std::vector<float>& per_neighbor, int num_neighbors, int width, int k,
                 const float* votes, float* out) {
  for (int pass = 0; pass < num_neighbors; ++pass) {
    for (int n = pass % 2; n + 1 < num_neighbors; n += 2) {
      float* a = &per_neighbor[static_cast<std::size_t>(n) * width];
      float* b = a + width;
      for (int c = 0; c < width; ++c) {
        const float lo = std::min(a[c], b[c]);
        const float hi = std::max(a[c], b[c]);
        a[c] = lo;
        b[c] = hi;
      }
    }
  }
  for (int c = 0; c < width; ++c) {
    const int m = std::min(k, static_cast<int>(votes[c]));
    float sum = 0.0f;
    for (int i = 0; i < m; ++i) sum += per_neighbor[static_cast<std::size_t>(i) * width + c];
    out[c] = m > 0 ? sum / static_cast<float>(m) : 0.0f;
  }
}

}  // namespace internal

namespace {

constexpr float kInfinityCost = std::numeric_limits<float>::infinity();
using internal::PackedImage;
using internal::SweepRow;

// Owns the pixels of a PackedImage (see sweep_kernels.h).
struct PackedImageBuffer {
  std::vector<std::uint32_t> pixels;
  PackedImage view;
};

PackedImageBuffer MakePackedImage(const cv::Mat& bgr) {
  PackedImageBuffer out;
  const int stride = bgr.cols + 1;
  out.pixels.resize(static_cast<std::size_t>(stride) * (bgr.rows + 1));
  for (int row = 0; row <= bgr.rows; ++row) {
    const cv::Vec3b* src = bgr.ptr<cv::Vec3b>(std::min(row, bgr.rows - 1));
    std::uint32_t* dst = &out.pixels[static_cast<std::size_t>(row) * stride];
    for (int col = 0; col <= bgr.cols; ++col) {
      const cv::Vec3b& p = src[std::min(col, bgr.cols - 1)];
      dst[col] = static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
                 (static_cast<std::uint32_t>(p[2]) << 16);
    }
  }
  out.view = PackedImage{out.pixels.data(), bgr.cols, bgr.rows, stride};
  return out;
}

void CheckView(const View& view, const std::string& role) {
  const std::string context = role + " view '" + view.name + "'";
  view.camera.Validate(context);
  if (view.image.empty() || view.image.type() != CV_8UC3) {
    throw Error(context + ": the plane sweep needs an 8-bit 3-channel (BGR) image");
  }
  if (view.image.cols != view.camera.width || view.image.rows != view.camera.height) {
    std::ostringstream s;
    s << context << ": image is " << view.image.cols << "x" << view.image.rows
      << " but its camera is " << view.camera.width << "x" << view.camera.height;
    throw Error(s.str());
  }
}

// Labels computed together for one row before they are interleaved into the label-fastest volume:
// one 64-byte cache line of 16-bit costs per pixel.
constexpr int kLabelBlock = 32;

// Per-thread scratch for one reference row.
struct RowScratch {
  RowScratch(int width, int num_neighbors)
      : ref_b(width),
        ref_g(width),
        ref_r(width),
        sum(width),
        votes(width),
        per_neighbor(static_cast<std::size_t>(width) * num_neighbors),
        block(static_cast<std::size_t>(width) * kLabelBlock) {}
  std::vector<float> ref_b, ref_g, ref_r;
  std::vector<float> sum, votes;
  std::vector<float> per_neighbor;   // best_k: [neighbour][col], +inf = no vote
  std::vector<std::uint16_t> block;  // [label in block][col]
};

// What every region of one sweep shares: the neighbour images (packed RGB, or grey for "zncc")
// and the homographies H_{n,l} (index l · neighbours + n).
struct SweepContext {
  std::vector<PackedImageBuffer> images;
  std::vector<internal::GreyImage> grey_images;
  std::vector<Eigen::Matrix3d> homographies;
};

SweepContext MakeSweepContext(const View& reference, const std::vector<View>& neighbors,
                              const LabelSpace& labels, const PlaneSweepOptions& options) {
  options.Check();
  CheckView(reference, "reference");
  if (neighbors.empty()) throw Error("plane sweep: no neighbour views to match against");
  for (const View& view : neighbors) CheckView(view, "neighbour");
  const int num_labels = labels.count();
  const int num_neighbors = static_cast<int>(neighbors.size());
  SweepContext context;
  context.images.reserve(neighbors.size());
  for (const View& view : neighbors) {
    if (options.measure == "zncc") {
      context.grey_images.push_back(internal::MakeGreyImage(view.image));
    } else {
      context.images.push_back(MakePackedImage(view.image));
    }
  }

  // H_{n,l} = K_n (R + t nᵀ / z_l) K_ref⁻¹ with X_n = R X_ref + t for the relative pose.
  const Camera& ref_camera = reference.camera;
  const Eigen::Matrix3d ref_k_inv = ref_camera.K.inverse();
  context.homographies.resize(static_cast<std::size_t>(num_labels) * num_neighbors);
  for (int n = 0; n < num_neighbors; ++n) {
    const Camera& cam = neighbors[n].camera;
    const Eigen::Matrix3d rotation =
        cam.world_from_camera_rotation.transpose() * ref_camera.world_from_camera_rotation;
    const Eigen::Vector3d translation =
        cam.world_from_camera_rotation.transpose() * (ref_camera.center_world - cam.center_world);
    for (int l = 0; l < num_labels; ++l) {
      const double depth = labels.DepthOfLabel(l);
      const double inverse_depth = std::isfinite(depth) ? 1.0 / depth : 0.0;
      Eigen::Matrix3d plane = rotation;
      plane.col(2) += translation * inverse_depth;
      context.homographies[static_cast<std::size_t>(l) * num_neighbors + n] =
          cam.K * plane * ref_k_inv;
    }
  }
  return context;
}

// The pixel-wise sweep of `region` (ComputePlaneSweepCost without the window filter).
CostVolume PlaneSweepPixelCost(const SweepContext& context, const View& reference,
                               const LabelSpace& labels, const cv::Rect& region,
                               const PlaneSweepOptions& options, const ProgressCallback& progress,
                               PlaneSweepSummary* summary) {
  const Timer timer;
  const cv::Rect image_rect(0, 0, reference.image.cols, reference.image.rows);
  if (region.empty() || (region & image_rect) != region) {
    std::ostringstream s;
    s << "plane sweep: region " << region.width << "x" << region.height << " at (" << region.x
      << ", " << region.y << ") is empty or not inside the " << image_rect.width << "x"
      << image_rect.height << " reference image '" << reference.name << "'";
    throw Error(s.str());
  }

  const int num_labels = labels.count();
  if (options.measure == "zncc") {
    internal::ZnccSweepParams params;
    params.window_px = options.zncc_window_px;
    params.truncation = static_cast<float>(options.truncation);
    params.best_k = options.aggregation == "best_k";
    params.k = std::min(options.best_k, static_cast<int>(context.grey_images.size()));
    params.min_voters = options.min_voters;
    if (options.zncc_flat_fallback) {
      params.flat_truncation = static_cast<float>(options.truncation / std::sqrt(3.0));
    }
    internal::ZnccSweepCounts counts;
    CostVolume volume =
        internal::ZnccSweep(reference.image, context.grey_images, context.homographies, num_labels,
                            region, params, progress, &counts);
    if (summary != nullptr) {
      summary->samples = static_cast<std::int64_t>(region.area()) * num_labels *
                         static_cast<std::int64_t>(context.grey_images.size());
      summary->votes = counts.votes;
      summary->no_data_costs = counts.no_data;
      summary->volume_bytes = static_cast<std::int64_t>(volume.memory_bytes());
      summary->seconds = timer.ElapsedSeconds();
      summary->cancelled = counts.cancelled;
    }
    return volume;
  }
  const int num_neighbors = static_cast<int>(context.images.size());
  const int width = region.width;
  const float truncation = static_cast<float>(options.truncation);
  const bool best_k = options.aggregation == "best_k";
  const int k = std::min(options.best_k, num_neighbors);
  const float min_votes = static_cast<float>(options.min_voters);
  CostVolume volume(region, num_labels, truncation);
  const float inv_step = 1.0f / volume.cost_step();
  const bool avx2 = internal::HaveAvx2Kernel();
  const std::vector<PackedImageBuffer>& images = context.images;
  const std::vector<Eigen::Matrix3d>& homographies = context.homographies;

  std::atomic<std::int64_t> total_votes{0};
  std::atomic<std::int64_t> total_no_data{0};
  const cv::Mat& ref_image = reference.image;

  auto process_row = [&](int row_local, RowScratch& s) {
    const int y_ref = region.y + row_local;
    const cv::Vec3b* ref_src = ref_image.ptr<cv::Vec3b>(y_ref) + region.x;
    for (int c = 0; c < width; ++c) {
      s.ref_b[c] = ref_src[c][0];
      s.ref_g[c] = ref_src[c][1];
      s.ref_r[c] = ref_src[c][2];
    }
    std::uint16_t* out = volume.MutablePixelData(row_local, 0);
    std::int64_t votes = 0;
    std::int64_t no_data = 0;
    for (int l0 = 0; l0 < num_labels; l0 += kLabelBlock) {
      const int block_labels = std::min(kLabelBlock, num_labels - l0);
      for (int b = 0; b < block_labels; ++b) {
        const int l = l0 + b;
        std::fill(s.sum.begin(), s.sum.end(), 0.0f);
        std::fill(s.votes.begin(), s.votes.end(), 0.0f);
        for (int n = 0; n < num_neighbors; ++n) {
          const Eigen::Matrix3d& h = homographies[static_cast<std::size_t>(l) * num_neighbors + n];
          SweepRow sweep_row;
          sweep_row.ax = static_cast<float>(h(0, 1) * y_ref + h(0, 2));
          sweep_row.ay = static_cast<float>(h(1, 1) * y_ref + h(1, 2));
          sweep_row.aw = static_cast<float>(h(2, 1) * y_ref + h(2, 2));
          sweep_row.bx = static_cast<float>(h(0, 0));
          sweep_row.by = static_cast<float>(h(1, 0));
          sweep_row.bw = static_cast<float>(h(2, 0));
          sweep_row.first_col = region.x;
          sweep_row.count = width;
          sweep_row.ref_b = s.ref_b.data();
          sweep_row.ref_g = s.ref_g.data();
          sweep_row.ref_r = s.ref_r.data();
          sweep_row.truncation = truncation;
          float* costs = best_k ? &s.per_neighbor[static_cast<std::size_t>(n) * width] : nullptr;
          float* sum = best_k ? nullptr : s.sum.data();
          const std::int64_t n_votes =
              avx2
                  ? internal::SweepRowAvx2(images[n].view, sweep_row, sum, s.votes.data(), costs)
                  : internal::SweepRowScalar(images[n].view, sweep_row, sum, s.votes.data(), costs);
          votes += n_votes;
          if (best_k) {
            // Count this neighbour's votes per column (the kernel does so only when accumulating).
            for (int c = 0; c < width; ++c) s.votes[c] += costs[c] < kInfinityCost ? 1.0f : 0.0f;
          }
        }
        if (best_k) {
          internal::MeanOfBestK(s.per_neighbor, num_neighbors, width, k, s.votes.data(),
                                s.sum.data());
        } else {
          for (int c = 0; c < width; ++c) {
            s.sum[c] = s.votes[c] > 0.0f ? s.sum[c] / s.votes[c] : 0.0f;
          }
        }
        std::uint16_t* q = &s.block[static_cast<std::size_t>(b) * width];
        for (int c = 0; c < width; ++c) {
          const bool has_data = s.votes[c] >= min_votes;
          no_data += has_data ? 0 : 1;
          q[c] = has_data ? internal::Quantise(s.sum[c], inv_step) : CostVolume::kNoData;
        }
      }
      // Interleave the block into the label-fastest layout.
      for (int c = 0; c < width; ++c) {
        std::uint16_t* dst = out + static_cast<std::size_t>(c) * num_labels + l0;
        for (int b = 0; b < block_labels; ++b)
          dst[b] = s.block[static_cast<std::size_t>(b) * width + c];
      }
    }
    total_votes += votes;
    total_no_data += no_data;
  };

  bool cancelled = false;
  const int block_rows = options.progress_rows;
  for (int row0 = 0; row0 < region.height; row0 += block_rows) {
    const int row1 = std::min(region.height, row0 + block_rows);
    tbb::parallel_for(
        tbb::blocked_range<int>(row0, row1, 1),
        [&](const tbb::blocked_range<int>& range) {
          RowScratch scratch(width, num_neighbors);
          for (int row = range.begin(); row != range.end(); ++row) process_row(row, scratch);
        },
        tbb::simple_partitioner());
    if (progress && !progress(static_cast<double>(row1) / region.height)) {
      cancelled = row1 < region.height;
      if (cancelled) {
        total_no_data += static_cast<std::int64_t>(region.height - row1) * width * num_labels;
      }
      break;
    }
  }

  if (summary != nullptr) {
    summary->samples = static_cast<std::int64_t>(region.area()) * num_labels * num_neighbors;
    summary->votes = total_votes.load();
    summary->no_data_costs = total_no_data.load();
    summary->volume_bytes = static_cast<std::int64_t>(volume.memory_bytes());
    summary->seconds = timer.ElapsedSeconds();
    summary->cancelled = cancelled;
  }
  return volume;
}

// One region of a sweep: pixel-wise, or grown by the window's margin, swept and filtered.
CostVolume SweepRegion(const SweepContext& context, const View& reference, const LabelSpace& labels,
                       const cv::Rect& region, const PlaneSweepOptions& options,
                       const ProgressCallback& progress, PlaneSweepSummary* summary) {
  const Timer timer;
  const cv::Rect image_rect(0, 0, reference.image.cols, reference.image.rows);
  if (options.window.window_px == 1 || region.empty() || (region & image_rect) != region) {
    // Pixel-wise (or a bad region, which the sweep reports).
    return PlaneSweepPixelCost(context, reference, labels, region, options, progress, summary);
  }
  const cv::Rect outer = GrowRegion(region, options.window.MarginPx(), reference.image.size());
  CostVolume volume = FilterCostVolume(
      PlaneSweepPixelCost(context, reference, labels, outer, options, progress, summary),
      reference.image, region, options.window);
  if (summary != nullptr) {
    std::int64_t no_data = 0;
    for (int r = 0; r < volume.height(); ++r) {
      for (int c = 0; c < volume.width(); ++c) {
        const std::uint16_t* costs = volume.PixelData(r, c);
        no_data += std::count(costs, costs + volume.num_labels(), CostVolume::kNoData);
      }
    }
    summary->no_data_costs = no_data;
    summary->volume_bytes = static_cast<std::int64_t>(volume.memory_bytes());
    summary->seconds = timer.ElapsedSeconds();
  }
  return volume;
}

}  // namespace

CostVolume ComputePlaneSweepCost(const View& reference, const std::vector<View>& neighbors,
                                 const LabelSpace& labels, const cv::Rect& region,
                                 const PlaneSweepOptions& options, const ProgressCallback& progress,
                                 PlaneSweepSummary* summary) {
  const Timer timer;
  const SweepContext context = MakeSweepContext(reference, neighbors, labels, options);
  CostVolume volume = SweepRegion(context, reference, labels, region, options, progress, summary);
  if (summary != nullptr) summary->seconds = timer.ElapsedSeconds();  // with the packing
  return volume;
}

std::vector<CostVolume> ComputePlaneSweepCostForRegions(const View& reference,
                                                        const std::vector<View>& neighbors,
                                                        const LabelSpace& labels,
                                                        const std::vector<cv::Rect>& regions,
                                                        const PlaneSweepOptions& options) {
  const SweepContext context = MakeSweepContext(reference, neighbors, labels, options);
  std::vector<CostVolume> volumes(regions.size());
  tbb::parallel_for(std::size_t{0}, regions.size(), [&](std::size_t i) {
    volumes[i] = SweepRegion(context, reference, labels, regions[i], options, {}, nullptr);
  });
  return volumes;
}

}  // namespace gcpstereo::cost
