// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Scene mesh from the fused oriented cloud: screened Poisson (Kazhdan & Hoppe, ACM ToG 32(3)
// 2013, eq. 4; PCL 1.13's pcl::Poisson, which ships Kazhdan's PoissonRecon with the screening
// weight as setPointWeight), then trimming by the distance to the input points and colours from
// the nearest input point (core/nearest_points.h). See surface_reconstruction.h for the energy.
//
// Deliberate deviations from PoissonRecon's own tool: no density-based trimming (PCL does not
// return the sampling density per vertex), a distance-based one instead; num_views and sigma do
// not weight the samples.
//
// Library choice, measured 2026-12-02 on this machine (2 cores, shared with 4 other builds, so
// the times are loaded wall-clock times): PCL 1.13 pcl::Poisson versus Open3D 0.16.1
// (python3-open3d, TriangleMesh.create_from_point_cloud_poisson) on the same input: the exact
// mesh of `gcpstereo synth --preset small` (gt/mesh.ply, 64.5 m bounding-box diagonal,
// 4 581 m²) sampled uniformly with triangle normals (300 000 points), 20 holes of radius 2 % of
// the diagonal cut out (285 139 points left, median spacing s = 6.6 cm), Gaussian noise of
// 0.5 ‰ of the diagonal (3.2 cm) on the positions and of 0.05 on the normals; depth 9,
// point weight 4. Accuracy: distance from 200 000 points sampled on the result to the true mesh;
// completeness: share of 200 000 points sampled on the true mesh within 5 s (33 cm) of the
// result. Script: /tmp/wtmesh_bench/compare.py (not kept; python3 + numpy + open3d)
//   compare.py small/gt/mesh.ply 300000 0.0005 9
//                             time   faces    acc med  acc p90  acc p99  complete
//   Open3D, untrimmed        10.7 s  945 822  8.5 cm   15.7 cm  106 cm   98.0 %
//   Open3D, density q 0.05   10.7 s  891 788  8.2 cm   13.3 cm  17.9 cm  96.1 %
//   Open3D, trim 3 s         10.7 s  914 874  8.2 cm   13.1 cm  17.3 cm  97.5 %
//   PCL 1 thread, untrimmed  14.2 s  917 392  8.7 cm   13.9 cm  18.6 cm  97.9 %
//   PCL 1 thread, trim 3 s   14.2 s  901 396  8.6 cm   13.7 cm  17.8 cm  97.4 %
//   PCL 1 thread, trim 5 s   14.2 s  916 399  8.7 cm   13.9 cm  18.5 cm  97.6 %
//   PCL 2 threads, trim 3 s  22.7 s  901 385  8.7 cm   13.7 cm  17.8 cm  97.4 %
// On a 2 × 1 × 1.5 box (100 000 points, depth 8) both give 3.9 mm median / 9.8 mm p99 error.
// The two are equal within 0.3 cm (0.1 noise σ) in accuracy and 0.1 % in completeness;
// libopen3d-dev would add 17 Debian packages (30 with recommends: filament, embree, mesa, glfw …),
// 27.8 MB download, 93.5 MB installed (`apt-get install -s libopen3d-dev`), for no clear win.
// PCL is already a dependency (pcl_surface is part of libpcl-dev): PCL it is.
//
// Threads: PCL's Poisson with 2 threads gave the same vertex set in a different order on two
// runs of the same input (the box, `cmp` of the PLY files; sorted vertices identical), and a mesh
// different from the 1-thread solve: 458 760 vs 458 762 vertices on the courtyard case above,
// 1 756 257 vs 1 756 457 on the 2 M-point case below. It was 1.3× faster on 2 M points and slower
// on 300 000 (a shared machine: loads of 3–8). The solve therefore runs on one thread
// (reproducible bytes whatever the thread count, house rule 6); SurfaceOptions::threads only
// drives the nearest-point queries. PCL's Poisson also keeps static state
// (TreeNodeData::UseIndex, the node allocator), so concurrent calls are serialised by a mutex.
//
// Size and time: 2 000 000 points sampled on the same courtyard mesh (3 cm noise),
// ReconstructSurface with the defaults (threads 0) on this machine at a load of ~3 on its 2 cores
// (/tmp/wtmesh_bench/drive big.ply DEPTH 0, not kept; Poisson time of PCL alone in brackets):
//   depth 10: 3 512 612 Poisson faces, 3 499 359 kept, 96 s (Poisson 93 s), peak RSS 1.4 GB
//   depth  9:   797 436 Poisson faces,   783 696 kept, 23 s (Poisson 20 s), peak RSS 0.76 GB
// PCL alone at depth 10: 1 thread 116 s, 2 threads 89 s (at loads of 5–8), 1.2 GB. The Poisson
// solve is nearly all of the time and grows ~4× per level; the nearest-point queries, median
// spacing and trimming take ~3 s. So a 2 M-point scene meets "well under 60 s" at depth 9, not
// at the default depth 10 on a loaded 2-core machine; `perf` shows no single hot spot in PCL's
// solver (octree neighbour look-ups, constraint updates, iso-surface extraction).
#include "gcpstereo/mesh/surface_reconstruction.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/surface/poisson.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/nearest_points.h"
#include "gcpstereo/core/system.h"

namespace gcpstereo::mesh {
namespace {

// PCL's Poisson (its bundled PoissonRecon 4) prints diagnostics with printf and fprintf
// ("Vertex pair not in list 2 [7] (38 78 41)" when marching cubes misses an edge's vertex pair,
// "[WARNING] Initial residual too low") straight to the terminal, between our progress lines.
// While the solve runs, file descriptors 1 and 2 go to a temporary file; Finish() restores them
// and returns the lines, which the caller logs at debug level and counts in the summary.
class CapturedOutput {
 public:
  CapturedOutput() {
    std::fflush(stdout);
    std::fflush(stderr);
    file_ = std::tmpfile();
    if (file_ == nullptr) return;
    saved_out_ = dup(1);
    saved_err_ = dup(2);
    dup2(fileno(file_), 1);
    dup2(fileno(file_), 2);
  }
  ~CapturedOutput() {
    Restore();
    if (file_ != nullptr) std::fclose(file_);
  }
  CapturedOutput(const CapturedOutput&) = delete;
  CapturedOutput& operator=(const CapturedOutput&) = delete;

  std::vector<std::string> Finish() const {
    Restore();
    std::vector<std::string> lines;
    if (file_ == nullptr) return lines;
    std::rewind(file_);
    char buffer[512];
    while (std::fgets(buffer, sizeof buffer, file_) != nullptr) {
      std::string line(buffer);
      while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
      if (!line.empty()) lines.push_back(line);
    }
    return lines;
  }

 private:
  void Restore() const {
    if (saved_out_ < 0) return;
    std::fflush(stdout);
    std::fflush(stderr);
    dup2(saved_out_, 1);
    dup2(saved_err_, 2);
    close(saved_out_);
    close(saved_err_);
    saved_out_ = saved_err_ = -1;
  }

  std::FILE* file_ = nullptr;
  mutable int saved_out_ = -1;
  mutable int saved_err_ = -1;
};

// Automatic trim distance: max(kTrimSpacings × median spacing, kTrimCells × finest cell).
constexpr double kTrimSpacings = 4.0;
constexpr double kTrimCells = 2.0;
// PCL's default: the octree spans 1.1 × the bounding box's largest side.
constexpr float kPoissonScale = 1.1f;
// The median spacing is taken over at most this many points (every k-th, deterministic).
constexpr size_t kSpacingSamples = 100000;

template <typename T>
std::string Str(T value) {
  std::ostringstream stream;
  stream << value;
  return stream.str();
}

void CheckCloud(const OrientedPointCloud& cloud) {
  const std::string context = "ReconstructSurface: ";
  if (cloud.empty()) throw Error(context + "the point cloud is empty");
  const size_t n = cloud.points.size();
  if (cloud.normals.empty()) {
    throw Error(context + "the point cloud has no normals (an oriented cloud is required)");
  }
  auto check_size = [&](size_t size, const char* channel, bool optional) {
    if (size != n && !(optional && size == 0)) {
      throw Error(context + "the point cloud has " + Str(n) + " points but " + Str(size) + " " +
                  channel);
    }
  };
  check_size(cloud.normals.size(), "normals", false);
  check_size(cloud.colors.size(), "colors", true);
  check_size(cloud.num_views.size(), "num_views", true);
  check_size(cloud.sigma.size(), "sigma", true);
  for (size_t i = 0; i < n; ++i) {
    if (!cloud.points[i].allFinite() || !cloud.normals[i].allFinite()) {
      throw Error(context + "point " + Str(i) + " has a non-finite position or normal");
    }
  }
}

// Runs `body(begin, end)` over [0, n) on `threads` threads (0 = all). Each index writes its own
// output, so the result does not depend on the thread count.
template <typename Body>
void ParallelFor(size_t n, int threads, const Body& body) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024),
                      [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
  });
}

double MedianSpacing(const NearestPoints& tree, const pcl::PointCloud<pcl::PointXYZ>& points,
                     int threads) {
  if (points.size() < 2) return 0.0;
  const size_t step = std::max<size_t>(1, points.size() / kSpacingSamples);
  const size_t samples = (points.size() + step - 1) / step;
  std::vector<float> spacing(samples, 0.0f);
  ParallelFor(samples, threads, [&](size_t begin, size_t end) {
    int index[2];
    float squared[2];
    for (size_t i = begin; i < end; ++i) {
      // k = 2: the point itself and its nearest neighbour (0 for duplicates).
      const pcl::PointXYZ& p = points[i * step];
      if (tree.Nearest(Eigen::Vector3f(p.x, p.y, p.z), 2, index, squared) == 2) {
        spacing[i] = std::sqrt(squared[1]);
      }
    }
  });
  auto middle = spacing.begin() + spacing.size() / 2;
  std::nth_element(spacing.begin(), middle, spacing.end());
  return *middle;
}

}  // namespace

void SurfaceOptions::Check() const {
  if (depth < 5 || depth > 14) {
    throw ConfigError(ViolatedConstraint("scene_mesh.depth", Str(depth), "5 <= depth <= 14"));
  }
  if (!(point_weight >= 0.0 && point_weight <= 1000.0)) {
    throw ConfigError(ViolatedConstraint("scene_mesh.point_weight", FormatNumber(point_weight),
                                         "0 <= point_weight <= 1000"));
  }
  if (!(trim_distance >= 0.0) || !std::isfinite(trim_distance)) {
    throw ConfigError(ViolatedConstraint("scene_mesh.trim_distance", FormatNumber(trim_distance),
                                         "trim_distance >= 0 and finite (0 = automatic)"));
  }
  if (threads < 0 || threads > 1024) {
    throw ConfigError(
        ViolatedConstraint("scene_mesh.threads", Str(threads), "0 <= threads <= 1024 (0 = all)"));
  }
}

nlohmann::json SurfaceSummary::ToJson() const {
  nlohmann::json j;
  j["input_points"] = input_points;
  j["poisson_vertices"] = poisson_vertices;
  j["poisson_faces"] = poisson_faces;
  j["vertices"] = vertices;
  j["faces"] = faces;
  j["trimmed_faces"] = trimmed_faces;
  j["median_spacing"] = median_spacing;
  j["trim_distance"] = trim_distance;
  j["poisson_seconds"] = poisson_seconds;
  j["library_messages"] = library_messages;
  j["seconds"] = seconds;
  return j;
}

std::string SurfaceSummary::FullReport() const {
  std::ostringstream s;
  s << "Scene mesh: " << input_points << " points -> Poisson " << poisson_vertices << " vertices, "
    << poisson_faces << " faces; trimmed " << trimmed_faces << " faces farther than "
    << trim_distance << " (median spacing " << median_spacing << ") -> " << vertices
    << " vertices, " << faces << " faces; " << seconds << " s (Poisson " << poisson_seconds
    << " s)";
  return s.str();
}

TriangleMesh ReconstructSurface(const OrientedPointCloud& cloud, const SurfaceOptions& options,
                                SurfaceSummary* summary) {
  options.Check();
  CheckCloud(cloud);
  const Timer timer;
  const size_t n = cloud.size();

  pcl::PointCloud<pcl::PointNormal>::Ptr oriented(new pcl::PointCloud<pcl::PointNormal>);
  pcl::PointCloud<pcl::PointXYZ>::Ptr positions(new pcl::PointCloud<pcl::PointXYZ>);
  oriented->resize(n);
  positions->resize(n);
  Eigen::Vector3f low = cloud.points[0];
  Eigen::Vector3f high = cloud.points[0];
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    const Eigen::Vector3f& normal = cloud.normals[i];
    pcl::PointNormal& q = (*oriented)[i];
    q.x = p.x();
    q.y = p.y();
    q.z = p.z();
    q.normal_x = normal.x();
    q.normal_y = normal.y();
    q.normal_z = normal.z();
    (*positions)[i] = pcl::PointXYZ(p.x(), p.y(), p.z());
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }

  // The Poisson solve (one thread, see the top of this file).
  std::vector<std::string> library_messages;
  pcl::PointCloud<pcl::PointNormal> poisson_points;
  std::vector<pcl::Vertices> polygons;
  const Timer poisson_timer;
  {
    static std::mutex poisson_mutex;
    const std::lock_guard<std::mutex> lock(poisson_mutex);
    pcl::Poisson<pcl::PointNormal> poisson;
    poisson.setDepth(options.depth);
    poisson.setPointWeight(static_cast<float>(options.point_weight));
    poisson.setScale(kPoissonScale);
    poisson.setThreads(1);
    poisson.setInputCloud(oriented);
    const CapturedOutput captured;
    poisson.reconstruct(poisson_points, polygons);
    library_messages = captured.Finish();
  }
  oriented.reset();
  const double poisson_seconds = poisson_timer.ElapsedSeconds();
  for (size_t i = 0; i < library_messages.size() && i < 20; ++i) {
    spdlog::debug("PCL Poisson: {}", library_messages[i]);
  }
  if (!library_messages.empty()) {
    spdlog::debug("PCL Poisson printed {} diagnostic lines", library_messages.size());
  }

  // Nearest input point of every Poisson vertex: its colour and its distance for the trim.
  // (NearestPoints: PCL's tree without its per-query OpenMP region.)
  std::vector<Eigen::Vector3f> input_points;
  input_points.reserve(positions->size());
  for (const pcl::PointXYZ& p : positions->points) input_points.emplace_back(p.x, p.y, p.z);
  const NearestPoints tree(input_points);
  const size_t poisson_vertices = poisson_points.size();
  std::vector<int> nearest(poisson_vertices, 0);
  std::vector<float> nearest_distance(poisson_vertices, 0.0f);
  ParallelFor(poisson_vertices, options.threads, [&](size_t begin, size_t end) {
    int index = 0;
    float squared = 0.0f;
    for (size_t v = begin; v < end; ++v) {
      const pcl::PointNormal& p = poisson_points[v];
      tree.Nearest(Eigen::Vector3f(p.x, p.y, p.z), 1, &index, &squared);
      nearest[v] = index;
      nearest_distance[v] = std::sqrt(squared);
    }
  });

  const double median_spacing = MedianSpacing(tree, *positions, options.threads);
  const double cell = kPoissonScale * static_cast<double>((high - low).maxCoeff()) /
                      static_cast<double>(1 << options.depth);
  const double trim_distance = options.trim_distance > 0.0
                                   ? options.trim_distance
                                   : std::max(kTrimSpacings * median_spacing, kTrimCells * cell);

  // Keep the triangles whose three vertices are near the data; renumber the vertices they use in
  // their original order.
  TriangleMesh mesh;
  std::vector<int> new_index(poisson_vertices, -1);
  std::vector<Eigen::Vector3i> kept_faces;
  kept_faces.reserve(polygons.size());
  std::int64_t poisson_faces = 0;
  for (const pcl::Vertices& polygon : polygons) {
    // PCL triangulates (setOutputPolygons(false) is the default); anything else is a PCL bug.
    if (polygon.vertices.size() != 3) {
      throw Error("ReconstructSurface: PCL's Poisson returned a polygon of " +
                  Str(polygon.vertices.size()) + " vertices");
    }
    ++poisson_faces;
    const Eigen::Vector3i face(static_cast<int>(polygon.vertices[0]),
                               static_cast<int>(polygon.vertices[1]),
                               static_cast<int>(polygon.vertices[2]));
    bool near = true;
    for (int k = 0; k < 3; ++k) near = near && nearest_distance[face[k]] <= trim_distance;
    if (!near) continue;
    for (int k = 0; k < 3; ++k) new_index[face[k]] = 0;  // mark as used
    kept_faces.push_back(face);
  }
  const bool with_colors = !cloud.colors.empty();
  for (size_t v = 0; v < poisson_vertices; ++v) {
    if (new_index[v] < 0) continue;
    new_index[v] = static_cast<int>(mesh.vertices.size());
    const pcl::PointNormal& p = poisson_points[v];
    mesh.vertices.emplace_back(p.x, p.y, p.z);
    if (with_colors) mesh.colors.push_back(cloud.colors[nearest[v]]);
  }
  mesh.faces.reserve(kept_faces.size());
  for (const Eigen::Vector3i& face : kept_faces) {
    mesh.faces.emplace_back(new_index[face[0]], new_index[face[1]], new_index[face[2]]);
  }

  if (summary != nullptr) {
    summary->input_points = static_cast<std::int64_t>(n);
    summary->poisson_vertices = static_cast<std::int64_t>(poisson_vertices);
    summary->poisson_faces = poisson_faces;
    summary->vertices = static_cast<std::int64_t>(mesh.vertices.size());
    summary->faces = static_cast<std::int64_t>(mesh.faces.size());
    summary->trimmed_faces = poisson_faces - summary->faces;
    summary->median_spacing = median_spacing;
    summary->trim_distance = trim_distance;
    summary->poisson_seconds = poisson_seconds;
    summary->library_messages = static_cast<std::int64_t>(library_messages.size());
    summary->seconds = timer.ElapsedSeconds();
  }
  return mesh;
}

}  // namespace gcpstereo::mesh
