// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// A model in an arbitrary frame and scale (a COLMAP reconstruction) put into a scan's frame: the
// similarity x_world = s R x_model + t (Umeyama, "Least-squares estimation of transformation
// parameters between two point patterns", PAMI 1991, through Eigen::umeyama), estimated
//   - from known positions of some model points (camera centres, COLMAP model_aligner's
//     convention): RANSAC over minimal samples of three, the best consensus refitted on its
//     inliers (locally optimised), or
//   - by registering the model's 3D points to a scan: coarse hypotheses from the two clouds'
//     centroids, principal axes and spreads, each refined by a short trimmed, scale-aware ICP
//     (nearest neighbours from PCL's k-d tree, Eigen::umeyama with scale), the best refined to
//     convergence against the whole scan, last by point-to-plane steps with scale (Chen &
//     Medioni, "Object modelling by registration of multiple range images", 1992), which do not
//     stall along planes as point-to-point ICP does.
// Neither decides alone whether the result is good enough: CheckAlignment refuses a poor one with
// its residuals (a wrong frame must never pass silently).
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
// `scan` (world frame). Throws Error for fewer than three finite points in either.
AlignmentResult AlignToScan(const std::vector<Eigen::Vector3d>& model_points,
                            const PointCloud& scan, const AlignmentOptions& options);

// Throws Error ("<what>: alignment refused: ..." with the residuals, inlier share and the
// thresholds) when the inlier share is below options.min_inlier_share, the median residual above
// options.max_residual or (scan) its relative value above options.max_relative_residual.
void CheckAlignment(const AlignmentResult& result, const AlignmentOptions& options,
                    const std::string& what);

}  // namespace gcpstereo::align
