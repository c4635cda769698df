// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// dataset.align: the synthetic `tiny` set written as a COLMAP workspace in another frame (scale
// 0.37, 40° rotation, a translation) is put back into the scan's frame, by registration to the
// scan or by known camera centres, and then gives the depth map of the workspace written in the
// scan's frame. Poor alignments, missing or bad centres and misconfigurations are errors.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
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
#include "gcpstereo/pipeline/run.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"

namespace gcpstereo::pipeline {
namespace {

using gcpstereo::testing::ErrorOf;
using gcpstereo::testing::FastTinySetting;
using gcpstereo::testing::ReadFile;
using gcpstereo::testing::WriteColmapWorkspace;
using nlohmann::json;
namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

// The reconstruction's frame: model_from_world = [sQ T; 0 1] with s = 0.37, 40° about a tilted
// axis.
Eigen::Matrix4d ModelFromWorld() {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() =
      0.37 * Eigen::AngleAxisd(40.0 * kPi / 180.0, Eigen::Vector3d(1.0, -2.0, 0.5).normalized())
                 .toRotationMatrix();
  m.topRightCorner<3, 1>() = Eigen::Vector3d(3.0, -1.5, 12.0);
  return m;
}

class ColmapAlign : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::MakeTempDir("gcpstereo-colmap-align"));
    synth::SynthOptions options;
    options.preset = "tiny";
    options.seed = 7;
    // A scan 3 times as dense as the preset's (2 mrad: 2 cm at 10 m): with the preset's 6 cm at
    // 10 m, wider than dataset.align_max_residual, point-to-point ICP stops a few degrees off.
    options.laser_angular_step_rad = 0.002;
    synth::WriteScene(synth::GenerateScene(options), options, *dir_ + "/strecha");
    WriteColmapWorkspace(*dir_ + "/strecha", *dir_ + "/true_frame", 40);
    WriteColmapWorkspace(*dir_ + "/strecha", *dir_ + "/moved", 40, "", ModelFromWorld());
    // The known centres: the Strecha cameras' (the scan's frame).
    std::ofstream centres(*dir_ + "/centres.txt");
    centres << std::setprecision(17) << "# name X Y Z\n";
    for (const std::string& name : io::ListDatasetViews("strecha", *dir_ + "/strecha")) {
      const Camera c = io::ReadStrechaCamera(*dir_ + "/strecha/cameras/" + name + ".png.camera");
      centres << name << ".png " << c.center_world.x() << ' ' << c.center_world.y() << ' '
              << c.center_world.z() << '\n';
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  static std::vector<std::string> Overrides(const std::string& workspace,
                                            const std::vector<std::string>& extra) {
    std::vector<std::string> overrides = {
        "dataset.format=colmap",      "dataset.path=" + *dir_ + "/" + workspace,
        "dataset.reference=0005.png", "dataset.neighbors=[0004.png, 0006.png]",
        "output.previews=false",      "output.mesh=false",
        "runtime.log_level=warn"};
    const std::vector<std::string> fast = FastTinySetting(*dir_ + "/strecha/gt/laser.ply");
    overrides.insert(overrides.end(), fast.begin(), fast.end());
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    return overrides;
  }

  static json Run(const std::string& workspace, const std::string& name,
                  const std::vector<std::string>& extra) {
    LoadedConfig config;
    config.Load("", Overrides(workspace, extra));
    return json::parse(RunPipeline(config, *dir_ + "/" + name, "(test)").report_json);
  }

  static std::string RunError(const std::string& workspace, const std::string& name,
                              const std::vector<std::string>& extra) {
    return ErrorOf([&] {
      LoadedConfig config;
      config.Load("", Overrides(workspace, extra));
      RunPipeline(config, *dir_ + "/" + name, "(test)");
    });
  }

  static std::string* dir_;
};
std::string* ColmapAlign::dir_ = nullptr;

// The alignment must be the inverse of ModelFromWorld: scale 1 / 0.37, 40°.
void ExpectInverseOfModelFromWorld(const json& alignment, double tolerance) {
  ASSERT_TRUE(alignment.is_object());
  Eigen::Matrix4d world_from_model;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c)
      world_from_model(r, c) = alignment["world_from_model"][r][c].get<double>();
  }
  const Eigen::Matrix4d product = world_from_model * ModelFromWorld();
  EXPECT_LT((product - Eigen::Matrix4d::Identity()).norm(), tolerance) << alignment.dump();
  EXPECT_NEAR(alignment["scale"].get<double>() * 0.37, 1.0, tolerance) << alignment.dump();
  EXPECT_NEAR(alignment["rotation_deg"].get<double>(), 40.0, 1e3 * tolerance) << alignment.dump();
}

// Known centres: exact up to the 17 printed digits of the model and centres files.
TEST_F(ColmapAlign, CentresRecoverTheSimilarityExactly) {
  const json report =
      Run("moved", "centres_load",
          {"dataset.align=centres", "dataset.align_centres=" + *dir_ + "/centres.txt",
           "runtime.stop_after=load"});
  const json& alignment = report["alignment"];
  EXPECT_EQ(alignment["method"], "centres");
  ExpectInverseOfModelFromWorld(alignment, 1e-9);
  EXPECT_EQ(alignment["inliers"], 5);
  EXPECT_EQ(alignment["centres"].size(), 5u);
  EXPECT_LT(alignment["residual_rms"].get<double>(), 1e-9);
}

// Registration to the scan: the model's points are every 7th scan point, stored as float in the
// PLY (about 1e-6 m at 10 m), so the recovery is exact to that precision (tolerance 1e-5 on the
// 4×4 product, 1e-5 relative on the scale).
TEST_F(ColmapAlign, ScanRegistrationRecoversTheSimilarity) {
  const json report = Run("moved", "scan_load", {"dataset.align=scan", "runtime.stop_after=load"});
  const json& alignment = report["alignment"];
  EXPECT_EQ(alignment["method"], "scan");
  std::cout << alignment.dump() << "\n";
  ExpectInverseOfModelFromWorld(alignment, 1e-5);
  EXPECT_DOUBLE_EQ(alignment["inlier_share"].get<double>(), 1.0) << alignment.dump();
  EXPECT_LT(alignment["residual_median"].get<double>(), 1e-5) << alignment.dump();
}

// With the model aligned, lidar GCPs, labels.min/max and the depth map are in the scan's frame:
// the run gives the depth map of the workspace written in the scan's frame. The cameras differ
// from those by the alignment's rounding (1e-6 m), so a label may flip where two costs tie.
TEST_F(ColmapAlign, AlignedRunGivesTheTrueFrameDepth) {
  Run("true_frame", "true_0005", {});
  const json aligned = Run("moved", "aligned_0005", {"dataset.align=scan"});
  EXPECT_TRUE(aligned.contains("alignment"));
  EXPECT_GT(aligned["gcps"]["count"].get<int>(), 50) << aligned["gcps"].dump();
  const cv::Mat a = io::ReadPfm(*dir_ + "/aligned_0005/depth.pfm");
  const cv::Mat b = io::ReadPfm(*dir_ + "/true_0005/depth.pfm");
  ASSERT_EQ(a.size(), b.size());
  const int same = testing::AgreeingDepthPixels(a, b, 1e-3f);
  EXPECT_GT(same, 0.99 * a.total()) << same << " of " << a.total();
  // dataset.align: none (the default) leaves the model where it is and reports no alignment.
  const json unaligned = Run("moved", "unaligned_load", {"runtime.stop_after=load"});
  EXPECT_FALSE(unaligned.contains("alignment"));
}

// A scan of which only a fifth is left (the points of least x): most of the model has no scan
// near it. Measured: the registration fits part of the model to it at scale 0.62 with 69 % of the
// points within 5 cm and a median residual of 2.4 cm, which the absolute thresholds let pass; the
// median is 2.4 % of the model's size, and that refuses it.
TEST_F(ColmapAlign, PoorOverlapIsRefusedWithTheResiduals) {
  const PointCloud laser = io::ReadPointCloud(*dir_ + "/strecha/gt/laser.ply");
  std::vector<float> xs;
  for (const auto& p : laser.points) xs.push_back(p.x());
  std::nth_element(xs.begin(), xs.begin() + xs.size() / 5, xs.end());
  const float cut = xs[xs.size() / 5];
  PointCloud part;
  for (const auto& p : laser.points) {
    if (p.x() < cut) part.points.push_back(p);
  }
  io::WritePointCloudPly(*dir_ + "/part.ply", part);
  const std::string error = RunError(
      "moved", "refused",
      {"dataset.align=scan", "gcp.lidar.path=" + *dir_ + "/part.ply", "runtime.stop_after=load"});
  std::cout << error << "\n";
  EXPECT_NE(error.find("alignment refused ("), std::string::npos) << error;
  EXPECT_NE(error.find("residuals median"), std::string::npos) << error;
  EXPECT_NE(error.find("part.ply"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(*dir_ + "/refused/report.json"));
}

TEST_F(ColmapAlign, BadCentresAreClearErrors) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"0004.png 1 2 3\n0005.png 4 5 6\n", "2 matched points, at least 3 non-collinear"},
      {"0004.png 0 0 0\n0005.png 1 0 0\n0006.png 2 0 0\n", "collinear"},
      {"0004.png 0 0 0\nnope.png 1 0 0\n0006.png 2 1 0\n", "names image 'nope.png'"},
      {"0004.png 0 0\n", "line 1: expected '<image name> X Y Z'"},
      {"0004.png 0 0 x\n", "line 1: 'x' is not a finite coordinate"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string file = *dir_ + "/bad_centres_" + std::to_string(i) + ".txt";
    std::ofstream(file) << cases[i].first;
    const std::string error = RunError(
        "moved", "bad_centres",
        {"dataset.align=centres", "dataset.align_centres=" + file, "runtime.stop_after=load"});
    EXPECT_NE(error.find(cases[i].second), std::string::npos) << error;
    EXPECT_NE(error.find(file), std::string::npos) << error;
  }
}

TEST_F(ColmapAlign, ConfigurationErrors) {
  auto config_error = [](const std::vector<std::string>& overrides) {
    return ErrorOf([&] {
      LoadedConfig config;
      config.Load("", overrides);
    });
  };
  const std::string base = "dataset.path=" + *dir_ + "/strecha";
  EXPECT_NE(config_error(
                {base, "dataset.reference=\"0005\"", "dataset.align=scan", "gcp.lidar.path=x.ply"})
                .find("dataset.align = scan. Violated constraint: none unless dataset.format is "
                      "colmap"),
            std::string::npos);
  const std::string colmap = "dataset.path=" + *dir_ + "/moved";
  EXPECT_NE(config_error({"dataset.format=colmap", colmap, "dataset.reference=0005.png",
                          "dataset.align=scan"})
                .find("dataset.align = scan needs the scan: set gcp.lidar.path"),
            std::string::npos);
  EXPECT_NE(config_error({"dataset.format=colmap", colmap, "dataset.reference=0005.png",
                          "dataset.align=centres"})
                .find("needs dataset.align_centres"),
            std::string::npos);
  EXPECT_NE(config_error({"dataset.format=colmap", colmap, "dataset.reference=0005.png",
                          "dataset.align_max_residual=0"})
                .find("dataset.align_max_residual"),
            std::string::npos);
}

// A measurement, not a check run by default (writing the fountain preset takes minutes): with
// GCPSTEREO_SYNTH_FOUNTAIN set to a folder `gcpstereo synth --preset fountain` wrote, its cameras
// and every 20th laser point (1 cm of noise added per axis: a triangulation's error) become a
// COLMAP model in the frame of ModelFromWorld(), which is then aligned to gt/laser.ply and to the
// true camera centres; the figures are printed (README, "COLMAP models"). Measured: scan, scale
// error −0.018 %, rotation error 0.006°, camera centres within 2.6 mm, residuals median 11.7 mm,
// 90th percentile 18.7 mm, RMS 13.1 mm, 100 % inliers, 25 s; centres exact.
TEST(ColmapAlignMeasure, SyntheticFountain) {
  const char* fountain = std::getenv("GCPSTEREO_SYNTH_FOUNTAIN");
  if (!fountain) GTEST_SKIP() << "set GCPSTEREO_SYNTH_FOUNTAIN to a synthetic fountain folder";
  const std::string dir = testing::MakeTempDir("gcpstereo-align-fountain");
  WriteColmapWorkspace(fountain, dir + "/ws", 20, "", ModelFromWorld(), 0.01);
  std::ofstream centres(dir + "/centres.txt");
  centres << std::setprecision(17);
  for (const std::string& name : io::ListDatasetViews("strecha", fountain)) {
    const Camera c =
        io::ReadStrechaCamera(std::string(fountain) + "/cameras/" + name + ".png.camera");
    centres << name << ".png " << c.center_world.transpose() << '\n';
  }
  centres.close();
  for (const std::string& method : std::vector<std::string>{"scan", "centres"}) {
    std::vector<std::string> overrides = {
        "dataset.format=colmap",
        "dataset.path=" + dir + "/ws",
        "dataset.reference=0005.png",
        "dataset.neighbors=[0004.png]",
        "gcp.sources=[]",
        "gcp.lidar.path=" + std::string(fountain) + "/gt/laser.ply",
        "dataset.align=" + method,
        "runtime.stop_after=load",
        "output.previews=false",
        "runtime.log_level=warn"};
    if (method == "centres") overrides.push_back("dataset.align_centres=" + dir + "/centres.txt");
    LoadedConfig config;
    config.Load("", overrides);
    const json report =
        json::parse(RunPipeline(config, dir + "/out_" + method, "(test)").report_json);
    json a = report["alignment"];
    a.erase("centres");
    Eigen::Matrix4d world_from_model;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c)
        world_from_model(r, c) = a["world_from_model"][r][c].get<double>();
    }
    // Where the aligned model puts each true camera centre, against the truth.
    double worst_m = 0.0;
    for (const std::string& name : io::ListDatasetViews("strecha", fountain)) {
      const Eigen::Vector3d c =
          io::ReadStrechaCamera(std::string(fountain) + "/cameras/" + name + ".png.camera")
              .center_world;
      const Eigen::Vector3d back =
          (world_from_model * ModelFromWorld() * c.homogeneous()).head<3>();
      worst_m = std::max(worst_m, (back - c).norm());
    }
    const Eigen::Matrix3d r = (world_from_model * ModelFromWorld()).topLeftCorner<3, 3>();
    std::cout << "synthetic fountain, align " << method << ": scale error "
              << a["scale"].get<double>() * 0.37 - 1.0 << ", rotation error "
              << Eigen::AngleAxisd(r / std::cbrt(r.determinant())).angle() * 180.0 / kPi
              << " deg, camera centres off by at most " << worst_m << " m; " << a.dump() << "\n";
    // Bounds of what was measured (README): a measurement, not a test of the defaults.
    EXPECT_NEAR(a["scale"].get<double>() * 0.37, 1.0, 0.01);
    EXPECT_LT(worst_m, 0.2);
  }
}

}  // namespace
}  // namespace gcpstereo::pipeline
