// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/render.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "common.h"
#include "gcpstereo/core/error.h"

namespace gcpstereo::eval {
namespace {

void CheckCamera(const Camera& camera, const std::string& what) {
  if (camera.width <= 0 || camera.height <= 0) {
    throw Error(what + ": the camera has no image size (" + std::to_string(camera.width) + "x" +
                std::to_string(camera.height) + ")");
  }
}

std::int64_t CountFinite(const cv::Mat& depth) {
  std::int64_t n = 0;
  for (int row = 0; row < depth.rows; ++row) {
    const float* d = depth.ptr<float>(row);
    for (int col = 0; col < depth.cols; ++col) n += std::isfinite(d[col]) ? 1 : 0;
  }
  return n;
}

// Twice the signed area of (a, b, p): positive when p is left of a→b in image coordinates.
inline double Edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double px, double py) {
  return (b.x() - a.x()) * (py - a.y()) - (b.y() - a.y()) * (px - a.x());
}

}  // namespace

nlohmann::json RenderSummary::ToJson() const {
  nlohmann::json j;
  j["primitives"] = primitives;
  j["skipped_behind"] = skipped_behind;
  j["skipped_degenerate"] = skipped_degenerate;
  j["pixels_covered"] = pixels_covered;
  return j;
}

void RenderMeshOptions::Check() const {
  if (!(near_depth >= 0.0) || !std::isfinite(near_depth)) {
    throw ConfigError(ViolatedConstraint("eval.render.near_depth",
                                         internal::FormatDouble(near_depth),
                                         "finite and near_depth >= 0"));
  }
  if (std::isnan(sigma)) {
    throw ConfigError(ViolatedConstraint("eval.render.mesh_sigma", "nan", "a number"));
  }
}

void RenderPointsOptions::Check() const {
  if (splat_radius_px < 0 || splat_radius_px > 16) {
    throw ConfigError(ViolatedConstraint("eval.render.splat_radius_px",
                                         std::to_string(splat_radius_px),
                                         "0 <= splat_radius_px <= 16"));
  }
  if (std::isnan(default_sigma)) {
    throw ConfigError(ViolatedConstraint("eval.render.default_sigma", "nan", "a number"));
  }
}

RenderedDepth RenderMeshDepth(const TriangleMesh& mesh, const Camera& camera,
                              const RenderMeshOptions& options) {
  options.Check();
  CheckCamera(camera, "RenderMeshDepth");
  const int width = camera.width, height = camera.height;
  RenderedDepth out;
  out.depth = cv::Mat(height, width, CV_32FC1, cv::Scalar(kInvalidDepth));
  out.summary.primitives = static_cast<std::int64_t>(mesh.faces.size());
  const int num_vertices = static_cast<int>(mesh.vertices.size());
  // z-buffer in double so that the nearest surface is decided before rounding to float.
  cv::Mat zbuffer(height, width, CV_64FC1, cv::Scalar(std::numeric_limits<double>::infinity()));
  for (const Eigen::Vector3i& face : mesh.faces) {
    bool bad_index = false;
    for (int k = 0; k < 3; ++k) bad_index |= face[k] < 0 || face[k] >= num_vertices;
    if (bad_index || face[0] == face[1] || face[1] == face[2] || face[0] == face[2]) {
      ++out.summary.skipped_degenerate;
      continue;
    }
    Eigen::Vector2d pixel[3];
    double z[3];
    bool behind = false;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d cam = camera.CameraFromWorld(mesh.vertices[face[k]].cast<double>());
      z[k] = cam.z();
      if (!(z[k] > options.near_depth)) {
        behind = true;
        break;
      }
      const Eigen::Vector3d h = camera.K * cam;
      pixel[k] = h.head<2>() / h.z();
    }
    if (behind) {
      ++out.summary.skipped_behind;
      continue;
    }
    const double area = Edge(pixel[0], pixel[1], pixel[2].x(), pixel[2].y());
    if (!(std::abs(area) > 1e-12)) {  // seen edge-on: covers no pixel centre in a stable way
      ++out.summary.skipped_degenerate;
      continue;
    }
    const double min_x = std::min({pixel[0].x(), pixel[1].x(), pixel[2].x()});
    const double max_x = std::max({pixel[0].x(), pixel[1].x(), pixel[2].x()});
    const double min_y = std::min({pixel[0].y(), pixel[1].y(), pixel[2].y()});
    const double max_y = std::max({pixel[0].y(), pixel[1].y(), pixel[2].y()});
    const int col0 = static_cast<int>(std::max(0.0, std::ceil(min_x)));
    const int col1 = static_cast<int>(std::min(width - 1.0, std::floor(max_x)));
    const int row0 = static_cast<int>(std::max(0.0, std::ceil(min_y)));
    const int row1 = static_cast<int>(std::min(height - 1.0, std::floor(max_y)));
    // Pixel centres exactly on an edge (up to rounding) count as inside: no cracks between faces.
    constexpr double kTolerance = 1e-9;
    for (int row = row0; row <= row1; ++row) {
      double* zrow = zbuffer.ptr<double>(row);
      for (int col = col0; col <= col1; ++col) {
        // Barycentrics b_k (weight of vertex k), sign-normalised by the area.
        double b0 = Edge(pixel[1], pixel[2], col, row) / area;
        double b1 = Edge(pixel[2], pixel[0], col, row) / area;
        double b2 = Edge(pixel[0], pixel[1], col, row) / area;
        if (b0 < -kTolerance || b1 < -kTolerance || b2 < -kTolerance) continue;
        b0 = std::max(b0, 0.0);
        b1 = std::max(b1, 0.0);
        b2 = std::max(b2, 0.0);
        const double sum = b0 + b1 + b2;
        const double inverse_depth = (b0 / z[0] + b1 / z[1] + b2 / z[2]) / sum;
        const double depth = 1.0 / inverse_depth;
        if (depth < zrow[col]) zrow[col] = depth;
      }
    }
  }
  zbuffer.convertTo(out.depth, CV_32F);
  out.summary.pixels_covered = CountFinite(out.depth);
  if (options.sigma > 0.0) {
    out.sigma = cv::Mat(height, width, CV_32FC1, cv::Scalar(kInvalidDepth));
    out.sigma.setTo(cv::Scalar(options.sigma), out.depth < std::numeric_limits<float>::max());
  }
  return out;
}

RenderedDepth RenderPointDepth(const PointCloud& cloud, const Camera& camera,
                               const Eigen::Matrix4d& world_from_cloud,
                               const RenderPointsOptions& options) {
  options.Check();
  CheckCamera(camera, "RenderPointDepth");
  const bool per_point_sigma = !cloud.sigma.empty();
  if (per_point_sigma && cloud.sigma.size() != cloud.points.size()) {
    throw Error("RenderPointDepth: the cloud has " + std::to_string(cloud.points.size()) +
                " points but " + std::to_string(cloud.sigma.size()) + " sigma values");
  }
  const bool with_sigma = per_point_sigma || options.default_sigma > 0.0;
  const int width = camera.width, height = camera.height;
  RenderedDepth out;
  out.depth = cv::Mat(height, width, CV_32FC1, cv::Scalar(kInvalidDepth));
  if (with_sigma) out.sigma = cv::Mat(height, width, CV_32FC1, cv::Scalar(kInvalidDepth));
  out.summary.primitives = static_cast<std::int64_t>(cloud.size());
  cv::Mat zbuffer(height, width, CV_64FC1, cv::Scalar(std::numeric_limits<double>::infinity()));
  const Eigen::Matrix3d rotation = world_from_cloud.topLeftCorner<3, 3>();
  const Eigen::Vector3d translation = world_from_cloud.topRightCorner<3, 1>();
  const int r = options.splat_radius_px;
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3d world = rotation * cloud.points[i].cast<double>() + translation;
    Eigen::Vector2d pixel;
    double depth = 0.0;
    if (!camera.Project(world, &pixel, &depth)) {
      ++out.summary.skipped_behind;
      continue;
    }
    if (!std::isfinite(pixel.x()) || !std::isfinite(pixel.y())) continue;
    const double col_center = std::floor(pixel.x() + 0.5);
    const double row_center = std::floor(pixel.y() + 0.5);
    if (col_center < -r || row_center < -r || col_center > width - 1 + r ||
        row_center > height - 1 + r) {
      continue;
    }
    const float sigma =
        per_point_sigma ? cloud.sigma[i] : static_cast<float>(options.default_sigma);
    for (int dr = -r; dr <= r; ++dr) {
      const int row = static_cast<int>(row_center) + dr;
      if (row < 0 || row >= height) continue;
      for (int dc = -r; dc <= r; ++dc) {
        const int col = static_cast<int>(col_center) + dc;
        if (col < 0 || col >= width) continue;
        double& z = zbuffer.at<double>(row, col);
        if (depth < z) {  // strict: on ties the lower index (drawn first) stays
          z = depth;
          if (with_sigma) out.sigma.at<float>(row, col) = sigma;
        }
      }
    }
  }
  zbuffer.convertTo(out.depth, CV_32F);
  out.summary.pixels_covered = CountFinite(out.depth);
  return out;
}

}  // namespace gcpstereo::eval
