// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/alpha_expansion.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/optimize/refinement.h"
#include "test_problems.h"

namespace gcpstereo::optimize {
namespace {

using testing::MakeScene;
using testing::RandomProblem;

// Exhaustive minimum over all L^n labellings of a tiny problem.
double BruteForceMinimum(const MrfProblem& problem, const EnergyOptions& options) {
  const int n = problem.width() * problem.height(), num_labels = problem.num_labels();
  cv::Mat labels(problem.height(), problem.width(), CV_32S, cv::Scalar(0));
  double best = std::numeric_limits<double>::infinity();
  while (true) {
    best = std::min(best, ComputeEnergy(problem, labels, options));
    int i = 0;
    for (; i < n; ++i) {
      int& l = labels.ptr<int>(0)[i];
      if (++l < num_labels) break;
      l = 0;
    }
    if (i == n) break;
  }
  return best;
}

ExpansionOptions PlainOptions() {
  ExpansionOptions options;
  options.candidate_labels = CandidateLabels::kAll;
  options.convergence_tolerance = 0.0;
  options.retry_changed_blocks_only = false;
  options.max_cycles = 100;
  options.verify_moves = true;
  return options;
}

EnergyOptions TinyEnergy(bool with_prior) {
  EnergyOptions options;
  options.use_gcp_energy = with_prior;
  return options;
}

TEST(AlphaExpansion, WithinTheBvzBoundOfTheBruteForceOptimum) {
  // 3x3 pixels, 3 labels, random costs (on the scale of λs so that smoothness matters).
  int equal_to_optimum = 0;
  const int instances = 60;
  for (int seed = 0; seed < instances; ++seed) {
    const OwnedMrfProblem owned = RandomProblem(3, 3, 3, 1000 + seed, seed % 2 ? 0.3 : 0.0);
    const MrfProblem problem = owned.View();
    const EnergyOptions energy = TinyEnergy(seed % 2 == 1);
    const double optimum = BruteForceMinimum(problem, energy);
    const ExpansionResult result = AlphaExpansion(problem, energy, PlainOptions());
    const double found = result.breakdown.total();
    // BVZ 2001, Thm. 6.1: E(f̂) <= 2c·E(f*), c = max V / min nonzero V = T / 1 = 2 here.
    const double c = energy.truncation / 1.0;
    EXPECT_LE(found, 2.0 * c * optimum + 1e-9) << "seed " << seed;
    EXPECT_GE(found, optimum - 1e-9) << "seed " << seed;
    if (found <= optimum + 1e-9) ++equal_to_optimum;
  }
  // Expansion is usually optimal on such tiny problems; the bound is loose.
  EXPECT_GE(equal_to_optimum, instances / 2);
}

TEST(AlphaExpansion, ExactOnTwoLabels) {
  for (int seed = 0; seed < 40; ++seed) {
    const OwnedMrfProblem owned = RandomProblem(3, 3, 2, 2000 + seed, seed % 2 ? 0.4 : 0.0);
    const MrfProblem problem = owned.View();
    const EnergyOptions energy = TinyEnergy(true);
    const double optimum = BruteForceMinimum(problem, energy);
    const ExpansionResult result = AlphaExpansion(problem, energy, PlainOptions());
    EXPECT_NEAR(result.breakdown.total(), optimum, 1e-9 * std::max(1.0, optimum))
        << "seed " << seed;
  }
}

TEST(ExpansionMove, GraphEnergyEqualsDirectEnergyAndTheMoveIsOptimal) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const int num_labels = 2 + trial % 5;
    OwnedMrfProblem owned = RandomProblem(3, 3, num_labels, 3000 + trial, 0.3);
    if (trial % 2 == 1) {  // eq. (9): a prior weight per pixel, some 0
      owned.prior_weight = cv::Mat(3, 3, CV_32F);
      cv::randu(owned.prior_weight, 0.0, 1.0);
      owned.prior_weight.at<float>(1, 1) = 0.0f;
    }
    const MrfProblem problem = owned.View();
    EnergyOptions energy;
    energy.truncation = 1.0 + trial % 3;
    cv::Mat labels(3, 3, CV_32S);
    std::uniform_int_distribution<int> label(0, num_labels - 1);
    for (int i = 0; i < 9; ++i) labels.ptr<int>(0)[i] = label(rng);
    const int alpha = label(rng);
    double graph_energy = 0.0;
    const cv::Mat moved = ExpansionMove(problem, energy, labels, alpha, &graph_energy);
    const double direct = ComputeEnergy(problem, moved, energy);
    EXPECT_NEAR(graph_energy, direct, 1e-9 * std::max(1.0, direct)) << "trial " << trial;
    // Brute force over the 2^9 binary choices keep / switch to α.
    double best = std::numeric_limits<double>::infinity();
    for (int mask = 0; mask < 512; ++mask) {
      cv::Mat candidate = labels.clone();
      for (int i = 0; i < 9; ++i) {
        if (mask & (1 << i)) candidate.ptr<int>(0)[i] = alpha;
      }
      best = std::min(best, ComputeEnergy(problem, candidate, energy));
    }
    EXPECT_NEAR(direct, best, 1e-9 * std::max(1.0, best)) << "trial " << trial;
    for (int i = 0; i < 9; ++i) {
      const int l = moved.ptr<int>(0)[i];
      EXPECT_TRUE(l == alpha || l == labels.ptr<int>(0)[i]);
    }
  }
}

// Pruning (prune_pixels) is exact move by move: the pruned move reaches the brute-force minimum
// of the binary move, and the cut's energy is the direct energy. Labellings are piecewise
// constant (runs of equal labels) so that the bound with fixed neighbours fires often.
TEST(ExpansionMove, PrunedMoveIsStillOptimal) {
  std::mt19937 rng(11);
  long long total_pruned = 0;
  for (int trial = 0; trial < 120; ++trial) {
    const int num_labels = 3 + trial % 6;
    const int w = 4, h = 3;
    const OwnedMrfProblem owned =
        RandomProblem(w, h, num_labels, 5000 + trial, 0.3, trial % 2 ? 60.0f : 150.0f);
    const MrfProblem problem = owned.View();
    EnergyOptions energy;
    energy.truncation = 1.0 + trial % 3;
    energy.lambda_s = trial % 3 == 0 ? 5.0 : 20.0;
    cv::Mat labels(h, w, CV_32S);
    std::uniform_int_distribution<int> label(0, num_labels - 1);
    std::bernoulli_distribution repeat(0.7);
    for (int i = 0; i < w * h; ++i) {
      labels.ptr<int>(0)[i] = i > 0 && repeat(rng) ? labels.ptr<int>(0)[i - 1] : label(rng);
    }
    const int alpha = label(rng);
    double graph_energy = 0.0;
    long long pruned = 0;
    const cv::Mat moved = ExpansionMove(problem, energy, labels, alpha, &graph_energy,
                                        /*prune_pixels=*/true, &pruned);
    total_pruned += pruned;
    const double direct = ComputeEnergy(problem, moved, energy);
    EXPECT_NEAR(graph_energy, direct, 1e-9 * std::max(1.0, direct)) << "trial " << trial;
    double best = std::numeric_limits<double>::infinity();
    for (int mask = 0; mask < (1 << (w * h)); ++mask) {
      cv::Mat candidate = labels.clone();
      for (int i = 0; i < w * h; ++i) {
        if (mask & (1 << i)) candidate.ptr<int>(0)[i] = alpha;
      }
      best = std::min(best, ComputeEnergy(problem, candidate, energy));
    }
    EXPECT_NEAR(direct, best, 1e-9 * std::max(1.0, best)) << "trial " << trial;
  }
  // The test means something only if pixels were actually pruned.
  EXPECT_GT(total_pruned, 100);
}

TEST(AlphaExpansion, EnergyNeverIncreasesAndMatchesTheDirectEnergy) {
  const testing::SceneProblem scene = MakeScene(48, 36, 16, 11, 6.0f, 0.02);
  const MrfProblem problem = scene.problem.View();
  for (CandidateLabels mode : {CandidateLabels::kAll, CandidateLabels::kLocal}) {
    ExpansionOptions options = PlainOptions();
    options.candidate_labels = mode;
    options.candidate_block_px = 8;
    const ExpansionResult result = AlphaExpansion(problem, EnergyOptions(), options);
    ASSERT_FALSE(result.energy_per_cycle.empty());
    double previous = result.initial_energy;
    for (double e : result.energy_per_cycle) {
      EXPECT_LE(e, previous);
      previous = e;
    }
    EXPECT_TRUE(result.converged);
    EXPECT_GT(result.moves_accepted, 0);
    EXPECT_LT(result.max_energy_mismatch, 1e-6 * result.breakdown.total());
    EXPECT_NEAR(result.energy_per_cycle.back(), result.breakdown.total(),
                1e-6 * result.breakdown.total());
    EXPECT_LT(result.breakdown.total(), result.initial_energy);
  }
}

TEST(AlphaExpansion, SkippingUnchangedLabelsDoesNotChangeTheAnswer) {
  const testing::SceneProblem scene = MakeScene(40, 30, 12, 5, 8.0f, 0.03);
  const MrfProblem problem = scene.problem.View();
  for (CandidateLabels mode : {CandidateLabels::kAll, CandidateLabels::kLocal}) {
    ExpansionOptions with = PlainOptions();
    with.candidate_labels = mode;
    with.candidate_block_px = 8;
    ExpansionOptions without = with;
    without.skip_unchanged_labels = false;
    with.prune_pixels = without.prune_pixels = false;  // compare labels bit for bit
    const ExpansionResult a = AlphaExpansion(problem, EnergyOptions(), with);
    const ExpansionResult b = AlphaExpansion(problem, EnergyOptions(), without);
    EXPECT_EQ(cv::norm(a.labels, b.labels, cv::NORM_INF), 0.0);
    EXPECT_EQ(a.breakdown.total(), b.breakdown.total());
    EXPECT_LT(a.moves_tried, b.moves_tried);
  }
}

TEST(AlphaExpansion, PruningPixelsDoesNotChangeTheEnergy) {
  for (std::uint32_t seed : {5u, 6u, 7u}) {
    const testing::SceneProblem scene = MakeScene(40, 30, 12, seed, 8.0f, 0.03);
    const MrfProblem problem = scene.problem.View();
    ExpansionOptions with = PlainOptions();
    ExpansionOptions without = with;
    without.prune_pixels = false;
    const ExpansionResult a = AlphaExpansion(problem, EnergyOptions(), with);
    const ExpansionResult b = AlphaExpansion(problem, EnergyOptions(), without);
    // Pruning keeps the set of optimal moves; max-flow may pick another optimum among ties, so
    // compare energies (and they are almost always the same labels).
    EXPECT_NEAR(a.breakdown.total(), b.breakdown.total(), 1e-9 * b.breakdown.total());
    EXPECT_GT(a.pixels_pruned, 0);
    EXPECT_LT(a.graph_nodes, b.graph_nodes);
  }
}

TEST(AlphaExpansion, LocalCandidatesStayCloseToPlainExpansion) {
  const testing::SceneProblem scene = MakeScene(64, 48, 24, 21, 6.0f, 0.01);
  const MrfProblem problem = scene.problem.View();
  ExpansionOptions plain = PlainOptions();
  plain.verify_moves = false;
  ExpansionOptions local = plain;
  local.candidate_labels = CandidateLabels::kLocal;
  const ExpansionResult a = AlphaExpansion(problem, EnergyOptions(), plain);
  const ExpansionResult b = AlphaExpansion(problem, EnergyOptions(), local);
  const double gap = (b.breakdown.total() - a.breakdown.total()) / a.breakdown.total();
  EXPECT_LT(gap, 0.005) << a.Summary() << "\n" << b.Summary();
  EXPECT_LT(b.graph_nodes, a.graph_nodes);
}

TEST(AlphaExpansion, RetryingChangedBlocksOnlyStaysCloseToPlainExpansion) {
  const testing::SceneProblem scene = MakeScene(64, 48, 16, 23, 6.0f, 0.01);
  const MrfProblem problem = scene.problem.View();
  ExpansionOptions plain = PlainOptions();  // verifies every move against ComputeEnergy
  plain.candidate_block_px = 8;
  ExpansionOptions retry = plain;
  retry.retry_changed_blocks_only = true;
  const ExpansionResult a = AlphaExpansion(problem, EnergyOptions(), plain);
  const ExpansionResult b = AlphaExpansion(problem, EnergyOptions(), retry);
  double previous = b.initial_energy;
  for (double e : b.energy_per_cycle) {
    EXPECT_LE(e, previous);
    previous = e;
  }
  EXPECT_LT(b.max_energy_mismatch, 1e-6 * b.breakdown.total());
  const double gap = (b.breakdown.total() - a.breakdown.total()) / a.breakdown.total();
  EXPECT_LT(gap, 0.005) << a.Summary() << "\n" << b.Summary();
  EXPECT_LT(b.graph_nodes, a.graph_nodes);
}

// CandidateLabelBands: the labels α-expansion with prior candidates and the refinement after it
// read. A data term holding only those (everything else the largest cost, as a banded cost volume
// holds it) gives the same labels, energy and refined labels as the full one; and the bands are
// every label whenever the options let the solver read others.
TEST(AlphaExpansion, CandidateLabelBandsHoldEveryCostTheSolverReads) {
  const int width = 64, height = 48, num_labels = 24;
  testing::SceneProblem scene = MakeScene(width, height, num_labels, 27, 6.0f, 0.01);
  std::mt19937 rng(5);
  std::normal_distribution<float> gauss(0.0f, 0.6f);
  scene.problem.prior = cv::Mat(height, width, CV_32F, cv::Scalar(std::nanf("")));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < 37; ++x) {  // a block column half covered: every label there
      // Some of the prior beyond the label range (the start label is then clamped to the end).
      scene.problem.prior.at<float>(y, x) = scene.truth.at<float>(y, x) + gauss(rng) +
                                            (y < 8 ? 9.0f : 0.0f) - (y >= 40 ? 14.0f : 0.0f);
    }
  }
  ExpansionOptions options;
  options.candidate_block_px = 8;
  options.candidate_labels = CandidateLabels::kPrior;
  options.initialization = Initialization::kPrior;
  options.verify_moves = true;
  const EnergyOptions energy;
  const LabelBands bands =
      CandidateLabelBands(scene.problem.prior, cv::Mat(), num_labels, options, energy, false);
  ASSERT_FALSE(bands.empty());
  const double share = bands.Fraction(cv::Size(width, height), num_labels);
  EXPECT_GT(share, 0.5);
  EXPECT_LT(share, 0.85);
  OwnedMrfProblem banded = scene.problem;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int lo = bands.lo.at<int>(y / 8, x / 8), hi = bands.hi.at<int>(y / 8, x / 8);
      std::uint16_t* entries = banded.data.MutablePixelData(y, x);
      for (int l = 0; l < num_labels; ++l) {
        if ((l < lo || l > hi) && entries[l] != CostVolume::kNoData) entries[l] = 65534;
      }
    }
  }
  const ExpansionResult full = AlphaExpansion(scene.problem.View(), energy, options);
  const ExpansionResult part = AlphaExpansion(banded.View(), energy, options);
  EXPECT_EQ(cv::norm(full.labels, part.labels, cv::NORM_INF), 0.0);
  EXPECT_EQ(full.breakdown.total(), part.breakdown.total());
  EXPECT_EQ(full.moves_tried, part.moves_tried);
  RefinementOptions refinement;
  const cv::Mat refined_full = RefineSubLabel(scene.problem.View(), full.labels, energy, refinement);
  const cv::Mat refined_part = RefineSubLabel(banded.View(), part.labels, energy, refinement);
  EXPECT_EQ(cv::norm(refined_full, refined_part, cv::NORM_INF), 0.0);
  // Final labels at a band's edge (the refinement reads one label beyond them).
  int at_edge = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < 37; ++x) {
      const int l = full.labels.at<int>(y, x);
      if (l == bands.lo.at<int>(y / 8, x / 8) + 1 || l == bands.hi.at<int>(y / 8, x / 8) - 1) {
        ++at_edge;
      }
    }
  }
  EXPECT_GT(at_edge, 0);

  // Options under which the solver may read any label: no bands.
  auto none = [&](const ExpansionOptions& o, const EnergyOptions& e, const cv::Mat& weight,
                  bool initial) {
    return CandidateLabelBands(scene.problem.prior, weight, num_labels, o, e, initial).empty();
  };
  EXPECT_TRUE(none(options, energy, cv::Mat(), true));
  ExpansionOptions o = options;
  o.candidate_labels = CandidateLabels::kLocal;
  EXPECT_TRUE(none(o, energy, cv::Mat(), false));
  o = options;
  o.initialization = Initialization::kWinnerTakeAll;
  EXPECT_TRUE(none(o, energy, cv::Mat(), false));
  o = options;
  o.candidate_min_confidence = 0.1;
  EXPECT_TRUE(none(o, energy, cv::Mat(), false));
  EnergyOptions e = energy;
  e.gcp_confidence = 0.5;
  EXPECT_TRUE(none(options, e, cv::Mat(), false));
  e = energy;
  e.use_gcp_energy = false;
  EXPECT_TRUE(none(options, e, cv::Mat(), false));
  const cv::Mat spread(height, width, CV_32F, cv::Scalar(0.5f));
  EXPECT_TRUE(none(options, energy, spread, false));  // gated by the data confidence
  e = energy;
  e.gcp_spread_gated = false;
  EXPECT_FALSE(none(options, e, spread, false));
  EXPECT_TRUE(CandidateLabelBands(cv::Mat(), cv::Mat(), num_labels, options, energy, false).empty());
}

// candidate_labels: prior. A dense prior near the truth over the left half, none over the right:
// a block that the prior reaches tries only the labels near its prior values and its start labels
// (the prior rounded), so every final label there lies within the block's prior range ±
// candidate_radius; a block that it does not reach tries only its pixels' start (WTA) labels.
TEST(AlphaExpansion, PriorCandidatesStayNearThePriorWhereItReaches) {
  const int width = 64, height = 48, num_labels = 24, block = 8, half = 32;
  testing::SceneProblem scene = MakeScene(width, height, num_labels, 21, 6.0f, 0.0);
  std::mt19937 rng(3);
  std::normal_distribution<float> gauss(0.0f, 0.4f);
  scene.problem.prior = cv::Mat(height, width, CV_32F, cv::Scalar(std::nanf("")));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < half; ++x) {
      scene.problem.prior.at<float>(y, x) = std::clamp(
          scene.truth.at<float>(y, x) + gauss(rng), 0.0f, static_cast<float>(num_labels - 1));
    }
  }
  ExpansionOptions local;
  local.candidate_block_px = block;
  local.initialization = Initialization::kPrior;
  local.verify_moves = true;
  ExpansionOptions prior = local;
  prior.candidate_labels = CandidateLabels::kPrior;
  const ExpansionResult a = AlphaExpansion(scene.problem.View(), EnergyOptions(), local);
  const ExpansionResult b = AlphaExpansion(scene.problem.View(), EnergyOptions(), prior);
  EXPECT_LT(b.mean_candidates_per_block, a.mean_candidates_per_block)
      << a.mean_candidates_per_block << " vs " << b.mean_candidates_per_block;
  EXPECT_LT(b.graph_nodes, a.graph_nodes);
  EXPECT_LT(b.max_energy_mismatch, 1e-6 * b.breakdown.total());
  EXPECT_LE(b.breakdown.total(), 1.005 * a.breakdown.total()) << a.Summary() << "\n" << b.Summary();
  int outside = 0, right_half_off_truth = 0;
  for (int by = 0; by < height / block; ++by) {
    for (int bx = 0; bx < half / block; ++bx) {
      const cv::Rect r(bx * block, by * block, block, block);
      double lo = 0.0, hi = 0.0;
      cv::minMaxLoc(scene.problem.prior(r), &lo, &hi);
      lo = std::floor(lo) - local.candidate_radius;
      hi = std::ceil(hi) + local.candidate_radius;
      for (int y = r.y; y < r.y + block; ++y) {
        for (int x = r.x; x < r.x + block; ++x) {
          const int label = b.labels.at<int>(y, x);
          if (label < lo || label > hi) ++outside;
        }
      }
    }
  }
  EXPECT_EQ(outside, 0);
  // Blocks without a prior: each final label is a WTA label (a least cost) of a pixel of the block.
  const CostVolume& data = scene.problem.data;
  int not_a_start_label = 0;
  for (int by = 0; by < height / block; ++by) {
    for (int bx = half / block; bx < width / block; ++bx) {
      std::set<int> starts;
      for (int y = by * block; y < (by + 1) * block; ++y) {
        for (int x = bx * block; x < (bx + 1) * block; ++x) {
          const std::uint16_t* costs = data.PixelData(y, x);
          const std::uint16_t least = *std::min_element(costs, costs + num_labels);
          for (int l = 0; l < num_labels; ++l) {
            if (costs[l] == least) starts.insert(l);
          }
        }
      }
      for (int y = by * block; y < (by + 1) * block; ++y) {
        for (int x = bx * block; x < (bx + 1) * block; ++x) {
          if (!starts.count(b.labels.at<int>(y, x))) ++not_a_start_label;
        }
      }
    }
  }
  EXPECT_EQ(not_a_start_label, 0);
  // Without the GCP energy there is no prior to stay near: kPrior is kLocal.
  EnergyOptions without_prior;
  without_prior.use_gcp_energy = false;
  const ExpansionResult c = AlphaExpansion(scene.problem.View(), without_prior, local);
  const ExpansionResult d = AlphaExpansion(scene.problem.View(), without_prior, prior);
  EXPECT_EQ(cv::norm(c.labels, d.labels, cv::NORM_INF), 0.0);
  EXPECT_EQ(c.mean_candidates_per_block, d.mean_candidates_per_block);
  // The data still decide there: the labels are mostly right.
  for (int y = 0; y < height; ++y) {
    for (int x = half + block; x < width; ++x) {
      if (std::abs(b.labels.at<int>(y, x) - scene.truth.at<float>(y, x)) > 2.0f) {
        ++right_half_off_truth;
      }
    }
  }
  EXPECT_LT(right_half_off_truth, (width - half - block) * height / 10);
}

// A "sky" over a textured scene: in the top rows every label costs about the same — a pixel's
// curve is noise over a faint lean towards label 30 — so their WTA labels are noise and, with the
// default options, nearly every label becomes a candidate there. With candidate_min_confidence
// those pixels vote for and start from their block's summed-cost label: fewer candidates and graph
// nodes, the same energy within the budget of the other approximations, and the sky on the
// label its summed data prefer.
TEST(AlphaExpansion, UnconfidentPixelsVoteForTheirBlocksLabel) {
  const int width = 64, height = 64, num_labels = 40, sky_rows = 32, lean_label = 30;
  testing::SceneProblem scene = MakeScene(width, height, num_labels, 31);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> noise(0.0f, 1.0f);
  for (int row = 0; row < sky_rows; ++row) {
    for (int col = 0; col < width; ++col) {
      for (int l = 0; l < num_labels; ++l) {
        const float lean = 0.02f * std::abs(l - lean_label);
        scene.problem.data.SetCost(row, col, l, 50.0f + lean + noise(rng));
      }
      scene.problem.image.at<cv::Vec3b>(row, col) = cv::Vec3b(230, 200, 150);
    }
  }
  const MrfProblem problem = scene.problem.View();
  ExpansionOptions off;
  off.candidate_block_px = 8;
  off.convergence_tolerance = 0.0;
  ExpansionOptions on = off;
  on.candidate_min_confidence = 0.1;
  const ExpansionResult a = AlphaExpansion(problem, EnergyOptions(), off);
  const ExpansionResult b = AlphaExpansion(problem, EnergyOptions(), on);
  EXPECT_EQ(a.unconfident_pixels, 0);
  // The sky and hardly anything else is unconfident.
  EXPECT_GE(b.unconfident_pixels, width * sky_rows * 9 / 10);
  EXPECT_LE(b.unconfident_pixels, width * sky_rows + width * height / 20);
  EXPECT_LT(b.mean_candidates_per_block, a.mean_candidates_per_block)
      << a.mean_candidates_per_block << " vs " << b.mean_candidates_per_block;
  EXPECT_LT(b.graph_nodes, a.graph_nodes);
  EXPECT_LE(b.breakdown.total(), 1.005 * a.breakdown.total()) << a.Summary() << "\n" << b.Summary();
  const cv::Mat sky = b.labels.rowRange(0, sky_rows - 2);
  // One label over the sky, within a step of the lean (the noise moves the summed minimum).
  double lo = 0.0, hi = 0.0;
  cv::minMaxLoc(sky, &lo, &hi);
  EXPECT_EQ(lo, hi);
  EXPECT_LE(std::abs(lo - lean_label), 1.0);
}

TEST(AlphaExpansion, DeterministicAndStartsFromGivenLabels) {
  const testing::SceneProblem scene = MakeScene(30, 20, 10, 8);
  const MrfProblem problem = scene.problem.View();
  const ExpansionResult a = AlphaExpansion(problem, EnergyOptions(), ExpansionOptions());
  const ExpansionResult b = AlphaExpansion(problem, EnergyOptions(), ExpansionOptions());
  ASSERT_EQ(a.labels.size(), b.labels.size());
  EXPECT_EQ(std::memcmp(a.labels.data, b.labels.data, a.labels.total() * sizeof(int)), 0);
  // Starting from the optimum of a run: nothing to improve.
  ExpansionOptions options;
  options.convergence_tolerance = 0.0;
  const ExpansionResult c = AlphaExpansion(problem, EnergyOptions(), options);
  const ExpansionResult d = AlphaExpansion(problem, EnergyOptions(), options, c.labels);
  EXPECT_EQ(d.moves_accepted, 0);
  EXPECT_EQ(d.breakdown.total(), c.breakdown.total());
}

// ω_p = 0 everywhere is no GCP energy at all: the same labels as use_gcp_energy = false, before
// and after refinement.
TEST(AlphaExpansion, ZeroPriorWeightsAreNoPrior) {
  testing::SceneProblem scene = MakeScene(40, 30, 16, 5);
  // A strong prior that is wrong everywhere, so that with any weight it moves labels.
  scene.problem.prior = cv::Mat(30, 40, CV_32F, cv::Scalar(15.0f));
  EnergyOptions without;
  without.use_gcp_energy = false;
  const ExpansionResult reference = AlphaExpansion(scene.problem.View(), without, {});
  EnergyOptions with;
  with.lambda_r = 100.0;
  const ExpansionResult pulled = AlphaExpansion(scene.problem.View(), with, {});
  ASSERT_GT(cv::countNonZero(pulled.labels != reference.labels), 0);
  scene.problem.prior_weight = cv::Mat(30, 40, CV_32F, cv::Scalar(0.0f));
  const ExpansionResult weighted = AlphaExpansion(scene.problem.View(), with, {});
  EXPECT_EQ(cv::countNonZero(weighted.labels != reference.labels), 0);
  EXPECT_EQ(weighted.breakdown.gcp, 0.0);
  for (const RefinementMethod method : {RefinementMethod::kCeres, RefinementMethod::kIrls}) {
    RefinementOptions refinement;
    refinement.method = method;
    const cv::Mat a = RefineSubLabel(scene.problem.View(), reference.labels, without, refinement);
    const cv::Mat b = RefineSubLabel(scene.problem.View(), weighted.labels, with, refinement);
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << RefinementMethodName(method);
  }
}

TEST(AlphaExpansion, RejectsBadInput) {
  const OwnedMrfProblem owned = RandomProblem(4, 3, 3, 1);
  try {
    AlphaExpansion(owned.View(), EnergyOptions(), ExpansionOptions(),
                   cv::Mat(3, 4, CV_32S, cv::Scalar(5)));
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "AlphaExpansion: the initial labelling has labels in [5, 5], outside [0, 3)");
  }
  ExpansionOptions options;
  options.max_cycles = 0;
  try {
    AlphaExpansion(owned.View(), EnergyOptions(), options);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "optimizer.max_cycles = 0. Violated constraint: >= 1");
  }
  EXPECT_THROW(ParseCandidateLabels("some"), ConfigError);
  for (CandidateLabels mode : {CandidateLabels::kAll, CandidateLabels::kLocal,
                               CandidateLabels::kPrior}) {
    EXPECT_EQ(ParseCandidateLabels(CandidateLabelsName(mode)), mode);
  }
  options = ExpansionOptions();
  options.candidate_min_confidence = 1.0;
  try {
    AlphaExpansion(owned.View(), EnergyOptions(), options);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "optimizer.candidate_min_confidence = 1. Violated constraint: in [0, 1)");
  }
}

TEST(AlphaExpansion, ProgressCanCancel) {
  const testing::SceneProblem scene = MakeScene(30, 20, 10, 9);
  int calls = 0;
  const ExpansionResult result =
      AlphaExpansion(scene.problem.View(), EnergyOptions(), PlainOptions(), {}, [&](double f) {
        EXPECT_GE(f, 0.0);
        EXPECT_LE(f, 1.0);
        return ++calls < 3;
      });
  EXPECT_TRUE(result.cancelled);
  EXPECT_FALSE(result.converged);
  EXPECT_EQ(calls, 3);
  EXPECT_LE(result.breakdown.total(), result.initial_energy);
}

}  // namespace
}  // namespace gcpstereo::optimize
