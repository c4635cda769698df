// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// A model in an arbitrary frame and scale (a COLMAP reconstruction) put into a scan's frame: the
// similarity x_world = s R x_model + t (Umeyama, "Least-squares estimation of transformation
// parameters between two point patterns", PAMI 1991, through Eigen::umeyama), estimated
//   - from known positions of some model points (camera centres, COLMAP model_aligner's
//     convention): RANSAC over minimal samples of three, the best consensus refitted on its
//     inliers (locally optimised), or
//   - by registering the model's 3D points to a scan: coarse hypotheses from the two clouds'
//     centroids, principal axes and spreads, and from rotations drawn uniformly, refined by a
//     trimmed, scale-aware ICP (nearest neighbours from PCL's k-d tree, Eigen::umeyama with
//     scale) with successive halving (all a few steps, the best quarter more, and so on), the
//     best few refined to convergence against the whole scan, last by point-to-plane steps with
//     scale (Chen & Medioni, "Object modelling by registration of multiple range images", 1992),
//     which do not stall along planes as point-to-point ICP does. The fine stage is then restarted
//     from a fixed set of perturbed poses (rotations about, and shifts along, the aligned model's
//     principal axes, and scale changes); the best-scoring restart wins, and the spread of those
//     that score about as well as it (the camera centres' largest displacement between them)
//     measures how well the scan pins the model down: a model that can slide or turn along a wall
//     without a worse fit is ambiguous.
// Neither decides alone whether the result is good enough: CheckAlignment refuses a poor or an
// ambiguous one with its residuals (a wrong frame must never pass silently).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "gcpstereo/core/types.h"

namespace gcpstereo::align {

// x_world = scale · rotation · x_model + translation.
struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  // From a 4×4 [sR t; 0 1] (Eigen::umeyama's result); throws Error unless it is one (s > 0, R a
  // rotation within 1e-6).
  static Similarity FromMatrix(const Eigen::Matrix4d& world_from_model);
  Eigen::Matrix4d Matrix() const;
  Eigen::Vector3d Apply(const Eigen::Vector3d& x_model) const {
    return scale * (rotation * x_model) + translation;
  }
  Similarity Inverse() const;
  // The angle of `rotation`, degrees in [0, 180].
  double RotationAngleDeg() const;
  // A camera of the model's frame in the world frame: same intrinsics, centre moved, orientation
  // rotated (its depths scale by `scale`).
  Camera Apply(const Camera& camera_model) const;
};

// The acceptance thresholds and the estimation's parameters (configuration keys dataset.align_*).
struct AlignmentOptions {
  // A correspondence (a model point and its nearest scan point, or a camera centre and its known
  // position) is an inlier when its residual is at most this; the median residual must not exceed
  // it either. World (scan) units. Range > 0.
  double max_residual = 0.05;
  // The alignment is refused when fewer correspondences are inliers. Range [0, 1].
  double min_inlier_share = 0.5;
  // Scan registration: the median residual must also be at most this fraction of the aligned
  // model's spread (RMS distance of its points from their centroid). Scale-free: a model shrunk
  // onto a small part of a wrong scan has small residuals in scan units, but not relative to its
  // own size. Range (0, 1].
  double max_relative_residual = 0.01;
  // Centres: RANSAC samples of three drawn (seeded, so reproducible). Range >= 1.
  int ransac_iterations = 2000;
  std::uint64_t seed = 1;
  // Scan registration: at most this many model points are used (every k-th). Range >= 3.
  int max_model_points = 20000;

  // Throws ConfigError naming the key (dataset.align_*), the value and the bound.
  void Check() const;
};

// What an alignment found: the transform and how well the model fits the target with it.
struct AlignmentResult {
  std::string method;  // "centres" or "scan"
  Similarity world_from_model;
  int num_correspondences = 0;  // centres matched, or model points used
  int num_inliers = 0;          // residual <= max_residual
  double inlier_share = 0.0;
  // Over every correspondence, world units: the median, the 90th percentile and the root mean
  // square of the residuals; the median relative to the aligned model's spread.
  double median_residual = 0.0;
  double p90_residual = 0.0;
  double rms_residual = 0.0;
  double relative_median_residual = 0.0;
  double model_spread = 0.0;  // RMS distance of the aligned points from their centroid, world units
  // Centres: each centre's residual, in the input's order.
  std::vector<double> residuals;
  int hypotheses = 0;  // scan: coarse hypotheses tried; centres: RANSAC samples drawn
  int iterations = 0;  // scan: ICP iterations of the final refinement
  // Scan: the fine stage's restarts from perturbed poses, how many of them converged to a score
  // about as good as the best's (the median of the distances to the scan's tangent planes within
  // the 95 % confidence interval of the best's median, from the order statistics), and the largest
  // displacement of a probe (a camera centre, or else an inlier model point) between the chosen
  // transform and any of those, world units: how far the scan leaves the model free to move.
  // CheckAlignment refuses the alignment when it exceeds max_residual.
  int restarts = 0;
  int restarts_alike = 0;
  double ambiguity = 0.0;
  std::string ambiguity_probes;  // "camera centres" or "model points"
  double seconds = 0.0;

  // "scale 0.37, rotation 40.0°, translation (1, 2, 3); residuals median 0.002, 90th percentile
  // 0.004, RMS 0.003; 98.5 % of 1234 within 0.05 (scan)".
  std::string Describe() const;
};

// The similarity mapping `model` onto `world` (matched pairs, e.g. camera centres). Throws Error
// when fewer than three pairs are given or the model points are (nearly) collinear: a similarity
// is then not determined. RANSAC (options.ransac_iterations samples, inliers within
// options.max_residual), the largest consensus refitted on its inliers until it no longer grows;
// with fewer than three inliers, the fit of all pairs.
AlignmentResult AlignToKnownPoints(const std::vector<Eigen::Vector3d>& model,
                                   const std::vector<Eigen::Vector3d>& world,
                                   const AlignmentOptions& options);

// The similarity registering `model_points` (a reconstruction's 3D points, any frame and scale) to
// `scan` (world frame). `model_centres` (the reconstruction's camera centres, model frame; may be
// empty) are the probes of AlignmentResult::ambiguity: where the cameras land decides the depth
// maps. Without them the inlier model points are the probes. Throws Error for fewer than three
// finite points in either cloud.
AlignmentResult AlignToScan(const std::vector<Eigen::Vector3d>& model_points,
                            const PointCloud& scan, const AlignmentOptions& options,
                            const std::vector<Eigen::Vector3d>& model_centres = {});

// The residual statistics (method "scan") of `model_points` moved by a given `world_from_model`
// against `scan`, as AlignToScan computes them for its own result: e.g. to score a transform known
// otherwise (from camera centres) on the same objective.
AlignmentResult EvaluateOnScan(const std::vector<Eigen::Vector3d>& model_points,
                               const PointCloud& scan, const Similarity& world_from_model,
                               const AlignmentOptions& options);

// Throws Error ("<what>: alignment refused: ..." with the residuals, inlier share and the
// thresholds) when the inlier share is below options.min_inlier_share, the median residual above
// options.max_residual, (scan) its relative value above options.max_relative_residual, or (scan)
// the ambiguity above options.max_residual (the message then advises dataset.align: centres).
void CheckAlignment(const AlignmentResult& result, const AlignmentOptions& options,
                    const std::string& what);

}  // namespace gcpstereo::align
