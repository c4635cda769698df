// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/pipeline_config.h"

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo::pipeline {
namespace {

namespace fs = std::filesystem;

TEST(PipelineConfig, EveryShippedConfigLoads) {
  const fs::path dir = fs::path(GCPSTEREO_SOURCE_DIR) / "configs";
  int count = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    LoadedConfig config;
    EXPECT_NO_THROW(config.Load(entry.path().string(), {}));
    ++count;
  }
  EXPECT_GE(count, 5);
}

TEST(PipelineConfig, PaperSettingInFountainConfig) {
  LoadedConfig config;
  config.Load((fs::path(GCPSTEREO_SOURCE_DIR) / "configs" / "fountain_p11.yaml").string(), {});
  const PipelineConfig& o = config.options();
  EXPECT_EQ(o.dataset.reference, "0005");
  EXPECT_EQ(o.dataset.neighbors.size(), 6u);
  EXPECT_EQ(o.dataset.scale, 0.5);
  EXPECT_EQ(o.labels.count, 360);
  // The paper's 2×2 tiles became 3×3: both cores busy, half the memory (the config says why).
  EXPECT_EQ(o.tiling.tiles, (std::vector<int>{3, 3}));
  EXPECT_EQ(o.tiling.tile_overlap, 16);
  EXPECT_EQ(o.gcp.downsample, 16);
}

TEST(PipelineConfig, CrossKeyChecks) {
  LoadedConfig config;
  try {
    config.Load("", {"dataset.path=/x", "dataset.reference=a", "labels.min=5", "labels.max=2"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "labels.min, labels.max = 5, 2. Violated constraint: min < max");
  }
  LoadedConfig missing_path;
  try {
    missing_path.Load("", {"dataset.reference=a"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "dataset.path is required (the data set's folder)");
  }
  LoadedConfig lidar_without_path;
  try {
    lidar_without_path.Load("", {"dataset.path=/x", "dataset.reference=a", "gcp.sources=[lidar]"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "gcp.sources lists lidar but gcp.lidar.path is not set");
  }
  LoadedConfig motion_of_a_world_cloud;  // strecha clouds are in world coordinates
  try {
    motion_of_a_world_cloud.Load(
        "", {"dataset.path=/x", "dataset.reference=a", "gcp.lidar.motion.mode=registration"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "gcp.lidar.motion.mode = registration. Violated constraint: off unless "
                 "dataset.format is kitti_raw (motion compensation needs the scan in the "
                 "scanner's own frame)");
  }
  LoadedConfig colmap_of_middlebury;  // no calibration: no COLMAP workspace
  try {
    colmap_of_middlebury.Load("", {"dataset.format=middlebury", "dataset.path=/x",
                                   "dataset.reference=im2", "output.colmap=true"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "output.colmap = true. Violated constraint: false for middlebury (it publishes "
                 "no camera calibration: its cameras and depths are in arbitrary units, so a "
                 "COLMAP workspace of them would not be the scene)");
  }
  for (const char* format : {"strecha", "colmap", "kitti_raw"}) {
    LoadedConfig calibrated;
    EXPECT_NO_THROW(calibrated.Load("", {std::string("dataset.format=") + format, "dataset.path=/x",
                                         "dataset.reference=a", "output.colmap=true"}))
        << format;
  }
}

// Every choice the schema offers for an algorithm key passes the module's own check (the schema
// once offered propagation.ordering "solver" where the module expected "amd").
TEST(PipelineConfig, EveryChoiceOfTheAlgorithmKeysLoads) {
  for (const char* setting :
       {"propagation.ordering=nested_dissection", "propagation.ordering=amd",
        "propagation.solver=umfpack", "propagation.solver=cholmod",
        "propagation.method=linear_system", "propagation.method=weighted_median",
        "optimizer.method=wta", "optimizer.method=graph_cuts", "optimizer.candidate_labels=all",
        "optimizer.candidate_labels=local", "optimizer.candidate_labels=prior"}) {
    SCOPED_TRACE(setting);
    LoadedConfig config;
    EXPECT_NO_THROW(config.Load("", {"dataset.path=/x", "dataset.reference=a", setting}));
  }
}

TEST(PipelineConfig, EffectiveConfigReloadsToTheSameValues) {
  LoadedConfig config;
  config.Load((fs::path(GCPSTEREO_SOURCE_DIR) / "configs" / "kitti_lidar.yaml").string(),
              {"optimizer.tiles=[3, 1]"});
  LoadedConfig again;
  config::Schema& s = const_cast<config::Schema&>(again.schema());
  s.LoadString(config.schema().ToYaml(), "effective_config.yaml");
  EXPECT_EQ(again.options().tiling.tiles, (std::vector<int>{3, 1}));
  EXPECT_EQ(again.options().dataset.references, std::vector<std::string>{"0000000010"});
  EXPECT_EQ(again.options().gcp.lidar_path, config.options().gcp.lidar_path);
}

}  // namespace
}  // namespace gcpstereo::pipeline
