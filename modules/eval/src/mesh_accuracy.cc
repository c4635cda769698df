// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/mesh_accuracy.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/flann.hpp>

#include "common.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::eval {
namespace {

struct Triangle {
  Eigen::Vector3d a, b, c;
  Eigen::Vector3i vertices;  // indices into the mesh's vertex list
};

// The faces of positive area (double precision), in input order.
std::vector<Triangle> ValidTriangles(const TriangleMesh& mesh, std::int64_t* degenerate) {
  std::vector<Triangle> triangles;
  const int n = static_cast<int>(mesh.vertices.size());
  for (const Eigen::Vector3i& f : mesh.faces) {
    if (f[0] < 0 || f[1] < 0 || f[2] < 0 || f[0] >= n || f[1] >= n || f[2] >= n) {
      ++*degenerate;
      continue;
    }
    Triangle t{mesh.vertices[f[0]].cast<double>(), mesh.vertices[f[1]].cast<double>(),
               mesh.vertices[f[2]].cast<double>(), f};
    const double area = 0.5 * (t.b - t.a).cross(t.c - t.a).norm();
    if (!(area > 0.0) || !std::isfinite(area)) {
      ++*degenerate;
      continue;
    }
    triangles.push_back(t);
  }
  return triangles;
}

double Area(const Triangle& t) { return 0.5 * (t.b - t.a).cross(t.c - t.a).norm(); }

// A uniform double in [0, 1) from the generator's raw bits (portable, unlike the std::
// distributions whose algorithms are implementation-defined).
inline double Uniform01(std::mt19937_64* rng) {
  return static_cast<double>((*rng)() >> 11) * 0x1.0p-53;
}

struct Samples {
  std::vector<Eigen::Vector3d> points;
  std::vector<int> triangle;  // index into the triangle list the sample lies on
  double area = 0.0;
};

// One uniform sample of the surface: the triangle (by area) and the point in it.
std::pair<size_t, Eigen::Vector3d> DrawSample(const std::vector<Triangle>& triangles,
                                              const std::vector<double>& cdf, double area,
                                              std::mt19937_64* rng) {
  const double u = Uniform01(rng) * area;
  const size_t i = std::min<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin(),
                                    triangles.size() - 1);
  const double r1 = std::sqrt(Uniform01(rng)), r2 = Uniform01(rng);
  const Triangle& t = triangles[i];
  return {i, (1.0 - r1) * t.a + r1 * (1.0 - r2) * t.b + r1 * r2 * t.c};
}

// Samples at `spacing` over the surface, or over the part `filter` accepts (its area estimated by
// a pilot draw; `kept_fraction` receives the estimate).
Samples SampleSurface(const std::vector<Triangle>& triangles, double spacing,
                      std::int64_t max_samples, std::uint64_t seed,
                      const std::function<bool(const Eigen::Vector3d&)>& filter = {},
                      double* kept_fraction = nullptr) {
  Samples s;
  std::vector<double> cdf(triangles.size());
  for (size_t i = 0; i < triangles.size(); ++i) {
    s.area += Area(triangles[i]);
    cdf[i] = s.area;
  }
  if (triangles.empty()) return s;
  std::mt19937_64 rng(seed);
  double fraction = 1.0;
  if (filter) {
    std::mt19937_64 pilot(seed ^ 0x9e3779b97f4a7c15ULL);
    std::int64_t accepted = 0;
    for (std::int64_t k = 0; k < MeshAccuracyOptions::kPilotSamples; ++k) {
      accepted += filter(DrawSample(triangles, cdf, s.area, &pilot).second) ? 1 : 0;
    }
    fraction = static_cast<double>(accepted) / MeshAccuracyOptions::kPilotSamples;
    if (kept_fraction != nullptr) *kept_fraction = fraction;
    if (accepted == 0) {
      s.area = 0.0;
      return s;
    }
  }
  const double wanted = std::ceil(fraction * s.area / (spacing * spacing));
  const std::int64_t count =
      std::max<std::int64_t>(1, std::min<double>(wanted, static_cast<double>(max_samples)));
  // With a filter, at most 4× the draws its pilot fraction predicts (then fewer samples).
  const double max_draws = filter ? 4.0 * count / fraction + 1000.0 : static_cast<double>(count);
  s.points.reserve(count);
  s.triangle.reserve(count);
  for (double draws = 0; static_cast<std::int64_t>(s.points.size()) < count && draws < max_draws;
       ++draws) {
    const auto [i, point] = DrawSample(triangles, cdf, s.area, &rng);
    if (filter && !filter(point)) continue;
    s.points.push_back(point);
    s.triangle.push_back(static_cast<int>(i));
  }
  s.area *= fraction;
  return s;
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, §5.1.5).
Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Triangle& t) {
  const Eigen::Vector3d ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return t.a;
  const Eigen::Vector3d bp = p - t.b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return t.b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return t.a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - t.c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return t.c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return t.a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return t.b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b);
  }
  const double denom = 1.0 / (va + vb + vc);
  return t.a + ab * (vb * denom) + ac * (vc * denom);
}

// For every vertex, the (valid) triangles that use it.
std::vector<std::vector<int>> VertexToTriangles(const std::vector<Triangle>& triangles,
                                                size_t num_vertices) {
  std::vector<std::vector<int>> adjacency(num_vertices);
  for (size_t i = 0; i < triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) adjacency[triangles[i].vertices[k]].push_back(static_cast<int>(i));
  }
  return adjacency;
}

// For every query sample, the distance to the other surface (see the header for the bound).
// Rows of float x y z for points[first, first + count) minus `origin`: the KD-tree works in
// float, so the coordinates are centred first to keep their precision.
cv::Mat CentredFeatures(const std::vector<Eigen::Vector3d>& points, size_t first, size_t count,
                        const Eigen::Vector3d& origin) {
  cv::Mat features(static_cast<int>(count), 3, CV_32F);
  for (int i = 0; i < features.rows; ++i) {
    const Eigen::Vector3d p = points[first + i] - origin;
    for (int k = 0; k < 3; ++k) features.at<float>(i, k) = static_cast<float>(p[k]);
  }
  return features;
}

std::vector<double> DistancesToSurface(const Samples& queries, const Samples& targets,
                                       const std::vector<Triangle>& target_triangles,
                                       size_t target_num_vertices, const Eigen::Vector3d& origin,
                                       int neighbors) {
  std::vector<double> distances(queries.points.size(), std::numeric_limits<double>::infinity());
  if (queries.points.empty() || targets.points.empty()) return distances;
  const std::vector<std::vector<int>> adjacency =
      VertexToTriangles(target_triangles, target_num_vertices);
  std::vector<int> candidates;
  const cv::Mat features = CentredFeatures(targets.points, 0, targets.points.size(), origin);
  cv::flann::GenericIndex<cvflann::L2_Simple<float>> index(features,
                                                           cvflann::KDTreeSingleIndexParams(10));
  const int knn = std::min<int>(neighbors, features.rows);
  // Queries in batches to bound the memory of the index/distance matrices.
  constexpr int kBatch = 65536;
  const int total = static_cast<int>(queries.points.size());
  for (int start = 0; start < total; start += kBatch) {
    const int count = std::min(kBatch, total - start);
    const cv::Mat query = CentredFeatures(queries.points, start, count, origin);
    cv::Mat indices(count, knn, CV_32S), squared(count, knn, CV_32F);
    // eps = 0: the single KD-tree search is exact.
    index.knnSearch(query, indices, squared, knn, cvflann::SearchParams(-1, 0.0f, true));
    for (int i = 0; i < count; ++i) {
      const Eigen::Vector3d& p = queries.points[start + i];
      // Candidate faces: those of the k nearest samples and every face sharing a vertex with them.
      candidates.clear();
      for (int k = 0; k < knn; ++k) {
        const int j = indices.at<int>(i, k);
        if (j < 0 || j >= static_cast<int>(targets.points.size())) continue;
        const Triangle& t = target_triangles[targets.triangle[j]];
        for (int v = 0; v < 3; ++v) {
          const std::vector<int>& ring = adjacency[t.vertices[v]];
          candidates.insert(candidates.end(), ring.begin(), ring.end());
        }
      }
      std::sort(candidates.begin(), candidates.end());
      candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
      double best = std::numeric_limits<double>::infinity();
      for (int c : candidates) {
        const Triangle& t = target_triangles[c];
        best = std::min(best, (ClosestPointOnTriangle(p, t) - p).norm());
      }
      distances[start + i] = best;
    }
  }
  return distances;
}

double Mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

}  // namespace

void MeshAccuracyOptions::Check() const {
  if (thresholds.empty()) {
    throw ConfigError(ViolatedConstraint("eval.mesh.thresholds", "[]", "at least one threshold"));
  }
  for (size_t i = 0; i < thresholds.size(); ++i) {
    if (!(thresholds[i] > 0.0) || !std::isfinite(thresholds[i])) {
      throw ConfigError(ViolatedConstraint("eval.mesh.thresholds[" + std::to_string(i) + "]",
                                           internal::FormatDouble(thresholds[i]),
                                           "finite and > 0"));
    }
  }
  if (std::isnan(sample_spacing) || std::isinf(sample_spacing)) {
    throw ConfigError(ViolatedConstraint("eval.mesh.sample_spacing",
                                         internal::FormatDouble(sample_spacing), "finite"));
  }
  if (max_samples < 100) {
    throw ConfigError(ViolatedConstraint("eval.mesh.max_samples", std::to_string(max_samples),
                                         "max_samples >= 100"));
  }
  if (neighbors < 1 || neighbors > 64) {
    throw ConfigError(ViolatedConstraint("eval.mesh.neighbors", std::to_string(neighbors),
                                         "1 <= neighbors <= 64"));
  }
}

nlohmann::json MeshAccuracy::ToJson() const {
  nlohmann::json j;
  j["definition"] =
      "accuracy: share of estimate samples within t of the gt surface; completeness: share of gt "
      "samples within t of the estimate; F = harmonic mean";
  j["thresholds"] = internal::JsonNumbers(thresholds);
  j["accuracy_percent"] = internal::JsonNumbers(accuracy_percent);
  j["completeness_percent"] = internal::JsonNumbers(completeness_percent);
  j["f_score_percent"] = internal::JsonNumbers(f_score_percent);
  j["accuracy_median"] = internal::JsonNumber(accuracy_median);
  j["accuracy_mean"] = internal::JsonNumber(accuracy_mean);
  j["completeness_median"] = internal::JsonNumber(completeness_median);
  j["completeness_mean"] = internal::JsonNumber(completeness_mean);
  j["estimate_samples"] = estimate_samples;
  j["gt_samples"] = gt_samples;
  j["estimate_area"] = internal::JsonNumber(estimate_area);
  j["gt_area"] = internal::JsonNumber(gt_area);
  j["estimate_spacing"] = internal::JsonNumber(estimate_spacing);
  j["gt_spacing"] = internal::JsonNumber(gt_spacing);
  j["degenerate_faces"] = degenerate_faces;
  j["gt_kept_fraction"] = gt_kept_fraction;
  return j;
}

namespace {

// Distance from each query to the nearest of `targets` (exact KD-tree search, coordinates
// centred on `origin` for float precision).
std::vector<double> DistancesToPoints(const Samples& queries, const Samples& targets,
                                      const Eigen::Vector3d& origin) {
  std::vector<double> distances(queries.points.size(), std::numeric_limits<double>::infinity());
  if (queries.points.empty() || targets.points.empty()) return distances;
  const cv::Mat features = CentredFeatures(targets.points, 0, targets.points.size(), origin);
  cv::flann::GenericIndex<cvflann::L2_Simple<float>> index(features,
                                                           cvflann::KDTreeSingleIndexParams(10));
  constexpr int kBatch = 65536;
  const int total = static_cast<int>(queries.points.size());
  for (int start = 0; start < total; start += kBatch) {
    const int count = std::min(kBatch, total - start);
    const cv::Mat query = CentredFeatures(queries.points, start, count, origin);
    cv::Mat indices(count, 1, CV_32S), squared(count, 1, CV_32F);
    index.knnSearch(query, indices, squared, 1, cvflann::SearchParams(-1, 0.0f, true));
    for (int i = 0; i < count; ++i) {
      const int j = indices.at<int>(i, 0);
      if (j < 0 || j >= static_cast<int>(targets.points.size())) continue;
      distances[start + i] = (targets.points[j] - queries.points[start + i]).norm();
    }
  }
  return distances;
}

// A point set as its own samples: every point, or every k-th when there are more than max.
Samples PointSamples(const std::vector<Eigen::Vector3f>& points, std::int64_t max_samples) {
  Samples s;
  const std::int64_t n = static_cast<std::int64_t>(points.size());
  const std::int64_t step = std::max<std::int64_t>(1, (n + max_samples - 1) / max_samples);
  s.points.reserve(static_cast<size_t>(n / step + 1));
  for (std::int64_t i = 0; i < n; i += step) s.points.push_back(points[i].cast<double>());
  return s;
}

// One side prepared for the comparison: its samples and, for a mesh, its triangles.
struct PreparedSide {
  Samples samples;
  std::vector<Triangle> triangles;
  size_t num_vertices = 0;
  bool is_mesh = false;
};

PreparedSide Prepare(const Surface& side, const char* which, double spacing,
                     std::int64_t max_samples, std::uint64_t seed, std::int64_t* degenerate,
                     const std::function<bool(const Eigen::Vector3d&)>& filter = {},
                     double* kept_fraction = nullptr) {
  if ((side.mesh == nullptr) == (side.points == nullptr)) {
    throw Error(std::string("EvaluateSurface: the ") + which +
                " must be exactly one of a mesh and a point set");
  }
  PreparedSide prepared;
  if (side.mesh != nullptr) {
    prepared.is_mesh = true;
    prepared.triangles = ValidTriangles(*side.mesh, degenerate);
    prepared.num_vertices = side.mesh->vertices.size();
    prepared.samples =
        SampleSurface(prepared.triangles, spacing, max_samples, seed, filter, kept_fraction);
  } else if (filter) {
    std::vector<Eigen::Vector3f> kept;
    for (const Eigen::Vector3f& p : *side.points) {
      if (filter(p.cast<double>())) kept.push_back(p);
    }
    if (kept_fraction != nullptr && !side.points->empty()) {
      *kept_fraction = static_cast<double>(kept.size()) / side.points->size();
    }
    prepared.samples = PointSamples(kept, max_samples);
  } else {
    prepared.samples = PointSamples(*side.points, max_samples);
  }
  return prepared;
}

std::vector<double> DistancesTo(const Samples& queries, const PreparedSide& target,
                                const Eigen::Vector3d& origin, int neighbors) {
  return target.is_mesh ? DistancesToSurface(queries, target.samples, target.triangles,
                                             target.num_vertices, origin, neighbors)
                        : DistancesToPoints(queries, target.samples, origin);
}

}  // namespace

// ETH3D (Schöps et al., CVPR 2017, §4) and DTU (Aanæs et al., IJCV 2016) style surface evaluation:
// accuracy(t) = |{p ∈ S_est : d(p, M_gt) < t}| / |S_est|,
// completeness(t) = |{q ∈ S_gt : d(q, M_est) < t}| / |S_gt|, F = 2 a c / (a + c).
// Deviations: a mesh side is sampled here (ETH3D samples only the estimate and uses the laser
// points as GT; DTU compares point clouds: both are possible with EvaluateSurface); a distance
// equal to t counts as within (<= t).
MeshAccuracy EvaluateSurface(const Surface& estimate, const Surface& gt,
                             const MeshAccuracyOptions& options) {
  options.Check();
  MeshAccuracy result;
  result.thresholds = options.thresholds;
  const double spacing =
      options.sample_spacing > 0.0
          ? options.sample_spacing
          : 0.25 * *std::min_element(options.thresholds.begin(), options.thresholds.end());
  // Distinct seeds so that identical meshes do not get identical sample sets.
  const PreparedSide gt_side =
      Prepare(gt, "ground truth", spacing, options.max_samples, options.seed * 2 + 0,
              &result.degenerate_faces, options.gt_filter, &result.gt_kept_fraction);
  if (gt_side.is_mesh && gt_side.triangles.empty()) {
    throw Error("EvaluateMesh: the ground-truth mesh has no face of positive area (" +
                std::to_string(gt.mesh->faces.size()) + " faces, " +
                std::to_string(gt.mesh->vertices.size()) + " vertices)");
  }
  if (gt_side.samples.points.empty()) {
    throw Error(options.gt_filter ? "EvaluateSurface: no part of the ground truth is observed"
                                  : "EvaluateSurface: the ground-truth point set is empty");
  }
  const PreparedSide est_side = Prepare(estimate, "estimate", spacing, options.max_samples,
                                        options.seed * 2 + 1, &result.degenerate_faces);
  const Samples& gt_samples = gt_side.samples;
  const Samples& est_samples = est_side.samples;
  result.gt_area = gt_samples.area;
  result.estimate_area = est_samples.area;
  result.gt_samples = static_cast<std::int64_t>(gt_samples.points.size());
  result.estimate_samples = static_cast<std::int64_t>(est_samples.points.size());
  result.gt_spacing = gt_side.is_mesh ? std::sqrt(gt_samples.area / gt_samples.points.size()) : 0.0;
  result.estimate_spacing = est_samples.points.empty() || !est_side.is_mesh
                                ? 0.0
                                : std::sqrt(est_samples.area / est_samples.points.size());

  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : gt_samples.points) origin += p;
  origin /= static_cast<double>(gt_samples.points.size());

  std::vector<double> accuracy = DistancesTo(est_samples, gt_side, origin, options.neighbors);
  std::vector<double> completeness = DistancesTo(gt_samples, est_side, origin, options.neighbors);
  for (double t : options.thresholds) {
    const auto within = [t](const std::vector<double>& d) {
      return static_cast<std::int64_t>(
          std::count_if(d.begin(), d.end(), [t](double v) { return v <= t; }));
    };
    const double a = internal::Percent(within(accuracy), result.estimate_samples);
    const double c = est_samples.points.empty()
                         ? 0.0
                         : internal::Percent(within(completeness), result.gt_samples);
    result.accuracy_percent.push_back(a);
    result.completeness_percent.push_back(c);
    result.f_score_percent.push_back(a + c > 0.0 ? 2.0 * a * c / (a + c) : 0.0);
  }
  result.accuracy_mean = Mean(accuracy);
  result.accuracy_median = internal::Median(&accuracy);
  if (!est_samples.points.empty()) {
    result.completeness_mean = Mean(completeness);
    result.completeness_median = internal::Median(&completeness);
  } else {
    result.completeness_mean = result.completeness_median = std::numeric_limits<double>::infinity();
  }
  return result;
}

MeshAccuracy EvaluateMesh(const TriangleMesh& estimate, const TriangleMesh& gt,
                          const MeshAccuracyOptions& options) {
  return EvaluateSurface(Surface{&estimate, nullptr}, Surface{&gt, nullptr}, options);
}

}  // namespace gcpstereo::eval
