// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Same input and options → the same output bytes, whatever runtime.threads (1 or 2) and on a
// second run: a single-view run and a whole scene on the synthetic `tiny` set, 2×2 tiles solved in
// parallel, and a Middlebury pair from ../shared/data (skipped without it).
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/pipeline/run.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"
#include "tiny_data.h"

namespace gcpstereo::pipeline {
namespace {

using gcpstereo::testing::ReadFile;
namespace fs = std::filesystem;

class Determinism : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::WriteTinyData("gcpstereo-determinism"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  // Tiles solved in parallel (2×2), Ceres refinement, LiDAR GCPs through the CHOLMOD solve.
  static std::vector<std::string> Overrides(const std::string& reference) {
    const std::string data = *dir_ + "/data";
    return {"dataset.path=" + data,
            "dataset.reference=" + reference,
            "labels.count=32",
            "gcp.sources=[lidar]",
            "gcp.lidar.path=" + data + "/gt/laser.ply",
            "gcp.downsample=8",
            "optimizer.tiles=[2, 2]",
            "optimizer.tile_overlap=8",
            "scene_mesh.depth=7",
            "eval.scene.max_samples=20000",
            "output.previews=false",
            "runtime.log_level=warn"};
  }

  static std::string Run(std::vector<std::string> overrides, int threads, const std::string& name) {
    overrides.push_back("runtime.threads=" + std::to_string(threads));
    LoadedConfig config;
    config.Load("", overrides);
    const std::string out = *dir_ + "/" + name;
    RunPipeline(config, out, "(test)");
    return out;
  }

  // Every file of `names` is in both folders with the same bytes.
  static void ExpectSameBytes(const std::string& a, const std::string& b,
                              const std::vector<std::string>& names) {
    for (const std::string& name : names) {
      const std::string bytes_a = ReadFile(a + "/" + name);
      ASSERT_FALSE(bytes_a.empty()) << a << "/" << name;
      EXPECT_TRUE(bytes_a == ReadFile(b + "/" + name)) << name << " differs: " << a << ", " << b;
    }
  }

  static std::string* dir_;
};
std::string* Determinism::dir_ = nullptr;

const std::vector<std::string> kViewFiles = {"depth.pfm", "mesh.ply", "propagated_depth.pfm",
                                             "gcps.ply"};

TEST_F(Determinism, SingleViewRunIsTheSameBytesWhateverTheThreads) {
  const std::string one = Run(Overrides("0005"), 1, "view_1");
  const std::string two = Run(Overrides("0005"), 2, "view_2");
  const std::string again = Run(Overrides("0005"), 2, "view_2_again");
  ExpectSameBytes(one, two, kViewFiles);
  ExpectSameBytes(two, again, kViewFiles);
}

TEST_F(Determinism, SceneRunIsTheSameBytesWhateverTheThreads) {
  const std::string one = Run(Overrides("all"), 1, "scene_1");
  const std::string two = Run(Overrides("all"), 2, "scene_2");
  const std::string again = Run(Overrides("all"), 2, "scene_2_again");
  std::vector<std::string> files = {"fused.ply", "mesh.ply", "mesh.obj"};
  for (const char* view : {"0003", "0004", "0005", "0006", "0007"}) {
    for (const std::string& file : kViewFiles)
      files.push_back(std::string("views/") + view + "/" + file);
  }
  ExpectSameBytes(one, two, files);
  ExpectSameBytes(two, again, files);
}

// Real data: Middlebury Venus at half size with the shipped stereo configuration (stereo GCPs,
// census + guided filter, left-right check, plane fit), in 2×2 tiles.
TEST_F(Determinism, MiddleburyPairIsTheSameBytesWhateverTheThreads) {
  GCPSTEREO_REQUIRE_SHARED_DATA(venus, "middlebury/venus");
  std::vector<std::string> overrides = {"dataset.path=" + venus,  "dataset.scale=0.5",
                                        "optimizer.tiles=[2, 2]", "optimizer.tile_overlap=16",
                                        "output.previews=false",  "runtime.log_level=warn"};
  auto run = [&](int threads, const std::string& name) {
    std::vector<std::string> o = overrides;
    o.push_back("runtime.threads=" + std::to_string(threads));
    LoadedConfig config;
    config.Load(std::string(GCPSTEREO_SOURCE_DIR) + "/configs/middlebury_stereo.yaml", o);
    const std::string out = *dir_ + "/" + name;
    RunPipeline(config, out, "(test)");
    return out;
  };
  const std::string one = run(1, "venus_1");
  const std::string two = run(2, "venus_2");
  ExpectSameBytes(one, two, {"disparity.pfm", "depth.pfm", "mesh.ply", "gcps.ply"});
}

}  // namespace
}  // namespace gcpstereo::pipeline
