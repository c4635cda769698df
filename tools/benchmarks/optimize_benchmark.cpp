// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Benchmarks of the optimize module.
//
//   gcpstereo_optimize_benchmark                       Google Benchmark: Teddy-size (450×375, 60
//                                                      labels) and Fountain-size (1536×1024, 360
//                                                      labels, 2×2 tiles, 16 px; arg 0 = threads)
//                                                      problems, the real Middlebury scenes of
//                                                      the gap report (BM_MiddleburyReal/0..3)
//                                                      and the sub-label refinements
//   gcpstereo_optimize_benchmark --gap_report          energy gap of every speed shortcut against
//                                                      plain α-expansion, per synthetic scene
//   gcpstereo_optimize_benchmark --gap_report_middlebury   the same on tsukuba, venus, Aloe,
//                                                      Rocks1 (two views, |ΔRGB| costs, sparse
//                                                      GT prior) from ../shared/data
//   gcpstereo_optimize_benchmark --seam_report         untiled vs 2×2 tiles on the Fountain-size
//                                                      problem: seams and energy
//   gcpstereo_optimize_benchmark --eta_report          the η study (GCP energy, see energy.h)
//
// The synthetic cost volumes are generated per region on demand (like the pipeline's plane sweep):
// a piecewise-smooth label field (slanted planes, a sphere-like bump, discs in front), a textured
// image whose colour changes at depth edges, truncated-linear costs with hash noise, and weakly
// textured patches where the costs are nearly flat.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "gcpstereo/core/system.h"
#include "gcpstereo/optimize/alpha_expansion.h"
#include "gcpstereo/optimize/energy.h"
#include "gcpstereo/optimize/refinement.h"
#include "gcpstereo/optimize/tiling.h"

namespace gcpstereo::optimize {
namespace {

std::uint32_t Hash(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  std::uint32_t h =
      a * 0x9E3779B1u ^ (b + 0x7F4A7C15u) * 0x85EBCA77u ^ (c + 0x165667B1u) * 0xC2B2AE3Du;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  h *= 0x297A2D39u;
  h ^= h >> 15;
  return h;
}
double Uniform(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return (Hash(a, b, c) >> 8) * (1.0 / 16777216.0);
}

// A synthetic scene of `width`×`height` pixels and `num_labels` labels.
struct SyntheticScene {
  int width, height, num_labels;
  double noise = 0.6;  // fraction of the label-error slope: cost noise amplitude

  double Truth(int x, int y) const {
    const double u = static_cast<double>(x) / width, v = static_cast<double>(y) / height;
    const double L = num_labels - 1;
    // Discs in front.
    const double d1 = (u - 0.62) * (u - 0.62) + (v - 0.4) * (v - 0.4);
    if (d1 < 0.02) return 0.85 * L;
    const double d2 = (u - 0.25) * (u - 0.25) + (v - 0.7) * (v - 0.7);
    if (d2 < 0.012) return 0.7 * L - 0.2 * L * d2 / 0.012;                  // a dome
    if (u < 0.45) return 0.15 * L + 0.2 * L * v;                            // slanted floor
    return 0.3 * L + 0.25 * L * (u - 0.45) + 0.05 * L * std::sin(6.0 * v);  // curved wall
  }
  bool Flat(int x, int y) const {  // weakly textured patch
    const double u = static_cast<double>(x) / width, v = static_cast<double>(y) / height;
    return u > 0.05 && u < 0.2 && v > 0.1 && v < 0.3;
  }
  cv::Vec3b Color(int x, int y) const {
    const double t = Truth(x, y);
    const int base = 60 + static_cast<int>(std::floor(t * 7.0 / num_labels)) * 20;
    const int tex = Flat(x, y) ? 0 : static_cast<int>(30 * Uniform(x, y, 77)) - 15;
    const int v = std::clamp(base + tex, 0, 255);
    return cv::Vec3b(v, std::clamp(255 - v, 0, 255), std::clamp(v / 2 + 40, 0, 255));
  }
  OwnedMrfProblem Make(const cv::Rect& region, double prior_fraction = 0.0,
                       double prior_noise = 0.5) const {
    const float max_cost = 120.0f;
    OwnedMrfProblem p{CostVolume(region, num_labels, max_cost),
                      cv::Mat(region.height, region.width, CV_8UC3), cv::Mat()};
    if (prior_fraction > 0.0) {
      p.prior = cv::Mat(region.height, region.width, CV_32F, cv::Scalar(std::nanf("")));
    }
    // Costs in units of "RGB difference": slope per label step scaled so that 60 labels over
    // the image behave like a disparity search.
    const double slope = 8.0 * std::max(1.0, 60.0 / num_labels);
    for (int row = 0; row < region.height; ++row) {
      for (int col = 0; col < region.width; ++col) {
        const int x = region.x + col, y = region.y + row;
        const double t = Truth(x, y);
        p.image.at<cv::Vec3b>(row, col) = Color(x, y);
        const double s = Flat(x, y) ? 0.05 * slope : slope;
        std::uint16_t* out = p.data.MutablePixelData(row, col);
        for (int l = 0; l < num_labels; ++l) {
          const double c = std::min(s * std::abs(l - t), 60.0) +
                           noise * slope * 4.0 * Uniform(x * 4099 + y, l, 12345);
          out[l] = p.data.Encode(static_cast<float>(c));
        }
        if (prior_fraction > 0.0 && Uniform(x, y, 999) < prior_fraction) {
          p.prior.at<float>(row, col) =
              static_cast<float>(t + prior_noise * (Uniform(x, y, 555) * 2.0 - 1.0));
        }
      }
    }
    return p;
  }
};

// Two-view rectified scene from ../shared/data: left/right images, costs = min(Σ_RGB |ΔI|, 60)
// averaged with the 3×3 box (cheap BT-like stand-in for the cost module, measurement only).
bool LoadMiddlebury(const std::string& left_path, const std::string& right_path, int num_labels,
                    OwnedMrfProblem* out) {
  const cv::Mat left = cv::imread(left_path, cv::IMREAD_COLOR);
  const cv::Mat right = cv::imread(right_path, cv::IMREAD_COLOR);
  if (left.empty() || right.empty()) return false;
  const int w = left.cols, h = left.rows;
  *out =
      OwnedMrfProblem{CostVolume(cv::Rect(0, 0, w, h), num_labels, 60.0f), left.clone(), cv::Mat()};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int d = 0; d < num_labels; ++d) {
        const int xr = std::max(0, x - d);
        double c = 0.0;
        for (int k = 0; k < 3; ++k) {
          c += std::abs(static_cast<int>(left.at<cv::Vec3b>(y, x)[k]) -
                        static_cast<int>(right.at<cv::Vec3b>(y, xr)[k]));
        }
        out->data.SetCost(y, x, d, static_cast<float>(std::min(c, 60.0)));
      }
    }
  }
  return true;
}

std::string SharedData() {
  const char* env = std::getenv("GCPSTEREO_DATA");
  return env ? env : GCPSTEREO_SOURCE_DIR "/../shared/data";
}

// CPU time of the calling thread (the machine may be shared: wall time is noisy).
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

struct Config {
  const char* name;
  CandidateLabels candidates;
  bool prune;
  bool skip;
  double tolerance;
  bool retry_changed_only = false;
};

const Config kConfigs[] = {
    {"plain (all labels, cycle to convergence)", CandidateLabels::kAll, false, false, 0.0},
    {"+ prune pixels (exact)", CandidateLabels::kAll, true, false, 0.0},
    {"+ skip unchanged labels (exact)", CandidateLabels::kAll, true, true, 0.0},
    {"+ tolerance 1e-4", CandidateLabels::kAll, true, true, 1e-4},
    {"+ local candidates", CandidateLabels::kLocal, true, true, 1e-4},
    {"+ retry changed blocks only (= default)", CandidateLabels::kLocal, true, true, 1e-4, true},
    {"default with tolerance 1e-3", CandidateLabels::kLocal, true, true, 1e-3, true},
};

void GapReport(const std::string& scene, const MrfProblem& problem, const EnergyOptions& energy) {
  std::printf("\n## %s (%dx%d, %d labels)\n", scene.c_str(), problem.width(), problem.height(),
              problem.num_labels());
  std::printf(
      "| configuration | energy | gap vs plain | cycles | max-flows | nodes (M) | wall s | CPU s "
      "|\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  double plain = 0.0;
  for (const Config& c : kConfigs) {
    ExpansionOptions options;
    options.candidate_labels = c.candidates;
    options.skip_unchanged_labels = c.skip;
    options.prune_pixels = c.prune;
    options.convergence_tolerance = c.tolerance;
    options.retry_changed_blocks_only = c.retry_changed_only;
    options.max_cycles = 100;
    const double cpu_start = ThreadCpuSeconds();
    const ExpansionResult r = AlphaExpansion(problem, energy, options);
    const double cpu = ThreadCpuSeconds() - cpu_start;
    const double e = r.breakdown.total();
    if (plain == 0.0) plain = e;
    std::printf("| %s | %.6g | %+.4f %% | %d | %lld | %.2f | %.2f | %.2f |\n", c.name, e,
                100.0 * (e - plain) / plain, r.cycles, r.moves_tried, r.graph_nodes / 1e6,
                r.time_seconds, cpu);
    std::fflush(stdout);
  }
}

int RunGapReport() {
  EnergyOptions energy;
  {
    const SyntheticScene teddy{450, 375, 60};
    const OwnedMrfProblem p = teddy.Make(cv::Rect(0, 0, 450, 375), 1.0 / 256);
    GapReport("synthetic Teddy-size, GCP prior on 0.4 % of pixels", p.View(), energy);
    EnergyOptions no_gcp = energy;
    no_gcp.use_gcp_energy = false;
    GapReport("synthetic Teddy-size, no GCP energy", p.View(), no_gcp);
  }
  {
    // A 1/4 crop of the Fountain setting (plain α-expansion on the full size takes too long to
    // repeat; the tiles are this size anyway).
    const SyntheticScene fountain{1536, 1024, 360};
    const OwnedMrfProblem p = fountain.Make(cv::Rect(384, 256, 784, 528), 1.0 / 256);
    GapReport("synthetic Fountain tile (784x528 of 1536x1024), 360 labels", p.View(), energy);
  }
  return 0;
}

// Sparse GCP prior from a ground-truth disparity image (value = I / scale, 0 = unknown): one
// value per 16×16 block, the one nearest the block centre (the paper's "downsample by 16").
cv::Mat SparsePrior(const std::string& gt_path, double scale, cv::Size size) {
  const cv::Mat gt = cv::imread(gt_path, cv::IMREAD_GRAYSCALE);
  cv::Mat prior(size, CV_32F, cv::Scalar(std::nanf("")));
  if (gt.empty() || gt.size() != size) return prior;
  for (int by = 0; by + 16 <= size.height; by += 16) {
    for (int bx = 0; bx + 16 <= size.width; bx += 16) {
      const int y = by + 8, x = bx + 8;
      if (gt.at<std::uint8_t>(y, x) > 0) prior.at<float>(y, x) = gt.at<std::uint8_t>(y, x) / scale;
    }
  }
  return prior;
}

bool g_candidate_sweep = false;

void CandidateSweep(const std::string& scene, const MrfProblem& problem,
                    const EnergyOptions& energy) {
  std::printf(
      "\n## candidate sweep: %s\n| min votes | radius | block | energy gap vs all | "
      "candidates/block | nodes (M) | CPU s |\n|---|---|---|---|---|---|---|\n",
      scene.c_str());
  ExpansionOptions reference;
  reference.candidate_labels = CandidateLabels::kAll;
  const double all = AlphaExpansion(problem, energy, reference).breakdown.total();
  for (int block : {16, 32}) {
    for (int votes : {3, 10, 30, 100}) {
      for (int radius : {1, 2}) {
        ExpansionOptions options;
        options.candidate_block_px = block;
        options.candidate_min_votes = votes;
        options.candidate_radius = radius;
        const double cpu_start = ThreadCpuSeconds();
        const ExpansionResult r = AlphaExpansion(problem, energy, options);
        const double cpu = ThreadCpuSeconds() - cpu_start;
        std::printf("| %d | %d | %d | %+.4f %% | %.1f | %.2f | %.2f |\n", votes, radius, block,
                    100.0 * (r.breakdown.total() - all) / all, r.mean_candidates_per_block,
                    r.graph_nodes / 1e6, cpu);
        std::fflush(stdout);
      }
    }
  }
}

// Two-view Middlebury pairs of the real-data reports (paths under ../shared/data/middlebury).
struct MiddleburyScene {
  const char* name;
  const char* left;
  const char* right;
  const char* gt;
  double gt_scale;
  int labels;
};
const MiddleburyScene kMiddleburyScenes[] = {
    {"tsukuba", "tsukuba/scene1.row3.col3.ppm", "tsukuba/scene1.row3.col4.ppm",
     "tsukuba/truedisp.row3.col3.pgm", 16.0, 16},
    {"venus", "venus/im2.ppm", "venus/im6.ppm", "venus/disp2.pgm", 8.0, 20},
    {"Aloe", "Aloe/view1.png", "Aloe/view5.png", "Aloe/disp1.png", 3.0, 80},
    {"Rocks1", "Rocks1/view1.png", "Rocks1/view5.png", "Rocks1/disp1.png", 3.0, 80},
};

int RunGapReportMiddlebury() {
  const std::string data = SharedData() + "/middlebury/";
  for (const MiddleburyScene& scene : kMiddleburyScenes) {
    OwnedMrfProblem p;
    if (!LoadMiddlebury(data + scene.left, data + scene.right, scene.labels, &p)) {
      std::printf("\n%s not found under %s: skipped\n", scene.name, data.c_str());
      continue;
    }
    p.prior = SparsePrior(data + scene.gt, scene.gt_scale, p.image.size());
    if (g_candidate_sweep) {
      if (scene.labels >= 60) CandidateSweep(scene.name, p.View(), EnergyOptions());
      continue;
    }
    GapReport(std::string("middlebury ") + scene.name +
                  " (|dRGB| costs, GCP prior from 1 GT value per 16x16 block)",
              p.View(), EnergyOptions());
  }
  return 0;
}

// η study. E_gcp uses the dense propagated map D̂ (Sec. 3.1), which is right on smooth surfaces
// and wrong near depth edges. We simulate D̂ as the true labels displaced by (6, 4) px (so a band
// along every edge is wrong by the full jump) plus ±0.5 label noise, and report, per η, the
// fraction of pixels with |D − truth| > 1 and the mean |D − truth| (paper parameters otherwise).
int RunEtaReport() {
  const SyntheticScene scene{450, 375, 60};
  const cv::Rect all(0, 0, 450, 375);
  OwnedMrfProblem problem = scene.Make(all);
  cv::Mat truth(375, 450, CV_32F);
  problem.prior = cv::Mat(375, 450, CV_32F);
  for (int y = 0; y < 375; ++y) {
    for (int x = 0; x < 450; ++x) {
      truth.at<float>(y, x) = static_cast<float>(scene.Truth(x, y));
      problem.prior.at<float>(y, x) =
          static_cast<float>(scene.Truth(std::min(x + 6, 449), std::min(y + 4, 374)) +
                             0.5 * (2.0 * Uniform(x, y, 4242) - 1.0));
    }
  }
  auto score = [&](const cv::Mat& labels) {
    cv::Mat f;
    labels.convertTo(f, CV_32F);
    const cv::Mat err = cv::abs(f - truth);
    return std::make_pair(cv::countNonZero(err > 1.0f) * 100.0 / err.total(), cv::mean(err)[0]);
  };
  {
    EnergyOptions energy;
    energy.use_gcp_energy = false;
    const auto s = score(AlphaExpansion(problem.View(), energy, ExpansionOptions()).labels);
    std::printf("no GCP energy: bad %.3f %%, mean |err| %.4f\n", s.first, s.second);
    cv::Mat prior_labels;
    problem.prior.convertTo(prior_labels, CV_32S);
    const auto d = score(prior_labels);
    std::printf("D-hat itself: bad %.3f %%, mean |err| %.4f\n", d.first, d.second);
  }
  std::printf("| eta | -ln eta | bad > 1 (%%) | mean abs err |\n|---|---|---|---|\n");
  for (double eta : {0.001, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5}) {
    EnergyOptions energy;
    energy.eta = eta;
    const auto s = score(AlphaExpansion(problem.View(), energy, ExpansionOptions()).labels);
    std::printf("| %g | %.2f | %.3f | %.4f |\n", eta, -std::log(eta), s.first, s.second);
    std::fflush(stdout);
  }
  return 0;
}

// η on real data: tsukuba and venus, |ΔRGB| costs, D̂ = the ground truth sampled at one pixel per
// 16×16 block and spread over its block (a crude stand-in for the propagation of Sec. 3.1, wrong
// near depth edges, which is where η matters). Score: % of non-occluded pixels (official mask)
// with |D − GT| > 1.
int RunEtaReportMiddlebury() {
  const std::string data = SharedData() + "/middlebury/";
  // tsukuba and venus: the scenes with official non-occlusion masks.
  for (const MiddleburyScene& scene :
       std::vector<MiddleburyScene>(kMiddleburyScenes, kMiddleburyScenes + 2)) {
    OwnedMrfProblem p;
    if (!LoadMiddlebury(data + scene.left, data + scene.right, scene.labels, &p)) {
      std::printf("%s not found: skipped\n", scene.name);
      continue;
    }
    const cv::Mat gt_raw = cv::imread(data + scene.gt, cv::IMREAD_GRAYSCALE);
    const cv::Mat mask =
        cv::imread(data + std::string(scene.name) + "/nonocc.png", cv::IMREAD_GRAYSCALE);
    cv::Mat gt;
    gt_raw.convertTo(gt, CV_32F, 1.0 / scene.gt_scale);
    const cv::Mat sparse = SparsePrior(data + scene.gt, scene.gt_scale, p.image.size());
    p.prior = cv::Mat(p.image.size(), CV_32F, cv::Scalar(std::nanf("")));
    for (int y = 0; y < p.image.rows; ++y) {
      for (int x = 0; x < p.image.cols; ++x) {
        const int cy = std::min((y / 16) * 16 + 8, p.image.rows - 1);
        const int cx = std::min((x / 16) * 16 + 8, p.image.cols - 1);
        p.prior.at<float>(y, x) = sparse.at<float>(cy, cx);
      }
    }
    auto bad = [&](const cv::Mat& labels) {
      int count = 0, total = 0;
      for (int y = 0; y < gt.rows; ++y) {
        for (int x = 0; x < gt.cols; ++x) {
          if (mask.at<std::uint8_t>(y, x) != 255) continue;
          ++total;
          const float l = labels.type() == CV_32S ? static_cast<float>(labels.at<int>(y, x))
                                                  : labels.at<float>(y, x);
          if (!(std::abs(l - gt.at<float>(y, x)) <= 1.0f)) ++count;
        }
      }
      return 100.0 * count / std::max(total, 1);
    };
    EnergyOptions energy;
    energy.use_gcp_energy = false;
    std::printf("\n## %s: no GCP energy: bad %.2f %%; D-hat alone: bad %.2f %%\n", scene.name,
                bad(AlphaExpansion(p.View(), energy, ExpansionOptions()).labels), bad(p.prior));
    std::printf("| eta | -ln eta | bad nonocc (%%) |\n|---|---|---|\n");
    for (double eta : {0.001, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5}) {
      energy = EnergyOptions();
      energy.eta = eta;
      std::printf("| %g | %.2f | %.2f |\n", eta, -std::log(eta),
                  bad(AlphaExpansion(p.View(), energy, ExpansionOptions()).labels));
      std::fflush(stdout);
    }
  }
  return 0;
}

// Seams: the Fountain-size synthetic problem untiled (one thread) against 2×2 tiles with 16 px
// overlap, mean and feather blends: SeamStatistics and the whole-image energy of the rounded
// results.
int RunSeamReport() {
  const SyntheticScene scene{1536, 1024, 360};
  const cv::Rect all(0, 0, 1536, 1024);
  const OwnedMrfProblem full = scene.Make(all, 1.0 / 256);
  const ExpansionResult untiled = AlphaExpansion(full.View(), EnergyOptions(), ExpansionOptions());
  std::printf("untiled: %s\n", untiled.Summary().c_str());
  const double untiled_energy = untiled.breakdown.total();
  for (const char* blend : {"mean", "feather"}) {
    TilingOptions tiling;
    tiling.blend = blend;
    ExpansionOptions options;
    options.num_threads = 2;
    const TiledResult tiled = OptimizeTiled(
        all.size(), [&](const cv::Rect& region) { return scene.Make(region, 1.0 / 256); },
        EnergyOptions(), options, tiling);
    cv::Mat rounded;
    tiled.labels.convertTo(rounded, CV_32S);
    const double energy = ComputeEnergy(full.View(), rounded, EnergyOptions());
    const SeamStatistics seams = MeasureSeams(tiled.labels, untiled.labels, tiling);
    std::printf(
        "2x2 tiles, 16 px, %s: energy of the rounded merge %.6g (%+.4f %% vs untiled), %.2f s; "
        "mean |tiled - untiled| in overlaps %.4f, elsewhere %.4f label steps; excess jump across "
        "core borders %.4f label steps over %d pairs\n",
        blend, energy, 100.0 * (energy - untiled_energy) / untiled_energy, tiled.time_seconds,
        seams.mean_abs_diff_overlap, seams.mean_abs_diff_interior, seams.mean_border_jump_excess,
        seams.border_pairs);
    std::fflush(stdout);
  }
  return 0;
}

void BM_TeddySize(benchmark::State& state) {
  const SyntheticScene scene{450, 375, 60};
  static const OwnedMrfProblem problem = scene.Make(cv::Rect(0, 0, 450, 375), 1.0 / 256);
  ExpansionOptions options;
  if (state.range(0) == 0) {  // plain
    options.candidate_labels = CandidateLabels::kAll;
    options.skip_unchanged_labels = false;
    options.retry_changed_blocks_only = false;
    options.prune_pixels = false;
    options.convergence_tolerance = 0.0;
    options.max_cycles = 100;
  }
  ExpansionResult result;
  for (auto _ : state) {
    result = AlphaExpansion(problem.View(), EnergyOptions(), options);
  }
  state.SetLabel(state.range(0) == 0 ? "plain" : "default");
  state.counters["energy"] = result.breakdown.total();
  state.counters["cycles"] = result.cycles;
  state.counters["peak_MiB"] = PeakResidentMemoryBytes() / (1024.0 * 1024.0);
}
BENCHMARK(BM_TeddySize)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1);

// Real Teddy-size data: Middlebury Aloe (427×370), 80 labels, |ΔRGB| costs, sparse GT prior.
// Arg 0: untiled (one thread); arg 1: 1×2 tiles, 16 px overlap, 2 threads. Counter `energy`:
// the energy of the (rounded) result on the whole image.
void BM_AloeReal(benchmark::State& state) {
  static OwnedMrfProblem problem;
  static bool loaded = false;
  if (!loaded) {
    const std::string data = SharedData() + "/middlebury/Aloe/";
    if (!LoadMiddlebury(data + "view1.png", data + "view5.png", 80, &problem)) {
      state.SkipWithError("../shared/data/middlebury/Aloe not found");
      return;
    }
    problem.prior = SparsePrior(data + "disp1.png", 3.0, problem.image.size());
    loaded = true;
  }
  cv::Mat labels;
  for (auto _ : state) {
    if (state.range(0) == 0) {
      labels = AlphaExpansion(problem.View(), EnergyOptions(), ExpansionOptions()).labels;
    } else {
      ExpansionOptions options;
      options.num_threads = 2;
      TilingOptions tiling;
      tiling.rows = 1;
      tiling.cols = 2;
      const TiledResult r = OptimizeTiled(
          problem.image.size(),
          [&](const cv::Rect& region) {
            OwnedMrfProblem tile{CostVolume(region, 80, problem.data.max_cost()),
                                 problem.image(region).clone(), problem.prior(region).clone()};
            for (int y = 0; y < region.height; ++y)
              for (int x = 0; x < region.width; ++x)
                std::memcpy(tile.data.MutablePixelData(y, x),
                            problem.data.PixelData(region.y + y, region.x + x), 80 * 2);
            return tile;
          },
          EnergyOptions(), options, tiling);
      r.labels.convertTo(labels, CV_32S);  // rounds the fractional overlap values
    }
  }
  state.SetLabel(state.range(0) == 0 ? "untiled" : "1x2 tiles, 2 threads");
  state.counters["energy"] = ComputeEnergy(problem.View(), labels, EnergyOptions());
}
BENCHMARK(BM_AloeReal)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// Every Middlebury scene of the gap report, untiled, default options (one thread). Arg: index
// into kMiddleburyScenes (0 tsukuba, 1 venus, 2 Aloe, 3 Rocks1).
void BM_MiddleburyReal(benchmark::State& state) {
  const MiddleburyScene& scene = kMiddleburyScenes[state.range(0)];
  const std::string data = SharedData() + "/middlebury/";
  OwnedMrfProblem problem;
  if (!LoadMiddlebury(data + scene.left, data + scene.right, scene.labels, &problem)) {
    state.SkipWithError("../shared/data/middlebury scene not found");
    return;
  }
  problem.prior = SparsePrior(data + scene.gt, scene.gt_scale, problem.image.size());
  ExpansionResult result;
  for (auto _ : state) {
    result = AlphaExpansion(problem.View(), EnergyOptions(), ExpansionOptions());
  }
  state.SetLabel(scene.name);
  state.counters["energy"] = result.breakdown.total();
  state.counters["cycles"] = result.cycles;
  state.counters["nodes_M"] = result.graph_nodes / 1e6;
  state.counters["peak_MiB"] = PeakResidentMemoryBytes() / (1024.0 * 1024.0);
}
BENCHMARK(BM_MiddleburyReal)->DenseRange(0, 3)->Unit(benchmark::kSecond)->Iterations(1);

// Sub-label refinement on the synthetic Teddy-size scene (true labels are fractional): time and
// mean |label − truth| of the discrete labels, the parabola fit and the Ceres problem.
void BM_Refinement(benchmark::State& state) {
  const SyntheticScene scene{450, 375, 60};
  static const OwnedMrfProblem problem = scene.Make(cv::Rect(0, 0, 450, 375), 1.0 / 256);
  static const cv::Mat discrete =
      AlphaExpansion(problem.View(), EnergyOptions(), ExpansionOptions()).labels;
  cv::Mat truth(375, 450, CV_32F);
  for (int y = 0; y < 375; ++y)
    for (int x = 0; x < 450; ++x) truth.at<float>(y, x) = static_cast<float>(scene.Truth(x, y));
  RefinementOptions options;
  options.method = static_cast<RefinementMethod>(state.range(0));
  options.max_iterations = static_cast<int>(state.range(1));  // Ceres only
  cv::Mat refined;
  RefinementSummary summary;
  for (auto _ : state) {
    refined = RefineSubLabel(problem.View(), discrete, EnergyOptions(), options, &summary);
  }
  state.SetLabel(RefinementMethodName(options.method));
  state.counters["solver_converged"] = summary.solver_converged;
  state.counters["mean_abs_err"] = cv::mean(cv::abs(refined - truth))[0];
  state.counters["iterations"] = summary.iterations;
  state.counters["build_s"] = summary.build_seconds;
  state.counters["solve_s"] = summary.solve_seconds;
  state.counters["final_cost"] = summary.final_cost;
  state.counters["cg_iterations"] = static_cast<double>(summary.linear_iterations);
  state.counters["peak_MiB"] = PeakResidentMemoryBytes() / (1024.0 * 1024.0);
}
BENCHMARK(BM_Refinement)
    ->Args({static_cast<int>(RefinementMethod::kNone), 50})
    ->Args({static_cast<int>(RefinementMethod::kParabola), 50})
    ->Args({static_cast<int>(RefinementMethod::kCeres), 50})
    ->Args({static_cast<int>(RefinementMethod::kCeres), 10})
    ->Args({static_cast<int>(RefinementMethod::kCeres), 3})
    ->Args({static_cast<int>(RefinementMethod::kIrls), 50})  // the default
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

void BM_Fountain(benchmark::State& state) {
  const SyntheticScene scene{1536, 1024, 360};
  ExpansionOptions options;
  options.num_threads = static_cast<int>(state.range(0));
  TilingOptions tiling;  // 2 x 2, 16 px, mean
  RefinementOptions refinement;
  refinement.method = static_cast<RefinementMethod>(state.range(1));
  TiledResult result;
  for (auto _ : state) {
    result = OptimizeTiled(
        cv::Size(1536, 1024), [&](const cv::Rect& region) { return scene.Make(region, 1.0 / 256); },
        EnergyOptions(), options, tiling, {}, {}, refinement);
  }
  state.SetLabel(std::string("refinement ") + RefinementMethodName(refinement.method));
  double setup = 0.0;
  for (const TileReport& t : result.tiles) setup += t.setup_seconds;
  state.counters["energy_sum"] = result.energy_sum;
  state.counters["cost_setup_s"] = setup;
  state.counters["peak_MiB"] = result.peak_memory_bytes / (1024.0 * 1024.0);
  std::fprintf(stderr, "%s\n", result.Summary().c_str());
}
BENCHMARK(BM_Fountain)
    ->Args({1, static_cast<int>(RefinementMethod::kNone)})
    ->Args({2, static_cast<int>(RefinementMethod::kNone)})
    ->Args({2, static_cast<int>(RefinementMethod::kCeres)})
    ->Args({2, static_cast<int>(RefinementMethod::kIrls)})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace
}  // namespace gcpstereo::optimize

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--gap_report") == 0) return gcpstereo::optimize::RunGapReport();
    if (std::strcmp(argv[i], "--candidate_sweep") == 0) {
      gcpstereo::optimize::g_candidate_sweep = true;
      return gcpstereo::optimize::RunGapReportMiddlebury();
    }
    if (std::strcmp(argv[i], "--gap_report_middlebury") == 0) {
      return gcpstereo::optimize::RunGapReportMiddlebury();
    }
    if (std::strcmp(argv[i], "--eta_report") == 0) return gcpstereo::optimize::RunEtaReport();
    if (std::strcmp(argv[i], "--seam_report") == 0) return gcpstereo::optimize::RunSeamReport();
    if (std::strcmp(argv[i], "--eta_report_middlebury") == 0) {
      return gcpstereo::optimize::RunEtaReportMiddlebury();
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
