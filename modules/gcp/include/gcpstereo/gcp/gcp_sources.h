// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// Ground control points from range data (paper §4.2: "sparse GCPs provided from laser range
// scans") and the bookkeeping shared by every GCP source: down-sampling to one GCP per s×s block
// (paper: s = 16, ≈0.4 %), merging sources, density.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::gcp {

// What one source contributed and why points were dropped. Lands in report.json.
struct GcpSourceSummary {
  std::string source;         // "lidar", "depth_map", "stereo", "sfm"
  int num_input = 0;          // points / valid pixels / matches offered by the source
  int num_invalid = 0;        // non-finite coordinates or depth <= min depth
  int num_behind_camera = 0;  // lidar: z <= 0 in the reference camera
  int num_outside_image = 0;  // lidar: projected outside the image
  int num_same_pixel = 0;     // lidar: lost the z-buffer (a nearer point on the same pixel)
  int num_inconsistent = 0;   // lidar: farther than a nearer neighbour allows (seen through a gap)
  int num_short_track = 0;    // sfm: seen in fewer than gcp.sfm.min_track_length images
  int num_large_error = 0;    // sfm: mean reprojection error above gcp.sfm.max_error_px
  int num_small_angle = 0;    // sfm: triangulation angle below gcp.sfm.min_angle_deg
  int num_gcps = 0;           // GCPs produced
  double density_percent = 0.0;  // 100 · num_gcps / (width · height)
};

// Summary of the whole GCP stage (all sources, after merging and down-sampling).
struct GcpStageSummary {
  std::vector<GcpSourceSummary> sources;
  int downsample = 1;             // s of gcp.downsample
  int num_before_downsample = 0;  // after merging
  int num_gcps = 0;
  double density_percent = 0.0;
};

// Options of the LiDAR / laser-scan source. YAML keys gcp.lidar.*.
struct LidarGcpOptions {
  // Half-size r of the (2r+1)² window of the depth-consistency test, pixels. 0 = z-buffer only.
  // Valid: [0, 20]. Key gcp.lidar.consistency_radius_px.
  int consistency_radius_px = 2;
  // Steepest surface slant (angle between surface normal and viewing ray) the consistency test
  // tolerates, degrees: a point is rejected when some z-buffer point at pixel distance δ in the
  // window is nearer by more than depth_tolerance + sigma_multiplier·σ + z·δ·tan(θ)/f, f the focal
  // length in pixels (the depth change across δ pixels of a plane slanted by θ). Valid: (0, 90).
  // Key gcp.lidar.max_surface_slant_deg.
  double max_surface_slant_deg = 85.0;
  // Absolute part of that tolerance, in the data set's unit (metres). Valid: >= 0.
  // Key gcp.lidar.depth_tolerance.
  double depth_tolerance = 0.0;
  // Multiple of the point's sigma added to the tolerance (range noise). Valid: >= 0.
  // Key gcp.lidar.sigma_multiplier.
  double sigma_multiplier = 3.0;
  // Sigma given to points when the cloud carries none, in the data set's unit (Velodyne HDL-64E:
  // ≈ 0.02 m). Valid: >= 0 (0 = unknown). Key gcp.lidar.default_sigma.
  double default_sigma = 0.02;
  // Points nearer than this depth (camera z) are ignored, data set's unit. Valid: >= 0.
  // Key gcp.lidar.min_depth.
  double min_depth = 0.0;

  void Check() const;  // throws ConfigError naming the key
};

// GCPs from a point cloud (paper §4.2, laser scan of Fountain-P11; also KITTI's Velodyne).
// Each point X (range-sensor frame) is moved to the world, X_w = world_from_lidar · X, projected
// into `reference` (Camera::Project) and kept when in the image. Visibility:
//   1. z-buffer: per pixel (the projection rounded to the nearest pixel centre) the nearest point
//      wins (ties: the lower point index);
//   2. depth consistency: a z-buffer winner is rejected when a winner within the (2r+1)² window
//      is nearer by more than the slant tolerance above — the point is seen through a gap in a
//      nearer surface, or was seen only from the scanner's other viewpoint (behind an object).
//      Side effect, by design: background points within r px of a foreground silhouette are
//      dropped too (conservative at depth discontinuities).
// GCP: the pixel, depth = camera z of the point, sigma = cloud.sigma[i] if present, else
// options.default_sigma; source kLidar. Output in raster order. Throws Error when the camera is
// invalid or cloud.sigma has the wrong length.
GcpSet GcpsFromPointCloud(const PointCloud& cloud, const Eigen::Matrix4d& world_from_lidar,
                          const Camera& reference, const LidarGcpOptions& options,
                          GcpSourceSummary* summary = nullptr);

// GCPs from a depth image of the reference view (gcp.depth_map, kind depth): one per pixel with a
// finite depth > 0 (0 / non-finite = no measurement), with the given sigma (data set's unit).
// Throws Error unless depth is a non-empty CV_32F.
GcpSet GcpsFromDepthMap(const cv::Mat& depth, double sigma, GcpSource source = GcpSource::kDepthMap,
                        GcpSourceSummary* summary = nullptr);

// depth = disparity_numerator / disparity for finite disparities > 0; +inf (kInvalidDepth)
// elsewhere. Throws Error unless disparity is CV_32F and disparity_numerator > 0.
cv::Mat DisparityToDepth(const cv::Mat& disparity, double disparity_numerator);

// Keeps one GCP per s×s block (blocks anchored at pixel (0, 0); the last row/column of blocks may
// be partial): the one nearest the centre of its (clipped) block; ties by smaller sigma, then
// lower source enum, then earlier position in the input. s = 1 keeps one per pixel. Output in
// raster order of the kept pixels. Throws Error when s < 1 or the size is not positive; GCPs
// outside [0, width)×[0, height) are an Error too (they indicate a caller bug).
GcpSet Downsample(const GcpSet& gcps, int s, int width, int height);

// Concatenates several sources (no dedup: Downsample keeps one per block/pixel).
GcpSet MergeGcpSets(const std::vector<GcpSet>& sets);

// 100 · size / (width · height).
double DensityPercent(const GcpSet& gcps, int width, int height);

}  // namespace gcpstereo::gcp
