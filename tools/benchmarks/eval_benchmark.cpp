// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Benchmarks of the eval module on synthetic inputs (seeded, no files).
#include <cmath>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include "gcpstereo/eval/depth_sigma.h"
#include "gcpstereo/eval/mesh_accuracy.h"
#include "gcpstereo/eval/middlebury.h"
#include "gcpstereo/eval/render.h"

namespace gcpstereo::eval {
namespace {

// A wavy height field z = 5 + 0.2 sin(3x) cos(2y) over [−2, 2]² with n × n squares.
TriangleMesh WavySurface(int n, double offset) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = -2.0 + 4.0 * i / n, y = -2.0 + 4.0 * j / n;
      mesh.vertices.emplace_back(x, y, 5.0 + offset + 0.2 * std::sin(3 * x) * std::cos(2 * y));
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      mesh.faces.emplace_back(a, a + 1, a + n + 2);
      mesh.faces.emplace_back(a, a + n + 2, a + n + 1);
    }
  }
  return mesh;
}

void BM_EvaluateMesh(benchmark::State& state) {
  const TriangleMesh gt = WavySurface(128, 0.0);
  const TriangleMesh estimate = WavySurface(96, 0.01);
  MeshAccuracyOptions options;
  options.sample_spacing = 4.0 / state.range(0);  // range(0)² samples per unit² of the square
  for (auto _ : state) {
    const MeshAccuracy m = EvaluateMesh(estimate, gt, options);
    benchmark::DoNotOptimize(m.accuracy_median);
    state.counters["samples"] = static_cast<double>(m.gt_samples + m.estimate_samples);
  }
}
BENCHMARK(BM_EvaluateMesh)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_RenderMeshDepth(benchmark::State& state) {
  const TriangleMesh gt = WavySurface(256, 0.0);
  const int width = static_cast<int>(state.range(0)), height = width * 2 / 3;
  const Camera camera =
      RectifiedSequenceCamera(width, width / 2.0, height / 2.0, 0.1, 0, width, height);
  for (auto _ : state) {
    const RenderedDepth r = RenderMeshDepth(gt, camera);
    benchmark::DoNotOptimize(r.summary.pixels_covered);
  }
}
BENCHMARK(BM_RenderMeshDepth)->Arg(640)->Arg(1536)->Unit(benchmark::kMillisecond);

void BM_EvaluateDepthSigmaAndDisparity(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0)), height = width * 2 / 3;
  cv::setRNGSeed(1);
  cv::Mat gt(height, width, CV_32F), estimate(height, width, CV_32F);
  cv::randu(gt, 1.0, 20.0);
  cv::randn(estimate, 0.0, 0.5);
  estimate += gt;
  const cv::Mat sigma(height, width, CV_32F, cv::Scalar(0.1f));
  const MiddleburyMasks masks = DeriveMasks(gt, cv::Mat());
  for (auto _ : state) {
    const SigmaHistogram h = EvaluateDepthSigma(estimate, gt, sigma);
    const MiddleburyResult r = EvaluateDisparity(estimate, gt, masks);
    benchmark::DoNotOptimize(h.counted + r.all.counted);
  }
}
BENCHMARK(BM_EvaluateDepthSigmaAndDisparity)->Arg(640)->Arg(1536)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gcpstereo::eval

BENCHMARK_MAIN();
