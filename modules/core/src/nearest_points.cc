// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/nearest_points.h"

#include <algorithm>

// FLANN's templates compiled without OpenMP: its `#pragma omp` lines are left out (and GCC's
// warning about them with them).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunknown-pragmas"
#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_single_index.h>
#pragma GCC diagnostic pop

namespace gcpstereo {

struct NearestPoints::Tree {
  std::vector<float> coordinates;  // x y z of the finite points, in input order
  std::vector<int> input_index;    // their indices in the input
  std::unique_ptr<flann::KDTreeSingleIndex<flann::L2_Simple<float>>> index;
};

NearestPoints::NearestPoints() : tree_(std::make_unique<Tree>()) {}

NearestPoints::NearestPoints(const std::vector<Eigen::Vector3f>& points)
    : tree_(std::make_unique<Tree>()) {
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    if (!points[i].allFinite()) continue;
    tree_->coordinates.insert(tree_->coordinates.end(), {points[i].x(), points[i].y(), points[i].z()});
    tree_->input_index.push_back(i);
  }
  if (tree_->input_index.empty()) return;
  tree_->index = std::make_unique<flann::KDTreeSingleIndex<flann::L2_Simple<float>>>(
      flann::Matrix<float>(tree_->coordinates.data(), tree_->input_index.size(), 3),
      flann::KDTreeSingleIndexParams(15));
  tree_->index->buildIndex();
}

NearestPoints::NearestPoints(NearestPoints&&) noexcept = default;
NearestPoints& NearestPoints::operator=(NearestPoints&&) noexcept = default;
NearestPoints::~NearestPoints() = default;

int NearestPoints::size() const { return static_cast<int>(tree_->input_index.size()); }

int NearestPoints::Nearest(const Eigen::Vector3f& query, int k, int* indices,
                           float* squared_distances) const {
  k = std::min(k, size());
  if (k <= 0 || !query.allFinite()) return 0;
  float q[3] = {query.x(), query.y(), query.z()};
  flann::Matrix<int> found(indices, 1, k);
  flann::Matrix<float> distances(squared_distances, 1, k);
  tree_->index->knnSearch(flann::Matrix<float>(q, 1, 3), found, distances, k,
                          flann::SearchParams(-1, 0.0f));
  for (int i = 0; i < k; ++i) indices[i] = tree_->input_index[indices[i]];
  return k;
}

}  // namespace gcpstereo
