// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "gcpstereo/core/camera.h"

namespace gcpstereo::cost {

// How the matching neighbours of a reference view are chosen when the configuration says
// `dataset.neighbors: auto`. YAML keys in brackets.
struct ViewSelectionOptions {
  // [dataset.neighbor_count]: how many neighbours to choose (fewer when fewer views score > 0).
  // The paper uses 6 for Fountain-P11. Range: 1 <= count <= 64.
  int count = 6;
  // [dataset.neighbor_selection.min_angle_deg]: triangulation angle θ_min, in degrees, below which
  // a point gives no depth information (its weight is 0; OpenMVS's fMinAngle, ~3°–5°). A view at
  // nearly the same position as the reference scores 0 and is never chosen.
  // Range: 0 < min_angle_deg < optimal_angle_deg.
  double min_angle_deg = 3.0;
  // [dataset.neighbor_selection.optimal_angle_deg]: triangulation angle θ_opt, in degrees, from
  // which a point has the full angle weight (OpenMVS's fOptimAngle, ~10°–15°; Goesele et al.'s
  // α_max = 10°). Range: min_angle_deg < optimal_angle_deg < max_angle_deg.
  double optimal_angle_deg = 10.0;
  // [dataset.neighbor_selection.max_angle_deg]: triangulation angle θ_max, in degrees, beyond which
  // the two views see the surface too differently to match it (foreshortening, occlusions); the
  // weight then falls as (cos θ / cos θ_max)² to 0 at 90°. Range: optimal_angle_deg < max_angle_deg
  // < 90.
  double max_angle_deg = 45.0;
  // [dataset.neighbor_selection.grid_step_px]: without scene points, the reference pixels sampled
  // every grid_step_px pixels in x and y (the first at grid_step_px / 2). Range: >= 1.
  int grid_step_px = 32;

  // Throws ConfigError "<key> = <value>. Violated constraint: <bound>" for the first invalid field.
  void Check() const;
};

// How well one candidate view would serve as a matching neighbour of the reference.
struct NeighborScore {
  int index = -1;                 // index of the candidate in `cameras`
  double score = 0.0;             // S_j of SelectNeighbors, in [0, 1]
  double median_angle_deg = 0.0;  // median triangulation angle over the shared points (0: none)
  double shared_fraction = 0.0;   // fraction of the reference's points the candidate sees
  int shared_points = 0;          // how many of the reference's points the candidate sees
};

struct ViewSelection {
  int reference_index = -1;
  std::vector<int> neighbors;             // chosen, best first
  std::vector<NeighborScore> candidates;  // every other view, best first (ties: lower index)
  std::string basis;                      // "points" (given scene points) or "frustum" (grid)
  int points_given = 0;                   // size of points_world
  int points_used = 0;                    // reference points the scores are computed over

  // {"reference", "basis", "points_given", "points_used", "neighbors": [names],
  //  "candidates": [{"name", "index", "score", "median_angle_deg", "shared_fraction",
  //  "shared_points"}]}; `names[i]` names camera i (an empty list: names are the indices). Throws
  // Error when a non-empty `names` has no entry for an index used.
  nlohmann::json ToJson(const std::vector<std::string>& names) const;
};

// Chooses the matching neighbours of `cameras[reference_index]` from the other cameras, as the
// view selection of multi-view stereo systems does:
//   M. Goesele, N. Snavely, B. Curless, H. Hoppe, S. M. Seitz, "Multi-View Stereo for Community
//   Photo Collections", ICCV 2007, §4.1 (global view selection: triangulation-angle weight
//   w_α = min((α/α_max)², 1) times scale weight w_s);
//   OpenMVS, DepthMapsData::SelectViews / Scene::SelectNeighborViews (angle weight rising to
//   fOptimAngle, footprint-ratio weight with 1.6 tolerance, covered area);
//   COLMAP, mvs::Workspace / PatchMatch "max_num_src_images" selection by shared points and
//   triangulation angle.
//
// The reference's sample points X_k, k = 1 … N:
//   - "points" basis: the given points_world that the reference sees (in front, inside the image,
//     depth within [min_depth, max_depth]), every ⌈n / 20000⌉-th of them in input order when more
//     than 20000 remain;
//   - "frustum" basis (no points given, or none of them seen by the reference): the reference
//     pixels on a grid of options.grid_step_px, placed at one scene depth z₀ (camera z): the median
//     over the other cameras of the depth at which their optical axis passes closest to the
//     reference's (counted when both axes meet in front of both cameras at a crossing angle of at
//     least 1°) — where converging cameras look; when no axis converges (a rectified sequence) z₀ =
//     b / tan θ_opt with b the median distance of the other centres from the reference's, so that
//     the median baseline sees the points at the optimal angle. z₀ is clamped to [min_depth,
//     max_depth]. The grid's points stand for a fronto-parallel surface: a candidate whose centre
//     is not in front of that plane (its reference-camera z >= z₀) would see it edge-on or from
//     behind, and sees none of them.
// Score of candidate j (dimensionless, in [0, 1]):
//   S_j = (1/N) Σ_{k: j sees X_k} w_θ(θ_jk) · w_s(r_jk)
// i.e. the shared fraction (points j sees, in front and inside its image; no occlusion test)
// times the mean weight over the shared points, where
//   θ_jk = angle between the rays C_ref → X_k and C_j → X_k;
//   w_θ(θ) = 0 for θ < θ_min; (θ − θ_min) / (θ_opt − θ_min) for θ_min <= θ < θ_opt; 1 up to θ_max;
//            (cos θ / cos θ_max)² beyond (0 from 90°);
//   r_jk = footprint_ref / footprint_j, footprint = camera depth of X_k / mean focal length
//          (metres per pixel); w_s(r) = r² for r < 1 (the candidate sees coarser), 1 for
//          1 <= r <= 1.6, (1.6 / r)² beyond (much finer) — OpenMVS's scale weight.
// The `count` best candidates with S_j > 0 are chosen, best first, ties broken by the lower index.
// Deliberate deviations: w_θ is 0 below θ_min (Goesele and OpenMVS keep a small weight) so a
// near-duplicate view is never chosen to fill the count; it also falls beyond θ_max; points need
// no SfM track (a laser scan or GCPs work the same way), so visibility is geometric only.
// Throws Error for a bad reference_index, an invalid camera or bad depth bounds (0 <= min_depth <
// max_depth); ConfigError for bad options. Deterministic; no randomness.
ViewSelection SelectNeighbors(const std::vector<Camera>& cameras, int reference_index,
                              const std::vector<Eigen::Vector3d>& points_world,
                              const ViewSelectionOptions& options, double min_depth = 0.0,
                              double max_depth = std::numeric_limits<double>::infinity());

}  // namespace gcpstereo::cost
