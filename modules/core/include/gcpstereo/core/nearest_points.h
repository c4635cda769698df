// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

namespace gcpstereo {

// Exact nearest neighbours among 3-D points: FLANN's single k-d tree (leaves of 15 points, the
// finite points in input order, exact search) — the tree pcl::KdTreeFLANN builds, so the same
// neighbours — compiled here without OpenMP. Debian's libpcl_kdtree runs FLANN with OpenMP,
// which opens a parallel region, two futex system calls, for every query however small: a loop
// of single-point queries (ICP, a mesh's nearest input points) spent two thirds of its time
// there. Queries are const and may run on any number of threads at once.
class NearestPoints {
 public:
  NearestPoints();
  // Indices refer to `points`; points that are not finite are left out.
  explicit NearestPoints(const std::vector<Eigen::Vector3f>& points);
  NearestPoints(NearestPoints&&) noexcept;
  NearestPoints& operator=(NearestPoints&&) noexcept;
  ~NearestPoints();

  // The number of (finite) points searched.
  int size() const;
  // The min(k, size()) nearest points to `query`, nearest first: their indices and squared
  // distances written to `indices` and `squared_distances` (each room for k); returns how many.
  // 0 for a query that is not finite.
  int Nearest(const Eigen::Vector3f& query, int k, int* indices, float* squared_distances) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

}  // namespace gcpstereo
