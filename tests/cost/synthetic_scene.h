// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// A small ray-cast scene for the cost tests: a textured fronto-parallel background plane and a
// slanted textured rectangle in front of it, seen by a reference camera and a few neighbours.
// Deterministic (hash-based value-noise texture, no random state).
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::cost::testing {

// Value noise on a square lattice of `cell` metres, smoothstep-interpolated, in [0, 1].
inline double Hash01(std::int64_t i, std::int64_t j, std::uint64_t seed) {
  std::uint64_t h =
      static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^
      (static_cast<std::uint64_t>(j) + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full ^
      seed * 0x165667B19E3779F9ull;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 29;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 32;
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53);
}

inline double ValueNoise(double u, double v, double cell, std::uint64_t seed) {
  const double x = u / cell, y = v / cell;
  const double fx = std::floor(x), fy = std::floor(y);
  const auto i = static_cast<std::int64_t>(fx), j = static_cast<std::int64_t>(fy);
  auto smooth = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double sx = smooth(x - fx), sy = smooth(y - fy);
  const double a = Hash01(i, j, seed), b = Hash01(i + 1, j, seed);
  const double c = Hash01(i, j + 1, seed), d = Hash01(i + 1, j + 1, seed);
  return (a + (b - a) * sx) * (1.0 - sy) + (c + (d - c) * sx) * sy;
}

struct Scene {
  // Background: plane z = background_depth (world = reference camera frame).
  double background_depth = 6.0;
  // Slanted rectangle: points X with n·X = offset, limited to x in [x_min, x_max], |y| <= y_half.
  Eigen::Vector3d slant_normal = Eigen::Vector3d(0.35, 0.1, -1.0).normalized();
  Eigen::Vector3d slant_point = Eigen::Vector3d(-0.5, 0.0, 4.0);
  double x_min = -1.5, x_max = 0.3, y_half = 0.7;
  double texture_cell_m = 0.06;

  // Nearest hit along the ray from `origin` in direction `dir`; returns false when nothing is hit.
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, Eigen::Vector3d* hit,
                 int* surface) const {
    double best = std::numeric_limits<double>::infinity();
    if (std::abs(dir.z()) > 1e-12) {
      const double t = (background_depth - origin.z()) / dir.z();
      if (t > 0.0) {
        best = t;
        *surface = 0;
      }
    }
    const double denom = slant_normal.dot(dir);
    if (std::abs(denom) > 1e-12) {
      const double t = slant_normal.dot(slant_point - origin) / denom;
      const Eigen::Vector3d p = origin + t * dir;
      if (t > 0.0 && t < best && p.x() >= x_min && p.x() <= x_max && std::abs(p.y()) <= y_half) {
        best = t;
        *surface = 1;
      }
    }
    if (!std::isfinite(best)) return false;
    *hit = origin + best * dir;
    return true;
  }

  // RGB texture (0…255 each) of a surface point.
  cv::Vec3b Color(const Eigen::Vector3d& p, int surface) const {
    cv::Vec3b out;
    for (int ch = 0; ch < 3; ++ch) {
      const std::uint64_t seed = 17 + 5 * ch + 101 * surface;
      const double v = 0.65 * ValueNoise(p.x(), p.y(), texture_cell_m, seed) +
                       0.35 * ValueNoise(p.x(), p.y(), 2.7 * texture_cell_m, seed + 1000);
      out[ch] = cv::saturate_cast<std::uint8_t>(20.0 + 215.0 * v);
    }
    return out;
  }

  // Renders a view; `depth` (optional) receives the camera-z depth of each pixel (+inf = none).
  View Render(const std::string& name, const Camera& camera, cv::Mat* depth = nullptr) const {
    View view;
    view.name = name;
    view.camera = camera;
    view.image = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(0, 0, 0));
    if (depth) *depth = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(kInvalidDepth));
    for (int row = 0; row < camera.height; ++row) {
      for (int col = 0; col < camera.width; ++col) {
        const Eigen::Vector3d target = camera.BackProject(Eigen::Vector2d(col, row), 1.0);
        const Eigen::Vector3d dir = (target - camera.center_world).normalized();
        Eigen::Vector3d hit;
        int surface = 0;
        if (!Intersect(camera.center_world, dir, &hit, &surface)) continue;
        view.image.at<cv::Vec3b>(row, col) = Color(hit, surface);
        if (depth) depth->at<float>(row, col) = static_cast<float>(camera.CameraFromWorld(hit).z());
      }
    }
    return view;
  }

  // True when world point `p` is the first surface that `camera` sees along its ray and projects
  // inside the image.
  bool Visible(const Camera& camera, const Eigen::Vector3d& p) const {
    Eigen::Vector2d pixel;
    double depth = 0.0;
    if (!camera.Project(p, &pixel, &depth) || !camera.InImage(pixel)) return false;
    const Eigen::Vector3d dir = (p - camera.center_world).normalized();
    Eigen::Vector3d hit;
    int surface = 0;
    if (!Intersect(camera.center_world, dir, &hit, &surface)) return false;
    return (hit - p).norm() < 1e-6 * (1.0 + p.norm());
  }
};

// A camera at `center` looking at `target` (y down in the image, roughly world y down).
inline Camera LookAtCamera(const Eigen::Vector3d& center, const Eigen::Vector3d& target,
                           double focal_px, int width, int height) {
  Camera camera;
  camera.K << focal_px, 0.0, (width - 1) / 2.0, 0.0, focal_px, (height - 1) / 2.0, 0.0, 0.0, 1.0;
  const Eigen::Vector3d z = (target - center).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  camera.world_from_camera_rotation.col(0) = x;
  camera.world_from_camera_rotation.col(1) = y;
  camera.world_from_camera_rotation.col(2) = z;
  camera.center_world = center;
  camera.width = width;
  camera.height = height;
  return camera;
}

}  // namespace gcpstereo::cost::testing
