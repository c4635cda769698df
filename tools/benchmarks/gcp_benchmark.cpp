// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Time of the stereo GCPs (paper §4.1) on a Middlebury-sized pair (Google Benchmark).
//   BM_StereoEvidence: gcp::ComputeStereoEvidence on a 450×375 pair with disparities 0–59 (the
//     Teddy setting of configs/middlebury_stereo.yaml): the BT, NCC and adaptive-weight WTAs of
//     both views, their uniqueness, texture and edges.
//   BM_StereoEvidenceAwStride/S: the same with gcp.stereo.aw_stride_px = S (1, 3, 4: the time per
//     window offset, and what the other matchers take).
// The left image is a random value-noise texture; the right one is it shifted by 20 px in the
// left half and by 40 px in the right half. The content hardly changes the work done.
#include <algorithm>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include "gcpstereo/gcp/stereo_gcps.h"
#include "random_texture.h"

namespace gcpstereo::gcp {
namespace {

constexpr int kWidth = 450;
constexpr int kHeight = 375;
constexpr int kMaxDisparity = 59;

struct Pair {
  cv::Mat left, right;
  Pair() {
    const cv::Mat texture = benchmarks::RandomTexture(kWidth + 2 * kMaxDisparity, kHeight, 7, 3);
    left = texture(cv::Rect(kMaxDisparity, 0, kWidth, kHeight)).clone();
    right = cv::Mat(kHeight, kWidth, CV_8UC3);
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const int d = x < kWidth / 2 ? 20 : 40;  // right x ↔ left x + d
        right.at<cv::Vec3b>(y, x) =
            texture.at<cv::Vec3b>(y, kMaxDisparity + std::min(x + d, kWidth - 1));
      }
    }
  }
};

void Evidence(benchmark::State& state, int stride) {
  static const Pair pair;
  StereoGcpOptions options;
  options.aw_stride_px = stride;
  for (auto _ : state) {
    const StereoPairEvidence e =
        ComputeStereoEvidence(pair.left, pair.right, 0, kMaxDisparity, options, {});
    benchmark::DoNotOptimize(e.left.wta_aw.data);
  }
}

void BM_StereoEvidence(benchmark::State& state) {
  Evidence(state, StereoGcpOptions{}.aw_stride_px);
}
void BM_StereoEvidenceAwStride(benchmark::State& state) {
  Evidence(state, static_cast<int>(state.range(0)));
}

BENCHMARK(BM_StereoEvidence)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StereoEvidenceAwStride)->Arg(1)->Arg(3)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace gcpstereo::gcp

BENCHMARK_MAIN();
