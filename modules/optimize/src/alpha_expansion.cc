// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/alpha_expansion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>

#include <maxflow.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/huge_page_allocator.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/cost/winner_take_all.h"

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
    use_prior_ = problem.UsesPrior(options_) && options_.lambda_r > 0.0;
    if (use_prior_) {
      prior_.resize(num_pixels_);
      prior_scale_.resize(num_pixels_);
      for (int row = 0; row < height_; ++row) {
        const float* src = problem.prior.ptr<float>(row);
        std::copy(src, src + width_, prior_.begin() + static_cast<std::size_t>(row) * width_);
        for (int col = 0; col < width_; ++col) {
          prior_scale_[static_cast<std::size_t>(row) * width_ + col] =
              options_.lambda_r * problem.PriorWeight(row, col);
        }
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
    node_of_pixel_.assign(num_pixels_, -1);
    mark_.assign(num_pixels_, 0);
    block_mark_.assign(static_cast<std::size_t>(blocks_x_) * blocks_y_, 0);
    nodes_.assign(num_pixels_, 0);
    cost_keep_.assign(num_pixels_, 0.0);
    cost_alpha_.assign(num_pixels_, 0.0);
    unary_alpha_.assign(num_pixels_, 0.0);
    block_stamp_.assign(static_cast<std::size_t>(blocks_x_) * blocks_y_, 0);
  }

  int num_blocks() const { return blocks_x_ * blocks_y_; }
  int blocks_x() const { return blocks_x_; }
  int blocks_y() const { return blocks_y_; }
  int block_px() const { return block_px_; }

  // Φ·data_weight + λr·ω_p·Ψ of label l at pixel p.
  double Unary(int p, int l) const {
    // The CostVolume's own (float) decoding, so that the graph and ComputeEnergy agree exactly.
    const std::uint16_t stored = costs_by_label_[static_cast<std::size_t>(l) * num_pixels_ + p];
    double u = options_.data_weight * static_cast<double>(cost_volume_->Decode(stored));
    if (use_prior_ && std::isfinite(prior_[p])) {
      u += prior_scale_[p] * GcpPenalty(l, prior_[p], options_);
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

  // The pair (first, second) of two nodes with labels f_first, f_second: the table
  // E00 = V(f_first, f_second), E01 = V(f_first, α), E10 = V(α, f_second), E11 = V(α, α) = 0
  // (x = 1: takes α) as unaries and one edge (add_term2 of Kolmogorov & Zabih).
  void AddPairEdge(int first, int f_first, int second, int f_second, double weight, int alpha,
                   double* energy_before) {
    const double a = Pair(weight, f_first, f_second);
    double b = Pair(weight, f_first, alpha);
    double c = Pair(weight, alpha, f_second);
    *energy_before += a;
    cost_keep_[first] += a;  // x_first = 0 pays A
    b -= a;                  // table now [0, B−A; C, 0]
    if (b < 0) {
      cost_keep_[first] += b;
      cost_keep_[second] -= b;
      c += b;
      b = 0;
    } else if (c < 0) {
      cost_keep_[first] -= c;
      cost_keep_[second] += c;
      b += c;
      c = 0;
    }
    // Regularity (b + c >= 0) holds because V is a metric; rounding can leave −1e-15.
    graph_->add_edge(first, second, std::max(b, 0.0), std::max(c, 0.0));
  }

  // Row-major spans of the blocks `blocks` (sorted block ids; all blocks when null); marks the
  // blocks of move serial_ in block_mark_.
  void BuildSpans(const std::vector<int>* blocks) {
    spans_.clear();
    auto add = [&](int by, int bx_begin, int bx_end) {
      spans_.push_back(Span{by * block_px_, std::min(height_, (by + 1) * block_px_),
                            bx_begin * block_px_, std::min(width_, bx_end * block_px_)});
    };
    if (!blocks) {
      std::fill(block_mark_.begin(), block_mark_.end(), serial_);
      for (int by = 0; by < blocks_y_; ++by) add(by, 0, blocks_x_);
      return;
    }
    for (int b : *blocks) block_mark_[b] = serial_;
    // Consecutive blocks of one block row merge into one span. Spans are visited one after the
    // other (each row by row), block rows top to bottom, so a pixel's left and upper neighbours
    // in the region are always visited before it.
    std::size_t k = 0;
    while (k < blocks->size()) {
      const int by = (*blocks)[k] / blocks_x_;
      int bx_begin = (*blocks)[k] % blocks_x_, bx_end = bx_begin + 1;
      ++k;
      while (k < blocks->size() && (*blocks)[k] / blocks_x_ == by &&
             (*blocks)[k] % blocks_x_ == bx_end) {
        ++bx_end;
        ++k;
      }
      add(by, bx_begin, bx_end);
    }
  }

  // Builds and solves the α-move over the pixels of `blocks` (all blocks when null) whose label
  // is not α. Returns the number of graph nodes; *delta = energy after − energy before of the
  // optimal move (<= 0 up to rounding). The move is applied only when `apply_if` says so.
  //
  // One pass over the region in row-major spans (BuildSpans): a pixel's left and upper
  // neighbours inside the region are visited before it, its right and lower ones after it, so
  // the graph is built with mostly sequential memory access and every pair is added once, when
  // its later pixel is visited (or from the inside when the later pixel is outside the region).
  // Per pixel p with f_p ≠ α:
  //  * pruning (prune_pixels): p keeps f_p in every optimal move when its unary increase
  //    U_p(α) − U_p(f_p) exceeds the most its pair terms can fall, Σ_q b_pq with
  //      b_pq = V_pq(f_p, α)                        q may still take α (a node, or not visited),
  //      b_pq = V_pq(f_p, f_q) − V_pq(α, f_q)       q keeps f_q (outside the region, labelled α,
  //                                                  or pruned before p),
  //    since V(f_p, x) − V(α, x) <= V(f_p, α) (triangle inequality) bounds the fall for every
  //    state of q. A pruned pixel is fixed in every optimal move, so using its exact term for
  //    later pixels keeps the pruning exact (tested against brute force);
  //  * otherwise p becomes a node with unaries U_p(f_p) (keep) and U_p(α) (take α).
  template <typename ApplyIf>
  int Move(int alpha, const std::vector<int>* blocks, long long stamp, double* delta,
           ApplyIf apply_if) {
    ++serial_;
    const std::uint32_t kFixed = 2 * serial_, kNode = 2 * serial_ + 1;
    BuildSpans(blocks);
    const double truncation = options_.truncation;
    if (!graph_) {
      graph_ = std::make_unique<Graph>(num_pixels_, 2 * num_pixels_, &ThrowMaxflowError);
    } else {
      graph_->reset();
    }
    int num_nodes = 0;
    long long pruned = 0;
    double energy_before = 0.0;  // the terms this move can change, at the current labelling
    for (const Span& span : spans_) {
      for (int row = span.row_begin; row < span.row_end; ++row) {
        const int base = row * width_;
        const bool has_up = row > 0, has_down = row + 1 < height_;
        const bool down_in_span = row + 1 < span.row_end;
        const int next_block_row = ((row + 1) / block_px_) * blocks_x_;
        for (int col = span.col_begin; col < span.col_end; ++col) {
          const int p = base + col;
          const int fp = labels_[p];
          const bool has_left = col > 0, has_right = col + 1 < width_;
          const bool right_in = col + 1 < span.col_end;  // spans never touch side by side
          const bool down_in =
              has_down &&
              (down_in_span || block_mark_[next_block_row + col / block_px_] == serial_);
          bool is_node = false;
          double u_alpha = 0.0;
          if (fp != alpha) {
            u_alpha = Unary(p, alpha);
            is_node = true;
            if (prune_pixels_) {
              const double v_alpha = std::min<double>(std::abs(fp - alpha), truncation);
              auto fixed_fall = [&](int q) {
                const int fq = labels_[q];
                return std::min<double>(std::abs(fp - fq), truncation) -
                       std::min<double>(std::abs(alpha - fq), truncation);
              };
              double bound = 0.0, weights = 0.0;
              if (has_left) {
                const double w = weight_right_[p - 1];
                weights += w;
                bound += w * (mark_[p - 1] == kNode ? v_alpha : fixed_fall(p - 1));
              }
              if (has_up) {
                const double w = weight_down_[p - width_];
                weights += w;
                bound += w * (mark_[p - width_] == kNode ? v_alpha : fixed_fall(p - width_));
              }
              if (has_right) {
                const double w = weight_right_[p];
                weights += w;
                bound += w * (right_in && labels_[p + 1] != alpha ? v_alpha : fixed_fall(p + 1));
              }
              if (has_down) {
                const double w = weight_down_[p];
                weights += w;
                bound += w * (down_in && labels_[p + width_] != alpha ? v_alpha
                                                                      : fixed_fall(p + width_));
              }
              const double increase = u_alpha - unary_current_[p];
              // Strictly greater, with a margin far above the rounding of these few sums.
              const double margin = 1e-9 * (1.0 + std::abs(u_alpha) + std::abs(unary_current_[p]) +
                                            weights * truncation);
              if (increase > bound + margin) {
                is_node = false;
                ++pruned;
              }
            }
          }
          mark_[p] = is_node ? kNode : kFixed;
          int i = -1;
          if (is_node) {
            i = num_nodes++;
            graph_->add_node(1);
            nodes_[i] = p;
            node_of_pixel_[p] = i;
            cost_keep_[i] = unary_current_[p];
            cost_alpha_[i] = u_alpha;
            unary_alpha_[i] = u_alpha;
            energy_before += unary_current_[p];
          }
          // The pairs with the left and upper neighbours (visited before p, or outside the region:
          // then they keep their labels, like pruned pixels).
          auto earlier = [&](int q, double weight) {
            const bool q_node = mark_[q] == kNode;
            if (!q_node && !is_node) return;
            const int fq = labels_[q];
            if (q_node && is_node) {
              AddPairEdge(node_of_pixel_[q], fq, i, fp, weight, alpha, &energy_before);
            } else if (q_node) {  // p keeps f_p: a unary of q
              const int j = node_of_pixel_[q];
              const double keep = Pair(weight, fq, fp);
              cost_keep_[j] += keep;
              cost_alpha_[j] += Pair(weight, alpha, fp);
              energy_before += keep;
            } else {  // q keeps f_q: a unary of p
              const double keep = Pair(weight, fp, fq);
              cost_keep_[i] += keep;
              cost_alpha_[i] += Pair(weight, alpha, fq);
              energy_before += keep;
            }
          };
          if (has_left) earlier(p - 1, weight_right_[p - 1]);
          if (has_up) earlier(p - width_, weight_down_[p - width_]);
          // The pairs with right and lower neighbours outside the region (they keep their labels).
          if (is_node) {
            auto outside = [&](int q, double weight) {
              const int fq = labels_[q];
              const double keep = Pair(weight, fp, fq);
              cost_keep_[i] += keep;
              cost_alpha_[i] += Pair(weight, alpha, fq);
              energy_before += keep;
            };
            if (has_right && !right_in) outside(p + 1, weight_right_[p]);
            if (has_down && !down_in) outside(p + width_, weight_down_[p]);
          }
        }
      }
    }
    last_pruned_ = pruned;
    *delta = 0.0;
    if (num_nodes == 0) return 0;
    for (int n = 0; n < num_nodes; ++n) graph_->add_tweights(n, cost_alpha_[n], cost_keep_[n]);
    const double energy_after = graph_->maxflow();
    *delta = energy_after - energy_before;
    const bool apply = apply_if(*delta, energy_before);
    if (apply) {
      for (int n = 0; n < num_nodes; ++n) {
        if (graph_->what_segment(n) != Graph::SINK) continue;
        const int p = nodes_[n];
        labels_[p] = alpha;
        unary_current_[p] = unary_alpha_[n];
        const int row = p / width_, col = p - row * width_;
        block_stamp_[(row / block_px_) * blocks_x_ + col / block_px_] = stamp;
      }
    }
    return num_nodes;
  }

  // The blocks of `blocks` (all when null) whose 3×3 block neighbourhood had a label change after
  // `since` (the blocks where the α-move tried at `since` may now find something else).
  std::vector<int> ChangedBlocks(const std::vector<int>* blocks, long long since) const {
    std::vector<int> out;
    auto changed = [&](int b) {
      const int bx = b % blocks_x_, by = b / blocks_x_;
      for (int y = std::max(0, by - 1); y <= std::min(blocks_y_ - 1, by + 1); ++y) {
        for (int x = std::max(0, bx - 1); x <= std::min(blocks_x_ - 1, bx + 1); ++x) {
          if (block_stamp_[y * blocks_x_ + x] > since) return true;
        }
      }
      return false;
    };
    if (blocks) {
      for (int b : *blocks) {
        if (changed(b)) out.push_back(b);
      }
    } else {
      for (int b = 0; b < num_blocks(); ++b) {
        if (changed(b)) out.push_back(b);
      }
    }
    return out;
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
  // As large as the cost volume and written whole at once: huge pages (huge_page_allocator.h).
  std::vector<std::uint16_t, HugePageAllocator<std::uint16_t>> costs_by_label_;
  bool use_prior_ = false;
  std::vector<float> prior_;
  std::vector<double> prior_scale_;  // λr·ω_p
  std::vector<double> weight_right_, weight_down_;
  std::vector<int> labels_;
  std::vector<double> unary_current_;
  struct Span {
    int row_begin, row_end, col_begin, col_end;
  };
  std::vector<Span> spans_;
  std::uint32_t serial_ = 0;         // α-moves built so far (pixel marks of move s: 2s, 2s + 1)
  std::vector<std::uint32_t> mark_;  // per pixel: 2s = fixed, 2s + 1 = node in move s
  std::vector<std::uint32_t> block_mark_;  // per block: s when the block is in move s
  std::vector<int> node_of_pixel_;
  std::vector<int> nodes_;                                    // per node: its pixel
  std::vector<double> cost_keep_, cost_alpha_, unary_alpha_;  // per node
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

// Per block: the candidate labels of CandidateLabels::kLocal or kPrior (see the header), returned
// as per-label lists of block ids in increasing order.
std::vector<std::vector<int>> LocalCandidateBlocks(const MrfProblem& problem, const cv::Mat& wta,
                                                   const cv::Mat& initial_labels,
                                                   const ExpansionOptions& options,
                                                   const EnergyOptions& energy_options,
                                                   int blocks_x, int blocks_y,
                                                   double* mean_candidates) {
  const int num_labels = problem.num_labels(), block = options.candidate_block_px;
  const int num_blocks = blocks_x * blocks_y, radius = options.candidate_radius;
  const bool use_prior = problem.UsesPrior(energy_options);
  // The WTA votes per block: kLocal, and kPrior without a prior (then the same as kLocal).
  const bool vote = options.candidate_labels == CandidateLabels::kLocal || !use_prior;
  std::vector<int> votes(vote ? static_cast<std::size_t>(num_blocks) * num_labels : 0, 0);
  for (int row = 0; vote && row < problem.height(); ++row) {
    for (int col = 0; col < problem.width(); ++col) {
      const int b = (row / block) * blocks_x + col / block;
      ++votes[static_cast<std::size_t>(b) * num_labels + wta.ptr<int>(row)[col]];
    }
  }
  std::vector<std::vector<int>> blocks_of_label(num_labels);
  std::vector<int> sum(num_labels);
  std::vector<char> candidate(num_labels);
  long long total = 0;
  auto mark = [&](int lo, int hi) {
    for (int l = std::max(0, lo); l <= std::min(num_labels - 1, hi); ++l) candidate[l] = 1;
  };
  for (int by = 0; by < blocks_y; ++by) {
    for (int bx = 0; bx < blocks_x; ++bx) {
      std::fill(candidate.begin(), candidate.end(), 0);
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
      if (vote) {
        std::fill(sum.begin(), sum.end(), 0);
        for (int y = std::max(0, by - 1); y <= std::min(blocks_y - 1, by + 1); ++y) {
          for (int x = std::max(0, bx - 1); x <= std::min(blocks_x - 1, bx + 1); ++x) {
            const int* v = &votes[static_cast<std::size_t>(y * blocks_x + x) * num_labels];
            for (int l = 0; l < num_labels; ++l) sum[l] += v[l];
          }
        }
        for (int l = 0; l < num_labels; ++l) {
          if (sum[l] >= options.candidate_min_votes) mark(l - radius, l + radius);
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

// ExpansionOptions::candidate_min_confidence: every pixel whose data confidence is below it
// votes for, and starts from, its block's label — the least summed cost over the block's
// unconfident pixels — instead of its own WTA label (it keeps a prior start of
// Initialization::kPrior). A flat-looking curve still leans, summed over many pixels (the sky
// matches best far away), and one label per block leaves the block's candidates few. *votes gets
// the votes. Returns how many pixels are unconfident; nothing changes when none or all are.
long long StartUnconfidentPixels(const MrfProblem& problem, const ExpansionOptions& options,
                                 const cv::Mat& wta, int blocks_x, int blocks_y, cv::Mat* labels,
                                 cv::Mat* votes) {
  const CostVolume& data = *problem.data;
  const cv::Mat confidence = cost::PeakRatioConfidence(data, options.candidate_confidence_radius);
  const cv::Mat unconfident = confidence < options.candidate_min_confidence;  // 255 where below
  const long long count = cv::countNonZero(unconfident);
  if (count == 0 || count == static_cast<long long>(unconfident.total())) return 0;
  const int num_labels = problem.num_labels(), block = options.candidate_block_px;
  // Summed stored costs (no data counts as the largest cost), per block and label.
  std::vector<std::uint64_t> sums(static_cast<std::size_t>(blocks_x) * blocks_y * num_labels, 0);
  for (int row = 0; row < problem.height(); ++row) {
    const uchar* u = unconfident.ptr<uchar>(row);
    for (int col = 0; col < problem.width(); ++col) {
      if (u[col] == 0) continue;
      const std::uint16_t* costs = data.PixelData(row, col);
      std::uint64_t* sum =
          &sums[static_cast<std::size_t>((row / block) * blocks_x + col / block) * num_labels];
      for (int l = 0; l < num_labels; ++l) {
        sum[l] += costs[l] == CostVolume::kNoData ? CostVolume::kNoData - 1 : costs[l];
      }
    }
  }
  std::vector<int> label_of_block(static_cast<std::size_t>(blocks_x) * blocks_y, 0);
  for (std::size_t b = 0; b < label_of_block.size(); ++b) {
    const std::uint64_t* sum = &sums[b * num_labels];
    label_of_block[b] = static_cast<int>(std::min_element(sum, sum + num_labels) - sum);
  }
  const bool keep_prior =
      options.initialization == Initialization::kPrior && !problem.prior.empty();
  *votes = wta.clone();
  for (int row = 0; row < problem.height(); ++row) {
    for (int col = 0; col < problem.width(); ++col) {
      if (unconfident.ptr<uchar>(row)[col] == 0) continue;
      const int l = label_of_block[(row / block) * blocks_x + col / block];
      votes->ptr<int>(row)[col] = l;
      if (!(keep_prior && std::isfinite(problem.prior.ptr<float>(row)[col]))) {
        labels->ptr<int>(row)[col] = l;
      }
    }
  }
  return count;
}

}  // namespace

const char* CandidateLabelsName(CandidateLabels mode) {
  switch (mode) {
    case CandidateLabels::kAll: return "all";
    case CandidateLabels::kLocal: return "local";
    case CandidateLabels::kPrior: return "prior";
  }
  return "?";
}

CandidateLabels ParseCandidateLabels(const std::string& name) {
  if (name == "all") return CandidateLabels::kAll;
  if (name == "local") return CandidateLabels::kLocal;
  if (name == "prior") return CandidateLabels::kPrior;
  throw ConfigError(ViolatedConstraint("optimizer.candidate_labels", name,
                                       "one of \"all\", \"local\", \"prior\""));
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
  if (!(candidate_min_confidence >= 0.0 && candidate_min_confidence < 1.0)) {
    throw ConfigError(ViolatedConstraint("optimizer.candidate_min_confidence",
                                         FormatNumber(candidate_min_confidence), "in [0, 1)"));
  }
  if (candidate_confidence_radius < 0 || candidate_confidence_radius > cost::kMaxConfidenceRadius) {
    throw ConfigError(ViolatedConstraint(
        "optimizer.candidate_confidence_radius", std::to_string(candidate_confidence_radius),
        "in [0, " + std::to_string(cost::kMaxConfidenceRadius) + "]"));
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

namespace {

// Initialization::kPrior's start label of a pixel with a finite prior: D̂ rounded, clamped to the
// labels (the prior clamped first, so that a far-off D̂ does not overflow the rounding).
int PriorStartLabel(float prior, int num_labels) {
  const float clamped = std::clamp(prior, -1.0f, static_cast<float>(num_labels));
  return std::clamp(static_cast<int>(std::lround(clamped)), 0, num_labels - 1);
}

}  // namespace

LabelBands CandidateLabelBands(const cv::Mat& prior, const cv::Mat& prior_weight, int num_labels,
                               const ExpansionOptions& options,
                               const EnergyOptions& energy_options, bool initial_labels_given) {
  if (options.candidate_labels != CandidateLabels::kPrior ||
      options.initialization != Initialization::kPrior || initial_labels_given ||
      options.candidate_min_confidence > 0.0 || !energy_options.use_gcp_energy || prior.empty() ||
      PriorWeightsReadData(prior_weight, energy_options)) {
    return {};
  }
  if (prior.type() != CV_32F) throw Error("CandidateLabelBands: the prior must be CV_32F");
  const int block = options.candidate_block_px;
  const int blocks_x = (prior.cols + block - 1) / block, blocks_y = (prior.rows + block - 1) / block;
  LabelBands bands;
  bands.block_px = block;
  bands.lo.create(blocks_y, blocks_x, CV_32S);
  bands.hi.create(blocks_y, blocks_x, CV_32S);
  // The candidates (LocalCandidateBlocks) of a block without votes: ±radius around every D̂ and
  // the start labels, D̂ rounded; one more label on each side for the refinement's parabola.
  const int reach = options.candidate_radius + 1;
  for (int by = 0; by < blocks_y; ++by) {
    for (int bx = 0; bx < blocks_x; ++bx) {
      float lowest = std::numeric_limits<float>::infinity();
      float highest = -std::numeric_limits<float>::infinity();
      bool complete = true;
      for (int row = by * block; complete && row < std::min(prior.rows, (by + 1) * block); ++row) {
        const float* p = prior.ptr<float>(row);
        for (int col = bx * block; col < std::min(prior.cols, (bx + 1) * block); ++col) {
          if (!std::isfinite(p[col])) {
            complete = false;
            break;
          }
          lowest = std::min(lowest, p[col]);
          highest = std::max(highest, p[col]);
        }
      }
      int lo = 0, hi = num_labels - 1;
      if (complete) {
        // A prior beyond the labels starts from the end label: it and its neighbour.
        const float limit = 4.0f * static_cast<float>(num_labels) + 16.0f;
        lowest = std::clamp(lowest, -limit, limit);
        highest = std::clamp(highest, -limit, limit);
        const int start_lo = PriorStartLabel(lowest, num_labels);
        const int start_hi = PriorStartLabel(highest, num_labels);
        lo = std::max(0, std::min(static_cast<int>(std::floor(lowest)) - reach, start_lo - 1));
        hi = std::min(num_labels - 1,
                      std::max(static_cast<int>(std::ceil(highest)) + reach, start_hi + 1));
      }
      bands.lo.at<int>(by, bx) = lo;
      bands.hi.at<int>(by, bx) = hi;
    }
  }
  return bands;
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
  }
  // The winner-take-all labels (one pass over the cost volume): the start labelling and the
  // votes of the local candidate sets.
  cv::Mat wta;
  const bool prior_candidates =
      options.candidate_labels == CandidateLabels::kPrior && problem.UsesPrior(energy_options);
  if (initial_labels.empty() ||
      (options.candidate_labels != CandidateLabels::kAll && !prior_candidates)) {
    wta = WinnerTakeAll(*problem.data);
  }
  if (initial_labels.empty()) {
    labels = wta.clone();
    if (options.initialization == Initialization::kPrior && !problem.prior.empty()) {
      for (int row = 0; row < labels.rows; ++row) {
        for (int col = 0; col < labels.cols; ++col) {
          const float prior = problem.prior.ptr<float>(row)[col];
          if (std::isfinite(prior)) {
            labels.ptr<int>(row)[col] = PriorStartLabel(prior, num_labels);
          }
        }
      }
    }
  }

  ExpansionResult result;
  ExpansionSolver solver(problem, energy_options, options.candidate_block_px, options.prune_pixels);
  cv::Mat votes = wta;
  if (initial_labels.empty() && options.candidate_min_confidence > 0.0) {
    result.unconfident_pixels = StartUnconfidentPixels(problem, options, wta, solver.blocks_x(),
                                                       solver.blocks_y(), &labels, &votes);
  }
  solver.SetLabels(labels);
  std::vector<std::vector<int>> blocks_of_label;
  if (options.candidate_labels != CandidateLabels::kAll) {
    blocks_of_label =
        LocalCandidateBlocks(problem, votes, labels, options, energy_options, solver.blocks_x(),
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
    const double cycle_start = timer.ElapsedSeconds();
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
      std::vector<int> changed_blocks;
      if (options.retry_changed_blocks_only && last_tried[alpha] >= 0) {
        changed_blocks = solver.ChangedBlocks(blocks, last_tried[alpha]);
        if (changed_blocks.empty()) {
          ++result.moves_skipped;
          continue;
        }
        blocks = &changed_blocks;
      } else if (options.skip_unchanged_labels && last_tried[alpha] >= 0 &&
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
    result.seconds_per_cycle.push_back(timer.ElapsedSeconds() - cycle_start);
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
                      const cv::Mat& labels, int alpha, double* graph_energy, bool prune_pixels,
                      long long* pixels_pruned) {
  problem.Validate();
  energy_options.Check();
  CheckLabels(problem, labels, "ExpansionMove: the labelling");
  ExpansionSolver solver(problem, energy_options, 16, prune_pixels);
  solver.SetLabels(labels);
  double delta = 0.0;
  solver.Move(alpha, nullptr, 1, &delta, [](double, double) { return true; });
  if (pixels_pruned) *pixels_pruned = solver.last_pruned();
  const cv::Mat out = solver.Labels();
  if (graph_energy) *graph_energy = ComputeEnergy(problem, labels, energy_options) + delta;
  return out;
}

}  // namespace gcpstereo::optimize
