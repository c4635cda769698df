// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Mesh export at the paper's Fountain-P11 working size, 1536×1024 (f = 1381 px, like the synthetic
// "fountain" preset), on a deterministic synthetic depth map: a wavy wall 9 m away with a slanted
// ground, two occluding columns and an unknown (sky) band, so the discontinuity tests have work.
//   BM_MeshFromDepthMap/<stride>: triangulation (≈3 M faces at stride 1).
//   BM_RenderMesh/<supersampling>/<view>/<crease angle>: the 3 M-face mesh rendered at 1536×1024
//   in "color_shaded" mode, view 0 = the reference camera, 1 = OrbitCamera(yaw 30°, pitch 15°)
//   about the median vertex; crease angle 0 = flat shading (no vertex normals to compute).
// Counters: faces, covered pixels.
#include <cmath>
#include <limits>
#include <random>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include "gcpstereo/mesh/meshing.h"
#include "gcpstereo/mesh/render.h"

namespace {

using gcpstereo::Camera;
using gcpstereo::TriangleMesh;
namespace mesh = gcpstereo::mesh;

constexpr int kWidth = 1536;
constexpr int kHeight = 1024;

Camera ReferenceCamera() {
  Camera camera;
  camera.K << 1381.0, 0.0, 759.6, 0.0, 1383.5, 503.2, 0.0, 0.0, 1.0;
  camera.width = kWidth;
  camera.height = kHeight;
  return camera;
}

cv::Mat SyntheticDepth() {
  cv::Mat depth(kHeight, kWidth, CV_32F);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      float z = 9.0f + 0.15f * std::sin(0.02f * c) * std::cos(0.015f * r);
      if (r > 700) z = std::min(z, 9.0f - 0.012f * (r - 700));  // ground rising toward the camera
      if (std::abs(c - 400) < 40 || std::abs(c - 1100) < 55) z = 7.0f;     // columns
      if (r < 60 && c > 1200) z = std::numeric_limits<float>::infinity();  // sky
      depth.at<float>(r, c) = z;
    }
  }
  return depth;
}

cv::Mat SyntheticImage() {
  cv::Mat image(kHeight, kWidth, CV_8UC3);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> noise(0, 40);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      const int base = 100 + static_cast<int>(60.0 * std::sin(0.01 * c + 0.02 * r));
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(base + noise(rng), base + 10, base + 30);
    }
  }
  return image;
}

const TriangleMesh& FullMesh() {
  static const TriangleMesh full = mesh::MeshFromDepthMap(
      SyntheticDepth(), SyntheticImage(), ReferenceCamera(), mesh::MeshingOptions());
  return full;
}

void BM_MeshFromDepthMap(benchmark::State& state) {
  const cv::Mat depth = SyntheticDepth();
  const cv::Mat image = SyntheticImage();
  mesh::MeshingOptions options;
  options.stride_px = static_cast<int>(state.range(0));
  mesh::MeshingSummary summary;
  for (auto _ : state) {
    TriangleMesh m = mesh::MeshFromDepthMap(depth, image, ReferenceCamera(), options, &summary);
    benchmark::DoNotOptimize(m.faces.data());
  }
  state.counters["faces"] = static_cast<double>(summary.faces);
  state.counters["dropped_ratio"] = static_cast<double>(summary.dropped_depth_ratio);
  state.counters["dropped_angle"] = static_cast<double>(summary.dropped_view_angle);
}
BENCHMARK(BM_MeshFromDepthMap)->Arg(1)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond);

void BM_RenderMesh(benchmark::State& state) {
  const TriangleMesh& m = FullMesh();
  mesh::MeshRenderOptions options;
  options.supersampling = static_cast<int>(state.range(0));
  options.crease_angle_deg = static_cast<double>(state.range(2));
  const Camera reference = ReferenceCamera();
  const Camera camera = state.range(1) == 0
                            ? reference
                            : mesh::OrbitCamera(reference, 30.0, 15.0, mesh::MedianVertex(m));
  mesh::MeshRenderResult result;
  for (auto _ : state) {
    result = mesh::RenderMesh(m, camera, options);
    benchmark::DoNotOptimize(result.image.data);
  }
  state.counters["faces"] = static_cast<double>(m.faces.size());
  state.counters["covered_px"] = static_cast<double>(result.covered_pixels);
}
BENCHMARK(BM_RenderMesh)
    ->Args({1, 0, 40})
    ->Args({1, 1, 40})
    ->Args({1, 1, 0})
    ->Args({2, 0, 40})
    ->Args({2, 1, 40})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
