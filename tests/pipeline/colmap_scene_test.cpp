// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// dataset.format: colmap through the whole pipeline: the synthetic `tiny` set written as a COLMAP
// workspace (text model, PINHOLE camera per view, laser points as the model's 3D points) runs as
// its Strecha layout does, as a whole scene with automatic neighbours chosen on the model's points.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "colmap_workspace.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/io/camera_io.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/pipeline/evaluate.h"
#include "gcpstereo/pipeline/run.h"
#include "gcpstereo/pipeline/scene.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"

namespace gcpstereo::pipeline {
namespace {

using gcpstereo::testing::ErrorOf;
using gcpstereo::testing::FastTinySetting;
using gcpstereo::testing::ReadFile;
using gcpstereo::testing::WriteColmapWorkspace;

namespace fs = std::filesystem;
using nlohmann::json;

class ColmapSceneRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::MakeTempDir("gcpstereo-colmap-scene"));
    synth::SynthOptions options;
    options.preset = "tiny";
    options.seed = 7;
    synth::WriteScene(synth::GenerateScene(options), options, *dir_ + "/strecha");
    WriteColmapWorkspace(*dir_ + "/strecha", *dir_ + "/colmap", 7);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  // The fast setting of scene_test.cpp.
  static json Run(const std::string& format, const std::string& name,
                  const std::vector<std::string>& extra) {
    std::vector<std::string> overrides = {"dataset.format=" + format,
                                          "dataset.path=" + *dir_ + "/" + format,
                                          "scene_mesh.depth=7", "runtime.log_level=warn"};
    const std::vector<std::string> fast = FastTinySetting(*dir_ + "/strecha/gt/laser.ply");
    overrides.insert(overrides.end(), fast.begin(), fast.end());
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    LoadedConfig config;
    config.Load("", overrides);
    return json::parse(RunPipeline(config, *dir_ + "/" + name, "(test)").report_json);
  }

  static std::string* dir_;
};
std::string* ColmapSceneRun::dir_ = nullptr;

TEST_F(ColmapSceneRun, SameDepthAsTheStrechaLayout) {
  const json colmap = Run(
      "colmap", "colmap_0005",
      {"dataset.reference=0005.png", "dataset.neighbors=[0003.png, 0004.png, 0006.png, 0007.png]"});
  Run("strecha", "strecha_0005",
      {"dataset.reference=\"0005\"", "dataset.neighbors=[\"0003\", \"0004\", \"0006\", \"0007\"]"});
  EXPECT_EQ(colmap["dataset"]["format"], "colmap");
  EXPECT_EQ(colmap["dataset"]["reference"]["camera_model"], "PINHOLE");
  EXPECT_EQ(colmap["dataset"]["reference"]["undistorted"], false);
  const cv::Mat a = io::ReadPfm(*dir_ + "/colmap_0005/depth.pfm");
  const cv::Mat b = io::ReadPfm(*dir_ + "/strecha_0005/depth.pfm");
  ASSERT_EQ(a.size(), b.size());
  // The cameras pass through a quaternion and 17 printed digits, so a label may flip where two
  // costs tie; everywhere else the maps agree (measured: all 17120 pixels; with COLMAP's cx taken
  // without its half-pixel shift, 38 %).
  const int same = testing::AgreeingDepthPixels(a, b, 1e-4f);
  EXPECT_GT(same, 0.99 * a.total()) << same << " of " << a.total();
}

TEST_F(ColmapSceneRun, WholeSceneWithNeighboursFromTheModelsPoints) {
  const json report =
      Run("colmap", "scene",
          {"dataset.reference=all", "dataset.neighbors=auto", "dataset.neighbor_count=2"});
  ASSERT_EQ(report["views"].size(), 5u);
  for (const json& v : report["views"]) EXPECT_EQ(v["status"], "done") << v.dump();
  EXPECT_TRUE(fs::exists(*dir_ + "/scene/fused.ply"));
  const json view = json::parse(ReadFile(*dir_ + "/scene/views/0005.png/report.json"));
  const json& selection = view["dataset"]["neighbor_selection"];
  EXPECT_EQ(selection["basis"], "points") << selection.dump();
  EXPECT_GT(selection["points_used"].get<int>(), 100) << selection.dump();
  ASSERT_EQ(view["dataset"]["neighbors"].size(), 2u);
  EXPECT_EQ(view["dataset"]["reference"]["camera_model"], "PINHOLE");
}

// gcp.sources: [sfm] takes the model's points that 0005 observes: on the tiny set those are laser
// points, so each GCP (gcps.ply, world frame) lies on the surface: its depth in 0005 matches the
// exact depth at its pixel to within the laser's noise plus the surface's change across the
// rounding to a pixel centre (measured: median 1.1 cm, 90th percentile 3.6 cm over 244 GCPs); a
// point in another frame or of another view would be metres off. The workspace writer gives a
// view every point that projects into it, occluded or not (COLMAP observes only what it matched),
// so a few GCPs lie behind the surface: hence percentiles, not the maximum. With lidar too, both
// sources contribute and the downsampling keeps one per block.
TEST_F(ColmapSceneRun, SfmGcpsLieOnTheSurfaceAndCombineWithLidar) {
  const json sfm = Run("colmap", "sfm_0005",
                       {"dataset.reference=0005.png", "dataset.neighbors=[0004.png, 0006.png]",
                        "gcp.sources=[sfm]"});
  const json& source = sfm["gcps"]["sources"][0];
  EXPECT_EQ(source["source"], "sfm");
  EXPECT_GT(source["gcps"].get<int>(), 50) << source.dump();
  EXPECT_EQ(source["input"].get<int>(),
            source["gcps"].get<int>() + source["short_track"].get<int>() +
                source["large_error"].get<int>() + source["small_angle"].get<int>() +
                source["same_pixel"].get<int>() + source["outside_image"].get<int>() +
                source["behind_camera"].get<int>() + source["invalid"].get<int>())
      << source.dump();

  const Camera camera = io::ReadStrechaCamera(*dir_ + "/strecha/cameras/0005.png.camera");
  const cv::Mat gt = io::ReadPfm(*dir_ + "/strecha/gt/0005.depth.pfm");
  const PointCloud gcps = io::ReadPointCloud(*dir_ + "/sfm_0005/gcps.ply");
  ASSERT_EQ(static_cast<int>(gcps.size()), sfm["gcps"]["count"].get<int>());
  std::vector<double> errors;
  for (const Eigen::Vector3f& p : gcps.points) {
    Eigen::Vector2d pixel;
    double depth = 0;
    ASSERT_TRUE(camera.Project(p.cast<double>(), &pixel, &depth));
    const float truth = gt.at<float>(static_cast<int>(std::lround(pixel.y())),
                                     static_cast<int>(std::lround(pixel.x())));
    if (std::isfinite(truth)) errors.push_back(std::abs(depth - truth));
  }
  ASSERT_GT(errors.size(), 50u);
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.05);
  EXPECT_LT(errors[errors.size() * 9 / 10], 0.2);

  const json both = Run("colmap", "sfm_lidar_0005",
                        {"dataset.reference=0005.png", "dataset.neighbors=[0004.png, 0006.png]",
                         "gcp.sources=[sfm, lidar]"});
  ASSERT_EQ(both["gcps"]["sources"].size(), 2u);
  int sum = 0;
  for (const json& s : both["gcps"]["sources"]) {
    EXPECT_GT(s["gcps"].get<int>(), 0) << s.dump();
    sum += s["gcps"].get<int>();
  }
  EXPECT_GT(both["gcps"]["count"].get<int>(), sfm["gcps"]["count"].get<int>());
  EXPECT_LE(both["gcps"]["count"].get<int>(), sum);
}

// eval.sfm_holdout: the model's points the reference observes are split by the 8-px checkerboard;
// the sfm GCPs come only from the GCP squares, the other squares' points score the depth maps.
TEST_F(ColmapSceneRun, SfmHoldoutScoresTheSquaresTheGcpsDidNotUse) {
  const std::vector<std::string> view = {
      "dataset.reference=0005.png", "dataset.neighbors=[0004.png, 0006.png]", "gcp.sources=[sfm]"};
  std::vector<std::string> with_holdout = view;
  with_holdout.push_back("eval.sfm_holdout=true");
  const json all = Run("colmap", "sfm_all_0005", view);
  const json held = Run("colmap", "sfm_holdout_0005", with_holdout);
  EXPECT_FALSE(all["metrics"].contains("sfm_holdout"));
  ASSERT_TRUE(held["metrics"].contains("sfm_holdout")) << held["metrics"].dump();
  const json& score = held["metrics"]["sfm_holdout"]["result"];
  const json& source = held["gcps"]["sources"][0];
  const json& source_all = all["gcps"]["sources"][0];
  // Every observed point in front of the camera and inside the image is in exactly one half.
  const int in_image = source_all["input"].get<int>() - source_all["outside_image"].get<int>() -
                       source_all["behind_camera"].get<int>();
  EXPECT_EQ(source["input"].get<int>() + score["counted"].get<int>(), in_image);
  EXPECT_GT(score["counted"].get<int>(), in_image / 3);
  EXPECT_GT(source["input"].get<int>(), in_image / 3);
  EXPECT_EQ(score["outside"].get<int>(), 0);

  // Every GCP lies in a GCP square (block (bc, br) with bc + br even).
  const Camera camera = io::ReadStrechaCamera(*dir_ + "/strecha/cameras/0005.png.camera");
  const PointCloud gcps = io::ReadPointCloud(*dir_ + "/sfm_holdout_0005/gcps.ply");
  ASSERT_GT(gcps.size(), 20u);
  for (const Eigen::Vector3f& p : gcps.points) {
    Eigen::Vector2d pixel;
    double depth = 0;
    ASSERT_TRUE(camera.Project(p.cast<double>(), &pixel, &depth));
    const int col = static_cast<int>(std::floor(pixel.x() + 0.5));
    const int row = static_cast<int>(std::floor(pixel.y() + 0.5));
    EXPECT_EQ((col / 8 + row / 8) % 2, 0) << pixel.transpose();
  }

  // The model's points are the laser's (on the true surface): the depth map agrees with most of
  // them, and the share above each threshold falls as the threshold grows.
  const double above1 = score["above_1_percent"], above2 = score["above_2_percent"];
  const double above5 = score["above_5_percent"];
  EXPECT_GE(above1, above2);
  EXPECT_GE(above2, above5);
  EXPECT_LT(score["median_relative_error_percent"].get<double>(), 2.0) << score.dump();
  EXPECT_LT(above5, 25.0) << score.dump();
  EXPECT_TRUE(held["metrics"]["sfm_holdout"].contains("propagated"));

  // `gcpstereo eval --run` makes the same split again and scores the same points.
  EvalRequest request;
  request.run_folder = *dir_ + "/sfm_holdout_0005";
  EXPECT_EQ(json::parse(RunEvaluation(request))["metrics"]["sfm_holdout"],
            held["metrics"]["sfm_holdout"]);
}

// Image names with a sub-folder: views/<folder>/<name>/ in the scene, and `fuse` of those folders
// gives the scene's model.
TEST_F(ColmapSceneRun, ImageNamesWithSubFolders) {
  WriteColmapWorkspace(*dir_ + "/strecha", *dir_ + "/colmap_sub", 7, "cams/");
  Run("colmap", "sub_scene",
      {"dataset.path=" + *dir_ + "/colmap_sub",
       "dataset.reference=[cams/0004.png, cams/0005.png, cams/0006.png]"});
  for (const char* name : {"0004.png", "0005.png", "0006.png"}) {
    EXPECT_TRUE(fs::exists(*dir_ + "/sub_scene/views/cams/" + name + "/depth.pfm")) << name;
  }
  FuseRequest request;
  for (const char* name : {"0004.png", "0005.png", "0006.png"}) {
    request.view_dirs.push_back(*dir_ + "/sub_scene/views/cams/" + name);
  }
  request.output_dir = *dir_ + "/sub_fused";
  FuseViewFolders(request);
  EXPECT_EQ(ReadFile(*dir_ + "/sub_fused/fused.ply"), ReadFile(*dir_ + "/sub_scene/fused.ply"));
}

// The message a configuration of the Strecha layout with `key_value` gets.
std::string StrechaConfigError(const std::string& key_value) {
  return ErrorOf([&] {
    LoadedConfig config;
    config.Load(
        "", {"dataset.format=strecha", "dataset.path=/x", "dataset.reference=\"0005\"", key_value});
  });
}

TEST(ColmapSfmConfig, SfmNeedsAColmapModel) {
  EXPECT_EQ(StrechaConfigError("gcp.sources=[sfm]"),
            "gcp.sources = sfm. Violated constraint: sfm needs dataset.format colmap (the SfM "
            "points are the COLMAP model's), not strecha");
}

TEST(ColmapSfmConfig, SfmHoldoutNeedsAColmapModel) {
  EXPECT_EQ(StrechaConfigError("eval.sfm_holdout=true"),
            "eval.sfm_holdout = true. Violated constraint: false unless dataset.format is colmap "
            "(the scored points are the COLMAP model's)");
}

}  // namespace
}  // namespace gcpstereo::pipeline
