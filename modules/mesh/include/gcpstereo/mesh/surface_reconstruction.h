// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "gcpstereo/core/types.h"

namespace gcpstereo::mesh {

// Options of the scene mesh (ReconstructSurface). YAML keys scene_mesh.*. Not in Wang & Yang
// (CVPR 2011): the scene mesh is an output format built from the fused cloud.
struct SurfaceOptions {
  // [scene_mesh.depth] Maximum depth of the octree on which the Poisson equation is solved. The
  // finest cell is 1.1 × (largest side of the cloud's bounding box) / 2^depth, which bounds the
  // detail the mesh can hold (a 50 m side at depth 10: 5.4 cm cells). Each extra level roughly
  // quadruples time and memory on a surface: 2 M points of the synthetic courtyard take 23 s at
  // depth 9 and 96 s at depth 10 on a loaded 2-core machine (surface_reconstruction.cc).
  // Dimensionless. Valid: [5, 14]. Default 10.
  int depth = 10;
  // [scene_mesh.point_weight] Screening weight α of screened Poisson (Kazhdan & Hoppe 2013, eq. 4):
  // how strongly the implicit function is pulled to 0 at the input points against fitting the
  // normal field. 0 = unscreened Poisson (Kazhdan et al. 2006), smoother and shrinking.
  // Dimensionless. Valid: [0, 1000]. Default 4 (the value PoissonRecon and PCL use).
  double point_weight = 4.0;
  // [scene_mesh.trim_distance] The Poisson surface is closed (watertight): it also spans the
  // holes and closes itself far from the data. Faces with a vertex farther than this from every
  // input point are removed. Scene units (metres). Valid: 0 (automatic) or a finite value > 0.
  // Automatic (default): max(4 × s, 2 × c), s = the median distance from an input point to its
  // nearest neighbour, c = the finest octree cell (see depth). 4 s keeps the surface over noise
  // and the gaps of an irregular sampling (on the synthetic courtyard with 0.5 ‰ noise, 3 s costs
  // 0.5 % of completeness, see surface_reconstruction.cc) and the cell term keeps it when depth is
  // too coarse for the sampling (a mesh vertex then lies up to a cell from the data).
  double trim_distance = 0.0;
  // [scene_mesh.threads] Worker threads for the nearest-point queries (colours, trimming); 0 = all
  // cores. The Poisson solve itself always runs on one thread: PCL's multi-threaded solve gives a
  // different mesh for different thread counts and a different vertex order from run to run (see
  // surface_reconstruction.cc). The output does not depend on this value. Valid: [0, 1024].
  int threads = 0;

  // Throws ConfigError naming the YAML key, value and violated bound.
  void Check() const;
};

// What ReconstructSurface did (for the log and report.json).
struct SurfaceSummary {
  std::int64_t input_points = 0;
  std::int64_t poisson_vertices = 0;  // vertices of the closed Poisson surface
  std::int64_t poisson_faces = 0;     // faces of the closed Poisson surface
  std::int64_t vertices = 0;          // of the output mesh
  std::int64_t faces = 0;             // of the output mesh
  std::int64_t trimmed_faces = 0;     // poisson_faces − faces
  double median_spacing = 0.0;   // median nearest-neighbour distance of the input (scene units)
  double trim_distance = 0.0;    // the trim distance used (scene units)
  double poisson_seconds = 0.0;  // wall-clock time of the Poisson solve alone
  // Diagnostic lines PCL's Poisson printed (captured, logged at debug level; e.g. marching cubes'
  // "Vertex pair not in list"): a count above 0 flags a surface that may have small holes.
  std::int64_t library_messages = 0;
  double seconds = 0.0;  // wall-clock time of the whole call

  nlohmann::json ToJson() const;
  std::string FullReport() const;
};

// Meshes a scene's fused, oriented point cloud into one triangle mesh: screened Poisson surface
// reconstruction (Kazhdan & Hoppe, "Screened Poisson Surface Reconstruction", ACM ToG 2013; PCL's
// pcl::Poisson), then trimming of the parts far from any data (SurfaceOptions::trim_distance).
//
// Poisson: find the indicator function χ minimising
//   E(χ) = ∫ ‖∇χ(p) − V(p)‖² dp + α · (Area / N) · Σ_i χ(p_i)²
// (V: the normal field splatted from the oriented points p_i, α = point_weight), on an octree of
// the given depth; the mesh is the iso-surface χ = mean χ(p_i) (marching cubes).
//
// cloud: points, unit normals pointing out of the surface (towards the cameras) and, optionally,
//   colours; num_views and sigma are not used (weighting by them is not done). Each output
//   vertex takes the colour of its nearest input point (none if the cloud has no colours).
// Faces are counter-clockwise seen from the side the normals point to. Vertices no face uses
// after trimming are dropped; the rest keep their order. The output is the same for the same
// input, whatever SurfaceOptions::threads.
// A cloud without extent (all points equal) gives an empty mesh, as the summary shows.
// Throws Error for an empty cloud, a cloud without normals, channels of the wrong size or
// non-finite coordinates; ConfigError (options.Check()) for bad options.
TriangleMesh ReconstructSurface(const OrientedPointCloud& cloud, const SurfaceOptions& options,
                                SurfaceSummary* summary = nullptr);

}  // namespace gcpstereo::mesh
