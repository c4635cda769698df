// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/progress.h"
#include "gcpstereo/optimize/alpha_expansion.h"
#include "gcpstereo/optimize/energy.h"
#include "gcpstereo/optimize/refinement.h"

namespace gcpstereo::optimize {

// The paper's tiling (Sec. 4.2): "we divide the reference image into 4 rectangular tiles (2 × 2).
// The width of the overlapping areas between two tiles is 16 pixels. We perform graph cuts
// optimization for each tile independently and merge the 4 depth maps … For pixels within
// overlapping areas their depths are set to the mean of multiple measurements".
struct TilingOptions {
  // Tile grid. YAML optimizer.tiles: [rows, cols]. Range: >= 1 each.
  int rows = 2;
  int cols = 2;
  // Width of the band two neighbouring tiles share, pixels. YAML optimizer.tile_overlap.
  // Range: >= 0 (and smaller than a tile).
  int overlap_px = 16;
  // "mean" (the paper: mean of the tiles' labels in the overlaps) or "feather" (weights falling
  // linearly to 0 across the overlap band). YAML optimizer.blend.
  std::string blend = "mean";

  void Check() const;
};

// Tile rectangles in image coordinates, row-major. Depends only on the image size and the
// options (never on the thread count). Core borders at floor(i·H/rows), floor(j·W/cols); each
// tile extends overlap_px/2 (rounded down) above/left and the rest below/right of an inner border.
// Throws ConfigError when a tile would be smaller than the overlap.
std::vector<cv::Rect> TileLayout(cv::Size image_size, const TilingOptions& options);

struct TileReport {
  cv::Rect region;
  ExpansionResult expansion;     // its labels are released after merging (empty)
  RefinementSummary refinement;  // when OptimizeTiled was asked to refine
  double setup_seconds = 0.0;    // time spent in make_problem (cost volume of the tile)
  double data_computed_share = 1.0;  // OwnedMrfProblem::data_computed_share of the tile
};

struct TiledResult {
  cv::Mat labels;  // CV_32F continuous labels of the whole image (fractional in overlaps)
  std::vector<TileReport> tiles;
  double energy_sum = 0.0;  // Σ of the tiles' final energies (each on its own region)
  double time_seconds = 0.0;
  std::size_t peak_memory_bytes = 0;  // PeakResidentMemoryBytes() at the end
  bool cancelled = false;
  std::string Summary() const;
};

inline RefinementOptions NoRefinement() {
  RefinementOptions options;
  options.method = RefinementMethod::kNone;
  return options;
}

// Builds the MRF of one region (a tile with its overlap). Called once per tile, possibly from
// several threads at once (it must be thread-safe); its result is freed after the tile is solved,
// so memory follows the tile. Its prior weights (ρ_p of eq. 10, or empty) become ω_p of eq. (9)
// by PriorWeights.
using MakeTileProblem = std::function<OwnedMrfProblem(const cv::Rect& region)>;

// Optimises every tile independently with AlphaExpansion (tiles in parallel on up to
// expansion_options.num_threads threads; the result does not depend on the thread count) and
// merges them (mean or feather blend, fixed tile order). A 1 × 1 tiling gives exactly the labels
// of AlphaExpansion on the whole image, as float. When `refinement.method` is not kNone, each
// tile is refined with RefineSubLabel while its costs exist, before merging (1 × 1 then equals
// AlphaExpansion + RefineSubLabel on the whole image). `initial_labels` (CV_32S, whole image) is
// optional. Progress: each tile counts for an equal share, advanced after its cost set-up, during
// its expansion cycles and when it is done; returning false from `progress` cancels.
TiledResult OptimizeTiled(cv::Size image_size, const MakeTileProblem& make_problem,
                          const EnergyOptions& energy_options,
                          const ExpansionOptions& expansion_options,
                          const TilingOptions& tiling_options, const cv::Mat& initial_labels = {},
                          const ProgressCallback& progress = {},
                          const RefinementOptions& refinement = NoRefinement());

// Seams of a tiled result against an untiled run of the same problem (both CV_32F or CV_32S).
struct SeamStatistics {
  double mean_abs_diff_overlap = 0.0;   // mean |tiled − untiled| over the overlap bands
  double mean_abs_diff_interior = 0.0;  // … over the rest of the image
  // Mean over 4-neighbour pairs straddling a core tile border of
  // | (tiled_p − tiled_q) − (untiled_p − untiled_q) |: jumps the tiling added at its borders.
  double mean_border_jump_excess = 0.0;
  int overlap_pixels = 0;
  int border_pairs = 0;
};
SeamStatistics MeasureSeams(const cv::Mat& tiled, const cv::Mat& untiled,
                            const TilingOptions& options);

}  // namespace gcpstereo::optimize
