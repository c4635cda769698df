// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// Ground control points from a structure-from-motion model's 3D points (the paper's §1 names
// "structure from motion point clouds" as a source of reliable sparse depth): the points that the
// reference image observes, per its keypoints' track entries (COLMAP's points2D → point3D ids).

#include <vector>

#include <Eigen/Core>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/gcp/gcp_sources.h"

namespace gcpstereo::gcp {

// Options of the SfM source. YAML keys gcp.sfm.*.
struct SfmGcpOptions {
  // Points observed in fewer images (the reference included) are dropped. Valid: >= 2.
  // Key gcp.sfm.min_track_length.
  int min_track_length = 3;
  // Points whose mean reprojection error (over their track, pixels of the model's images) is
  // larger are dropped. Valid: > 0. Key gcp.sfm.max_error_px.
  double max_error_px = 2.0;
  // Points whose widest triangulation angle with the reference's ray is smaller are dropped: their
  // depth is ill-determined. Valid: (0, 90). Key gcp.sfm.min_angle_deg.
  double min_angle_deg = 2.0;
  // Smallest image error σ assumes, pixels of the model's images (a mean reprojection error of a
  // few hundredths of a pixel does not make a depth exact). Valid: > 0. Key gcp.sfm.min_error_px.
  double min_error_px = 0.5;
  // Also the points that the reference does not observe but that project into it and pass the
  // LiDAR source's visibility tests (z-buffer and depth consistency with gcp.lidar.*, over all
  // the model's points). Off by default: an SfM cloud is sparse, so a nearer surface between its
  // points does not hide what lies behind it from those tests. Key gcp.sfm.projected.
  bool projected = false;

  void Check() const;  // throws ConfigError naming the key
};

// One 3D point of the model that the reference observes.
struct SfmPoint {
  Eigen::Vector3d point_world = Eigen::Vector3d::Zero();
  double error_px = 0.0;  // mean reprojection error in the model's images (COLMAP's ERROR)
  int track_length = 0;   // images observing it, the reference included
  bool observed = true;   // the reference observes it (false: only projected, options.projected)
  // Centres of the other images of its track (world frame), for the triangulation angle.
  std::vector<Eigen::Vector3d> other_centers_world;
};

// GCPs from the reference's observed SfM points. Each point is projected into `reference`
// (Camera::Project, rounded to the nearest pixel centre) and kept when it is in front of the
// camera, inside the image, passes the filters (track length, error, angle) and is the nearest
// point on its pixel (ties: the lower index). Its depth is the camera z; its sigma is the
// two-view error along the reference's ray of an image error e in another observer i, at
// distance d_i from the point, whose ray meets the reference's at θ_i (best observer):
//   σ = min_i d_i · (e / f_model) / sin θ_i,   e = max(error_px, min_error_px)
// (≈ z · e / (f · tan θ) for small angles), f_model = reference.K(0,0) / image_scale the focal
// length of the model's images (image_scale: dataset.scale; the errors are in the model's
// pixels). The angle filter takes the widest min(θ_i, 180° − θ_i). Source kSfm, raster order.
// Points with observed = false are skipped unless options.projected; then every point that passes
// the filters goes through GcpsFromPointCloud(…, lidar) (observed ones as occluders), and an
// unobserved point that wins its pixel there, on a pixel without an observed GCP, is a GCP too
// (summary: num_inconsistent counts the unobserved points the visibility tests reject).
GcpSet GcpsFromSfmPoints(const std::vector<SfmPoint>& points, const Camera& reference,
                         double image_scale, const SfmGcpOptions& options,
                         GcpSourceSummary* summary = nullptr,
                         const LidarGcpOptions& lidar = LidarGcpOptions());

}  // namespace gcpstereo::gcp
