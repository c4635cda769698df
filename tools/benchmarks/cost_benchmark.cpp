// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Throughput of the matching costs (Google Benchmark).
//   BM_PlaneSweepThroughput/L: the paper's Fountain setting (1536×1024 reference, 6 neighbours)
//     with L labels; counter samples_per_second = pixels · L · neighbours / s.
//   BM_PlaneSweepZnccThroughput/L: the same with cost.sweep_measure zncc (7×7 window).
//   BM_PlaneSweepFountain: the full 360-label sweep (one iteration; 1.1 GB cost volume).
//   BM_BirchfieldTomasi: a Middlebury-sized pair, 450×375 × 60 disparities.
//   BM_BirchfieldTomasiCensusGuided/W: the same with the 7×7 census term and a W×W guided filter
//     (configs/middlebury_stereo.yaml: W = 3).
// The images are random value-noise textures and the cameras are placed like fountain-P11's
// (converging, ≈0.6 m apart, scene at 4–14 m); the content does not change the work done.
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/labels.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/cost/birchfield_tomasi.h"
#include "gcpstereo/cost/plane_sweep.h"
#include "random_texture.h"

namespace gcpstereo::cost {
namespace {

constexpr int kWidth = 1536;
constexpr int kHeight = 1024;
constexpr int kNeighbors = 6;

using benchmarks::RandomTexture;

Camera FountainLikeCamera(int index) {
  // Cameras on an arc of radius 8 m around the point (0, 0, 8), 0.6 m apart; index 0 = reference.
  const double angle = index * 0.6 / 8.0;
  Camera camera;
  camera.K << 1380.0, 0.0, 767.5, 0.0, 1380.0, 511.5, 0.0, 0.0, 1.0;
  camera.center_world = Eigen::Vector3d(8.0 * std::sin(angle), 0.0, 8.0 - 8.0 * std::cos(angle));
  camera.world_from_camera_rotation = Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitY()).matrix();
  camera.width = kWidth;
  camera.height = kHeight;
  return camera;
}

struct Fountain {
  View reference;
  std::vector<View> neighbors;
  Fountain() {
    reference = View{"ref", RandomTexture(kWidth, kHeight, 1), FountainLikeCamera(0)};
    const int offsets[kNeighbors] = {-3, -2, -1, 1, 2, 3};
    for (int i = 0; i < kNeighbors; ++i) {
      neighbors.push_back(View{"nb" + std::to_string(offsets[i]),
                               RandomTexture(kWidth, kHeight, 10 + i),
                               FountainLikeCamera(offsets[i])});
    }
  }
};

const Fountain& GetFountain() {
  static const Fountain fountain;
  return fountain;
}

void SweepThroughput(benchmark::State& state, const std::string& measure) {
  const Fountain& f = GetFountain();
  const int num_labels = static_cast<int>(state.range(0));
  const LabelSpace labels(LabelSpaceKind::kDepth, num_labels, 4.0, 14.0);
  PlaneSweepOptions options;
  options.measure = measure;
  PlaneSweepSummary summary;
  for (auto _ : state) {
    CostVolume volume = ComputePlaneSweepCost(
        f.reference, f.neighbors, labels, cv::Rect(0, 0, kWidth, kHeight), options, {}, &summary);
    benchmark::DoNotOptimize(volume.PixelData(0, 0));
  }
  state.counters["samples_per_second"] = benchmark::Counter(
      static_cast<double>(summary.samples) * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["vote_fraction"] = static_cast<double>(summary.votes) / summary.samples;
}

void BM_PlaneSweepThroughput(benchmark::State& state) { SweepThroughput(state, "rgb"); }
BENCHMARK(BM_PlaneSweepThroughput)->Arg(8)->Arg(32)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PlaneSweepZnccThroughput(benchmark::State& state) { SweepThroughput(state, "zncc"); }
BENCHMARK(BM_PlaneSweepZnccThroughput)
    ->Arg(8)
    ->Arg(32)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_PlaneSweepFountain(benchmark::State& state) {
  const Fountain& f = GetFountain();
  const LabelSpace labels(LabelSpaceKind::kDepth, 360, 4.0, 14.0);
  PlaneSweepSummary summary;
  for (auto _ : state) {
    CostVolume volume = ComputePlaneSweepCost(f.reference, f.neighbors, labels,
                                              cv::Rect(0, 0, kWidth, kHeight), {}, {}, &summary);
    benchmark::DoNotOptimize(volume.PixelData(0, 0));
  }
  state.counters["samples_per_second"] = benchmark::Counter(
      static_cast<double>(summary.samples) * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["volume_MB"] = summary.volume_bytes / 1e6;
}
BENCHMARK(BM_PlaneSweepFountain)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

void BM_BirchfieldTomasi(benchmark::State& state) {
  const cv::Mat left = RandomTexture(450, 375, 3);
  const cv::Mat right = RandomTexture(450, 375, 4);
  std::vector<double> disparities;
  for (int d = 0; d < 60; ++d) disparities.push_back(d);
  for (auto _ : state) {
    CostVolume volume =
        ComputeBirchfieldTomasiCost(left, right, disparities, cv::Rect(0, 0, 450, 375));
    benchmark::DoNotOptimize(volume.PixelData(0, 0));
  }
  state.counters["costs_per_second"] =
      benchmark::Counter(450.0 * 375 * 60 * state.iterations(), benchmark::Counter::kIsRate);
}

void BM_BirchfieldTomasiCensusGuided(benchmark::State& state) {
  const cv::Mat left = RandomTexture(450, 375, 3);
  const cv::Mat right = RandomTexture(450, 375, 4);
  std::vector<double> disparities;
  for (int d = 0; d < 60; ++d) disparities.push_back(d);
  BirchfieldTomasiOptions options;
  options.truncation = 60;
  options.census_window_px = 7;
  options.census_weight = 2;
  options.window.window_px = static_cast<int>(state.range(0));
  for (auto _ : state) {
    CostVolume volume =
        ComputeBirchfieldTomasiCost(left, right, disparities, cv::Rect(0, 0, 450, 375), options);
    benchmark::DoNotOptimize(volume.PixelData(0, 0));
  }
  state.counters["costs_per_second"] =
      benchmark::Counter(450.0 * 375 * 60 * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BirchfieldTomasiCensusGuided)->Arg(1)->Arg(3)->Arg(9)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BirchfieldTomasi)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace gcpstereo::cost

BENCHMARK_MAIN();
