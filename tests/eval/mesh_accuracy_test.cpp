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

}  // namespace
}  // namespace gcpstereo::eval
