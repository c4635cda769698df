// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/camera.h"

#include <cmath>
#include <sstream>

#include <Eigen/LU>

#include "gcpstereo/core/error.h"

namespace gcpstereo {

bool Camera::Project(const Eigen::Vector3d& point_world, Eigen::Vector2d* pixel,
                     double* depth) const {
  const Eigen::Vector3d p = CameraFromWorld(point_world);
  if (!(p.z() > 0.0)) return false;
  const Eigen::Vector3d h = K * p;
  *pixel = h.head<2>() / h.z();
  *depth = p.z();
  return true;
}

Eigen::Vector3d Camera::BackProject(const Eigen::Vector2d& pixel, double depth) const {
  const Eigen::Vector3d ray = K.inverse() * Eigen::Vector3d(pixel.x(), pixel.y(), 1.0);
  return WorldFromCamera(ray * (depth / ray.z()));
}

Eigen::Matrix<double, 3, 4> Camera::ProjectionMatrix() const {
  Eigen::Matrix<double, 3, 4> Rt;
  const Eigen::Matrix3d camera_from_world = world_from_camera_rotation.transpose();
  Rt.leftCols<3>() = camera_from_world;
  Rt.col(3) = -camera_from_world * center_world;
  return K * Rt;
}

Camera Camera::Rescaled(double scale) const {
  Camera out = *this;
  // x' = s (x + 0.5) − 0.5 with x = fx X/Z + s_k Y/Z + cx  ⇒ fx' = s fx, skew' = s skew,
  // cx' = s (cx + 0.5) − 0.5, and likewise for y.
  out.K(0, 0) *= scale;
  out.K(0, 1) *= scale;
  out.K(1, 1) *= scale;
  out.K(0, 2) = scale * (K(0, 2) + 0.5) - 0.5;
  out.K(1, 2) = scale * (K(1, 2) + 0.5) - 0.5;
  out.width = static_cast<int>(std::lround(width * scale));
  out.height = static_cast<int>(std::lround(height * scale));
  return out;
}

void Camera::Validate(const std::string& context) const {
  auto fail = [&](const std::string& problem) { throw Error(context + ": " + problem); };
  if (!K.allFinite()) fail("intrinsic matrix K has non-finite entries");
  if (!(K(0, 0) > 0.0) || !(K(1, 1) > 0.0)) {
    std::ostringstream s;
    s << "focal lengths must be positive, got fx = " << K(0, 0) << ", fy = " << K(1, 1);
    fail(s.str());
  }
  if (K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || std::abs(K(2, 2) - 1.0) > 1e-9) {
    fail("intrinsic matrix K must be upper triangular with K(2,2) = 1");
  }
  const Eigen::Matrix3d& R = world_from_camera_rotation;
  if (!R.allFinite()) fail("rotation has non-finite entries");
  const double orthogonality_error =
      (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality_error > 1e-3) {
    std::ostringstream s;
    s << "rotation is not orthonormal (max |RᵀR − I| = " << orthogonality_error
      << ", tolerance 1e-3)";
    fail(s.str());
  }
  const double det = R.determinant();
  if (std::abs(det - 1.0) > 1e-3) {
    std::ostringstream s;
    s << "rotation determinant is " << det << ", expected +1 within 1e-3";
    fail(s.str());
  }
  if (!center_world.allFinite()) fail("camera centre has non-finite entries");
  if (width <= 0 || height <= 0) {
    std::ostringstream s;
    s << "image size must be positive, got " << width << "x" << height;
    fail(s.str());
  }
}

Camera RectifiedSequenceCamera(double focal_px, double cx, double cy, double baseline_per_view,
                               int index, int width, int height) {
  Camera camera;
  camera.K << focal_px, 0.0, cx, 0.0, focal_px, cy, 0.0, 0.0, 1.0;
  camera.center_world = Eigen::Vector3d(index * baseline_per_view, 0.0, 0.0);
  camera.width = width;
  camera.height = height;
  return camera;
}

}  // namespace gcpstereo
