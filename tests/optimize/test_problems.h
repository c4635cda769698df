// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Synthetic MRF problems for the optimize tests (seeded, generated in memory).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>

#include <opencv2/core.hpp>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/optimize/energy.h"

namespace gcpstereo::optimize::testing {

// Uniformly random costs in [0, max_cost], random colours, an optional sparse random prior.
inline OwnedMrfProblem RandomProblem(int width, int height, int num_labels, std::uint32_t seed,
                                     double prior_fraction = 0.0, float max_cost = 60.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> cost(0.0f, max_cost);
  std::uniform_int_distribution<int> color(0, 255);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  OwnedMrfProblem problem{CostVolume(cv::Rect(0, 0, width, height), num_labels, max_cost),
                          cv::Mat(height, width, CV_8UC3), cv::Mat()};
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      for (int l = 0; l < num_labels; ++l) problem.data.SetCost(row, col, l, cost(rng));
      // Few distinct colours so that some w_pq are large and some are ε.
      const int c = color(rng) < 128 ? 100 : 104;
      problem.image.at<cv::Vec3b>(row, col) = cv::Vec3b(c, c, c);
    }
  }
  if (prior_fraction > 0.0) {
    problem.prior = cv::Mat(height, width, CV_32F, cv::Scalar(std::nanf("")));
    std::uniform_real_distribution<float> label(0.0f, num_labels - 1.0f);
    for (int row = 0; row < height; ++row) {
      for (int col = 0; col < width; ++col) {
        if (unit(rng) < prior_fraction) problem.prior.at<float>(row, col) = label(rng);
      }
    }
  }
  return problem;
}

// A piecewise-smooth scene: the true label field `truth(x, y)` (continuous), an image whose
// colour changes at label discontinuities plus texture, and truncated-linear costs with noise
// (σ = noise), kNoData on a few entries. Costs are computed for the whole image; Crop() gives the
// tile problems.
struct SceneProblem {
  cv::Mat truth;  // CV_32F continuous labels
  OwnedMrfProblem problem;
};

inline float SceneTruth(int x, int y, int width, int height, int num_labels) {
  // Two planes and a disc in front.
  const float cx = 0.6f * width, cy = 0.45f * height, r = 0.22f * std::min(width, height);
  if ((x - cx) * (x - cx) + (y - cy) * (y - cy) < r * r) return 0.8f * (num_labels - 1);
  if (x < 0.4f * width) return 0.2f * (num_labels - 1) + 0.01f * y;
  return 0.35f * (num_labels - 1) + 0.03f * (x - 0.4f * width) * (num_labels / 60.0f);
}

inline SceneProblem MakeScene(int width, int height, int num_labels, std::uint32_t seed,
                              float noise = 6.0f, double prior_fraction = 0.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const float max_cost = 100.0f;
  SceneProblem scene{cv::Mat(height, width, CV_32F),
                     {CostVolume(cv::Rect(0, 0, width, height), num_labels, max_cost),
                      cv::Mat(height, width, CV_8UC3), cv::Mat()}};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float t = std::min<float>(SceneTruth(x, y, width, height, num_labels), num_labels - 1);
      scene.truth.at<float>(y, x) = t;
      const int base = static_cast<int>(40 + 3 * std::floor(t / 4.0f)) % 200;
      const int tex = static_cast<int>(8 * gauss(rng));
      const int v = std::clamp(base + tex, 0, 255);
      scene.problem.image.at<cv::Vec3b>(y, x) = cv::Vec3b(v, std::clamp(v + 10, 0, 255), v / 2);
      // A weakly textured area (costs almost flat) where smoothness must decide.
      const bool flat = x > 0.1 * width && x < 0.3 * width && y > 0.6 * height;
      for (int l = 0; l < num_labels; ++l) {
        float c =
            (flat ? 0.5f : 8.0f) * std::min(std::abs(l - t), 6.0f) + noise * std::abs(gauss(rng));
        if (unit(rng) < 0.002) {
          scene.problem.data.SetNoData(y, x, l);
        } else {
          scene.problem.data.SetCost(y, x, l, std::min(c, max_cost));
        }
      }
    }
  }
  if (prior_fraction > 0.0) {
    scene.problem.prior = cv::Mat(height, width, CV_32F, cv::Scalar(std::nanf("")));
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        if (unit(rng) < prior_fraction) {
          scene.problem.prior.at<float>(y, x) = scene.truth.at<float>(y, x) + 0.5f * gauss(rng);
        }
      }
    }
  }
  return scene;
}

// The sub-problem of `region` (copies costs, image and prior).
inline OwnedMrfProblem Crop(const OwnedMrfProblem& full, const cv::Rect& region) {
  OwnedMrfProblem out{CostVolume(region, full.data.num_labels(), full.data.max_cost()),
                      full.image(region).clone(),
                      full.prior.empty() ? cv::Mat() : full.prior(region).clone()};
  const int num_labels = full.data.num_labels();
  for (int row = 0; row < region.height; ++row) {
    for (int col = 0; col < region.width; ++col) {
      const std::uint16_t* src = full.data.PixelData(region.y + row, region.x + col);
      std::copy(src, src + num_labels, out.data.MutablePixelData(row, col));
    }
  }
  return out;
}

}  // namespace gcpstereo::optimize::testing
