// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The benchmarks' test images: random value noise, a random colour every `cell` pixels, smoothly
// interpolated (bicubic), so that every window has texture and matches are unambiguous.
#pragma once

#include <cstdint>
#include <random>

#include <opencv2/imgproc.hpp>

namespace gcpstereo::benchmarks {

inline cv::Mat RandomTexture(int width, int height, std::uint32_t seed, int cell = 4) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> v(0, 255);
  cv::Mat small(height / cell + 1, width / cell + 1, CV_8UC3);
  for (int r = 0; r < small.rows; ++r)
    for (int c = 0; c < small.cols; ++c)
      small.at<cv::Vec3b>(r, c) = cv::Vec3b(v(rng), v(rng), v(rng));
  cv::Mat image;
  cv::resize(small, image, cv::Size(width, height), 0, 0, cv::INTER_CUBIC);
  return image;
}

}  // namespace gcpstereo::benchmarks
