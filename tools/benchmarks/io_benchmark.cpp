// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Throughput of the io module's readers and writers at the paper's sizes (1536×1024 maps, a
// laser scan of a million points) and the time to load fountain-P11 at half size when the real
// data is present (GCPSTEREO_DATA or ../shared/data).
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/types.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"

namespace {

namespace fs = std::filesystem;
using namespace gcpstereo;

std::string TempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("gcpstereo_io_benchmark_" + name)).string();
}

cv::Mat DepthMap() {
  cv::Mat depth(1024, 1536, CV_32F);
  cv::randu(depth, 5.0f, 15.0f);
  return depth;
}

PointCloud Cloud(int n) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-10.0f, 10.0f);
  PointCloud cloud;
  for (int i = 0; i < n; ++i) {
    cloud.points.emplace_back(u(rng), u(rng), u(rng));
    cloud.sigma.push_back(0.01f);
  }
  return cloud;
}

void BM_WritePfm(benchmark::State& state) {
  const cv::Mat depth = DepthMap();
  const std::string path = TempPath("w.pfm");
  for (auto _ : state) io::WritePfm(path, depth);
  state.SetBytesProcessed(state.iterations() * depth.total() * 4);
  fs::remove(path);
}
BENCHMARK(BM_WritePfm)->Unit(benchmark::kMillisecond);

void BM_ReadPfm(benchmark::State& state) {
  const std::string path = TempPath("r.pfm");
  io::WritePfm(path, DepthMap());
  for (auto _ : state) benchmark::DoNotOptimize(io::ReadPfm(path));
  state.SetBytesProcessed(state.iterations() * 1536 * 1024 * 4);
  fs::remove(path);
}
BENCHMARK(BM_ReadPfm)->Unit(benchmark::kMillisecond);

void BM_WritePointCloudPly(benchmark::State& state) {
  const PointCloud cloud = Cloud(static_cast<int>(state.range(0)));
  const std::string path = TempPath("w.ply");
  for (auto _ : state) io::WritePointCloudPly(path, cloud);
  state.SetItemsProcessed(state.iterations() * cloud.size());
  fs::remove(path);
}
BENCHMARK(BM_WritePointCloudPly)->Arg(1 << 20)->Unit(benchmark::kMillisecond);

void BM_ReadPointCloudPly(benchmark::State& state) {
  const std::string path = TempPath("r.ply");
  io::WritePointCloudPly(path, Cloud(static_cast<int>(state.range(0))));
  for (auto _ : state) benchmark::DoNotOptimize(io::ReadPointCloud(path));
  state.SetItemsProcessed(state.iterations() * state.range(0));
  fs::remove(path);
}
BENCHMARK(BM_ReadPointCloudPly)->Arg(1 << 20)->Unit(benchmark::kMillisecond);

void BM_LoadFountainHalf(benchmark::State& state) {
  const char* env = std::getenv("GCPSTEREO_DATA");
  const fs::path root = env && *env ? fs::path(env) : fs::path("../shared/data");
  io::DatasetRequest request;
  request.format = "strecha";
  request.path = (root / "strecha/fountain-P11").string();
  request.reference = "0005";
  request.neighbors = {"0002", "0003", "0004", "0006", "0007", "0008"};  // the paper's 6
  request.scale = 0.5;
  if (!fs::is_directory(request.path)) {
    state.SkipWithError("fountain-P11 not found (set GCPSTEREO_DATA)");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(io::LoadDataset(request));
}
BENCHMARK(BM_LoadFountainHalf)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
