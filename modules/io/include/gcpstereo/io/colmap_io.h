// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// COLMAP sparse models (Schönberger & Frahm, "Structure-from-Motion Revisited", CVPR 2016), read
// from the binary (.bin) or text (.txt) files that COLMAP writes, after the format description at
// https://colmap.github.io/format.html, and turned into the project's pinhole cameras.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"

namespace gcpstereo::io {

// One entry of cameras.{bin,txt}: a COLMAP camera model and its parameters, in COLMAP's pixel
// convention (the image's top-left corner at (0, 0), the centre of pixel (col, row) at
// (col + 0.5, row + 0.5)).
struct ColmapCamera {
  std::uint32_t camera_id = 0;
  int model_id = -1;       // COLMAP's id: 0 SIMPLE_PINHOLE, 1 PINHOLE, 2 SIMPLE_RADIAL, …
  std::string model_name;  // "PINHOLE", "OPENCV", …
  std::uint64_t width = 0;
  std::uint64_t height = 0;
  std::vector<double> params;  // as COLMAP orders them (e.g. OPENCV: fx fy cx cy k1 k2 p1 p2)
};

// A keypoint of an image and the 3D point it observes (kNoPoint3D: none).
struct ColmapPoint2D {
  static constexpr std::uint64_t kNoPoint3D =
      ~std::uint64_t{0};                                   // COLMAP writes -1 (text) or 2⁶⁴−1
  Eigen::Vector2d xy_colmap_px = Eigen::Vector2d::Zero();  // COLMAP's pixel convention (above)
  std::uint64_t point3d_id = kNoPoint3D;
  bool HasPoint3D() const { return point3d_id != kNoPoint3D; }
};

// One entry of images.{bin,txt}: a registered image's pose and its keypoints. The pose is
// COLMAP's camera_from_world: X_camera = R(q) X_world + t, q = (w, x, y, z) a unit quaternion.
struct ColmapImage {
  std::uint32_t image_id = 0;
  Eigen::Vector4d qvec_wxyz = Eigen::Vector4d(1, 0, 0, 0);
  Eigen::Vector3d tvec = Eigen::Vector3d::Zero();
  std::uint32_t camera_id = 0;
  std::string name;  // relative to the workspace's images/ folder; may contain sub-folders
  std::vector<ColmapPoint2D> points2d;

  // camera_from_world rotation R(q) (q normalised first).
  Eigen::Matrix3d CameraFromWorldRotation() const;
  // The camera centre in world coordinates, −Rᵀ t.
  Eigen::Vector3d CenterWorld() const;
};

// One observation of a 3D point: the image and the index of the keypoint in its points2d.
struct ColmapTrackElement {
  std::uint32_t image_id = 0;
  std::uint32_t point2d_idx = 0;
};

// One entry of points3D.{bin,txt}.
struct ColmapPoint3D {
  std::uint64_t point3d_id = 0;
  Eigen::Vector3d xyz_world = Eigen::Vector3d::Zero();
  std::array<std::uint8_t, 3> rgb = {0, 0, 0};
  double error_px = 0.0;  // mean reprojection error, pixels
  std::vector<ColmapTrackElement> track;
};

// A sparse model: cameras, registered images and 3D points, each keyed by its COLMAP id (sorted,
// so iteration order is reproducible).
struct ColmapModel {
  std::string sparse_dir;  // the folder it was read from
  std::map<std::uint32_t, ColmapCamera> cameras;
  std::map<std::uint32_t, ColmapImage> images;
  std::map<std::uint64_t, ColmapPoint3D> points3d;

  // The image with this name, nullptr when there is none.
  const ColmapImage* FindImage(const std::string& name) const;
  // The image names, sorted.
  std::vector<std::string> ImageNames() const;
};

// Reads <sparse_dir>/{cameras,images,points3D}, each from its .bin file when it exists, else from
// its .txt file. Throws IoError naming the file for a missing file ("<dir>: no cameras.bin or
// cameras.txt"), a truncated or corrupt binary file (every count is checked against the bytes
// left before anything is allocated; nothing is read past the end; trailing bytes are an error),
// an unparsable text line ("line N: …"), an unknown model id or name (naming the camera id), a
// model whose parameter count is wrong, duplicate ids, and references to cameras, images or
// keypoints that do not exist.
ColmapModel ReadColmapModel(const std::string& sparse_dir);

// The camera models gcpstereo turns into pinhole cameras: SIMPLE_PINHOLE and PINHOLE directly;
// SIMPLE_RADIAL, RADIAL, OPENCV and FULL_OPENCV by undistorting the image (their distortion is
// OpenCV's with the remaining coefficients zero).
bool IsSupportedColmapCameraModel(const std::string& model_name);

// A COLMAP camera as a pinhole camera of the same image size, and the maps that undistort its
// images into that camera (empty for pinhole models).
//
// Choice of the new camera matrix: cv::getOptimalNewCameraMatrix with alpha = 0, i.e. the pinhole
// camera whose every pixel sees image content (no black border, which the plane sweep would
// match as if it were scene texture); the image keeps its size, so the focal length grows slightly
// for barrel distortion. The distorted camera's own K would keep the focal length but leave
// unobserved border pixels.
struct ColmapPinhole {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // the project's convention (pixel centres at
                                                    // integers): COLMAP's cx, cy minus 0.5
  int width = 0;
  int height = 0;
  bool undistorted = false;  // true: remap images with map_x / map_y (CV_32FC1)
  cv::Mat map_x, map_y;
  std::string model_name;
};

// Throws IoError(context, …) naming the camera id and model for an unsupported model.
ColmapPinhole MakeColmapPinhole(const ColmapCamera& camera, const std::string& context);

// The image undistorted into the pinhole camera (bilinear; returned unchanged when
// !pinhole.undistorted). Its size must be the camera's.
cv::Mat UndistortColmapImage(const cv::Mat& image, const ColmapPinhole& pinhole);

// The project's camera of a registered image: pinhole.K, the size, and COLMAP's pose converted
// (world_from_camera_rotation = R(q)ᵀ, center_world = −R(q)ᵀ t).
Camera ColmapImageCamera(const ColmapImage& image, const ColmapPinhole& pinhole);

// Writes <sparse_dir>/cameras.txt, images.txt and points3D.txt in COLMAP's text format (the
// format ReadColmapModel reads, with COLMAP's comment headers), each file atomically; numbers with
// 17 significant digits, so a model read back is the same to the last bit; keypoints without a 3D
// point as −1. `sparse_dir` must exist. Throws IoError naming the file for an I/O failure, and for
// a model that ReadColmapModel would refuse: a camera whose model name or parameter count is not
// COLMAP's, an image name that is empty, holds a line break or begins or ends with a blank, and
// references to cameras, images, keypoints or 3D points that do not exist.
void WriteColmapModelText(const std::string& sparse_dir, const ColmapModel& model);

// <path>/sparse: the model folder of a workspace as `colmap image_undistorter` writes it.
std::string ColmapSparseDir(const std::string& workspace);

// Moves a model into another frame, x_world = M x_model for a similarity M = [sR t; 0 1]
// (world_from_model, e.g. the result of dataset.align): every 3D point, and every image's pose so
// that its camera keeps its intrinsics and sees the same image (camera_from_world R' = R Rᵀ_M,
// t' = s t − R' t_M: the camera frame scales with the world, so depths scale by s). Throws Error
// unless M is a similarity (s > 0, R a rotation within 1e-6, last row 0 0 0 1).
void TransformColmapModel(const Eigen::Matrix4d& world_from_model, ColmapModel* model);

// Known camera centres in COLMAP model_aligner's convention: one "<image name> X Y Z" per line
// (the name may contain spaces: the last three fields are the coordinates); empty lines and lines
// starting with # are skipped. Returned in the file's order. Throws IoError naming the file and
// line for a malformed line, a non-finite coordinate or a name listed twice, and for a file
// without any centre.
struct KnownCentre {
  std::string name;
  Eigen::Vector3d center_world = Eigen::Vector3d::Zero();
};
std::vector<KnownCentre> ReadKnownCentres(const std::string& path);

}  // namespace gcpstereo::io
