// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// Synthetic fixtures shared by the mesh tests.

#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "gcpstereo/core/types.h"
#include "gcpstereo/synth/generator.h"

namespace gcpstereo::mesh::testing {

// A camera with a general rotation and centre (not the identity, to catch frame mix-ups).
inline Camera TiltedCamera(int width, int height, double focal_px) {
  Camera camera;
  camera.K << focal_px, 0.0, 0.5 * (width - 1) + 1.3, 0.0, focal_px * 1.02,
      0.5 * (height - 1) - 0.7, 0.0, 0.0, 1.0;
  camera.world_from_camera_rotation =
      (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(-0.3, Eigen::Vector3d(1.0, 0.2, 0.1).normalized()))
          .toRotationMatrix();
  camera.center_world = Eigen::Vector3d(1.5, -2.0, 0.7);
  camera.width = width;
  camera.height = height;
  return camera;
}

// The depth map of the world plane {X : n·X = d} seen by `camera` (+inf where the ray misses it or
// the plane is behind the camera).
inline cv::Mat PlaneDepth(const Camera& camera, const Eigen::Vector3d& normal_world,
                          double offset) {
  cv::Mat depth(camera.height, camera.width, CV_32F);
  const Eigen::Matrix3d k_inverse = camera.K.inverse();
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 0; col < camera.width; ++col) {
      const Eigen::Vector3d ray_camera = k_inverse * Eigen::Vector3d(col, row, 1.0);
      const Eigen::Vector3d ray_world = camera.world_from_camera_rotation * ray_camera;
      // n·(C + t r) = d  →  t = (d − n·C) / (n·r); depth = t · r_camera.z.
      const double t =
          (offset - normal_world.dot(camera.center_world)) / normal_world.dot(ray_world);
      depth.at<float>(row, col) =
          t > 0.0 ? static_cast<float>(t * ray_camera.z()) : std::numeric_limits<float>::infinity();
    }
  }
  return depth;
}

// An image whose pixel (col, row) is BGR (col, row, 7), so colours identify pixels.
inline cv::Mat CoordinateImage(int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      image.at<cv::Vec3b>(row, col) =
          cv::Vec3b(static_cast<std::uint8_t>(col), static_cast<std::uint8_t>(row), 7);
    }
  }
  return image;
}

// The synthetic "tiny" courtyard (generated once per test executable).
inline const synth::SyntheticScene& TinyScene() {
  static const synth::SyntheticScene scene = [] {
    synth::SynthOptions options;
    options.preset = "tiny";
    return synth::GenerateScene(options);
  }();
  return scene;
}

}  // namespace gcpstereo::mesh::testing
