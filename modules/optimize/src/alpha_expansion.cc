// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/alpha_expansion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <sstream>

#include <maxflow.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"

namespace gcpstereo::optimize {
namespace {

using Graph = maxflow::Graph<double, double, double>;

// libmaxflow calls this (then exit(1)) when it runs out of memory; throwing first keeps the
// library from ending the process.
void ThrowMaxflowError(const char* message) {
  throw Error(std::string("max-flow (libmaxflow): ") + message);
}

// Everything one α-expansion run needs, precomputed once per region.
class ExpansionSolver {
 public:
  ExpansionSolver(const MrfProblem& problem, const EnergyOptions& energy_options, int block_px,
                  bool prune_pixels)
      : problem_(problem),
        prune_pixels_(prune_pixels),
        options_(energy_options),
        width_(problem.width()),
        height_(problem.height()),
        num_labels_(problem.num_labels()),
        num_pixels_(width_ * height_),
        block_px_(block_px),
        blocks_x_((width_ + block_px - 1) / block_px),
        blocks_y_((height_ + block_px - 1) / block_px) {
    const CostVolume& costs = *problem.data;
    cost_volume_ = &costs;
    // A label-major copy of the stored costs: an α-move reads Φ(p, α) for every pixel, which in
    // the label-fastest CostVolume is one cache line per pixel (measured: ~20 % of the run time
    // on a 80-label problem went to those misses). Costs one more cost volume of memory.
    costs_by_label_.resize(static_cast<std::size_t>(num_pixels_) * num_labels_);
    const std::uint16_t* src = costs.PixelData(0, 0);
    constexpr int kChunk = 256;
    for (int p0 = 0; p0 < num_pixels_; p0 += kChunk) {
      const int p1 = std::min(num_pixels_, p0 + kChunk);
      for (int l = 0; l < num_labels_; ++l) {
        std::uint16_t* dst = &costs_by_label_[static_cast<std::size_t>(l) * num_pixels_];
        for (int p = p0; p < p1; ++p) dst[p] = src[static_cast<std::size_t>(p) * num_labels_ + l];
      }
    }
    use_prior_ = options_.use_gcp_energy && !problem.prior.empty() && options_.lambda_r > 0.0;
    if (use_prior_) {
      prior_.resize(num_pixels_);
      for (int row = 0; row < height_; ++row) {
        const float* src = problem.prior.ptr<float>(row);
        std::copy(src, src + width_, prior_.begin() + static_cast<std::size_t>(row) * width_);
      }
    }
    // λs·w_pq to the right and lower neighbour (0 at the border).
    weight_right_.assign(num_pixels_, 0.0);
    weight_down_.assign(num_pixels_, 0.0);
    for (int row = 0; row < height_; ++row) {
      const cv::Vec3b* color = problem.image.ptr<cv::Vec3b>(row);
      const cv::Vec3b* below = row + 1 < height_ ? problem.image.ptr<cv::Vec3b>(row + 1) : nullptr;
      for (int col = 0; col < width_; ++col) {
        const int p = row * width_ + col;
        if (col + 1 < width_) {
          weight_right_[p] = options_.lambda_s * PairWeight(color[col], color[col + 1], options_);
        }
        if (below)
          weight_down_[p] = options_.lambda_s * PairWeight(color[col], below[col], options_);
      }
    }
    // Σ_q λs·w_pq over the 4 neighbours (for the exact pixel pruning in Move()).
    weight_sum_.assign(num_pixels_, 0.0);
    for (int p = 0; p < num_pixels_; ++p) {
      const int col = p % width_;
      weight_sum_[p] = weight_right_[p] + weight_down_[p] + (col > 0 ? weight_right_[p - 1] : 0.0) +
                       (p >= width_ ? weight_down_[p - width_] : 0.0);
    }
    node_of_pixel_.assign(num_pixels_, -1);
    block_stamp_.assign(static_cast<std::size_t>(blocks_x_) * blocks_y_, 0);
  }

  int num_blocks() const { return blocks_x_ * blocks_y_; }
  int blocks_x() const { return blocks_x_; }
  int blocks_y() const { return blocks_y_; }
  int block_px() const { return block_px_; }

  // Φ·data_weight + λr·Ψ of label l at pixel p.
  double Unary(int p, int l) const {
    // The CostVolume's own (float) decoding, so that the graph and ComputeEnergy agree exactly.
    const std::uint16_t stored = costs_by_label_[static_cast<std::size_t>(l) * num_pixels_ + p];
    double u = options_.data_weight * static_cast<double>(cost_volume_->Decode(stored));
    if (use_prior_ && std::isfinite(prior_[p])) {
      u += options_.lambda_r * GcpPenalty(l, prior_[p], options_);
    }
    return u;
  }
  double Pair(double weight, int a, int b) const {
    return weight * std::min<double>(std::abs(a - b), options_.truncation);
  }

  void SetLabels(const cv::Mat& labels) {
    labels_.resize(num_pixels_);
    unary_current_.resize(num_pixels_);
    for (int row = 0; row < height_; ++row) {
      const int* src = labels.ptr<int>(row);
      for (int col = 0; col < width_; ++col) {
        const int p = row * width_ + col;
        labels_[p] = src[col];
        unary_current_[p] = Unary(p, src[col]);
      }
    }
  }
  cv::Mat Labels() const {
    cv::Mat out(height_, width_, CV_32S);
    for (int row = 0; row < height_; ++row) {
      std::copy(labels_.begin() + static_cast<std::size_t>(row) * width_,
                labels_.begin() + static_cast<std::size_t>(row + 1) * width_, out.ptr<int>(row));
    }
    return out;
  }
  int label(int p) const { return labels_[p]; }
  long long last_pruned() const { return last_pruned_; }

  // Builds and solves the α-move over the pixels of `blocks` (all blocks when empty) whose label
  // is not α. Returns the number of graph nodes; *delta = energy after − energy before of the
  // optimal move (<= 0 up to rounding). The move is applied only when `apply_if` says so.
  template <typename ApplyIf>
  int Move(int alpha, const std::vector<int>* blocks, long long stamp, double* delta,
           ApplyIf apply_if) {
    nodes_.clear();
    unary_alpha_.clear();
    long long pruned = 0;
    auto collect_block = [&](int b) {
      const int bx = b % blocks_x_, by = b / blocks_x_;
      const int row_end = std::min(height_, (by + 1) * block_px_);
      const int col_end = std::min(width_, (bx + 1) * block_px_);
      for (int row = by * block_px_; row < row_end; ++row) {
        for (int col = bx * block_px_; col < col_end; ++col) {
          const int p = row * width_ + col;
          const int fp = labels_[p];
          if (fp == alpha) continue;
          const double u_alpha = Unary(p, alpha);
          // Exact pruning: switching p to α changes its pair terms by at most
          // Σ_q [V(f_p, x_q) − V(α, x_q)] <= Σ_q V(f_p, α) (triangle inequality), so when the
          // unary increase exceeds that, every labelling with p = α is strictly improved by
          // putting f_p back: p keeps f_p in every optimal move and can stay out of the graph.
          if (prune_pixels_ &&
              u_alpha - unary_current_[p] >
                  weight_sum_[p] * std::min<double>(std::abs(fp - alpha), options_.truncation) *
                          (1.0 + 1e-12) +
                      1e-9) {
            ++pruned;
            continue;
          }
          node_of_pixel_[p] = static_cast<int>(nodes_.size());
          nodes_.push_back(p);
          unary_alpha_.push_back(u_alpha);
        }
      }
    };
    if (blocks) {
      for (int b : *blocks) collect_block(b);
    } else {
      for (int b = 0; b < num_blocks(); ++b) collect_block(b);
    }
    last_pruned_ = pruned;
    const int num_nodes = static_cast<int>(nodes_.size());
    *delta = 0.0;
    if (num_nodes == 0) return 0;
    if (!graph_) {
      graph_ = std::make_unique<Graph>(num_pixels_, 2 * num_pixels_, &ThrowMaxflowError);
    } else {
      graph_->reset();
    }
    graph_->add_node(num_nodes);
    cost_keep_.assign(num_nodes, 0.0);
    cost_alpha_.assign(num_nodes, 0.0);
    double energy_before = 0.0;  // the terms this move can change, at the current labelling
    for (int i = 0; i < num_nodes; ++i) {
      const int p = nodes_[i];
      const int fp = labels_[p];
      const int row = p / width_, col = p - row * width_;
      cost_keep_[i] += unary_current_[p];
      cost_alpha_[i] += unary_alpha_[i];
      energy_before += unary_current_[p];
      // Pairs with the left/upper neighbour are handled here only when that neighbour is fixed;
      // pairs between two nodes are added once, from the left/upper node.
      auto fixed_neighbour = [&](int q, double weight) {
        const int fq = labels_[q];
        const double keep = Pair(weight, fp, fq);
        cost_keep_[i] += keep;
        cost_alpha_[i] += Pair(weight, alpha, fq);
        energy_before += keep;
      };
      auto pair = [&](int q, double weight) {
        const int j = node_of_pixel_[q];
        if (j < 0) {
          fixed_neighbour(q, weight);
          return;
        }
        const int fq = labels_[q];
        // E00 = A, E01 = B, E10 = C, E11 = D = V(α, α) = 0; add_term2 of Kolmogorov & Zabih.
        const double a = Pair(weight, fp, fq);
        double b = Pair(weight, fp, alpha);
        double c = Pair(weight, alpha, fq);
        energy_before += a;
        cost_keep_[i] += a;  // x_p = 0 pays A
        b -= a;              // table now [0, B−A; C, 0]
        if (b < 0) {
          cost_keep_[i] += b;
          cost_keep_[j] -= b;
          c += b;
          b = 0;
        } else if (c < 0) {
          cost_keep_[i] -= c;
          cost_keep_[j] += c;
          b += c;
          c = 0;
        }
        // Regularity (b + c >= 0) holds because V is a metric; rounding can leave −1e-15.
        graph_->add_edge(i, j, std::max(b, 0.0), std::max(c, 0.0));
      };
      if (col > 0 && node_of_pixel_[p - 1] < 0) fixed_neighbour(p - 1, weight_right_[p - 1]);
      if (row > 0 && node_of_pixel_[p - width_] < 0) {
        fixed_neighbour(p - width_, weight_down_[p - width_]);
      }
      if (col + 1 < width_) pair(p + 1, weight_right_[p]);
      if (row + 1 < height_) pair(p + width_, weight_down_[p]);
    }
    for (int i = 0; i < num_nodes; ++i) graph_->add_tweights(i, cost_alpha_[i], cost_keep_[i]);
    const double energy_after = graph_->maxflow();
    *delta = energy_after - energy_before;
    const bool apply = apply_if(*delta, energy_before);
    for (int i = 0; i < num_nodes; ++i) {
      const int p = nodes_[i];
      node_of_pixel_[p] = -1;
      if (apply && graph_->what_segment(i) == Graph::SINK) {
        labels_[p] = alpha;
        unary_current_[p] = unary_alpha_[i];
        const int row = p / width_, col = p - row * width_;
        block_stamp_[(row / block_px_) * blocks_x_ + col / block_px_] = stamp;
      }
    }
    return num_nodes;
  }

  // True when no label in `blocks` or their 8 neighbour blocks changed after `since`.
  bool Unchanged(const std::vector<int>* blocks, long long since) const {
    if (!blocks) {
      return std::all_of(block_stamp_.begin(), block_stamp_.end(),
                         [since](long long s) { return s <= since; });
    }
    for (int b : *blocks) {
      const int bx = b % blocks_x_, by = b / blocks_x_;
      for (int y = std::max(0, by - 1); y <= std::min(blocks_y_ - 1, by + 1); ++y) {
        for (int x = std::max(0, bx - 1); x <= std::min(blocks_x_ - 1, bx + 1); ++x) {
          if (block_stamp_[y * blocks_x_ + x] > since) return false;
        }
      }
    }
    return true;
  }

 private:
  const MrfProblem& problem_;
  const bool prune_pixels_;
  const EnergyOptions& options_;
  const int width_, height_, num_labels_, num_pixels_;
  const int block_px_, blocks_x_, blocks_y_;
  const CostVolume* cost_volume_ = nullptr;
  std::vector<std::uint16_t> costs_by_label_;
  bool use_prior_ = false;
  std::vector<float> prior_;
  std::vector<double> weight_right_, weight_down_, weight_sum_;
  std::vector<int> labels_;
  std::vector<double> unary_current_;
  std::vector<int> node_of_pixel_, nodes_;
  std::vector<double> cost_keep_, cost_alpha_, unary_alpha_;
  std::vector<long long> block_stamp_;
  std::unique_ptr<Graph> graph_;
  long long last_pruned_ = 0;
};

void CheckLabels(const MrfProblem& problem, const cv::Mat& labels, const char* what) {
  if (labels.type() != CV_32S || labels.cols != problem.width() ||
      labels.rows != problem.height()) {
    throw Error(std::string(what) + " must be CV_32S of the problem's size " +
                std::to_string(problem.width()) + "x" + std::to_string(problem.height()) +
                " (got " + std::to_string(labels.cols) + "x" + std::to_string(labels.rows) + ")");
  }
  double min_value = 0.0, max_value = 0.0;
  cv::minMaxLoc(labels, &min_value, &max_value);
  if (min_value < 0 || max_value >= problem.num_labels()) {
    throw Error(std::string(what) + " has labels in [" + FormatNumber(min_value) + ", " +
                FormatNumber(max_value) + "], outside [0, " + std::to_string(problem.num_labels()) +
                ")");
  }
}

// Per block: the candidate labels of CandidateLabels::kLocal (see the header), returned as
// per-label lists of block ids in increasing order.
std::vector<std::vector<int>> LocalCandidateBlocks(
    const MrfProblem& problem, const cv::Mat& initial_labels, const ExpansionOptions& options,
    const EnergyOptions& energy_options, int blocks_x, int blocks_y, double* mean_candidates) {
  const int num_labels = problem.num_labels(), block = options.candidate_block_px;
  const int num_blocks = blocks_x * blocks_y, radius = options.candidate_radius;
  const cv::Mat wta = WinnerTakeAll(*problem.data);
  std::vector<int> votes(static_cast<std::size_t>(num_blocks) * num_labels, 0);
  for (int row = 0; row < problem.height(); ++row) {
    for (int col = 0; col < problem.width(); ++col) {
      const int b = (row / block) * blocks_x + col / block;
      ++votes[static_cast<std::size_t>(b) * num_labels + wta.ptr<int>(row)[col]];
    }
  }
  const bool use_prior = energy_options.use_gcp_energy && !problem.prior.empty();
  std::vector<std::vector<int>> blocks_of_label(num_labels);
  std::vector<int> sum(num_labels);
  std::vector<char> candidate(num_labels);
  long long total = 0;
  auto mark = [&](int lo, int hi) {
    for (int l = std::max(0, lo); l <= std::min(num_labels - 1, hi); ++l) candidate[l] = 1;
  };
  for (int by = 0; by < blocks_y; ++by) {
    for (int bx = 0; bx < blocks_x; ++bx) {
      std::fill(sum.begin(), sum.end(), 0);
      std::fill(candidate.begin(), candidate.end(), 0);
      for (int y = std::max(0, by - 1); y <= std::min(blocks_y - 1, by + 1); ++y) {
        for (int x = std::max(0, bx - 1); x <= std::min(blocks_x - 1, bx + 1); ++x) {
          const int* v = &votes[static_cast<std::size_t>(y * blocks_x + x) * num_labels];
          for (int l = 0; l < num_labels; ++l) sum[l] += v[l];
        }
      }
      for (int l = 0; l < num_labels; ++l) {
        if (sum[l] >= options.candidate_min_votes) mark(l - radius, l + radius);
      }
      const int row_end = std::min(problem.height(), (by + 1) * block);
      const int col_end = std::min(problem.width(), (bx + 1) * block);
      for (int row = by * block; row < row_end; ++row) {
        for (int col = bx * block; col < col_end; ++col) {
          const int l0 = initial_labels.ptr<int>(row)[col];
          mark(l0, l0);
          if (use_prior) {
            const float prior = problem.prior.ptr<float>(row)[col];
            if (std::isfinite(prior)) {
              mark(static_cast<int>(std::floor(prior)) - radius,
                   static_cast<int>(std::ceil(prior)) + radius);
            }
          }
        }
      }
      for (int l = 0; l < num_labels; ++l) {
        if (candidate[l]) {
          blocks_of_label[l].push_back(by * blocks_x + bx);
          ++total;
        }
      }
    }
  }
  *mean_candidates = static_cast<double>(total) / num_blocks;
  return blocks_of_label;
}

}  // namespace

const char* CandidateLabelsName(CandidateLabels mode) {
  return mode == CandidateLabels::kAll ? "all" : "local";
}

CandidateLabels ParseCandidateLabels(const std::string& name) {
  if (name == "all") return CandidateLabels::kAll;
  if (name == "local") return CandidateLabels::kLocal;
  throw ConfigError(
      ViolatedConstraint("optimizer.candidate_labels", name, "one of \"all\", \"local\""));
}

void ExpansionOptions::Check() const {
  if (max_cycles < 1) {
    throw ConfigError(
        ViolatedConstraint("optimizer.max_cycles", std::to_string(max_cycles), ">= 1"));
  }
  if (!(convergence_tolerance >= 0.0 && convergence_tolerance < 1.0)) {
    throw ConfigError(ViolatedConstraint("optimizer.convergence_tolerance",
                                         FormatNumber(convergence_tolerance), "in [0, 1)"));
  }
  if (candidate_block_px < 4) {
    throw ConfigError(ViolatedConstraint("optimizer.candidate_block",
                                         std::to_string(candidate_block_px), ">= 4"));
  }
  if (candidate_radius < 0) {
    throw ConfigError(
        ViolatedConstraint("optimizer.candidate_radius", std::to_string(candidate_radius), ">= 0"));
  }
  if (candidate_min_votes < 1) {
    throw ConfigError(ViolatedConstraint("optimizer.candidate_min_votes",
                                         std::to_string(candidate_min_votes), ">= 1"));
  }
  if (num_threads < 0) {
    throw ConfigError(
        ViolatedConstraint("optimizer.num_threads", std::to_string(num_threads), ">= 0"));
  }
}

std::string ExpansionResult::Summary() const {
  std::ostringstream s;
  s << "alpha-expansion: energy " << initial_energy << " -> " << breakdown.total() << " (data "
    << breakdown.data << ", smooth " << breakdown.smooth << ", gcp " << breakdown.gcp << "), "
    << cycles << " cycles" << (converged ? " (converged)" : "") << (cancelled ? " (cancelled)" : "")
    << ", moves tried/accepted/skipped " << moves_tried << "/" << moves_accepted << "/"
    << moves_skipped << ", " << time_seconds << " s";
  return s.str();
}

ExpansionResult AlphaExpansion(const MrfProblem& problem, const EnergyOptions& energy_options,
                               const ExpansionOptions& options, cv::Mat initial_labels,
                               const ProgressCallback& progress) {
  const Timer timer;
  problem.Validate();
  energy_options.Check();
  options.Check();
  const int num_labels = problem.num_labels();

  cv::Mat labels;
  if (!initial_labels.empty()) {
    CheckLabels(problem, initial_labels, "AlphaExpansion: the initial labelling");
    labels = initial_labels.clone();
  } else {
    labels = WinnerTakeAll(*problem.data);
    if (options.initialization == Initialization::kPrior && !problem.prior.empty()) {
      for (int row = 0; row < labels.rows; ++row) {
        for (int col = 0; col < labels.cols; ++col) {
          const float prior = problem.prior.ptr<float>(row)[col];
          if (std::isfinite(prior)) {
            labels.ptr<int>(row)[col] =
                std::clamp(static_cast<int>(std::lround(prior)), 0, num_labels - 1);
          }
        }
      }
    }
  }

  ExpansionResult result;
  ExpansionSolver solver(problem, energy_options, options.candidate_block_px, options.prune_pixels);
  solver.SetLabels(labels);
  std::vector<std::vector<int>> blocks_of_label;
  if (options.candidate_labels == CandidateLabels::kLocal) {
    blocks_of_label =
        LocalCandidateBlocks(problem, labels, options, energy_options, solver.blocks_x(),
                             solver.blocks_y(), &result.mean_candidates_per_block);
  } else {
    result.mean_candidates_per_block = num_labels;
  }
#ifndef NDEBUG
  const bool verify = true;
#else
  const bool verify = options.verify_moves;
#endif

  double energy = ComputeEnergy(problem, labels, energy_options);
  result.initial_energy = energy;
  std::vector<long long> last_tried(num_labels, -1);
  long long stamp = 0;
  const double total_steps = static_cast<double>(options.max_cycles) * num_labels;
  for (int cycle = 0; cycle < options.max_cycles && !result.cancelled; ++cycle) {
    const double energy_at_start = energy;
    long long accepted_in_cycle = 0;
    for (int alpha = 0; alpha < num_labels; ++alpha) {
      const std::vector<int>* blocks = nullptr;
      if (!blocks_of_label.empty()) {
        blocks = &blocks_of_label[alpha];
        if (blocks->empty()) {
          ++result.moves_skipped;
          continue;
        }
      }
      if (options.skip_unchanged_labels && last_tried[alpha] >= 0 &&
          solver.Unchanged(blocks, last_tried[alpha])) {
        ++result.moves_skipped;
        continue;
      }
      ++stamp;
      double delta = 0.0;
      bool accepted = false;
      const int nodes = solver.Move(alpha, blocks, stamp, &delta, [&](double d, double before) {
        // Accept only a real decrease (rounding of the flow must not trigger a move).
        accepted = d < -1e-9 * std::max(1.0, std::abs(before));
        return accepted;
      });
      last_tried[alpha] = stamp;
      result.pixels_pruned += solver.last_pruned();
      if (nodes == 0) {
        ++result.moves_skipped;
        continue;
      }
      ++result.moves_tried;
      result.graph_nodes += nodes;
      if (accepted) {
        energy += delta;
        ++result.moves_accepted;
        ++accepted_in_cycle;
        if (verify) {
          const double direct = ComputeEnergy(problem, solver.Labels(), energy_options);
          const double mismatch = std::abs(direct - energy);
          result.max_energy_mismatch = std::max(result.max_energy_mismatch, mismatch);
          if (mismatch > 1e-6 * std::max(1.0, std::abs(direct))) {
            throw Error("AlphaExpansion: the energy of the cut (" + FormatNumber(energy) +
                        ") differs from the direct energy (" + FormatNumber(direct) +
                        ") after the move of label " + std::to_string(alpha));
          }
        }
      }
      if (progress && !progress((cycle * num_labels + alpha + 1) / total_steps)) {
        result.cancelled = true;
        break;
      }
    }
    result.energy_per_cycle.push_back(energy);
    result.cycles = cycle + 1;
    if (accepted_in_cycle == 0 ||
        energy_at_start - energy <= options.convergence_tolerance * std::abs(energy_at_start)) {
      result.converged = !result.cancelled;
      break;
    }
  }
  if (progress && !result.cancelled) progress(1.0);
  result.labels = solver.Labels();
  ComputeEnergy(problem, result.labels, energy_options, &result.breakdown);
  result.time_seconds = timer.ElapsedSeconds();
  return result;
}

cv::Mat ExpansionMove(const MrfProblem& problem, const EnergyOptions& energy_options,
                      const cv::Mat& labels, int alpha, double* graph_energy) {
  problem.Validate();
  energy_options.Check();
  CheckLabels(problem, labels, "ExpansionMove: the labelling");
  ExpansionSolver solver(problem, energy_options, 16, /*prune_pixels=*/false);
  solver.SetLabels(labels);
  double delta = 0.0;
  solver.Move(alpha, nullptr, 1, &delta, [](double, double) { return true; });
  const cv::Mat out = solver.Labels();
  if (graph_energy) *graph_energy = ComputeEnergy(problem, labels, energy_options) + delta;
  return out;
}

}  // namespace gcpstereo::optimize
