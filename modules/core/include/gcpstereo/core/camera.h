// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include <Eigen/Core>

namespace gcpstereo {

// A pinhole camera without distortion (Strecha's images are undistorted; Middlebury and KITTI are
// rectified). Conventions:
//   - pixel coordinates: x to the right, y down, the centre of pixel (col, row) at (col, row);
//   - camera frame: x right, y down, z forward (depth = z of the point in the camera frame);
//   - world_from_camera_rotation is Strecha's R (camera-to-world), center_world its C, so
//     X_camera = Rᵀ (X_world − C) and x ~ K X_camera.
struct Camera {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d world_from_camera_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center_world = Eigen::Vector3d::Zero();
  int width = 0;
  int height = 0;

  Eigen::Vector3d CameraFromWorld(const Eigen::Vector3d& point_world) const {
    return world_from_camera_rotation.transpose() * (point_world - center_world);
  }
  Eigen::Vector3d WorldFromCamera(const Eigen::Vector3d& point_camera) const {
    return world_from_camera_rotation * point_camera + center_world;
  }

  // Projects a world point. Returns false (leaving outputs untouched) when the point is not in
  // front of the camera (depth <= 0). Does not test the image bounds: see InImage().
  bool Project(const Eigen::Vector3d& point_world, Eigen::Vector2d* pixel, double* depth) const;

  // The world point at `depth` (camera z) seen through `pixel`.
  Eigen::Vector3d BackProject(const Eigen::Vector2d& pixel, double depth) const;

  // True when the pixel lies inside the image (pixel centres 0 … width−1, with half a pixel
  // margin).
  bool InImage(const Eigen::Vector2d& pixel) const {
    return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < width - 0.5 &&
           pixel.y() < height - 0.5;
  }

  // 3×4 matrix P = K [Rᵀ | −Rᵀ C] with x ~ P X_world.
  Eigen::Matrix<double, 3, 4> ProjectionMatrix() const;

  // The same camera for the image resized by `scale` (e.g. 0.5 for half resolution). Keeps the
  // pixel-centre convention: x' = scale · (x + 0.5) − 0.5. Width and height are rounded.
  Camera Rescaled(double scale) const;

  // Throws Error(context + ": ...") unless K has positive focal lengths and finite entries,
  // the rotation is orthonormal with det +1 within 1e-3, the centre is finite and the size
  // positive.
  void Validate(const std::string& context) const;
};

// The camera of view `index` of a rectified sequence whose views are equally spaced along x:
// identity rotation, centre (index · baseline_per_view, 0, 0). With focal length f (pixels), a
// point at depth z then has disparity f · baseline_per_view / z per view step, so Middlebury
// sequences run through the same plane-sweep code as calibrated Strecha views.
Camera RectifiedSequenceCamera(double focal_px, double cx, double cy, double baseline_per_view,
                               int index, int width, int height);

}  // namespace gcpstereo
