// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Whole scenes on the synthetic `tiny` set (views 0003–0007): the scene run's views are the
// per-view runs' bytes, the fused points lie on the true surface, an interrupted run resumes, a
// failed view is reported and skipped, and `fuse` refuses folders of different scenes.
#include "gcpstereo/pipeline/scene.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/pipeline/run.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"
#include "tiny_data.h"

namespace gcpstereo::pipeline {
namespace {

using gcpstereo::testing::ReadFile;

namespace fs = std::filesystem;
using nlohmann::json;

class TinySceneRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::WriteTinyData("gcpstereo-scene"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  // The fast setting of run_test.cpp, for every view of the scene.
  static std::vector<std::string> Overrides(const std::string& data = "") {
    const std::string path = data.empty() ? *dir_ + "/data" : data;
    return {"dataset.path=" + path,
            "dataset.reference=all",
            "labels.count=48",
            "gcp.sources=[lidar]",
            "gcp.lidar.path=" + path + "/gt/laser.ply",
            "gcp.downsample=8",
            "optimizer.tiles=[1, 1]",
            "optimizer.refinement=parabola",
            "scene_mesh.depth=7",
            "eval.scene.max_samples=100000",
            "runtime.log_level=warn"};
  }

  static json RunScene(const std::string& name, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> overrides = Overrides();
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    LoadedConfig config;
    config.Load("", overrides);
    const RunSummary summary = RunPipeline(config, *dir_ + "/" + name, "(test)");
    return json::parse(summary.report_json);
  }

  static json ViewStatus(const json& report, const std::string& name) {
    for (const json& v : report["views"]) {
      if (v["name"] == name) return v;
    }
    return nullptr;
  }

  static std::string* dir_;
};
std::string* TinySceneRun::dir_ = nullptr;

TEST_F(TinySceneRun, FusedPointsLieOnTheTrueSurface) {
  const json report = RunScene("scene");
  const std::string out = *dir_ + "/scene";
  ASSERT_EQ(report["views"].size(), 5u);
  for (const json& v : report["views"]) {
    EXPECT_EQ(v["status"], "done") << v.dump();
    EXPECT_TRUE(fs::exists(out + "/views/" + v["name"].get<std::string>() + "/depth.pfm"));
  }
  for (const char* file : {"fused.ply", "mesh.ply", "mesh.obj", "report.json", "index.html",
                           "effective_config.yaml", "model_1.png"}) {
    EXPECT_TRUE(fs::exists(out + "/" + file)) << file;
  }
  const OrientedPointCloud fused = io::ReadOrientedPointCloudPly(out + "/fused.ply");
  EXPECT_GT(fused.size(), 5000u);
  // The tiny views (f ≈ 144 px) see the fountain 9 m away at about 6 cm per pixel, with 48 depth
  // labels about 14 cm apart: the fused points' median distance to the exact surface is under a
  // pixel's footprint and most lie within two (measured: 3.1 cm; 87 % within 10 cm).
  const double footprint_m = 9.0 / 144.0;
  const json& points = report["metrics"]["fused_points_vs_gt_mesh"];
  EXPECT_LT(points["accuracy_median"].get<double>(), footprint_m) << points.dump();
  EXPECT_GT(points["accuracy_percent"][3].get<double>(), 80.0) << points.dump();  // 10 cm
  const json& mesh = report["metrics"]["mesh_vs_gt_mesh"];
  EXPECT_LT(mesh["accuracy_median"].get<double>(), footprint_m) << mesh.dump();
  EXPECT_EQ(report["metrics"]["views_sigma"]["views"].size(), 5u);
}

TEST_F(TinySceneRun, ViewsAreTheSingleReferenceRunsBytes) {
  RunScene("scene_bytes", {"dataset.reference=[\"0004\", \"0006\"]"});
  std::vector<std::string> overrides = Overrides();
  overrides.push_back("dataset.reference=\"0006\"");
  LoadedConfig single;
  single.Load("", overrides);
  RunPipeline(single, *dir_ + "/single_0006", "(test)");
  for (const char* file : {"depth.pfm", "gcps.ply", "mesh.ply", "effective_config.yaml"}) {
    EXPECT_EQ(ReadFile(*dir_ + "/scene_bytes/views/0006/" + file),
              ReadFile(*dir_ + "/single_0006/" + file))
        << file;
  }
}

TEST_F(TinySceneRun, ResumesWithTheMissingViews) {
  const std::string out = *dir_ + "/resume";
  RunScene("resume", {"dataset.reference=[\"0003\", \"0004\", \"0005\"]"});
  const auto kept_time = fs::last_write_time(out + "/views/0003/depth.pfm");
  // View 0004 was being computed when the run was killed: its folder holds only a staging folder.
  fs::remove_all(out + "/views/0004");
  fs::create_directories(out + "/views/0004/.gcpstereo-staging-999999999");
  std::ofstream(out + "/views/0004/.gcpstereo-staging-999999999/depth.pfm") << "partial";
  const json report = RunScene("resume", {"dataset.reference=[\"0003\", \"0004\", \"0005\"]"});
  EXPECT_EQ(ViewStatus(report, "0003")["status"], "reused");
  EXPECT_EQ(ViewStatus(report, "0004")["status"], "done");
  EXPECT_EQ(ViewStatus(report, "0005")["status"], "reused");
  EXPECT_EQ(fs::last_write_time(out + "/views/0003/depth.pfm"), kept_time);
  EXPECT_TRUE(fs::exists(out + "/views/0004/depth.pfm"));
  EXPECT_FALSE(fs::exists(out + "/views/0004/.gcpstereo-staging-999999999"));
  // A changed configuration is not reused.
  const json changed =
      RunScene("resume", {"dataset.reference=[\"0003\", \"0004\", \"0005\"]", "labels.count=40"});
  EXPECT_EQ(ViewStatus(changed, "0003")["status"], "done");
}

TEST_F(TinySceneRun, AFailedViewIsReportedAndLeftOut) {
  const std::string out = *dir_ + "/failed";
  fs::create_directories(out + "/views");
  std::ofstream(out + "/views/0004") << "a file where the view's folder should be";
  const json report = RunScene("failed", {"dataset.reference=[\"0004\", \"0005\", \"0006\"]"});
  const json failed = ViewStatus(report, "0004");
  EXPECT_EQ(failed["status"], "failed");
  EXPECT_NE(failed["error"].get<std::string>().find("views/0004"), std::string::npos)
      << failed.dump();
  EXPECT_EQ(report["fused_views"], 2);
  EXPECT_TRUE(fs::exists(out + "/fused.ply"));
}

TEST_F(TinySceneRun, FailsWhenNoViewIsLeft) {
  const std::string out = *dir_ + "/none_left";
  fs::create_directories(out + "/views");
  std::ofstream(out + "/views/0005") << "not a folder";
  std::vector<std::string> overrides = Overrides();
  overrides.push_back("dataset.reference=[\"0005\"]");
  LoadedConfig config;
  config.Load("", overrides);
  // One name in a list is a single reference: it fails as a single run does.
  EXPECT_THROW(RunPipeline(config, out + "/views/0005", "(test)"), IoError);
  overrides.back() = "dataset.reference=[\"0005\", \"0006\"]";
  std::ofstream(out + "/views/0006") << "not a folder";
  LoadedConfig scene;
  scene.Load("", overrides);
  try {
    RunPipeline(scene, out, "(test)");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene: no view finished, nothing to fuse (0005: "),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(out + "/fused.ply"));
  EXPECT_FALSE(fs::exists(out + "/report.json"));
}

TEST_F(TinySceneRun, FuseRefusesFoldersOfDifferentScenesOrCameras) {
  RunScene("fuse_a", {"dataset.reference=[\"0004\", \"0005\"]"});
  RunScene("fuse_b", {"dataset.reference=[\"0004\", \"0005\"]", "dataset.scale=0.5"});
  FuseRequest request;
  request.view_dirs = {*dir_ + "/fuse_a/views/0004", *dir_ + "/fuse_b/views/0005"};
  request.output_dir = *dir_ + "/fused_mixed";
  try {
    FuseViewFolders(request);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(
        std::string(e.what()).find("only views of one scene with the same cameras can be fused"),
        std::string::npos)
        << e.what();
  }
  request.view_dirs = {*dir_ + "/fuse_a/views/0004", *dir_ + "/fuse_a/views/0004"};
  EXPECT_THROW(FuseViewFolders(request), Error);
  request.view_dirs = {*dir_ + "/fuse_a/views/0004", *dir_ + "/data"};
  EXPECT_THROW(FuseViewFolders(request), IoError);
  EXPECT_FALSE(fs::exists(*dir_ + "/fused_mixed/fused.ply"));
  // The same folders fused apart give the scene run's model.
  request.view_dirs = {*dir_ + "/fuse_a/views/0004", *dir_ + "/fuse_a/views/0005"};
  FuseViewFolders(request);
  EXPECT_EQ(ReadFile(*dir_ + "/fused_mixed/fused.ply"), ReadFile(*dir_ + "/fuse_a/fused.ply"));
  EXPECT_EQ(ReadFile(*dir_ + "/fused_mixed/mesh.ply"), ReadFile(*dir_ + "/fuse_a/mesh.ply"));
}

// A view run alone with PlanViewJobs' overrides is the scene's view: the scene run with
// compute_views = false (`run --fuse-only`, the workflow's fusion job) reuses it, computes no
// other view and reports the missing one as failed, with the error its run.log ends on.
TEST_F(TinySceneRun, ViewJobsRunAloneAreReusedByAFuseOnlyScene) {
  const std::string out = *dir_ + "/jobs";
  // An explicit neighbour list: each view uses the others of the list.
  std::vector<std::string> scene_overrides = Overrides();
  scene_overrides.push_back("dataset.reference=[\"0004\", \"0005\", \"0006\"]");
  scene_overrides.push_back("dataset.neighbors=[\"0004\", \"0005\", \"0006\", \"0007\"]");
  LoadedConfig scene;
  scene.Load("", scene_overrides);
  const std::vector<ViewJob> jobs = PlanViewJobs(scene);
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[1].name, "0005");
  EXPECT_EQ(jobs[1].width_px, 160);
  EXPECT_EQ(jobs[1].height_px, 107);
  EXPECT_EQ(jobs[1].overrides,
            (std::vector<std::string>{"dataset.reference=\"0005\"",
                                      "dataset.neighbors=[\"0004\", \"0006\", \"0007\"]"}));
  for (const ViewJob& job : {jobs[0], jobs[1]}) {
    std::vector<std::string> overrides = scene_overrides;
    overrides.insert(overrides.end(), job.overrides.begin(), job.overrides.end());
    LoadedConfig view;
    view.Load("", overrides);
    RunPipeline(view, out + "/views/" + job.name, "(test)");
  }
  // View 0006 failed in its own job: its folder holds only its run.log.
  fs::create_directories(out + "/views/0006");
  std::ofstream(out + "/views/0006/run.log") << "[00:00:00] run failed: out of memory\n";
  const json report =
      json::parse(gcpstereo::pipeline::RunScene(scene, out, {/*compute_views=*/false}).report_json);
  EXPECT_EQ(ViewStatus(report, "0004")["status"], "reused");
  EXPECT_EQ(ViewStatus(report, "0005")["status"], "reused");
  const json failed = ViewStatus(report, "0006");
  EXPECT_EQ(failed["status"], "failed");
  EXPECT_NE(failed["error"].get<std::string>().find("--fuse-only"), std::string::npos);
  EXPECT_NE(failed["error"].get<std::string>().find("its run.log: out of memory"),
            std::string::npos)
      << failed.dump();
  EXPECT_FALSE(fs::exists(out + "/views/0006/depth.pfm"));
  EXPECT_EQ(report["fused_views"], 2);
  // A single reference is one job, the run as configured.
  LoadedConfig single;
  std::vector<std::string> one = Overrides();
  one.push_back("dataset.reference=\"0005\"");
  single.Load("", one);
  const std::vector<ViewJob> single_jobs = PlanViewJobs(single);
  ASSERT_EQ(single_jobs.size(), 1u);
  EXPECT_EQ(single_jobs[0].name, "0005");
  EXPECT_TRUE(single_jobs[0].overrides.empty());
}

TEST_F(TinySceneRun, AutomaticNeighboursAreRecorded) {
  const json report = RunScene("auto", {"dataset.reference=[\"0005\", \"0006\"]",
                                        "dataset.neighbors=auto", "dataset.neighbor_count=2"});
  const json view = json::parse(ReadFile(*dir_ + "/auto/views/0005/report.json"));
  ASSERT_TRUE(view["dataset"].contains("neighbor_selection")) << view["dataset"].dump();
  ASSERT_EQ(view["dataset"]["neighbors"].size(), 2u);
  // One station on either side of 0005 (at 10° and 20° both score fully: cost::SelectNeighbors).
  std::vector<std::string> names;
  for (const json& n : view["dataset"]["neighbors"]) names.push_back(n["name"]);
  std::sort(names.begin(), names.end());
  EXPECT_LT(names[0], "0005");
  EXPECT_GT(names[1], "0005");
  EXPECT_EQ(view["dataset"]["neighbor_selection"]["neighbors"].size(), 2u)
      << view["dataset"]["neighbor_selection"].dump();
}

TEST(SceneConfig, BadValuesAreRefusedByName) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"fusion.min_views=0", "fusion.min_views = 0. Violated constraint: 1 <= fusion.min_views"},
      {"fusion.depth_tolerance=0", "fusion.depth_tolerance = 0. Violated constraint"},
      {"fusion.normal_tolerance_deg=200", "fusion.normal_tolerance_deg = 200. Violated constraint"},
      {"fusion.stride_px=0", "fusion.stride_px = 0. Violated constraint"},
      {"scene_mesh.depth=3", "scene_mesh.depth = 3. Violated constraint"},
      {"dataset.neighbors=[auto, im1]", "dataset.neighbors = [..., auto, ...]"},
      {"dataset.neighbors=some", "dataset.neighbors = some. Violated constraint: a list or auto"},
      {"dataset.reference=[all, im2]", "dataset.reference = [..., all, ...]"},
      {"dataset.reference=[im2, im2]", "dataset.reference = im2. Violated constraint: each view"},
  };
  for (const auto& [assignment, message] : cases) {
    LoadedConfig config;
    try {
      config.Load("", {"dataset.path=/x", "dataset.reference=im2", assignment});
      ADD_FAILURE() << assignment << " was accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
          << assignment << ": " << e.what();
    }
  }
  LoadedConfig kitti;
  EXPECT_THROW(
      kitti.Load("", {"dataset.format=kitti_raw", "dataset.path=/x", "dataset.reference=all"}),
      ConfigError);
}

}  // namespace
}  // namespace gcpstereo::pipeline
