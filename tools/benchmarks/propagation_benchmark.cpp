// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Adaptive propagation (eq. 5) at the paper's Fountain-P11 working size, 1536×1024, with GCPs at
// s = 16 (one per 16×16 block, ≈0.4 %), for both SuiteSparse backends.
//   BM_PropagateSynthetic: a deterministic textured image (smooth shading, soft-edged blobs,
//   noise). BM_PropagateFountain:  fountain-P11 frame 0005 at half size when ../shared/data is
//   present
//                          (set GCPSTEREO_DATA to the data folder); skipped otherwise.
// Counters: unknowns, unreached pixels, setup and solve seconds of the last iteration.
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/propagation/propagation.h"

namespace {

constexpr int kWidth = 1536;
constexpr int kHeight = 1024;
constexpr int kBlock = 16;

cv::Mat SyntheticImage() {
  cv::Mat image(kHeight, kWidth, CV_8UC3);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 1.5f);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      const float shade = 0.5f + 0.5f * std::sin(0.004f * c) * std::cos(0.006f * r);
      const bool blob = std::hypot(((c % 256) - 128.0f), ((r % 256) - 128.0f)) < 60.0f;
      const float base = blob ? 180.0f : 60.0f + 80.0f * shade;
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(cv::saturate_cast<uchar>(base + noise(rng)),
                                            cv::saturate_cast<uchar>(0.8f * base + noise(rng)),
                                            cv::saturate_cast<uchar>(0.6f * base + noise(rng)));
    }
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.8);
  return image;
}

cv::Mat GridGcps() {
  cv::Mat sparse(kHeight, kWidth, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (int r = kBlock / 2; r < kHeight; r += kBlock) {
    for (int c = kBlock / 2; c < kWidth; c += kBlock) {
      sparse.at<float>(r, c) = 100.0f + 50.0f * std::sin(0.01f * c) + 0.05f * r;
    }
  }
  return sparse;
}

void RunPropagation(benchmark::State& state, const cv::Mat& image, const std::string& solver) {
  const cv::Mat sparse = GridGcps();
  gcpstereo::propagation::PropagationOptions options;
  options.solver = solver;
  gcpstereo::propagation::PropagationResult result;
  for (auto _ : state) {
    result = gcpstereo::propagation::Propagate(image, sparse, options);
    benchmark::DoNotOptimize(result.values.data);
  }
  state.counters["unknowns"] = result.num_unknowns;
  state.counters["unreached_px"] = result.num_unreached_pixels;
  state.counters["setup_s"] = result.setup_seconds;
  state.counters["solve_s"] = result.solve_seconds;
}

void BM_PropagateSynthetic(benchmark::State& state, const std::string& solver) {
  static const cv::Mat image = SyntheticImage();
  RunPropagation(state, image, solver);
}

void BM_PropagateFountain(benchmark::State& state, const std::string& solver) {
  const char* data = std::getenv("GCPSTEREO_DATA");
  const std::string root = data ? data : "../shared/data";
  static const cv::Mat image = [&] {
    cv::Mat full = cv::imread(root + "/strecha/fountain-P11/images/0005.jpg", cv::IMREAD_COLOR);
    cv::Mat half;
    if (!full.empty()) cv::resize(full, half, cv::Size(kWidth, kHeight), 0, 0, cv::INTER_AREA);
    return half;
  }();
  if (image.empty()) {
    state.SkipWithError("fountain-P11 0005.jpg not found (set GCPSTEREO_DATA)");
    return;
  }
  RunPropagation(state, image, solver);
}

BENCHMARK_CAPTURE(BM_PropagateSynthetic, umfpack, std::string("umfpack"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_PropagateSynthetic, cholmod, std::string("cholmod"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_PropagateFountain, umfpack, std::string("umfpack"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_PropagateFountain, cholmod, std::string("cholmod"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
