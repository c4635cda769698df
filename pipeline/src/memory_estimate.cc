// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/memory_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <unistd.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "gcpstereo/core/error.h"
#include "gcpstereo/pipeline/pipeline_config.h"

namespace gcpstereo::pipeline {
namespace {

// Without the resident memory (a plan made before the run, `gcpstereo views`): the process before
// any data, the executable with OpenCV, PCL, VTK, Ceres, SuiteSparse and TBB loaded (peak of
// `run --set runtime.stop_after=load` on the tiny preset, whose images are 0.1 MB: 112 MB) ...
constexpr double kBaseBytes = 110e6;

// ... and per pixel of each view held (the reference and every neighbour): the BGR image, its grey
// and float copies and the plane sweep's padded copy of each neighbour. Measured: the small
// preset's 7 views of 640×427 add 11 MB at runtime.stop_after=load over the tiny preset's 112.
constexpr double kViewBytesPerPixel = 8.0;

// Per pixel of the reference, the propagation (D̂, eq. 5) at its peak, from the small preset
// (640×427, LiDAR GCPs at s = 8) with runtime.stop_after=propagation minus stop_after=load:
// linear_system with CHOLMOD 367 − 123 MB, with UMFPACK 482 − 123 MB (the sparse 5-point system,
// its symmetric form and the factor's fill-in); the windowed methods keep a few maps
// (weighted_median 128 − 123, local_plane 130 − 123 MB).
double PropagationBytesPerPixel(const std::string& method, const std::string& solver) {
  if (method == "linear_system") return solver == "umfpack" ? 1320.0 : 900.0;
  return 30.0;
}

// Per pixel of a tile and label: the cost volume (CostVolume, 16 bits) and the expansion's copy
// ordered by label (alpha_expansion.cc costs_by_label_, 16 bits).
constexpr double kTileBytesPerPixelLabel = 2.0 + 2.0;

// Per pixel of a tile, whatever the labels: the Boykov–Kolmogorov graph (maxflow::Graph<double,
// double, double>: a 48-byte node and two 2-arc edges of 32 bytes per arc, 176 bytes), the
// expansion's per-pixel arrays (weights, labels, unaries, marks, node indices, the per-node costs:
// about 68 bytes), the tile's image, prior and result (11 bytes).
constexpr double kTileBytesPerPixel = 176.0 + 68.0 + 11.0;

// Per pixel of a tile, the Ceres sub-label refinement (optimizer.refinement: ceres), which runs
// after the expansion's graph and buffers are freed while the cost volume stays: a parameter, a
// data and a GCP residual and two Huber-weighted smoothness residuals per pixel with Ceres'
// program, Jacobians and solver (conjugate gradients, refinement.cc). Measured: the small preset
// (640×427, 48 labels, one tile, one thread) peaked at 810 MB with it, 236 MB with the parabola,
// which needs nothing more, when Ceres factorised the normal equations (sparse Cholesky); with
// conjugate gradients, synthetic_fountain.yaml on the small preset (360 labels, one tile, one
// thread) peaks at 808 MB instead of 907 MB, about 1640 bytes per pixel for Ceres. With the losses
// shared and the cost functions in deques (one residual block per pixel with a prior), KITTI frame
// 10 (kitti_lidar.yaml, two tiles at once) peaks at 870-890 MB instead of 1081-1110 MB: about
// 1300 bytes per pixel beside the cost volume.
constexpr double kCeresBytesPerPixel = 1400.0;
// Per pixel of a tile, the IRLS refinement (optimizer.refinement: irls): the problem's arrays (5
// doubles and two pair records), the 5-point matrix (values, column indices and the positions of
// its entries), the right-hand side, two solution vectors and conjugate gradients' four vectors
// and diagonal, plus the triplets and Eigen's transposed copy while the matrix is built: about
// 400 bytes, below the expansion's phase for any label count.
constexpr double kIrlsBytesPerPixel = 400.0;

constexpr double kWindowFilterBytesPerPixel = 300.0;

std::string Megabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.0f MB", bytes / 1e6);
  return text;
}

}  // namespace

double MemoryEstimate::total_bytes() const {
  return base_bytes + views_bytes + std::max(propagation_bytes, optimization_bytes) + partner_bytes;
}

nlohmann::json MemoryEstimate::ToJson() const {
  return {{"total_bytes", total_bytes()},
          {"base_bytes", base_bytes},
          {"views_bytes", views_bytes},
          {"propagation_bytes", propagation_bytes},
          {"optimization_bytes", optimization_bytes},
          {"partner_bytes", partner_bytes},
          {"concurrent_tiles", concurrent_tiles},
          {"tile_pixels", tile_pixels},
          {"note",
           "estimated before the propagation and the optimisation allocate (base + views + the "
           "larger of propagation and optimisation + the left-right partner's); compare "
           "peak_memory_bytes"}};
}

ViewMemoryInput ViewMemoryInputOf(const PipelineConfig& options, int width_px, int height_px,
                                  int labels, int neighbors) {
  ViewMemoryInput input;
  input.width_px = width_px;
  input.height_px = height_px;
  input.labels = labels;
  input.neighbors = neighbors;
  input.tile_rows = options.tiling.tiles[0];
  input.tile_cols = options.tiling.tiles[1];
  input.tile_overlap_px = options.tiling.tile_overlap;
  input.threads = options.runtime.threads;
  input.propagation = options.propagation.method;
  input.solver = options.propagation.solver;
  input.refinement = options.optimizer.refinement_method;
  input.has_gcps = !options.gcp.sources.empty();
  input.window_filter = options.cost.birchfield_tomasi.window.window_px > 1 ||
                        options.cost.plane_sweep.window.window_px > 1;
  input.optimize = options.runtime.stop_after == "all";
  input.left_right_check = options.optimizer.left_right_check;
  return input;
}

MemoryEstimate EstimateViewMemory(const ViewMemoryInput& in) {
  MemoryEstimate e;
  const double pixels = static_cast<double>(in.width_px) * in.height_px;
  if (in.resident_bytes > 0.0) {
    e.base_bytes = in.resident_bytes;
  } else {
    e.base_bytes = kBaseBytes;
    e.views_bytes = kViewBytesPerPixel * pixels * (1 + std::max(0, in.neighbors));
  }
  if (in.has_gcps)
    e.propagation_bytes = PropagationBytesPerPixel(in.propagation, in.solver) * pixels;
  if (in.optimize) {
    // The largest tile: the image split evenly, plus the overlap on both sides (tiling.cc).
    const int rows = std::max(1, in.tile_rows), cols = std::max(1, in.tile_cols);
    const auto side = [&](int length, int parts) {
      const double inner = std::ceil(static_cast<double>(length) / parts);
      return std::min<double>(length, inner + (parts > 1 ? 2.0 * in.tile_overlap_px : 0.0));
    };
    e.tile_pixels = side(in.width_px, cols) * side(in.height_px, rows);
    const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    e.concurrent_tiles = std::min(rows * cols, in.threads > 0 ? in.threads : cores);
    const double labels = std::max(1, in.labels);
    double expansion = kTileBytesPerPixelLabel * labels + kTileBytesPerPixel;
    // The window aggregation (cost_filter.cc) returns a filtered volume beside the raw one, with
    // the guided filter's per-pixel double images (the guide, its means and inverse covariances,
    // and each thread's cost, mean, result and coefficient rows: about 300 bytes).
    if (in.window_filter) expansion += 2.0 * labels + kWindowFilterBytesPerPixel;
    const double refinement = in.refinement == "ceres"  ? 2.0 * labels + kCeresBytesPerPixel + 11.0
                              : in.refinement == "irls" ? 2.0 * labels + kIrlsBytesPerPixel + 11.0
                                                        : 0.0;
    e.optimization_bytes = e.concurrent_tiles * e.tile_pixels * std::max(expansion, refinement);
    // The neighbour's solve of the left-right check: its D̂ and then its tiles, alongside the
    // reference's (pipeline/src/view_stages.h, StartPartnerSolve), on an image of the same size.
    if (in.left_right_check) e.partner_bytes = std::max(e.propagation_bytes, e.optimization_bytes);
  }
  return e;
}

double ResidentMemoryBytes() {
  std::ifstream in("/proc/self/statm");
  double total_pages = 0.0, resident_pages = 0.0;
  if (!(in >> total_pages >> resident_pages)) return 0.0;
  return resident_pages * static_cast<double>(sysconf(_SC_PAGESIZE));
}

void ReleaseFreedHeapMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

double AvailableMemoryBytes() {
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("MemAvailable:", 0) != 0) continue;
    std::istringstream fields(line.substr(13));
    double kilobytes = 0.0;
    if (fields >> kilobytes) return kilobytes * 1024.0;
  }
  return 0.0;
}

double MemoryBudgetBytes(double max_memory_gb) {
  if (max_memory_gb > 0.0) return max_memory_gb * 1e9;
  return AvailableMemoryBytes();
}

void CheckMemoryBudget(const MemoryEstimate& estimate, double max_memory_gb) {
  const double budget = MemoryBudgetBytes(max_memory_gb);
  if (budget <= 0.0 || estimate.total_bytes() <= budget) return;
  const std::string limit = max_memory_gb > 0.0
                                ? "runtime.max_memory_gb = " + FormatNumber(max_memory_gb)
                                : "the memory available (/proc/meminfo MemAvailable)";
  throw Error("this view needs an estimated " + Megabytes(estimate.total_bytes()) + ", more than " +
              limit + " (" + Megabytes(budget) +
              "): lower it with more optimizer.tiles, a smaller dataset.scale or fewer "
              "labels.count");
}

}  // namespace gcpstereo::pipeline
