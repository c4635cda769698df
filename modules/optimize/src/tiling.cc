// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/tiling.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"

namespace gcpstereo::optimize {
namespace {

// Core borders 0 = b_0 < b_1 < … < b_n = size.
std::vector<int> CoreBorders(int size, int n) {
  std::vector<int> borders(n + 1);
  for (int i = 0; i <= n; ++i) borders[i] = static_cast<int>(static_cast<long long>(i) * size / n);
  return borders;
}

// Linear feather weight along one axis of a tile spanning [begin, end) whose first/last
// `overlap` pixels are shared with a neighbour when has_before/has_after.
double Ramp(int x, int begin, int end, bool has_before, bool has_after, int overlap) {
  if (overlap <= 0) return 1.0;
  double w = 1.0;
  if (has_before && x < begin + overlap) w = std::min(w, (x - begin + 0.5) / overlap);
  if (has_after && x >= end - overlap) w = std::min(w, (end - x - 0.5) / overlap);
  return w;
}

}  // namespace

void TilingOptions::Check() const {
  if (rows < 1 || cols < 1) {
    throw ConfigError(ViolatedConstraint(
        "optimizer.tiles", "[" + std::to_string(rows) + ", " + std::to_string(cols) + "]",
        "rows >= 1 and cols >= 1"));
  }
  if (overlap_px < 0) {
    throw ConfigError(
        ViolatedConstraint("optimizer.tile_overlap", std::to_string(overlap_px), ">= 0"));
  }
  if (blend != "mean" && blend != "feather") {
    throw ConfigError(ViolatedConstraint("optimizer.blend", blend, "one of \"mean\", \"feather\""));
  }
}

std::vector<cv::Rect> TileLayout(cv::Size image_size, const TilingOptions& options) {
  options.Check();
  if (image_size.width <= 0 || image_size.height <= 0) {
    throw Error("TileLayout: empty image size " + std::to_string(image_size.width) + "x" +
                std::to_string(image_size.height));
  }
  const int min_core = std::min(image_size.height / options.rows, image_size.width / options.cols);
  if (min_core < 1 || ((options.rows > 1 || options.cols > 1) && min_core < options.overlap_px)) {
    throw ConfigError(ViolatedConstraint(
        "optimizer.tile_overlap", std::to_string(options.overlap_px),
        "<= the smallest tile (" + std::to_string(min_core) + " px for " +
            std::to_string(options.rows) + "x" + std::to_string(options.cols) + " tiles of " +
            std::to_string(image_size.width) + "x" + std::to_string(image_size.height) + ")"));
  }
  const int before = options.overlap_px / 2, after = options.overlap_px - before;
  const std::vector<int> ys = CoreBorders(image_size.height, options.rows);
  const std::vector<int> xs = CoreBorders(image_size.width, options.cols);
  std::vector<cv::Rect> tiles;
  for (int r = 0; r < options.rows; ++r) {
    const int top = r > 0 ? ys[r] - before : 0;
    const int bottom = r + 1 < options.rows ? ys[r + 1] + after : image_size.height;
    for (int c = 0; c < options.cols; ++c) {
      const int left = c > 0 ? xs[c] - before : 0;
      const int right = c + 1 < options.cols ? xs[c + 1] + after : image_size.width;
      tiles.emplace_back(left, top, right - left, bottom - top);
    }
  }
  return tiles;
}

std::string TiledResult::Summary() const {
  std::ostringstream s;
  s << tiles.size() << " tiles, energy sum " << energy_sum << ", " << time_seconds << " s, peak "
    << peak_memory_bytes / (1024.0 * 1024.0) << " MiB" << (cancelled ? " (cancelled)" : "");
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const cv::Rect& r = tiles[i].region;
    s << "\n  tile " << i << " [" << r.x << ", " << r.y << ", " << r.width << "x" << r.height
      << "]: setup " << tiles[i].setup_seconds << " s; " << tiles[i].expansion.Summary();
    const RefinementSummary& refinement = tiles[i].refinement;
    if (refinement.method != RefinementMethod::kNone) {
      s << "; refinement " << RefinementMethodName(refinement.method) << ": "
        << refinement.iterations << " iterations, mean |offset| " << refinement.mean_abs_offset
        << (refinement.solver_converged ? "" : " (solver did not converge)") << ", "
        << refinement.time_seconds << " s";
    }
  }
  return s.str();
}

TiledResult OptimizeTiled(cv::Size image_size, const MakeTileProblem& make_problem,
                          const EnergyOptions& energy_options,
                          const ExpansionOptions& expansion_options,
                          const TilingOptions& tiling_options, const cv::Mat& initial_labels,
                          const ProgressCallback& progress, const RefinementOptions& refinement) {
  const Timer timer;
  energy_options.Check();
  expansion_options.Check();
  refinement.Check();
  const std::vector<cv::Rect> layout = TileLayout(image_size, tiling_options);
  if (!initial_labels.empty() &&
      (initial_labels.type() != CV_32S || initial_labels.size() != image_size)) {
    throw Error("OptimizeTiled: the initial labelling must be CV_32S of the image size " +
                std::to_string(image_size.width) + "x" + std::to_string(image_size.height));
  }
  const int num_tiles = static_cast<int>(layout.size());
  TiledResult result;
  result.tiles.resize(num_tiles);
  std::vector<cv::Mat> tile_labels(num_tiles);
  std::atomic<bool> cancel{false};
  std::mutex progress_mutex;
  // Progress: each tile counts for 1/num_tiles, split over its phases (cost set-up 0.3, the
  // expansion cycles 0.5 as AlphaExpansion reports them, refinement and hand-over 0.2).
  std::vector<double> tile_fraction(num_tiles, 0.0);
  auto report_progress = [&](int t, double fraction) {
    if (progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      tile_fraction[t] = fraction;
      double sum = 0.0;
      for (double f : tile_fraction) sum += f;
      if (!progress(std::min(1.0, sum / num_tiles))) cancel = true;
    }
    return !cancel.load();
  };

  auto solve_tile = [&](int t) {
    if (cancel.load()) return;
    const cv::Rect region = layout[t];
    TileReport& report = result.tiles[t];
    report.region = region;
    const Timer setup_timer;
    OwnedMrfProblem owned = make_problem(region);
    report.data_computed_share = owned.data_computed_share;
    if (energy_options.use_gcp_energy && !owned.prior.empty()) {
      // Eqs. (9)–(10): the data confidence's factors with the caller's spread factors ρ_p.
      owned.prior_weight = PriorWeights(owned.data, owned.prior_weight, energy_options);
    }
    report.setup_seconds = setup_timer.ElapsedSeconds();
    report_progress(t, 0.3);
    const MrfProblem problem = owned.View();
    problem.Validate();
    if (problem.width() != region.width || problem.height() != region.height) {
      throw Error("OptimizeTiled: make_problem returned a " + std::to_string(problem.width()) +
                  "x" + std::to_string(problem.height()) + " problem for a " +
                  std::to_string(region.width) + "x" + std::to_string(region.height) + " tile");
    }
    const cv::Mat init = initial_labels.empty() ? cv::Mat() : initial_labels(region).clone();
    report.expansion =
        AlphaExpansion(problem, energy_options, expansion_options, init,
                       [&](double fraction) { return report_progress(t, 0.3 + 0.5 * fraction); });
    if (refinement.method == RefinementMethod::kNone) {
      report.expansion.labels.convertTo(tile_labels[t], CV_32F);
    } else {
      tile_labels[t] = RefineSubLabel(problem, report.expansion.labels, energy_options, refinement,
                                      &report.refinement);
    }
    report.expansion.labels.release();
    report_progress(t, 1.0);
  };

  const int threads = expansion_options.num_threads > 0 ? expansion_options.num_threads
                                                        : tbb::task_arena::automatic;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, num_tiles, 1),
                      [&](const tbb::blocked_range<int>& range) {
                        for (int t = range.begin(); t != range.end(); ++t) solve_tile(t);
                      });
  });

  // Merge in the fixed tile order (independent of the order the tiles finished in).
  const bool feather = tiling_options.blend == "feather";
  cv::Mat sum(image_size, CV_64F, cv::Scalar(0.0)), weight(image_size, CV_64F, cv::Scalar(0.0));
  for (int t = 0; t < num_tiles; ++t) {
    const cv::Rect& r = layout[t];
    const TileReport& report = result.tiles[t];
    if (tile_labels[t].empty() || report.expansion.cancelled) {
      result.cancelled = true;
      if (tile_labels[t].empty()) continue;
    }
    result.energy_sum += report.expansion.breakdown.total();
    const int tile_row = t / tiling_options.cols, tile_col = t % tiling_options.cols;
    const bool up = tile_row > 0, down = tile_row + 1 < tiling_options.rows;
    const bool left = tile_col > 0, right = tile_col + 1 < tiling_options.cols;
    for (int y = 0; y < r.height; ++y) {
      const float* labels = tile_labels[t].ptr<float>(y);
      double* s = sum.ptr<double>(r.y + y) + r.x;
      double* w = weight.ptr<double>(r.y + y) + r.x;
      const double wy = feather ? Ramp(y, 0, r.height, up, down, tiling_options.overlap_px) : 1.0;
      for (int x = 0; x < r.width; ++x) {
        const double wx =
            feather ? Ramp(x, 0, r.width, left, right, tiling_options.overlap_px) : 1.0;
        s[x] += wy * wx * labels[x];
        w[x] += wy * wx;
      }
    }
  }
  result.labels.create(image_size, CV_32F);
  for (int y = 0; y < image_size.height; ++y) {
    const double* s = sum.ptr<double>(y);
    const double* w = weight.ptr<double>(y);
    float* out = result.labels.ptr<float>(y);
    for (int x = 0; x < image_size.width; ++x) {
      out[x] =
          w[x] > 0.0 ? static_cast<float>(s[x] / w[x]) : std::numeric_limits<float>::quiet_NaN();
    }
  }
  result.time_seconds = timer.ElapsedSeconds();
  result.peak_memory_bytes = PeakResidentMemoryBytes();
  return result;
}

SeamStatistics MeasureSeams(const cv::Mat& tiled, const cv::Mat& untiled,
                            const TilingOptions& options) {
  if (tiled.size() != untiled.size() || tiled.channels() != 1 || untiled.channels() != 1) {
    throw Error("MeasureSeams: the tiled and untiled maps must be single-channel of one size");
  }
  cv::Mat a, b;
  tiled.convertTo(a, CV_64F);
  untiled.convertTo(b, CV_64F);
  const std::vector<cv::Rect> layout = TileLayout(tiled.size(), options);
  cv::Mat coverage(tiled.size(), CV_32S, cv::Scalar(0));
  for (const cv::Rect& r : layout) {
    cv::Mat roi = coverage(r);
    roi += 1;
  }
  SeamStatistics stats;
  double overlap_sum = 0.0, interior_sum = 0.0;
  long long interior_count = 0;
  for (int y = 0; y < a.rows; ++y) {
    for (int x = 0; x < a.cols; ++x) {
      const double d = std::abs(a.at<double>(y, x) - b.at<double>(y, x));
      if (coverage.at<int>(y, x) > 1) {
        overlap_sum += d;
        ++stats.overlap_pixels;
      } else {
        interior_sum += d;
        ++interior_count;
      }
    }
  }
  double jump_sum = 0.0;
  auto pair = [&](int y0, int x0, int y1, int x1) {
    jump_sum += std::abs((a.at<double>(y0, x0) - a.at<double>(y1, x1)) -
                         (b.at<double>(y0, x0) - b.at<double>(y1, x1)));
    ++stats.border_pairs;
  };
  const std::vector<int> ys = CoreBorders(a.rows, options.rows);
  const std::vector<int> xs = CoreBorders(a.cols, options.cols);
  for (int i = 1; i < options.rows; ++i) {
    for (int x = 0; x < a.cols; ++x) pair(ys[i] - 1, x, ys[i], x);
  }
  for (int j = 1; j < options.cols; ++j) {
    for (int y = 0; y < a.rows; ++y) pair(y, xs[j] - 1, y, xs[j]);
  }
  if (stats.overlap_pixels > 0) stats.mean_abs_diff_overlap = overlap_sum / stats.overlap_pixels;
  if (interior_count > 0) stats.mean_abs_diff_interior = interior_sum / interior_count;
  if (stats.border_pairs > 0) stats.mean_border_jump_excess = jump_sum / stats.border_pairs;
  return stats;
}

}  // namespace gcpstereo::optimize
