// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// output.colmap: a COLMAP dense workspace of the run's depth maps (colmap_export.h).
#include "colmap_export.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/fusion/fusion.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/colmap_dense_io.h"
#include "gcpstereo/io/image_io.h"

namespace fs = std::filesystem;

namespace gcpstereo::pipeline::internal {
namespace {

void CheckView(const ColmapExportView& v) {
  const Camera& c = v.camera;
  c.Validate("output.colmap: view " + v.name);
  if (v.image_bgr.cols != c.width || v.image_bgr.rows != c.height) {
    throw Error("output.colmap: view " + v.name + ": the image is " +
                std::to_string(v.image_bgr.cols) + "x" + std::to_string(v.image_bgr.rows) +
                ", its camera " + std::to_string(c.width) + "x" + std::to_string(c.height));
  }
  if (v.image_bgr.type() != CV_8UC3 && v.image_bgr.type() != CV_8UC1) {
    throw Error("output.colmap: view " + v.name + ": the image is neither CV_8UC3 nor CV_8UC1");
  }
  if (!v.depth.empty() &&
      (v.depth.type() != CV_32FC1 || v.depth.cols != c.width || v.depth.rows != c.height)) {
    throw Error("output.colmap: view " + v.name + ": the depth map is not CV_32F of the camera's " +
                "size");
  }
  // COLMAP's PINHOLE camera (fx, fy, cx, cy) has no skew.
  if (std::abs(c.K(0, 1)) > 1e-9 * c.K(0, 0) || c.K(1, 0) != 0.0 || c.K(2, 0) != 0.0 ||
      c.K(2, 1) != 0.0 || c.K(2, 2) != 1.0) {
    throw Error("output.colmap: view " + v.name + ": its camera matrix has skew (K(0, 1) = " +
                FormatNumber(c.K(0, 1)) + "), which a COLMAP PINHOLE camera cannot express");
  }
}

// The view's PINHOLE camera and its pose as COLMAP writes them.
io::ColmapCamera PinholeCamera(std::uint32_t id, const Camera& c) {
  io::ColmapCamera camera;
  camera.camera_id = id;
  camera.model_id = 1;
  camera.model_name = "PINHOLE";
  camera.width = static_cast<std::uint64_t>(c.width);
  camera.height = static_cast<std::uint64_t>(c.height);
  // COLMAP's pixel centres are at +0.5 (colmap_io.h), the project's at integers.
  camera.params = {c.K(0, 0), c.K(1, 1), c.K(0, 2) + 0.5, c.K(1, 2) + 0.5};
  return camera;
}

io::ColmapImage PosedImage(std::uint32_t id, const std::string& name, const Camera& c) {
  io::ColmapImage image;
  image.image_id = id;
  image.camera_id = id;
  image.name = name;
  const Eigen::Matrix3d camera_from_world = c.world_from_camera_rotation.transpose();
  Eigen::Quaterniond q(camera_from_world);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() *= -1.0;  // one of the two equal quaternions, always the same
  image.qvec_wxyz = Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
  image.tvec = -camera_from_world * c.center_world;
  return image;
}

// COLMAP's normal map: the world-frame normals of DepthMapNormals in the camera frame, the unit
// vector towards the camera where it has none at a valid depth, 0 at an invalid depth.
cv::Mat CameraFrameNormals(const cv::Mat& depth, const Camera& camera, int radius_px) {
  const cv::Mat world = fusion::DepthMapNormals(depth, camera, radius_px);
  const Eigen::Matrix3d camera_from_world = camera.world_from_camera_rotation.transpose();
  const Eigen::Matrix3d K_inv = camera.K.inverse();
  cv::Mat normals(depth.size(), CV_32FC3, cv::Scalar::all(0.0));
  for (int r = 0; r < depth.rows; ++r) {
    const float* d = depth.ptr<float>(r);
    const cv::Vec3f* n_world = world.ptr<cv::Vec3f>(r);
    cv::Vec3f* n = normals.ptr<cv::Vec3f>(r);
    for (int c = 0; c < depth.cols; ++c) {
      if (!IsValidDepth(d[c])) continue;
      Eigen::Vector3d normal;
      if (std::isfinite(n_world[c][0]) && std::isfinite(n_world[c][1]) &&
          std::isfinite(n_world[c][2])) {
        normal = camera_from_world * Eigen::Vector3d(n_world[c][0], n_world[c][1], n_world[c][2]);
      } else {
        normal = -(K_inv * Eigen::Vector3d(c, r, 1.0));  // from the point towards the camera
      }
      normal.normalize();
      n[c] = cv::Vec3f(static_cast<float>(normal.x()), static_cast<float>(normal.y()),
                       static_cast<float>(normal.z()));
    }
  }
  return normals;
}

// The RGB colour of a pixel of a CV_8UC3 (BGR) or CV_8UC1 image.
std::array<std::uint8_t, 3> Rgb(const cv::Mat& image, int row, int col) {
  if (image.type() == CV_8UC1) {
    const std::uint8_t g = image.at<std::uint8_t>(row, col);
    return {g, g, g};
  }
  const cv::Vec3b& bgr = image.at<cv::Vec3b>(row, col);
  return {bgr[2], bgr[1], bgr[0]};
}

// Adds the sparse points sampled from view `s`'s depth map (colmap_export.h).
void AddSparsePoints(const std::vector<ColmapExportView>& views, size_t s,
                     const ColmapExportOptions& options, io::ColmapModel* model) {
  const ColmapExportView& source = views[s];
  const cv::Mat& depth = source.depth;
  const double pixels = static_cast<double>(depth.rows) * depth.cols;
  const int step = std::max(
      1, static_cast<int>(std::ceil(std::sqrt(pixels / std::max(1, options.max_points_per_view)))));
  const size_t min_track = views.size() > 1 ? 2 : 1;
  for (int r = step / 2; r < depth.rows; r += step) {
    for (int c = step / 2; c < depth.cols; c += step) {
      const float d = depth.at<float>(r, c);
      if (!IsValidDepth(d)) continue;
      const Eigen::Vector3d X = source.camera.BackProject(Eigen::Vector2d(c, r), d);
      // (view, pixel in the project's convention) of every view that observes X.
      std::vector<std::pair<size_t, Eigen::Vector2d>> observers = {{s, Eigen::Vector2d(c, r)}};
      for (size_t j = 0; j < views.size(); ++j) {
        if (j == s) continue;
        Eigen::Vector2d pixel;
        double z = 0.0;
        const Camera& camera = views[j].camera;
        if (!camera.Project(X, &pixel, &z) || !camera.InImage(pixel)) continue;
        if (!views[j].depth.empty()) {
          const int qc = std::clamp(static_cast<int>(std::lround(pixel.x())), 0, camera.width - 1);
          const int qr = std::clamp(static_cast<int>(std::lround(pixel.y())), 0, camera.height - 1);
          const float dj = views[j].depth.at<float>(qr, qc);
          if (!IsValidDepth(dj) || std::abs(z - dj) > options.depth_tolerance * dj) continue;
        }
        observers.emplace_back(j, pixel);
      }
      if (observers.size() < min_track) continue;
      const std::uint64_t point_id = model->points3d.size() + 1;
      io::ColmapPoint3D point;
      point.point3d_id = point_id;
      point.xyz_world = X;
      point.rgb = Rgb(source.image_bgr, r, c);
      point.error_px = 0.0;  // the keypoints are its exact projections
      for (const auto& [j, pixel] : observers) {
        io::ColmapImage& image = model->images.at(static_cast<std::uint32_t>(j + 1));
        io::ColmapPoint2D keypoint;
        keypoint.xy_colmap_px = pixel + Eigen::Vector2d(0.5, 0.5);
        keypoint.point3d_id = point_id;
        point.track.push_back({image.image_id, static_cast<std::uint32_t>(image.points2d.size())});
        image.points2d.push_back(keypoint);
      }
      model->points3d.emplace(point_id, std::move(point));
    }
  }
}

}  // namespace

ColmapExportOptions ColmapExportOptionsOf(const PipelineConfig& options) {
  ColmapExportOptions out;
  out.normal_radius_px = options.fusion.normal_radius_px;
  out.depth_tolerance = options.fusion.depth_tolerance;
  return out;
}

std::string ColmapImageName(const std::string& view_name) {
  const std::string ext = ".png";
  if (view_name.size() >= ext.size()) {
    std::string tail = view_name.substr(view_name.size() - ext.size());
    std::transform(tail.begin(), tail.end(), tail.begin(),
                   [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
    if (tail == ext) return view_name;
  }
  return view_name + ext;
}

ColmapWorkspace MakeColmapWorkspace(const std::vector<ColmapExportView>& views,
                                    const ColmapExportOptions& options) {
  if (views.empty()) throw Error("output.colmap: no view to write");
  ColmapWorkspace ws;
  std::map<std::string, std::string> image_name_of;
  for (size_t i = 0; i < views.size(); ++i) {
    const ColmapExportView& v = views[i];
    CheckView(v);
    const std::string image_name = ColmapImageName(v.name);
    if (!image_name_of.emplace(v.name, image_name).second) {
      throw Error("output.colmap: view " + v.name + " appears twice");
    }
    ws.image_names.push_back(image_name);
    const auto id = static_cast<std::uint32_t>(i + 1);
    ws.model.cameras.emplace(id, PinholeCamera(id, v.camera));
    ws.model.images.emplace(id, PosedImage(id, image_name, v.camera));
  }
  for (size_t s = 0; s < views.size(); ++s) {
    if (!views[s].depth.empty()) AddSparsePoints(views, s, options, &ws.model);
  }
  for (const ColmapExportView& v : views) {
    if (v.depth.empty()) {
      ws.depth.emplace_back();
      ws.normals.emplace_back();
      continue;
    }
    ws.depth.push_back(io::ColmapDepthFromDepthMap(v.depth));
    ws.normals.push_back(CameraFrameNormals(v.depth, v.camera, options.normal_radius_px));
    const std::string& image_name = image_name_of.at(v.name);
    ws.fusion_cfg += image_name + "\n";
    std::string sources;
    for (const std::string& name : v.sources) {
      const auto it = image_name_of.find(name);
      if (it == image_name_of.end() || name == v.name) continue;
      sources += (sources.empty() ? "" : ", ") + it->second;
    }
    ws.patch_match_cfg += image_name + "\n" + (sources.empty() ? "__auto__, 20" : sources) + "\n";
  }
  return ws;
}

nlohmann::json WriteColmapWorkspace(const std::string& dir,
                                    const std::vector<ColmapExportView>& views,
                                    const ColmapExportOptions& options) {
  const ColmapWorkspace ws = MakeColmapWorkspace(views, options);
  const fs::path root(dir);
  auto make_dirs = [](const fs::path& path) {
    std::error_code ec;
    fs::create_directories(path, ec);
    if (ec) throw IoError(path.string(), "cannot create folder: " + ec.message());
  };
  for (const char* sub : {"images", "sparse", "stereo/depth_maps", "stereo/normal_maps"}) {
    make_dirs(root / sub);
  }
  io::WriteColmapModelText((root / "sparse").string(), ws.model);
  int depth_maps = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    // Image names may hold sub-folders (a COLMAP model's); the maps follow them.
    const fs::path image = root / "images" / ws.image_names[i];
    make_dirs(image.parent_path());
    io::WritePng(image.string(), views[i].image_bgr);
    if (ws.depth[i].empty()) continue;
    const fs::path depth = root / "stereo/depth_maps" / (ws.image_names[i] + ".geometric.bin");
    const fs::path normals = root / "stereo/normal_maps" / (ws.image_names[i] + ".geometric.bin");
    make_dirs(depth.parent_path());
    make_dirs(normals.parent_path());
    io::WriteColmapArray(depth.string(), ws.depth[i]);
    io::WriteColmapArray(normals.string(), ws.normals[i]);
    ++depth_maps;
  }
  io::WriteBytesAtomically((root / "stereo/fusion.cfg").string(), ws.fusion_cfg.data(),
                           ws.fusion_cfg.size());
  io::WriteBytesAtomically((root / "stereo/patch-match.cfg").string(), ws.patch_match_cfg.data(),
                           ws.patch_match_cfg.size());
  size_t track_elements = 0;
  for (const auto& [id, point] : ws.model.points3d) track_elements += point.track.size();
  return {{"images", views.size()},
          {"depth_maps", depth_maps},
          {"points3D", ws.model.points3d.size()},
          {"mean_track_length", ws.model.points3d.empty()
                                    ? 0.0
                                    : static_cast<double>(track_elements) /
                                          static_cast<double>(ws.model.points3d.size())}};
}

}  // namespace gcpstereo::pipeline::internal
