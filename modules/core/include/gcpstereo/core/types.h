// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"

namespace gcpstereo {

// Depth and disparity maps are cv::Mat of CV_32F; this value marks "no estimate / unknown".
inline constexpr float kInvalidDepth = std::numeric_limits<float>::infinity();

inline bool IsValidDepth(float depth) { return std::isfinite(depth) && depth > 0.0f; }

// One calibrated image. `image` is CV_8UC3 in OpenCV's BGR channel order.
struct View {
  std::string name;
  cv::Mat image;
  Camera camera;
  // Where the camera came from, for the report: the source's camera model (COLMAP's "PINHOLE",
  // "OPENCV", …; empty for formats with one model) and whether the loader undistorted the image
  // into `camera` (then `image` is the undistorted image).
  std::string source_camera_model;
  bool undistorted = false;
};

// Ground truth that a data set may carry for its reference view. Empty Mats mean "not available".
struct GroundTruth {
  cv::Mat depth;            // CV_32F, depth along the reference camera's z; kInvalidDepth = unknown
  cv::Mat sigma;            // CV_32F, per-pixel standard deviation of `depth` (laser sigma)
  cv::Mat disparity;        // CV_32F, rectified data: disparity in the data set's GT convention;
                            // kInvalidDepth = unknown
  cv::Mat disparity_right;  // CV_32F, the right view's GT disparity where the set has one
  cv::Mat mask_nonocc;      // CV_8U, 255 = counted (Middlebury v2 masks where available)
  cv::Mat mask_all;         // CV_8U, 255 = counted
  cv::Mat mask_disc;  // CV_8U, 255 = near a discontinuity, 128 = other non-occluded, 0 = excluded

  bool HasDepth() const { return !depth.empty(); }
  bool HasDisparity() const { return !disparity.empty(); }
};

// A point cloud in some frame (see where it is produced). Optional per-point channels are either
// empty or of the same length as `points`.
struct PointCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> sigma;      // per-point range standard deviation (simulated laser scans)
  std::vector<float> intensity;  // reflectance (KITTI) or intensity

  size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
};

// A coloured, oriented point cloud in the world frame: the fused points of a scene (fusion
// module), the input of the scene mesh. All channels have one entry per point.
struct OrientedPointCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;                   // unit length, towards the cameras
  std::vector<Eigen::Matrix<std::uint8_t, 3, 1>> colors;  // RGB, 0…255
  std::vector<std::uint16_t> num_views;  // views whose depth maps agree on the point; 0 = a GCP
  std::vector<float> sigma;              // a GCP's measured standard deviation; 0 = fused point

  size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
};

// Where a ground control point came from (paper §4.1: image matches; §4.2: laser scan; §1's
// "structure from motion point clouds": a COLMAP model's 3D points).
enum class GcpSource : std::uint8_t { kLidar = 0, kDepthMap = 1, kStereo = 2, kSfm = 3 };
const char* GcpSourceName(GcpSource source);

// A ground control point of the reference view: a pixel with a measured depth.
struct Gcp {
  int col = 0;
  int row = 0;
  double depth = 0.0;  // along the reference camera's z, in the data set's unit (metres)
  double sigma = 0.0;  // standard deviation of `depth` (same unit); 0 when unknown
  GcpSource source = GcpSource::kLidar;
};

struct GcpSet {
  std::vector<Gcp> points;
  size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
};

// A loaded data set: the reference view, its neighbours, and what else the set provides.
struct Dataset {
  std::string format;  // "strecha", "middlebury", "kitti_raw", "colmap"
  std::string path;
  View reference;
  std::vector<View> neighbors;
  // Rectified data (middlebury, kitti_raw): all cameras share orientation and intrinsics and differ
  // by a shift along x. Disparity in the data set's ground-truth convention is
  // disparity_numerator / depth.
  bool rectified = false;
  double disparity_numerator = 0.0;
  // Maps range-sensor coordinates to the world frame of the cameras: identity for strecha (the
  // laser defines the world frame), the Velodyne-to-rectified-camera transform for kitti_raw.
  Eigen::Matrix4d world_from_lidar = Eigen::Matrix4d::Identity();
  GroundTruth ground_truth;
};

}  // namespace gcpstereo

namespace gcpstereo {

// An indexed triangle mesh with optional per-vertex colours (RGB, 0…255).
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Matrix<std::uint8_t, 3, 1>> colors;  // empty or one per vertex
  std::vector<Eigen::Vector3i> faces;                     // counter-clockwise seen from outside
};

}  // namespace gcpstereo
