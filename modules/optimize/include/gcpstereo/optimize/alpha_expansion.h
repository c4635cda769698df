// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/optimize/energy.h"

namespace gcpstereo::optimize {

// Which labels α are tried at which pixels.
enum class CandidateLabels {
  // Plain α-expansion: every label at every pixel (Boykov, Veksler & Zabih 2001).
  kAll,
  // Per block of candidate_block_px² pixels: the labels within ±candidate_radius of a label that
  // is the winner-take-all label of at least candidate_min_votes pixels of the block (or of its
  // 8 neighbouring blocks), of a prior D̂_p in the block, and the initial labels in the block.
  // An α-move then only involves the blocks where α is a candidate. This restricts the label
  // space (an approximation: its energy gap to kAll is measured by the benchmark).
  kLocal,
  // Per block: only the labels within ±candidate_radius of a prior D̂_p in the block and the
  // initial labels in the block — kLocal without the WTA votes. For a dense, trusted D̂ (a LiDAR
  // scan), where the cost's winner-take-all labels add mostly noise candidates: with
  // Initialization::kPrior the start is D̂ rounded, so a block of D̂ tries a few labels around it,
  // and a block that D̂ does not reach tries its pixels' start (WTA) labels only; without a prior
  // (no D̂, or EnergyOptions::use_gcp_energy false) it is kLocal. A stronger
  // approximation than kLocal; energy and accuracy measured in configs/kitti_lidar.yaml (keeping
  // the votes where D̂ does not reach: the same accuracy there, twice the expansion time).
  kPrior,
};
const char* CandidateLabelsName(CandidateLabels mode);
// "all", "local" or "prior"; throws ConfigError naming optimizer.candidate_labels otherwise.
CandidateLabels ParseCandidateLabels(const std::string& name);

// How the labelling starts when AlphaExpansion gets no initial labels.
enum class Initialization { kWinnerTakeAll, kPrior };

struct ExpansionOptions {
  // Maximum number of cycles over all labels. YAML optimizer.max_cycles. Range: >= 1.
  int max_cycles = 8;
  // Stop when a cycle lowers the energy by less than this fraction of the energy before it
  // (0 = cycle until no move improves). YAML optimizer.convergence_tolerance. Range: [0, 1).
  double convergence_tolerance = 1e-4;
  // YAML optimizer.candidate_labels ("all" | "local" | "prior").
  CandidateLabels candidate_labels = CandidateLabels::kLocal;
  // Block side for candidate sets and change tracking, pixels. YAML optimizer.candidate_block.
  // Range: >= 4.
  int candidate_block_px = 16;
  // Labels within this many steps of a voted WTA label / prior are candidates, label steps.
  // YAML optimizer.candidate_radius. Range: >= 0.
  int candidate_radius = 2;
  // Minimum WTA votes (pixels in the 3×3 block neighbourhood) to make a label a candidate.
  // YAML optimizer.candidate_min_votes. Range: >= 1.
  int candidate_min_votes = 3;
  // Pixels whose data confidence c_p (cost::PeakRatioConfidence of their cost curves averaged over
  // the (2·candidate_confidence_radius+1)² window) is below this vote for, and start from, their
  // block's label — the least cost summed over the block's unconfident pixels — instead of their
  // own winner-take-all label (a prior start of Initialization::kPrior is kept). Where the cost
  // curve is nearly flat (sky, a blank wall) the WTA label is noise, yet summed over many pixels
  // the curves still lean (the sky matches best far away); each noise label made a candidate of
  // its block, so that nearly every label was tried there (issue 20: the sky tiles of the
  // synthetic fountain). Only when AlphaExpansion starts from its own labelling (no initial labels
  // given). 0 = off. An approximation otherwise (it changes the start and the candidate sets;
  // energy and accuracy measured in the README). YAML optimizer.candidate_min_confidence.
  // Range: [0, 1).
  double candidate_min_confidence = 0.0;
  // Window radius of that confidence, px. YAML optimizer.candidate_confidence_radius.
  // Range: [0, cost::kMaxConfidenceRadius].
  int candidate_confidence_radius = 2;
  // Exact shortcut: skip the α-move when no label inside α's region (or next to it) changed
  // since α was last tried (the move would find the same cut again). YAML
  // optimizer.skip_unchanged_labels.
  bool skip_unchanged_labels = true;
  // Approximation (energy gap measured by the benchmark): when α is tried again, the move only
  // covers the blocks of α whose 3×3 block neighbourhood had a label change since α was last
  // tried (the rest of the image already rejected α then; a min cut is not strictly local, so
  // this can miss a change there). Implies skip_unchanged_labels. YAML
  // optimizer.retry_changed_blocks_only.
  bool retry_changed_blocks_only = true;
  // Exact shortcut: leave out of the α-move graph every pixel whose unary increase
  // U_p(α) − U_p(f_p) exceeds the most its pair terms can fall, Σ_q b_pq with
  // b_pq = λs·w_pq·min(|f_p − α|, T) for a neighbour that may take α and
  // b_pq = V_pq(f_p, f_q) − V_pq(α, f_q) for one that keeps f_q in the move (such a pixel keeps
  // f_p in every optimal move). YAML optimizer.prune_pixels.
  bool prune_pixels = true;
  // Start from the WTA labels or from the rounded prior (WTA where there is none) when no initial
  // labelling is given. YAML optimizer.initialization ("wta" | "prior").
  Initialization initialization = Initialization::kWinnerTakeAll;
  // After every accepted move compare the graph's energy with ComputeEnergy (slow; tests). Debug
  // builds always verify. A mismatch throws Error.
  bool verify_moves = false;
  // Threads for tiles in parallel (OptimizeTiled); 0 = all cores. One AlphaExpansion call runs on
  // one thread. YAML optimizer.num_threads. Range: >= 0.
  int num_threads = 0;

  void Check() const;
};

// The labels of a problem's data term that AlphaExpansion with `options` and the sub-pixel
// refinement after it (RefineSubLabel, which reads the labels next to each pixel's) can read, per
// block of options.candidate_block_px pixels of the problem's region (the candidate sets' blocks),
// known before the data term is computed. Only with candidate_labels prior, initialization prior,
// no initial labelling, candidate_min_confidence 0, the GCP energy on with a prior, and GCP
// weights that do not read the data (energy_options.gcp_confidence 0 and the spread not gated:
// see PriorWeights): a block whose every pixel has a finite prior D̂ then reads
// [⌊min D̂⌋ − candidate_radius − 1, ⌈max D̂⌉ + candidate_radius + 1] (clipped to the labels) and
// any other block every label. Otherwise, empty bands: every label everywhere. `prior` and
// `prior_weight` are the problem's (MrfProblem::prior, ::prior_weight); `initial_labels_given`
// whether AlphaExpansion will be handed a start.
LabelBands CandidateLabelBands(const cv::Mat& prior, const cv::Mat& prior_weight, int num_labels,
                               const ExpansionOptions& options,
                               const EnergyOptions& energy_options, bool initial_labels_given);

struct ExpansionResult {
  cv::Mat labels;                         // CV_32S, region-sized
  EnergyBreakdown breakdown;              // of `labels`, from ComputeEnergy
  double initial_energy = 0.0;            // of the initial labelling
  std::vector<double> energy_per_cycle;   // energy after each completed cycle
  std::vector<double> seconds_per_cycle;  // wall time of each completed cycle
  int cycles = 0;
  bool converged = false;            // a cycle improved by less than the tolerance (or not at all)
  bool cancelled = false;            // the progress callback asked to stop
  long long moves_tried = 0;         // α-moves for which a max-flow was computed
  long long moves_skipped = 0;       // α-moves skipped (no candidate pixel, or nothing changed)
  long long moves_accepted = 0;      // moves that lowered the energy
  long long graph_nodes = 0;         // total nodes over all max-flow problems
  long long pixels_pruned = 0;       // candidate pixels left out by prune_pixels (total)
  long long unconfident_pixels = 0;  // pixels below candidate_min_confidence (0 when off)
  double max_energy_mismatch = 0.0;  // max |graph energy − ComputeEnergy| (when verified)
  double mean_candidates_per_block = 0.0;
  double time_seconds = 0.0;
  std::string Summary() const;
};

// α-expansion (Y. Boykov, O. Veksler, R. Zabih, "Fast approximate energy minimization via graph
// cuts", PAMI 23(11), 2001) of the energy in energy.h, each move solved exactly as a binary
// problem by Boykov–Kolmogorov max-flow (libmaxflow), with the graph construction of
// V. Kolmogorov, R. Zabih, "What energy functions can be minimized via graph cuts?", PAMI 2004:
// for a pair (p, q) the table E00 = V(f_p, f_q), E01 = V(f_p, α), E10 = V(α, f_q), E11 = 0 is
// regular because V(a, b) = λs·w_pq·min(|a−b|, T) is a metric; pixels already labelled α stay α
// and are left out of the graph (their pair terms become unaries of their neighbours), as are
// pixels where α is not a candidate. Labels α = 0 … L−1 are tried in this fixed order each cycle.
// A move is accepted only when it lowers the energy, so the energy never increases. The energy
// of the cut (constant + max-flow) is the energy of the new labelling; with verify_moves it is
// compared with ComputeEnergy. Throws Error for bad problems/initial labels, ConfigError for
// bad options.
//
// Speed (energy gaps measured against plain expansion by gcpstereo_optimize_benchmark
// --gap_report / --gap_report_middlebury; all well inside the 0.5 % budget):
//  * prune_pixels, skip_unchanged_labels: exact (same optimal move; ExpansionMove with
//    prune_pixels is tested against brute force). The pruning bound uses the exact pair change
//    V(f_p, f_q) − V(α, f_q) for neighbours that are fixed in the move (outside it, labelled α,
//    or pruned before), which removes 70 % of the nodes of plain expansion on Aloe (80 labels).
//  * convergence_tolerance 1e-4: stops after the cycle that gained < 0.01 %; gaps 0–0.002 %.
//  * CandidateLabels::kLocal: 40× fewer graph nodes on the Fountain-size tile (360 labels), gap
//    0.0003 %; little gain with 16–80 labels on Middlebury (noisy WTA votes cover most labels).
//  * retry_changed_blocks_only: when α comes round again, only the blocks near a change since
//    its last try; 25–35 % fewer nodes, gaps unchanged on the dev scenes.
//  * the region is visited in row-major spans, so a node's graph neighbours are near it in
//    memory; costs are copied once into a label-major array (one more cost volume of memory) so
//    that an α-move streams Φ(·, α) instead of touching one cache line per pixel.
// Memory: the label-major cost copy (2 bytes × pixels × labels), ~70 bytes per pixel of
// per-pixel/per-node arrays, and the max-flow graph (≈ 48 bytes per node + 64 bytes per
// 4-neighbour pair, allocated for the whole region once).
ExpansionResult AlphaExpansion(const MrfProblem& problem, const EnergyOptions& energy_options,
                               const ExpansionOptions& options, cv::Mat initial_labels = {},
                               const ProgressCallback& progress = {});

// The exact minimum of the binary α-expansion move from `labels` (testing hook): returns the
// labelling after the optimal move over ALL pixels and sets *graph_energy to the energy the cut
// reports (constant + max-flow). With prune_pixels, the pixels ExpansionOptions::prune_pixels
// leaves out are left out here too (their count in *pixels_pruned), so that the exactness of the
// pruning can be tested move by move.
cv::Mat ExpansionMove(const MrfProblem& problem, const EnergyOptions& energy_options,
                      const cv::Mat& labels, int alpha, double* graph_energy,
                      bool prune_pixels = false, long long* pixels_pruned = nullptr);

}  // namespace gcpstereo::optimize
