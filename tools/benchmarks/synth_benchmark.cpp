// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Generation time of the synthetic presets (gcpstereo synth). "fountain" takes tens of seconds:
// run it explicitly with --benchmark_filter=Fountain.
#include <benchmark/benchmark.h>

#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/scene.h"

namespace {

void GeneratePreset(benchmark::State& state, const char* preset) {
  gcpstereo::synth::SynthOptions options;
  options.preset = preset;
  for (auto _ : state) {
    auto scene = gcpstereo::synth::GenerateScene(options);
    benchmark::DoNotOptimize(scene.views.data());
  }
}
void BM_GenerateTiny(benchmark::State& state) { GeneratePreset(state, "tiny"); }
void BM_GenerateSmall(benchmark::State& state) { GeneratePreset(state, "small"); }
void BM_GenerateFountain(benchmark::State& state) { GeneratePreset(state, "fountain"); }
BENCHMARK(BM_GenerateTiny)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GenerateSmall)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_GenerateFountain)->Unit(benchmark::kMillisecond)->Iterations(1);

// One primary ray with shading inputs (intersection + albedo) against the courtyard scene.
void BM_IntersectAndShade(benchmark::State& state) {
  const auto geometry = gcpstereo::synth::MakePresetGeometry("small");
  const auto scene =
      gcpstereo::synth::AnalyticScene::MakeCourtyard(geometry.texture_min_wavelength_m, 1);
  const auto& camera = geometry.cameras[geometry.reference_index];
  int col = 0, row = 0;
  for (auto _ : state) {
    const Eigen::Vector3d x = camera.BackProject(Eigen::Vector2d(col, row), 1.0);
    const Eigen::Vector3d d = (x - camera.center_world).normalized();
    gcpstereo::synth::SurfaceHit hit;
    if (scene.Intersect(camera.center_world, d, 1e4, &hit)) {
      benchmark::DoNotOptimize(scene.Albedo(hit.primitive, camera.center_world + hit.t * d));
    }
    col = (col + 37) % camera.width;
    row = (row + 11) % camera.height;
  }
}
BENCHMARK(BM_IntersectAndShade);

}  // namespace

BENCHMARK_MAIN();
