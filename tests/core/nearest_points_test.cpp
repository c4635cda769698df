// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/nearest_points.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <thread>

#include <gtest/gtest.h>

namespace gcpstereo {
namespace {

// Against a brute-force search: the k nearest, nearest first, indices into the input (with
// points that are not finite in it), from several threads at once.
TEST(NearestPoints, SameAsBruteForce) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> coordinate(-20.0f, 20.0f);
  std::vector<Eigen::Vector3f> points(3000);
  for (auto& p : points) p = Eigen::Vector3f(coordinate(rng), coordinate(rng), coordinate(rng));
  points[17] = Eigen::Vector3f(std::nanf(""), 0.0f, 0.0f);
  points[2000].z() = std::numeric_limits<float>::infinity();
  const NearestPoints nearest(points);
  EXPECT_EQ(nearest.size(), 2998);
  std::vector<Eigen::Vector3f> queries(400);
  for (auto& q : queries) q = Eigen::Vector3f(coordinate(rng), coordinate(rng), coordinate(rng));
  queries[0] = points[5];  // on a point: distance 0
  int mismatches = 0;
  auto check = [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const Eigen::Vector3f& q = queries[i];
      std::vector<int> order(points.size());
      std::iota(order.begin(), order.end(), 0);
      auto distance2 = [&](int j) {
        return points[j].allFinite() ? (points[j] - q).squaredNorm()
                                     : std::numeric_limits<float>::infinity();
      };
      std::partial_sort(order.begin(), order.begin() + 4, order.end(),
                        [&](int a, int b) { return distance2(a) < distance2(b); });
      int indices[4];
      float squared[4];
      if (nearest.Nearest(q, 4, indices, squared) != 4) ++mismatches;
      for (int k = 0; k < 4; ++k) {
        if (indices[k] != order[k] || std::abs(squared[k] - distance2(order[k])) > 1e-3f) {
          ++mismatches;
        }
      }
    }
  };
  std::thread other(check, 0, 200);
  check(200, 400);
  other.join();
  EXPECT_EQ(mismatches, 0);
  int index = -1;
  float squared = -1.0f;
  ASSERT_EQ(nearest.Nearest(queries[0], 1, &index, &squared), 1);
  EXPECT_EQ(index, 5);
  EXPECT_EQ(squared, 0.0f);
  EXPECT_EQ(nearest.Nearest(Eigen::Vector3f(std::nanf(""), 0, 0), 1, &index, &squared), 0);
}

TEST(NearestPoints, FewerPointsThanAskedForAndNone) {
  const NearestPoints two({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0)});
  int indices[5];
  float squared[5];
  ASSERT_EQ(two.Nearest(Eigen::Vector3f(0.9f, 0, 0), 5, indices, squared), 2);
  EXPECT_EQ(indices[0], 1);
  EXPECT_EQ(indices[1], 0);
  const NearestPoints none;
  EXPECT_EQ(none.size(), 0);
  EXPECT_EQ(none.Nearest(Eigen::Vector3f(0, 0, 0), 1, indices, squared), 0);
  const NearestPoints all_invalid({Eigen::Vector3f(std::nanf(""), 0, 0)});
  EXPECT_EQ(all_invalid.Nearest(Eigen::Vector3f(0, 0, 0), 1, indices, squared), 0);
}

}  // namespace
}  // namespace gcpstereo
