// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/mesh_accuracy.h"

#include <cmath>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::eval {
namespace {

// An n×n grid of squares over [x0, x1] × [0, 1] in the plane z = offset.
TriangleMesh Grid(int n, float x0, float x1, float offset) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.vertices.push_back({x0 + (x1 - x0) * i / n, static_cast<float>(j) / n, offset});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      mesh.faces.push_back({a, a + 1, a + n + 2});
      mesh.faces.push_back({a, a + n + 2, a + n + 1});
    }
  }
  return mesh;
}

TEST(MeshAccuracy, IdenticalMeshesAreFullyAccurateAndComplete) {
  const TriangleMesh gt = Grid(8, 0.0f, 1.0f, 2.0f);
  const MeshAccuracy m = EvaluateMesh(gt, gt);
  ASSERT_EQ(m.thresholds.size(), 4u);
  for (size_t i = 0; i < m.thresholds.size(); ++i) {
    EXPECT_DOUBLE_EQ(m.accuracy_percent[i], 100.0);
    EXPECT_DOUBLE_EQ(m.completeness_percent[i], 100.0);
    EXPECT_DOUBLE_EQ(m.f_score_percent[i], 100.0);
  }
  EXPECT_LT(m.accuracy_median, 1e-6);
  EXPECT_NEAR(m.gt_area, 1.0, 1e-6);
  // Spacing a quarter of the smallest threshold (0.01): 160 000 samples on the unit square.
  // (± 1: ceil of an area ratio computed in floating point)
  EXPECT_NEAR(m.gt_samples, 160000, 1);
  EXPECT_NEAR(m.estimate_samples, 160000, 1);
  EXPECT_EQ(m.degenerate_faces, 0);
}

TEST(MeshAccuracy, OffsetByTwiceTheThreshold) {
  const double t = 0.02;
  MeshAccuracyOptions options;
  options.thresholds = {t, 3 * t};
  const TriangleMesh gt = Grid(4, 0.0f, 1.0f, 2.0f);
  const TriangleMesh estimate = Grid(4, 0.0f, 1.0f, static_cast<float>(2.0 + 2 * t));
  const MeshAccuracy m = EvaluateMesh(estimate, gt, options);
  EXPECT_DOUBLE_EQ(m.accuracy_percent[0], 0.0);
  EXPECT_DOUBLE_EQ(m.completeness_percent[0], 0.0);
  EXPECT_DOUBLE_EQ(m.f_score_percent[0], 0.0);
  EXPECT_DOUBLE_EQ(m.accuracy_percent[1], 100.0);
  EXPECT_DOUBLE_EQ(m.completeness_percent[1], 100.0);
  EXPECT_NEAR(m.accuracy_median, 2 * t, 1e-6);
  EXPECT_NEAR(m.completeness_mean, 2 * t, 1e-6);
}

TEST(MeshAccuracy, HalfAnEstimateIsAccurateButHalfComplete) {
  MeshAccuracyOptions options;
  options.thresholds = {0.01};
  options.seed = 7;
  const TriangleMesh gt = Grid(8, 0.0f, 1.0f, 0.0f);
  const TriangleMesh half = Grid(4, 0.0f, 0.5f, 0.0f);
  const MeshAccuracy m = EvaluateMesh(half, gt, options);
  EXPECT_DOUBLE_EQ(m.accuracy_percent[0], 100.0);
  // GT samples within 0.01 of the half: x <= 0.51, i.e. 51 % of the area (sampling noise: the
  // binomial standard deviation with 160 000 samples is 0.125 %).
  EXPECT_NEAR(m.completeness_percent[0], 51.0, 0.5);
  EXPECT_NEAR(m.f_score_percent[0], 2 * 100.0 * 51.0 / 151.0, 0.5);
  // Exact distances for the samples far from the half: the mean over x ∈ [0.5, 1] of (x − 0.5) is
  // 0.25, weighted by one half → 0.125 (sampling noise: standard deviation ≈ 0.0004).
  EXPECT_NEAR(m.completeness_mean, 0.125, 0.002);

  // Deterministic for a seed, different for another one.
  const MeshAccuracy again = EvaluateMesh(half, gt, options);
  EXPECT_EQ(again.completeness_percent, m.completeness_percent);
  EXPECT_EQ(again.completeness_mean, m.completeness_mean);
  options.seed = 8;
  const MeshAccuracy other = EvaluateMesh(half, gt, options);
  EXPECT_NE(other.completeness_mean, m.completeness_mean);
}

TEST(MeshAccuracy, DistancesAreToTheSurfaceNotToTheSamples) {
  // Coarse sampling (spacing 0.2 on a unit square): point-to-sample distances would be about
  // 0.1, but the distance to the nearest sample's triangle of an identical mesh is ~0.
  MeshAccuracyOptions options;
  options.thresholds = {0.001};
  options.sample_spacing = 0.2;
  const TriangleMesh gt = Grid(1, 0.0f, 1.0f, 1.0f);
  const MeshAccuracy m = EvaluateMesh(gt, gt, options);
  EXPECT_EQ(m.gt_samples, 25);
  EXPECT_DOUBLE_EQ(m.accuracy_percent[0], 100.0);
  EXPECT_DOUBLE_EQ(m.completeness_percent[0], 100.0);
}

TEST(MeshAccuracy, EmptyAndDegenerateInputs) {
  const TriangleMesh gt = Grid(2, 0.0f, 1.0f, 0.0f);
  TriangleMesh flat;  // all faces zero-area
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.faces = {{0, 1, 2}, {0, 1, 5}};
  try {
    EvaluateMesh(gt, flat);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "EvaluateMesh: the ground-truth mesh has no face of positive area (2 faces, 3 "
                 "vertices)");
  }
  const MeshAccuracy m = EvaluateMesh(flat, gt);
  EXPECT_EQ(m.estimate_samples, 0);
  EXPECT_EQ(m.degenerate_faces, 2);
  EXPECT_DOUBLE_EQ(m.accuracy_percent[0], 0.0);
  EXPECT_DOUBLE_EQ(m.completeness_percent[0], 0.0);
  EXPECT_TRUE(m.ToJson()["completeness_median"].is_null());

  MeshAccuracyOptions options;
  options.thresholds = {0.01, -1.0};
  try {
    EvaluateMesh(gt, gt, options);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "eval.mesh.thresholds[1] = -1. Violated constraint: finite and > 0");
  }
}

// Points on a grid of the plane z = offset, `n` per side over [0, 1]².
std::vector<Eigen::Vector3f> GridPoints(int n, float offset) {
  std::vector<Eigen::Vector3f> points;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) points.push_back({(i + 0.5f) / n, (j + 0.5f) / n, offset});
  }
  return points;
}

TEST(SurfaceAccuracy, PointsAgainstAMeshAndAMeshAgainstPoints) {
  MeshAccuracyOptions options;
  options.thresholds = {0.01, 0.05};
  const TriangleMesh gt = Grid(4, 0.0f, 1.0f, 2.0f);
  // Points 3 cm off the plane: all within 5 cm, none within 1 cm, and the dense GT samples are all
  // within 5 cm of some point (spacing 1 cm, offset 3 cm: at most √(0.5² + 0.5² + 3²) cm).
  const std::vector<Eigen::Vector3f> points = GridPoints(100, 2.03f);
  const MeshAccuracy m = EvaluateSurface({nullptr, &points}, {&gt, nullptr}, options);
  EXPECT_EQ(m.estimate_samples, 10000);
  EXPECT_DOUBLE_EQ(m.accuracy_percent[0], 0.0);
  EXPECT_DOUBLE_EQ(m.accuracy_percent[1], 100.0);
  EXPECT_DOUBLE_EQ(m.completeness_percent[1], 100.0);
  EXPECT_NEAR(m.accuracy_median, 0.03, 1e-5);
  // Half the square covered: half complete.
  std::vector<Eigen::Vector3f> half;
  for (const auto& p : GridPoints(100, 2.0f)) {
    if (p.x() < 0.5f) half.push_back(p);
  }
  const MeshAccuracy h = EvaluateSurface({nullptr, &half}, {&gt, nullptr}, options);
  EXPECT_DOUBLE_EQ(h.accuracy_percent[0], 100.0);
  EXPECT_NEAR(h.completeness_percent[1], 54.5, 1.5);  // x <= 0.495 + 0.05
  // The other way round: a mesh against laser points.
  const MeshAccuracy r = EvaluateSurface({&gt, nullptr}, {nullptr, &points}, options);
  EXPECT_DOUBLE_EQ(r.accuracy_percent[1], 100.0);
  EXPECT_DOUBLE_EQ(r.completeness_percent[0], 0.0);
  EXPECT_DOUBLE_EQ(r.completeness_percent[1], 100.0);
  // More points than max_samples: every k-th.
  options.max_samples = 1000;
  EXPECT_EQ(EvaluateSurface({nullptr, &points}, {&gt, nullptr}, options).estimate_samples, 1000);
  const std::vector<Eigen::Vector3f> none;
  EXPECT_THROW(EvaluateSurface({&gt, nullptr}, {nullptr, &none}, options), Error);
  EXPECT_THROW(EvaluateSurface({&gt, &points}, {&gt, nullptr}, options), Error);
}

}  // namespace
}  // namespace gcpstereo::eval
