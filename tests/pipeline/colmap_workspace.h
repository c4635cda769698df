// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// A Strecha-layout data set (the synthetic scenes) written as a COLMAP workspace, optionally in
// another frame: what the COLMAP pipeline tests run on.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/io/camera_io.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/point_cloud_io.h"

namespace gcpstereo::testing {

// Writes <strecha>'s views as a COLMAP workspace in <out>: images/ copied, sparse/ as text. Each
// camera K becomes PINHOLE with COLMAP's +0.5 pixel-centre shift; the pose world-to-camera
// (q = R^T as a quaternion, t = -R^T C). Every `step`-th laser point is a 3D point with a
// keypoint in each view that sees it. Image names are <folder><name>.png (folder "" or "x/").
// The model is written in the frame model_from_world = [sQ T; 0 1] (a similarity): points
// X' = sQX + T, camera centres likewise, orientations rotated by Q (intrinsics unchanged), as a
// reconstruction of the same scene in its own frame and scale would be. point_noise_m > 0 moves
// each 3D point by Gaussian noise of that standard deviation per axis (world units, seeded: a
// triangulation's error) before the change of frame; the keypoints stay where the exact point
// projects.
inline void WriteColmapWorkspace(
    const std::string& strecha, const std::string& out, int step, const std::string& folder = "",
    const Eigen::Matrix4d& model_from_world = Eigen::Matrix4d::Identity(),
    double point_noise_m = 0.0) {
  namespace fs = std::filesystem;
  std::mt19937 random(11);
  std::normal_distribution<double> noise(0.0, point_noise_m > 0.0 ? point_noise_m : 1.0);
  const Eigen::Matrix3d sq = model_from_world.topLeftCorner<3, 3>();
  const double scale = std::cbrt(sq.determinant());
  const Eigen::Matrix3d q_world = sq / scale;
  auto to_model = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return (model_from_world * x.homogeneous()).head<3>();
  };
  const std::vector<std::string> names = io::ListDatasetViews("strecha", strecha);
  fs::create_directories(out + "/images/" + folder);
  fs::create_directories(out + "/sparse");
  std::vector<Camera> cameras;
  for (const std::string& name : names) {
    const std::string file = name + ".png";
    fs::copy_file(strecha + "/images/" + file, out + "/images/" + folder + file,
                  fs::copy_options::overwrite_existing);
    cameras.push_back(io::ReadStrechaCamera(strecha + "/cameras/" + file + ".camera"));
  }
  const PointCloud laser = io::ReadPointCloud(strecha + "/gt/laser.ply");
  std::vector<std::ostringstream> keypoints(names.size());
  std::vector<int> keypoint_count(names.size(), 0);
  std::ostringstream points;
  points << std::setprecision(17);
  int point_id = 1;
  for (std::size_t i = 0; i < laser.size(); i += step, ++point_id) {
    const Eigen::Vector3d X = laser.points[i].cast<double>();
    std::ostringstream track;
    int seen = 0;
    for (std::size_t v = 0; v < cameras.size(); ++v) {
      Eigen::Vector2d pixel;
      double depth = 0;
      if (!cameras[v].Project(X, &pixel, &depth) || !cameras[v].InImage(pixel)) continue;
      keypoints[v] << std::setprecision(17) << (keypoint_count[v] ? " " : "") << pixel.x() + 0.5
                   << ' ' << pixel.y() + 0.5 << ' ' << point_id;
      track << ' ' << v + 1 << ' ' << keypoint_count[v]++;
      ++seen;
    }
    if (seen == 0) continue;
    Eigen::Vector3d noisy = X;
    if (point_noise_m > 0.0) noisy += Eigen::Vector3d(noise(random), noise(random), noise(random));
    const Eigen::Vector3d Xm = to_model(noisy);
    points << point_id << ' ' << Xm.x() << ' ' << Xm.y() << ' ' << Xm.z() << " 128 128 128 0.5"
           << track.str() << '\n';
  }
  std::ostringstream camera_file, image_file;
  camera_file << std::setprecision(17);
  image_file << std::setprecision(17);
  for (std::size_t v = 0; v < cameras.size(); ++v) {
    const Camera& c = cameras[v];
    camera_file << v + 1 << " PINHOLE " << c.width << ' ' << c.height << ' ' << c.K(0, 0) << ' '
                << c.K(1, 1) << ' ' << c.K(0, 2) + 0.5 << ' ' << c.K(1, 2) + 0.5 << '\n';
    const Eigen::Matrix3d R = (q_world * c.world_from_camera_rotation).transpose();
    const Eigen::Quaterniond q(R);
    const Eigen::Vector3d t = -R * to_model(c.center_world);
    image_file << v + 1 << ' ' << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
               << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << v + 1 << ' ' << folder << names[v]
               << ".png\n"
               << keypoints[v].str() << '\n';
  }
  std::ofstream(out + "/sparse/cameras.txt") << camera_file.str();
  std::ofstream(out + "/sparse/images.txt") << image_file.str();
  std::ofstream(out + "/sparse/points3D.txt") << points.str();
}

// The fast setting of the tiny preset's pipeline tests (scene_test.cpp): 48 labels, laser GCPs
// from `laser_ply` one per 8×8 block, one tile, the parabola refinement.
inline std::vector<std::string> FastTinySetting(const std::string& laser_ply) {
  return {"labels.count=48",
          "labels.min=5",
          "labels.max=14",
          "gcp.sources=[lidar]",
          "gcp.lidar.path=" + laser_ply,
          "gcp.downsample=8",
          "optimizer.tiles=[1, 1]",
          "optimizer.refinement=parabola"};
}

// Pixels where two depth maps of one size agree: both without depth (inf), or within `relative` of
// the second's depth.
inline int AgreeingDepthPixels(const cv::Mat& a, const cv::Mat& b, float relative) {
  int same = 0;
  for (int r = 0; r < a.rows; ++r) {
    for (int c = 0; c < a.cols; ++c) {
      const float x = a.at<float>(r, c), y = b.at<float>(r, c);
      if ((std::isinf(x) && std::isinf(y)) || std::abs(x - y) <= relative * std::abs(y)) ++same;
    }
  }
  return same;
}

}  // namespace gcpstereo::testing
