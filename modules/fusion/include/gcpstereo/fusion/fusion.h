// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::fusion {

// Options of the depth-map fusion (FuseDepthMaps). YAML keys fusion.*. Not in the paper (the
// paper stops at per-view depth maps); they follow COLMAP's stereo_fusion options of the same
// meaning (min_num_pixels, max_depth_error, max_normal_error).
struct FusionOptions {
  // [fusion.min_views] A source pixel becomes a point when at least this many views agree on it,
  // the source view included (COLMAP: min_num_pixels). 1 keeps every valid pixel (no outlier
  // rejection at all; the consumed marks still thin out the redundancy). Count of views.
  // Valid: [1, 64]. Default 2: one other view must confirm the depth.
  int min_views = 2;
  // [fusion.depth_tolerance] Depth agreement: view j agrees with the source point X when
  // |z_j(X) − d_j(q)| / d_j(q) <= depth_tolerance, with z_j(X) the depth of X in camera j, q the
  // pixel of camera j nearest to X's projection and d_j(q) its depth-map value (COLMAP:
  // max_depth_error). Dimensionless (relative). Valid: (0, 1]. Default 0.01 (1 %: 9 cm at 9 m,
  // about two depth labels of the paper's fountain setting).
  double depth_tolerance = 0.01;
  // [fusion.normal_tolerance_deg] Normal agreement: the angle between the source pixel's normal
  // and view j's normal at q (both from DepthMapNormals, world frame) must not exceed this
  // (COLMAP: max_normal_error). Degrees. Valid: (0, 180]; 180 turns the test off (but a pixel
  // still needs a defined normal to take part). Default 30.
  double normal_tolerance_deg = 30.0;
  // [fusion.normal_radius_px] The pixel normals (DepthMapNormals) take their tangents from the
  // pixels this far away on either side: a longer baseline divides the angular error that depth
  // noise or label quantisation causes by about this factor (exact depth maps of planes give the
  // same normal for every radius). Pixels. Valid: [1, 16]. Default 2.
  int normal_radius_px = 2;
  // [fusion.stride_px] Source pixels are sampled on the grid of columns and rows that are
  // multiples of this (the other views are always looked up at their nearest pixel). 1 = every
  // pixel. Pixels. Valid: [1, 64].
  int stride_px = 1;

  // Throws ConfigError "fusion.<key> = <value>. Violated constraint: <bound>" for the first bad
  // value (in the order of the fields above).
  void Check() const;
};

// One view of the scene: its depth map, camera and image (all of the same size).
struct FusionView {
  std::string name;   // for messages and the summary
  Camera camera;      // camera.width × camera.height is the size of depth and image_bgr
  cv::Mat depth;      // CV_32F, depth along the camera's z; kInvalidDepth (+inf) = no estimate
  cv::Mat image_bgr;  // CV_8UC3 (BGR) or CV_8UC1 (grey): the colours of the points
};

// Counts of one view's pass as the source view.
struct FusionViewSummary {
  std::string name;
  std::int64_t valid_pixels = 0;  // pixels with a valid depth (whole image)
  std::int64_t samples = 0;       // valid pixels on the stride grid
  std::int64_t consumed = 0;      // samples skipped: already part of an earlier view's point
  std::int64_t no_normal = 0;     // samples skipped: DepthMapNormals undefined there
  std::int64_t rejected = 0;      // samples with fewer than min_views agreeing views
  std::int64_t kept = 0;          // points emitted with this view as the source
  double mean_views_kept = 0.0;   // mean num_views of the kept points (0 when none)
};

// What a fusion did (for the log and report.json).
struct FusionSummary {
  std::vector<FusionViewSummary> views;  // in the order of the input views
  std::int64_t total_points = 0;
  double seconds = 0.0;  // wall-clock time, normals included

  nlohmann::json ToJson() const;
  std::string FullReport() const;
};

// Fuses the views' depth maps into one coloured, oriented point cloud in the world frame: the
// multi-view consistency check of COLMAP's stereo_fusion (Schönberger, Zheng, Frahm, Pollefeys,
// "Pixelwise View Selection for Unstructured Multi-View Stereo", ECCV 2016: filtering and
// fusion) and of Merrell et al.'s stability-based fusion ("Real-Time Visibility-Based Fusion of
// Depth Maps", ICCV 2007, where a depth is kept when enough views confirm it), simplified to be
// deterministic.
//
// Algorithm. The normals n_v of every view are computed once (DepthMapNormals with
// normal_radius_px). Each pixel of each view carries a "consumed" mark, initially clear. For every
// view s in input order and every source pixel p = (col, row) of s on the stride grid with a valid
// depth d_s(p), a defined normal and no consumed mark:
//   X = camera_s.BackProject(p, d_s(p)); count = 1;
//   for every other view j: project X into j (in front of the camera, inside the image); q = the
//     nearest pixel; view j agrees when d_j(q) is valid, |z_j(X) − d_j(q)| / d_j(q) <=
//     depth_tolerance and angle(n_s(p), n_j(q)) <= normal_tolerance_deg; then count += 1;
//   if count >= min_views, emit ONE point: position = mean of X and of camera_j.BackProject(q,
//     d_j(q)) over the agreeing views, colour = mean of the pixels' colours (stored RGB),
//     normal = the normalised mean of the normals, num_views = count, sigma = 0; and set the
//     consumed mark of every agreeing pixel q, so that the same surface patch is not emitted
//     again when view j becomes the source (without this, a surface seen by N views would appear
//     N times).
// Output order: views in input order, pixels in raster order.
//
// Deliberate deviations from COLMAP:
//   - no transitive traversal: a point gathers the source pixel and one pixel per other view
//     (COLMAP follows the agreeing pixels' own projections up to max_traversal_depth);
//   - a consumed pixel is never a source again, but it still votes (and contributes its 3D point)
//     for later source pixels of other views. So whether a source pixel agrees with view j does
//     not depend on the order of the pixels within a view, and the marks set by view s only act
//     on later views: the per-view pass runs in parallel over rows and the output bytes do not
//     depend on the thread count;
//   - no reprojection-error test (the depth test at the nearest pixel plays its part) and no
//     per-point maximum of fused pixels (at most one per view).
//
// Progress is reported after each source view; if the callback returns false, throws Error.
// Throws Error naming the view for: no views, a depth map that is not CV_32FC1, a depth map or
// image whose size is not the camera's, an image that is neither CV_8UC3 nor CV_8UC1, an invalid
// camera; ConfigError (options.Check()) for bad options.
OrientedPointCloud FuseDepthMaps(const std::vector<FusionView>& views, const FusionOptions& options,
                                 FusionSummary* summary = nullptr,
                                 const ProgressCallback& progress = {});

// The per-pixel unit normals of a depth map in the WORLD frame, CV_32FC3 (x, y, z), oriented
// towards the camera (n · (center − X) > 0). With X(c, r) the back-projection of pixel (c, r):
// the horizontal tangent is the difference to X(c + radius_px, r) or X(c − radius_px, r), the
// vertical one to X(c, r + radius_px) or X(c, r − radius_px); of each pair the valid pixel whose
// depth is closer to the pixel's depth is taken (so a pixel beside a depth step takes its tangent
// from its own surface), and the immediate neighbours (radius 1) when neither is valid;
// normal = horizontal × vertical, normalised. NaN in all three channels where the pixel's depth is
// invalid, where it has no valid horizontal or no valid vertical neighbour, or where the cross
// product vanishes. Throws Error for a depth map that is not CV_32FC1 or not of the camera's size,
// or radius_px outside [1, 16].
cv::Mat DepthMapNormals(const cv::Mat& depth, const Camera& camera, int radius_px = 1);

// Appends ground control points (WORLD coordinates, e.g. a laser scan in the cameras' frame) to a
// fused cloud: num_views = 0 marks them, sigma = gcps_world.sigma[i] (0 when gcps_world has no
// sigma channel). Normal and colour come from the fused points (num_views > 0) already in the
// cloud: normal = the normalised mean of the normals of the (up to) 8 nearest fused points
// (exact KD-tree search), colour = the nearest fused point's colour, so a GCP continues the
// surface it lies on. Throws Error when gcps_world is not empty but the cloud has no fused point,
// when gcps_world.sigma is neither empty nor one per point, or when the cloud's channels have
// different lengths.
void AppendGcpPoints(const PointCloud& gcps_world, OrientedPointCloud* cloud);

}  // namespace gcpstereo::fusion
