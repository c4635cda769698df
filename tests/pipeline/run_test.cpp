// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// End to end on the synthetic `tiny` scene: every output of the contract is written, the metrics
// are in report.json, and the GCP energy brings the depth closer to the truth.
#include "gcpstereo/pipeline/run.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"

namespace gcpstereo::pipeline {
namespace {

namespace fs = std::filesystem;

class TinyScene : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::MakeTempDir("gcpstereo-run"));
    synth::SynthOptions options;
    options.preset = "tiny";
    options.seed = 7;
    synth::WriteScene(synth::GenerateScene(options), options, *dir_ + "/data");
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  // A fast setting: few labels, parabola refinement, one tile.
  static std::vector<std::string> Overrides() {
    return {"dataset.path=" + *dir_ + "/data",
            "dataset.reference=0005",
            "labels.count=48",
            "gcp.sources=[lidar]",
            "gcp.lidar.path=" + *dir_ + "/data/gt/laser.ply",
            "gcp.downsample=8",
            "optimizer.tiles=[1, 1]",
            "optimizer.refinement=parabola",
            "runtime.log_level=warn"};
  }

  static nlohmann::json Run(const std::vector<std::string>& extra, const std::string& name) {
    std::vector<std::string> overrides = Overrides();
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    LoadedConfig config;
    config.Load("", overrides);
    const RunSummary summary = RunPipeline(config, *dir_ + "/" + name, "(test)");
    return nlohmann::json::parse(summary.report_json);
  }

  static std::string* dir_;
};
std::string* TinyScene::dir_ = nullptr;

TEST_F(TinyScene, WritesEveryContractOutput) {
  const nlohmann::json report = Run({}, "out");
  const fs::path out = *dir_ + "/out";
  for (const char* name :
       {"depth.pfm", "gcps.ply", "report.json", "effective_config.yaml", "depth.png", "gcps.png",
        "propagated.png", "sigma_histogram.png", "error_sigma.png", "index.html", "run.log"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  EXPECT_FALSE(fs::exists(out / "disparity.pfm"));  // not rectified data
  const cv::Mat depth = io::ReadPfm((out / "depth.pfm").string());
  EXPECT_EQ(depth.cols, 160);
  EXPECT_EQ(depth.rows, 107);
  EXPECT_GT(report["gcps"]["count"].get<int>(), 50);
  EXPECT_TRUE(report["metrics"]["depth_sigma"].contains("result"));
  EXPECT_TRUE(report["metrics"]["depth_sigma"].contains("propagated"));
  for (const char* stage : {"load", "gcps", "propagation", "cost_and_optimization", "write"}) {
    EXPECT_TRUE(report["stages"].contains(stage)) << stage;
  }
  // No staging folder or partial file is left behind.
  for (const auto& entry : fs::directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    EXPECT_EQ(name.find(".gcpstereo-staging"), std::string::npos) << name;
    EXPECT_NE(entry.path().extension(), ".partial") << name;
  }
}

TEST_F(TinyScene, GcpEnergyBringsDepthCloserToTheTruth) {
  const nlohmann::json with = Run({"optimizer.use_gcp_energy=true"}, "with");
  const nlohmann::json without = Run({"optimizer.use_gcp_energy=false"}, "without");
  const auto& w = with["metrics"]["depth_sigma"]["result"];
  const auto& wo = without["metrics"]["depth_sigma"]["result"];
  EXPECT_LT(w["mean_abs_error"].get<double>(), wo["mean_abs_error"].get<double>());
  EXPECT_GT(w["within_n_sigma_percent"][2].get<double>(),
            wo["within_n_sigma_percent"][2].get<double>());
}

TEST_F(TinyScene, BadReferenceNameFailsWithoutOutputs) {
  std::vector<std::string> overrides = Overrides();
  overrides.push_back("dataset.reference=0099");
  LoadedConfig config;
  config.Load("", overrides);
  EXPECT_THROW(RunPipeline(config, *dir_ + "/bad", "(test)"), Error);
  EXPECT_FALSE(fs::exists(*dir_ + "/bad/report.json"));
  EXPECT_FALSE(fs::exists(*dir_ + "/bad/depth.pfm"));
}

}  // namespace
}  // namespace gcpstereo::pipeline
