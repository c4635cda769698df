// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// output.colmap: the depth maps of a run as a COLMAP dense workspace, the folder layout that
// `colmap image_undistorter` and `colmap patch_match_stereo` leave and that `colmap stereo_fusion`
// and `colmap poisson_mesher` / `delaunay_mesher` read (https://colmap.github.io/format.html):
//
//   images/<image>                          the views' images as the run used them (dataset.scale
//                                           applied, undistorted where the loader undistorted)
//   sparse/cameras.txt, images.txt,         one PINHOLE camera per view, the views' poses, and a
//          points3D.txt                     sparse cloud sampled from the depth maps (below)
//   stereo/depth_maps/<image>.geometric.bin  the depth map (io/colmap_dense_io.h; 0 = no estimate)
//   stereo/normal_maps/<image>.geometric.bin its normals in the camera frame
//   stereo/fusion.cfg                       the images with a depth map, one per line
//   stereo/patch-match.cfg                  per such image: its name, then its source images
//
// <image> is the view's name with ".png" appended unless it already ends in ".png" (Strecha's
// 0005 → 0005.png; a COLMAP model's 0005.jpg → 0005.jpg.png): every image is written as a lossless
// PNG of exactly the pixels gcpstereo matched.
//
// Why the sparse cloud. stereo_fusion decides which images to check a pixel against from the
// sparse model alone: the images that share 3D points with it (Model::GetMaxOverlappingImages).
// Without points3D it fuses nothing. So every `step`-th pixel of each depth map (step chosen so
// that a view gives at most ColmapExportOptions::max_points_per_view) becomes a 3D point observed
// by its own view and by every other view in which it projects inside the image and in front of
// the camera and — when that view has a depth map — agrees with it within depth_tolerance (the
// fusion's own test; a view without a depth map, a single run's neighbour, is tested on its
// frustum only). Points that only their own view observes are dropped unless the workspace has a
// single image. Keypoints are the exact projections (error 0).
//
// Conventions. COLMAP's sparse model puts the centre of the top-left pixel at (0.5, 0.5), so
// cx, cy are written as the project's K(0, 2), K(1, 2) + 0.5 (the inverse of io::MakeColmapPinhole:
// the workspace read back as dataset.format colmap has the run's cameras). COLMAP's dense code
// (patch_match_stereo, stereo_fusion) then back-projects depth-map pixel (col, row) through
// K⁻¹ (col, row, 1), half a pixel from its sparse convention: the points stereo_fusion makes of
// any depth map, its own or these, lie half a pixel's footprint (depth / 2f) off the rays the
// sparse model defines. The poses are COLMAP's camera_from_world (q, t = −R C).
//
// Normals: fusion::DepthMapNormals (fusion.normal_radius_px, the normals gcpstereo's own fusion
// uses), rotated into the camera frame; where it has none at a valid depth (an isolated pixel, a
// one-pixel-wide strip) the unit vector from the point towards the camera stands in; 0 where the
// depth is invalid.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/io/colmap_io.h"
#include "gcpstereo/pipeline/pipeline_config.h"

namespace gcpstereo::pipeline::internal {

// One view of the workspace.
struct ColmapExportView {
  std::string name;   // gcpstereo's view name
  Camera camera;      // as the run used it
  cv::Mat image_bgr;  // CV_8UC3 or CV_8UC1, the camera's size
  cv::Mat depth;      // CV_32F, the camera's size, kInvalidDepth = none; empty = an image
                      // without a depth map (a single run's neighbour: sparse model and images
                      // only)
  std::vector<std::string> sources;  // patch-match.cfg's source images: names of other views of
                                     // the workspace (others are skipped); empty = "__auto__, 20"
};

struct ColmapExportOptions {
  int normal_radius_px = 2;        // fusion.normal_radius_px
  double depth_tolerance = 0.01;   // fusion.depth_tolerance (relative)
  int max_points_per_view = 2000;  // sparse points sampled per depth map, at most
};
// The options of a run's configuration (fusion.normal_radius_px, fusion.depth_tolerance).
ColmapExportOptions ColmapExportOptionsOf(const PipelineConfig& options);

// The image name of a view in the workspace (see above).
std::string ColmapImageName(const std::string& view_name);

// The workspace in memory: the sparse model, and per view with a depth map its COLMAP depth
// (0 = none) and camera-frame normals (CV_32FC3). Pure; throws Error naming the view for an image,
// depth map or camera of mismatched size, a camera with skew (PINHOLE has none), duplicate names.
struct ColmapWorkspace {
  io::ColmapModel model;
  std::vector<std::string> image_names;  // per view, in input order
  std::vector<cv::Mat> depth;            // per view; empty without a depth map
  std::vector<cv::Mat> normals;          // per view; empty without a depth map
  std::string fusion_cfg;
  std::string patch_match_cfg;
};
ColmapWorkspace MakeColmapWorkspace(const std::vector<ColmapExportView>& views,
                                    const ColmapExportOptions& options);

// Writes MakeColmapWorkspace's result into `dir` (created, with its sub-folders; every file
// written atomically — callers stage `dir` inside an OutputFolder, so that a killed run leaves no
// part of it under its final name). Returns report.json's "colmap" entry (counts).
nlohmann::json WriteColmapWorkspace(const std::string& dir,
                                    const std::vector<ColmapExportView>& views,
                                    const ColmapExportOptions& options);

}  // namespace gcpstereo::pipeline::internal
