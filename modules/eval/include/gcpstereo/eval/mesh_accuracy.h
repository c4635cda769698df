// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "gcpstereo/core/types.h"

namespace gcpstereo::eval {

// Mesh against a ground-truth surface, as the ETH3D (Schöps et al., CVPR 2017) and DTU (Aanæs et
// al., IJCV 2016) evaluations do:
//   accuracy(t)     = share of points sampled on the ESTIMATE within distance t (<= t) of the GT;
//   completeness(t) = share of points sampled on the GT within distance t of the estimate surface;
//   F(t)            = 2 · acc · compl / (acc + compl) (0 when both are 0).
// Both meshes are sampled uniformly by area (std::mt19937_64 seeded with `seed`; a face is chosen
// with probability ∝ its area, then a uniform point in it). The distance of a sample to the other
// surface is the minimum exact point-to-triangle distance over the candidate faces: the faces of
// its k nearest samples of the other mesh (exact KD-tree search, opencv_flann) and every face
// sharing a vertex with those. This is an upper bound of the true point-to-surface distance, never
// larger than the point-to-sample distance, and exact whenever the nearest face is a candidate
// (dense sampling makes it so; the test suite checks it on coarse samplings of planar meshes).
struct MeshAccuracyOptions {
  // Distance thresholds in scene units, each > 0. YAML: eval.mesh.thresholds.
  std::vector<double> thresholds = {0.01, 0.02, 0.05, 0.1};
  // Mean spacing of the samples (scene units): about area / spacing² samples per mesh.
  // <= 0: automatic, a quarter of the smallest threshold. YAML: eval.mesh.sample_spacing.
  double sample_spacing = 0.0;
  // Upper bound of samples per mesh (the summary reports the spacing actually reached).
  // Range: >= 100. YAML: eval.mesh.max_samples.
  std::int64_t max_samples = 2'000'000;
  // Candidate samples per query (k). Range: 1 … 64. YAML: eval.mesh.neighbors.
  int neighbors = 4;
  // RNG seed for the sampling. YAML: eval.mesh.seed.
  std::uint64_t seed = 0;
  // The part of the ground truth that counts (EvaluateSurface; no YAML key): a GT sample or point
  // it rejects is in no denominator — the surface no camera observed, which no estimate can
  // complete (the DTU and ETH3D evaluations mask it too). Empty = all. A mesh is then sampled
  // until the accepted samples reach the spacing over the accepted area (estimated by a pilot
  // draw of kPilotSamples), or max_samples.
  std::function<bool(const Eigen::Vector3d&)> gt_filter;
  static constexpr std::int64_t kPilotSamples = 20000;

  void Check() const;
};

struct MeshAccuracy {
  std::vector<double> thresholds;
  std::vector<double> accuracy_percent;      // per threshold
  std::vector<double> completeness_percent;  // per threshold
  std::vector<double> f_score_percent;       // per threshold
  double accuracy_median = 0.0;              // median estimate→GT distance (scene units)
  double accuracy_mean = 0.0;
  double completeness_median = 0.0;  // median GT→estimate distance
  double completeness_mean = 0.0;
  std::int64_t estimate_samples = 0;
  std::int64_t gt_samples = 0;
  double estimate_area = 0.0;
  double gt_area = 0.0;
  double estimate_spacing = 0.0;  // sqrt(area / samples) actually reached
  double gt_spacing = 0.0;
  std::int64_t degenerate_faces = 0;  // zero-area faces or bad indices (ignored), both meshes
  double gt_kept_fraction = 1.0;      // share of the GT (area or points) the gt_filter accepted
  nlohmann::json ToJson() const;
};

// Throws Error when the GT mesh has no face of positive area, ConfigError on bad options. An
// estimate without area gives accuracy 0 and completeness 0 (reported, not thrown).
MeshAccuracy EvaluateMesh(const TriangleMesh& estimate, const TriangleMesh& gt,
                          const MeshAccuracyOptions& options = {});

// One side of the comparison: a mesh (sampled as above) or a point set (a fused cloud, a laser
// scan), which is its own sample set — every point, or every k-th in input order when there are
// more than max_samples — and whose distance to a query is that of its nearest point. Exactly one
// of the two pointers is set.
struct Surface {
  const TriangleMesh* mesh = nullptr;
  const std::vector<Eigen::Vector3f>* points = nullptr;
};

// The measures above with either side a mesh or points (EvaluateMesh = both meshes; areas and
// spacings are 0 for a point side). Throws Error when a side sets neither or both pointers, a GT
// mesh has no face of positive area or GT points are empty.
MeshAccuracy EvaluateSurface(const Surface& estimate, const Surface& gt,
                             const MeshAccuracyOptions& options = {});

}  // namespace gcpstereo::eval
