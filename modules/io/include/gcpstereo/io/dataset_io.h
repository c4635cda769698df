// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "gcpstereo/core/types.h"

namespace gcpstereo::io {

// What to load (configuration keys dataset.format, dataset.path, dataset.reference,
// dataset.neighbors, dataset.scale).
struct DatasetRequest {
  std::string format;                  // "strecha", "middlebury", "kitti_raw" or "colmap"
  std::string path;                    // the data set's folder (kitti_raw: the drive folder)
  std::string reference;               // reference view name ("0005", "im2", "0000000010")
  std::vector<std::string> neighbors;  // neighbour names; empty = all other views (kitti: ignored)
  double scale = 1.0;                  // image scale factor, valid range (0, 4]; paper: 0.5
  // false: the reference view (and its ground truth) only, `neighbors` ignored (strecha and
  // middlebury; kitti_raw always loads its pair): what a scene's fusion needs of each view.
  bool load_neighbors = true;
  // colmap only: the similarity [sR t; 0 1] that moves the model into the world frame
  // (TransformColmapModel) before its cameras are made; identity = the model's own frame
  // (dataset.align: none). Ignored by the other formats.
  Eigen::Matrix4d world_from_model = Eigen::Matrix4d::Identity();
};

// Loads a data set; throws IoError / Error naming the file and the problem for anything missing or
// malformed, and Error listing the valid names for an unknown view name.
//
// strecha     <path>/images/<name>.<ext> + <path>/cameras/<name>.<ext>.camera (any image extension
//             OpenCV reads). Image size must equal the camera's. With scale ≠ 1 images are resized
//             with INTER_AREA and cameras with Camera::Rescaled. Ground truth, if present
//             (synthetic sets): <path>/gt/<ref>.depth.pfm and <ref>.sigma.pfm (nearest-neighbour
//             resize; values unchanged). rectified = false, world_from_lidar = I.
// middlebury  2001 tsukuba (scene1.row3.colN.ppm, truedisp.row3.col3.pgm), 2001/2003 im0…im8
//             (disp2/disp6), 2005/2006 view0…view6 (disp1/disp5); masks nonocc/all/disc when
//             present. See middlebury_io.cc for the camera model and disparity scales.
// kitti_raw   <path> = <date>/<date>_drive_NNNN_sync, calibration from the parent folder; reference
//             = frame name, left image_02 = reference, right image_03 = the single neighbour.
// colmap      a COLMAP workspace as `colmap image_undistorter` writes it: <path>/images/<name> and
//             <path>/sparse/{cameras,images,points3D}.{bin,txt} (colmap_io.h). View names are the
//             model's image names ("0005.jpg", may contain sub-folders). PINHOLE and
//             SIMPLE_PINHOLE cameras are used as they are; SIMPLE_RADIAL, RADIAL, OPENCV and
//             FULL_OPENCV images are undistorted on load (View::undistorted,
//             View::source_camera_model); any other model is an error naming it and the camera
//             id. Each image must have its camera's size. Scale as for strecha; no ground truth.
//             rectified = false, world_from_lidar = I: the world frame is the model's, moved by
//             request.world_from_model (a scan's frame when dataset.align placed it there).
Dataset LoadDataset(const DatasetRequest& request);

// The individual loaders (LoadDataset dispatches to them).
Dataset LoadStrechaDataset(const DatasetRequest& request);
Dataset LoadMiddleburyDataset(const DatasetRequest& request);
Dataset LoadKittiRawDataset(const DatasetRequest& request);
Dataset LoadColmapDataset(const DatasetRequest& request);

// Names of the views a data set folder offers (sorted as the loader numbers them), for messages and
// for tools. Throws like the loaders when the folder is not a data set of that format.
std::vector<std::string> ListDatasetViews(const std::string& format, const std::string& path);

// <drive_path>/velodyne_points/data/<frame>.bin (not checked for existence).
std::string KittiVelodynePath(const std::string& drive_path, const std::string& frame);

// A Velodyne scan of a KITTI raw drive and its time relative to another frame's scan.
struct KittiScanTime {
  std::string frame;                     // "0000000030"
  std::string path;                      // <drive>/velodyne_points/data/<frame>.bin
  double seconds_after_reference = 0.0;  // < 0: earlier than the reference frame
};

// The scans of the drive nearest in time to `frame` on either side — at most one earlier and one
// later — taken within max_gap_s of it, for registering `frame`'s scan (gcp::EstimateSweepMotion).
// Times come from <drive>/velodyne_points/timestamps.txt when it exists (line k: the time of frame
// k, "YYYY-MM-DD hh:mm:ss.fffffffff"), else from the frame numbers at KITTI's 10 Hz. Throws IoError
// naming the file when timestamps.txt is malformed or too short, and for a frame name that is not
// a number.
std::vector<KittiScanTime> KittiNeighbourScans(const std::string& drive_path,
                                               const std::string& frame, double max_gap_s);

}  // namespace gcpstereo::io
