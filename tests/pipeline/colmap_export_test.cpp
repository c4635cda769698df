// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// output.colmap on the synthetic `tiny` set: the COLMAP dense workspace holds the run's depth map
// pixel for pixel (same orientation, 0 where there is none), normals towards the camera, the
// run's images and cameras (at dataset.scale; read back as dataset.format colmap they are the
// run's cameras), a sparse cloud whose keypoints are its exact projections, and the cfg files
// stereo_fusion and patch_match_stereo read; a scene's workspace holds every view.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "gcpstereo/core/types.h"
#include "gcpstereo/io/colmap_dense_io.h"
#include "gcpstereo/io/colmap_io.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/pipeline/run.h"
#include "test_data.h"
#include "tiny_data.h"

namespace gcpstereo::pipeline {
namespace {

using gcpstereo::testing::ReadFile;
namespace fs = std::filesystem;
using nlohmann::json;

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> CommaList(const std::string& line) {
  std::vector<std::string> items;
  std::istringstream in(line);
  for (std::string item; std::getline(in, item, ',');) {
    item.erase(0, item.find_first_not_of(' '));
    items.push_back(item);
  }
  return items;
}

// The view as the run loaded it (strecha, at `scale`).
View LoadView(const std::string& data, const std::string& name, double scale) {
  io::DatasetRequest request;
  request.format = "strecha";
  request.path = data;
  request.reference = name;
  request.scale = scale;
  request.load_neighbors = false;
  return io::LoadDataset(request).reference;
}

void ExpectSameCamera(const Camera& a, const Camera& b, const std::string& what) {
  EXPECT_EQ(a.width, b.width) << what;
  EXPECT_EQ(a.height, b.height) << what;
  EXPECT_LT((a.K - b.K).cwiseAbs().maxCoeff(), 1e-9) << what;
  EXPECT_LT((a.world_from_camera_rotation - b.world_from_camera_rotation).cwiseAbs().maxCoeff(),
            1e-12)
      << what;
  EXPECT_LT((a.center_world - b.center_world).norm(), 1e-9) << what;
}

// The COLMAP depth array of `image` in `workspace` is `pfm` pixel for pixel (0 where the PFM has
// no estimate); returns the number of valid pixels.
int ExpectDepthIsThePfm(const std::string& workspace, const std::string& image,
                        const std::string& pfm) {
  const cv::Mat depth = io::ReadPfm(pfm);
  const cv::Mat colmap =
      io::ReadColmapArray(workspace + "/stereo/depth_maps/" + image + ".geometric.bin");
  EXPECT_EQ(colmap.type(), CV_32FC1);
  EXPECT_EQ(colmap.size(), depth.size());
  if (colmap.size() != depth.size()) return 0;
  int valid = 0, wrong = 0;
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      const float d = depth.at<float>(r, c);
      const float expected = IsValidDepth(d) ? d : 0.0f;
      valid += IsValidDepth(d);
      wrong += colmap.at<float>(r, c) != expected;
    }
  }
  EXPECT_EQ(wrong, 0) << image;
  return valid;
}

// Unit normals towards the camera where the depth is valid, 0 elsewhere.
void ExpectNormalsFaceTheCamera(const std::string& workspace, const std::string& image,
                                const Camera& camera) {
  const cv::Mat depth =
      io::ReadColmapArray(workspace + "/stereo/depth_maps/" + image + ".geometric.bin");
  const cv::Mat normals =
      io::ReadColmapArray(workspace + "/stereo/normal_maps/" + image + ".geometric.bin");
  ASSERT_EQ(normals.type(), CV_32FC3);
  ASSERT_EQ(normals.size(), depth.size());
  const Eigen::Matrix3d K_inv = camera.K.inverse();
  int bad = 0;
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      const cv::Vec3f n = normals.at<cv::Vec3f>(r, c);
      const Eigen::Vector3d normal(n[0], n[1], n[2]);
      if (depth.at<float>(r, c) <= 0.0f) {
        bad += normal.norm() != 0.0;
        continue;
      }
      const Eigen::Vector3d ray = K_inv * Eigen::Vector3d(c, r, 1.0);
      bad += std::abs(normal.norm() - 1.0) > 1e-5 || !(normal.dot(ray) < 0.0);
    }
  }
  EXPECT_EQ(bad, 0) << image;
}

// Every keypoint of the sparse model with a 3D point is that point's projection in the image's
// camera (COLMAP's +0.5 convention); every track has at least `min_track` images.
void ExpectConsistentSparseModel(const io::ColmapModel& model, size_t min_track) {
  ASSERT_GT(model.points3d.size(), 50u);
  for (const auto& [id, point] : model.points3d) {
    ASSERT_GE(point.track.size(), min_track) << id;
    for (const io::ColmapTrackElement& element : point.track) {
      const io::ColmapImage& image = model.images.at(element.image_id);
      const Camera camera = io::ColmapImageCamera(
          image, io::MakeColmapPinhole(model.cameras.at(image.camera_id), "test"));
      const io::ColmapPoint2D& keypoint = image.points2d.at(element.point2d_idx);
      ASSERT_EQ(keypoint.point3d_id, id);
      Eigen::Vector2d pixel;
      double z = 0.0;
      ASSERT_TRUE(camera.Project(point.xyz_world, &pixel, &z));
      EXPECT_LT((pixel + Eigen::Vector2d(0.5, 0.5) - keypoint.xy_colmap_px).norm(), 1e-6);
      EXPECT_TRUE(camera.InImage(pixel));
    }
  }
}

// No temporary file (a ".partial" of the atomic writes) anywhere under `dir`.
void ExpectNoPartialFiles(const std::string& dir) {
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
  }
}

class ColmapExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::WriteTinyData("gcpstereo-colmap-export"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string Data() { return *dir_ + "/data"; }

  // The fast setting of run_test.cpp.
  static json Run(const std::vector<std::string>& extra, const std::string& name) {
    std::vector<std::string> overrides = {"dataset.path=" + Data(),
                                          "dataset.reference=0005",
                                          "labels.count=48",
                                          "gcp.sources=[lidar]",
                                          "gcp.lidar.path=" + Data() + "/gt/laser.ply",
                                          "gcp.downsample=8",
                                          "optimizer.tiles=[1, 1]",
                                          "optimizer.refinement=parabola",
                                          "scene_mesh.depth=7",
                                          "eval.scene.max_samples=100000",
                                          "output.colmap=true",
                                          "runtime.log_level=warn"};
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    LoadedConfig config;
    config.Load("", overrides);
    return json::parse(RunPipeline(config, *dir_ + "/" + name, "(test)").report_json);
  }

  static std::string* dir_;
};
std::string* ColmapExport::dir_ = nullptr;

TEST_F(ColmapExport, SingleViewWorkspaceHoldsTheDepthMap) {
  const json report = Run({}, "single");
  const std::string out = *dir_ + "/single", ws = out + "/colmap";
  EXPECT_TRUE(report["stages"].contains("colmap_export"));
  EXPECT_EQ(report["colmap"]["depth_maps"], 1);
  EXPECT_EQ(report["colmap"]["depth"], "depth.pfm");

  // The depth map, pixel for pixel, and its normals.
  EXPECT_GT(ExpectDepthIsThePfm(ws, "0005.png", out + "/depth.pfm"), 160 * 107 / 2);
  const View reference = LoadView(Data(), "0005", 1.0);
  ExpectNormalsFaceTheCamera(ws, "0005.png", reference.camera);

  // The views (the reference and its neighbours) with the run's images and cameras.
  const std::vector<std::string> names = io::ListDatasetViews("strecha", Data());
  const io::ColmapModel model = io::ReadColmapModel(ws + "/sparse");
  ASSERT_EQ(model.images.size(), names.size());
  for (const std::string& name : names) {
    const View view = LoadView(Data(), name, 1.0);
    const io::ColmapImage* image = model.FindImage(name + ".png");
    ASSERT_NE(image, nullptr) << name;
    const io::ColmapCamera& camera = model.cameras.at(image->camera_id);
    EXPECT_EQ(camera.model_name, "PINHOLE");
    ExpectSameCamera(io::ColmapImageCamera(*image, io::MakeColmapPinhole(camera, "test")),
                     view.camera, name);
    const cv::Mat written = io::ReadColorImage(ws + "/images/" + name + ".png");
    ASSERT_EQ(written.size(), view.image.size()) << name;
    EXPECT_EQ(cv::norm(written, view.image, cv::NORM_INF), 0.0) << name;
    // Only the reference has a depth map.
    EXPECT_EQ(fs::exists(ws + "/stereo/depth_maps/" + name + ".png.geometric.bin"), name == "0005");
  }
  ExpectConsistentSparseModel(model, 2);

  // The cfg files: the reference to fuse, its neighbours as the source images.
  EXPECT_EQ(ReadFile(ws + "/stereo/fusion.cfg"), "0005.png\n");
  const std::vector<std::string> patch_match = Lines(ReadFile(ws + "/stereo/patch-match.cfg"));
  ASSERT_EQ(patch_match.size(), 2u);
  EXPECT_EQ(patch_match[0], "0005.png");
  std::set<std::string> sources;
  for (const std::string& s : CommaList(patch_match[1])) sources.insert(s);
  std::set<std::string> others;
  for (const std::string& name : names) {
    if (name != "0005") others.insert(name + ".png");
  }
  EXPECT_EQ(sources, others);

  // The workspace is a COLMAP workspace gcpstereo itself reads: the same camera.
  io::DatasetRequest request;
  request.format = "colmap";
  request.path = ws;
  request.reference = "0005.png";
  request.load_neighbors = false;
  ExpectSameCamera(io::LoadDataset(request).reference.camera, reference.camera, "read back");
  ExpectNoPartialFiles(out);
}

// dataset.scale: the workspace holds the images and cameras as the run used them; a run stopped
// after the propagation exports D̂.
TEST_F(ColmapExport, ScaledRunStoppedAfterThePropagation) {
  const json report = Run({"dataset.scale=0.5", "runtime.stop_after=propagation"}, "scaled");
  const std::string out = *dir_ + "/scaled", ws = out + "/colmap";
  EXPECT_EQ(report["colmap"]["depth"], "propagated_depth.pfm");
  EXPECT_GT(ExpectDepthIsThePfm(ws, "0005.png", out + "/propagated_depth.pfm"), 0);
  const View reference = LoadView(Data(), "0005", 0.5);
  const cv::Mat image = io::ReadColorImage(ws + "/images/0005.png");
  EXPECT_EQ(image.cols, reference.camera.width);
  EXPECT_EQ(image.rows, reference.camera.height);
  EXPECT_LT(image.cols, 160);
  const io::ColmapModel model = io::ReadColmapModel(ws + "/sparse");
  const io::ColmapImage* colmap_image = model.FindImage("0005.png");
  ASSERT_NE(colmap_image, nullptr);
  ExpectSameCamera(
      io::ColmapImageCamera(
          *colmap_image, io::MakeColmapPinhole(model.cameras.at(colmap_image->camera_id), "test")),
      reference.camera, "scaled");
}

// A scene: the scene's workspace holds every view's depth map (each view's folder its own, as a
// single run writes it), sparse points observed by the views whose depth maps agree.
TEST_F(ColmapExport, SceneWorkspaceHoldsEveryView) {
  const json report = Run({"dataset.reference=[\"0004\", \"0005\", \"0006\"]"}, "scene");
  const std::string out = *dir_ + "/scene", ws = out + "/colmap";
  EXPECT_EQ(report["colmap"]["depth_maps"], 3);
  EXPECT_EQ(report["colmap"]["images"], 3);
  const std::vector<std::string> fused = {"0004", "0005", "0006"};
  EXPECT_EQ(ReadFile(ws + "/stereo/fusion.cfg"), "0004.png\n0005.png\n0006.png\n");
  const std::vector<std::string> patch_match = Lines(ReadFile(ws + "/stereo/patch-match.cfg"));
  ASSERT_EQ(patch_match.size(), 6u);
  for (size_t i = 0; i < fused.size(); ++i) {
    const std::string& name = fused[i];
    EXPECT_EQ(patch_match[2 * i], name + ".png");
    for (const std::string& source : CommaList(patch_match[2 * i + 1])) {
      EXPECT_NE(source, name + ".png");
      EXPECT_NE(std::find(fused.begin(), fused.end(), source.substr(0, 4)), fused.end()) << source;
    }
    EXPECT_GT(ExpectDepthIsThePfm(ws, name + ".png", out + "/views/" + name + "/depth.pfm"), 0);
    ExpectNormalsFaceTheCamera(ws, name + ".png", LoadView(Data(), name, 1.0).camera);
    // The view's own folder holds what a single run writes: its own one-view workspace.
    EXPECT_EQ(ReadFile(out + "/views/" + name + "/colmap/stereo/fusion.cfg"), name + ".png\n");
  }
  const io::ColmapModel model = io::ReadColmapModel(ws + "/sparse");
  ASSERT_EQ(model.images.size(), 3u);
  ExpectConsistentSparseModel(model, 2);
  // Each observer's depth map agrees with the point (fusion.depth_tolerance, 1 %).
  for (const auto& [id, point] : model.points3d) {
    for (const io::ColmapTrackElement& element : point.track) {
      const io::ColmapImage& image = model.images.at(element.image_id);
      const cv::Mat depth = io::DepthMapFromColmapDepth(
          io::ReadColmapArray(ws + "/stereo/depth_maps/" + image.name + ".geometric.bin"));
      const Camera camera = io::ColmapImageCamera(
          image, io::MakeColmapPinhole(model.cameras.at(image.camera_id), "test"));
      Eigen::Vector2d pixel;
      double z = 0.0;
      ASSERT_TRUE(camera.Project(point.xyz_world, &pixel, &z));
      // The nearest pixel, as the export looks it up.
      const int col = std::clamp(static_cast<int>(std::lround(pixel.x())), 0, depth.cols - 1);
      const int row = std::clamp(static_cast<int>(std::lround(pixel.y())), 0, depth.rows - 1);
      const float d = depth.at<float>(row, col);
      ASSERT_TRUE(IsValidDepth(d));
      EXPECT_LE(std::abs(z - d), 0.01 * d + 1e-6) << id << " in " << image.name;
    }
  }
  ExpectNoPartialFiles(out);
}

}  // namespace
}  // namespace gcpstereo::pipeline
