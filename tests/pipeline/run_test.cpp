// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// End to end on the synthetic `tiny` scene: every output of the contract is written, the metrics
// are in report.json, and the GCP energy brings the depth closer to the truth.
#include "gcpstereo/pipeline/run.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/pipeline/evaluate.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"
#include "tiny_data.h"

namespace gcpstereo::pipeline {
namespace {

namespace fs = std::filesystem;

class TinyScene : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { dir_ = new std::string(testing::WriteTinyData("gcpstereo-run")); }
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

  // A run with one more override must throw E and leave no output in the folder `name`.
  template <typename E>
  static void ExpectRunFails(const std::string& override, const std::string& name) {
    std::vector<std::string> overrides = Overrides();
    overrides.push_back(override);
    LoadedConfig config;
    config.Load("", overrides);
    const std::string out = *dir_ + "/" + name;
    EXPECT_THROW(RunPipeline(config, out, "(test)"), E);
    EXPECT_FALSE(fs::exists(out + "/report.json"));
    EXPECT_FALSE(fs::exists(out + "/depth.pfm"));
    // run.log, which stays, ends with the error.
    std::ifstream log(out + "/run.log");
    const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("[error] run failed: "), std::string::npos) << text;
  }

  static std::string* dir_;
};
std::string* TinyScene::dir_ = nullptr;

TEST_F(TinyScene, WritesEveryContractOutput) {
  const nlohmann::json report = Run({}, "out");
  const fs::path out = *dir_ + "/out";
  for (const char* name : {"depth.pfm", "gcps.ply", "report.json", "effective_config.yaml",
                           "depth.png", "gcps.png", "propagated.png", "propagated_depth.pfm",
                           "sigma_histogram.png", "error_sigma.png", "index.html", "run.log"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  EXPECT_FALSE(fs::exists(out / "disparity.pfm"));  // not rectified data
  EXPECT_FALSE(fs::exists(out / "propagated_disparity.pfm"));
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

// runtime.stop_after = propagation: D̂ is the product (LiDAR depth completion without stereo): the
// same map as a full run's propagated_depth.pfm, scored and previewed, and no stereo result.
TEST_F(TinyScene, StopAfterPropagationWritesAndScoresThePropagatedMap) {
  const nlohmann::json full = Run({}, "full_for_stop");
  const nlohmann::json stopped = Run({"runtime.stop_after=propagation"}, "stop_propagation");
  const fs::path out = fs::path(*dir_) / "stop_propagation";
  for (const char* name : {"propagated_depth.pfm", "gcps.ply", "report.json", "propagated.png",
                           "gcps.png", "sigma_histogram.png", "index.html"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  for (const char* name : {"depth.pfm", "depth.png", "mesh.ply"}) {
    EXPECT_FALSE(fs::exists(out / name)) << name;
  }
  EXPECT_FALSE(stopped["stages"].contains("cost_and_optimization"));
  const auto& sigma = stopped["metrics"]["depth_sigma"];
  EXPECT_FALSE(sigma.contains("result"));
  ASSERT_TRUE(sigma.contains("propagated"));
  EXPECT_EQ(sigma["propagated"], full["metrics"]["depth_sigma"]["propagated"]);
  const cv::Mat a = io::ReadPfm((out / "propagated_depth.pfm").string());
  const cv::Mat b =
      io::ReadPfm((fs::path(*dir_) / "full_for_stop" / "propagated_depth.pfm").string());
  ASSERT_EQ(a.size(), b.size());
  int finite = 0;
  for (int r = 0; r < a.rows; ++r) {
    for (int c = 0; c < a.cols; ++c) {
      const float x = a.at<float>(r, c), y = b.at<float>(r, c);
      EXPECT_TRUE(x == y || (std::isnan(x) && std::isnan(y))) << r << "," << c;
      finite += std::isfinite(x);
    }
  }
  EXPECT_GT(finite, a.total() / 2);

  // `gcpstereo eval --run` on either folder scores what the run wrote, as the run itself did.
  EvalRequest request;
  request.run_folder = out.string();
  const nlohmann::json rescored = nlohmann::json::parse(RunEvaluation(request));
  EXPECT_FALSE(rescored["metrics"]["depth_sigma"].contains("result"));
  EXPECT_EQ(rescored["metrics"]["depth_sigma"]["propagated"], sigma["propagated"]);
  request.run_folder = (fs::path(*dir_) / "full_for_stop").string();
  EXPECT_EQ(nlohmann::json::parse(RunEvaluation(request))["metrics"]["depth_sigma"],
            full["metrics"]["depth_sigma"]);
}

// propagation.method = local_plane on the tiny scene's laser GCPs (one per 8 × 8 block): D̂ from
// robust local planes, fitted in inverse depth (the labels are depths), is closer to the truth
// than the paper's membrane (measured: mean |error| 0.310 m against 0.349 m, within 3σ 55.6 %
// against 52.1 %).
TEST_F(TinyScene, LocalPlanesBeatTheMembraneOnASparseScan) {
  const nlohmann::json membrane = Run({"runtime.stop_after=propagation"}, "membrane");
  const nlohmann::json planes =
      Run({"runtime.stop_after=propagation", "propagation.method=local_plane"}, "planes");
  EXPECT_EQ(planes["stages"]["propagation"]["solver"], "local planes");
  const auto& m = membrane["metrics"]["depth_sigma"]["propagated"];
  const auto& p = planes["metrics"]["depth_sigma"]["propagated"];
  EXPECT_LT(p["mean_abs_error"].get<double>(), m["mean_abs_error"].get<double>() - 0.02);
  EXPECT_GT(p["within_n_sigma_percent"][2].get<double>(),
            m["within_n_sigma_percent"][2].get<double>() + 2.0);
}

// Stereo GCPs on the calibrated tiny views: by default (gcp.stereo.refine_px 1) each match's depth
// is searched again on the plane-sweep cost of the labels, which puts more of them within one
// label of the truth than the rectified pairs' integer disparities do.
TEST_F(TinyScene, StereoGcpsAreRefinedOnThePlaneSweepCost) {
  const std::vector<std::string> stereo = {"gcp.sources=[stereo]", "gcp.downsample=1",
                                           "labels.min=4", "labels.max=13",
                                           "runtime.stop_after=propagation"};
  std::vector<std::string> off = stereo;
  off.push_back("gcp.stereo.refine_px=0");
  const nlohmann::json refined = Run(stereo, "stereo_refined");
  const nlohmann::json plain = Run(off, "stereo_plain");
  ASSERT_TRUE(refined["gcps"].contains("stereo_refinement"));
  EXPECT_FALSE(plain["gcps"].contains("stereo_refinement"));
  const auto& summary = refined["gcps"]["stereo_refinement"];
  const int input = summary["input"].get<int>(), kept = summary["refined"].get<int>();
  EXPECT_EQ(input, plain["gcps"]["count"].get<int>());
  EXPECT_EQ(kept, refined["gcps"]["count"].get<int>());
  EXPECT_EQ(kept + summary["dropped_at_edge"].get<int>() + summary["dropped_no_data"].get<int>(),
            input);
  const double before = plain["gcps"]["outliers"]["percent"].get<double>();
  const double after = refined["gcps"]["outliers"]["percent"].get<double>();
  std::cout << "[ measured ] tiny stereo GCPs: " << input << " -> " << kept
            << ", more than a label off " << before << " % -> " << after << " %\n";
  EXPECT_GT(kept, input * 3 / 4);
  EXPECT_LT(after, before / 2.0);  // measured 31.2 % -> 3.8 %
}

// LiDAR and image matches together with an automatic label range: the matches search the range
// the scan's GCPs give (the views' overlap alone is unbounded in depth, which failed before), and
// the report lists the sources in the configuration's order.
TEST_F(TinyScene, StereoWithLidarTakesTheRangeFromTheScan) {
  const nlohmann::json report =
      Run({"gcp.sources=[stereo, lidar]", "runtime.stop_after=propagation"}, "stereo_lidar");
  ASSERT_EQ(report["gcps"]["sources"].size(), 2u);
  EXPECT_EQ(report["gcps"]["sources"][0]["source"], "stereo");
  EXPECT_EQ(report["gcps"]["sources"][1]["source"], "lidar");
  EXPECT_GT(report["gcps"]["sources"][0]["gcps"].get<int>(), 20);
  EXPECT_EQ(report["labels"]["range_source"], "gcps");
}

// A label range that misses the scene (the tiny scene spans ≈ 5–12 m) is reported: every GCP
// lies outside it (report and a warning), rather than the run quietly scoring 0 %.
TEST_F(TinyScene, GcpsOutsideTheLabelRangeAreCounted) {
  const nlohmann::json inside = Run({"runtime.stop_after=propagation"}, "range_ok");
  const nlohmann::json outside =
      Run({"runtime.stop_after=propagation", "labels.min=20", "labels.max=30"}, "range_off");
  EXPECT_EQ(inside["labels"]["gcps_outside_range"].get<int>(), 0);
  EXPECT_EQ(outside["labels"]["gcps_outside_range"].get<int>(),
            outside["gcps"]["count"].get<int>());
}

// eval.lidar_holdout: half of the simulated scan feeds the GCPs, the other half is scored; scan
// points the camera cannot see (the scanner stands 0.4 m beside it) are not scored but counted.
TEST_F(TinyScene, LidarHoldoutScoresOnlyVisiblePoints) {
  const nlohmann::json report =
      Run({"eval.lidar_holdout=true", "eval.holdout_block_px=4", "gcp.downsample=1"}, "holdout");
  const auto& holdout = report["metrics"]["lidar_holdout"];
  ASSERT_TRUE(holdout.contains("result")) << holdout.dump();
  const int counted = holdout["result"]["counted"].get<int>();
  const int not_visible = holdout["not_visible_not_scored"].get<int>();
  std::cout << "[ measured ] tiny hold-out: " << counted << " points scored, " << not_visible
            << " not visible, mean |error| " << holdout["result"]["mean_abs_error"] << " m\n";
  EXPECT_GT(counted, 500);
  EXPECT_GT(not_visible, 0);
  EXPECT_LT(not_visible, counted / 4);
  EXPECT_EQ(holdout["unit"].get<std::string>(), "depth");
  // The scored half never fed the GCPs: the GCPs are at most the other half of the scan.
  EXPECT_LT(report["gcps"]["count"].get<int>(), counted + not_visible + 50);
  // Depth along z in metres; the tiny scene spans ≈ 5–12 m over 48 labels.
  EXPECT_LT(holdout["result"]["mean_abs_error"].get<double>(), 0.5);
  EXPECT_TRUE(fs::exists(fs::path(*dir_) / "holdout" / "error_holdout.png"));
  // `gcpstereo eval --run` makes the same split again and scores the same points.
  EvalRequest request;
  request.run_folder = (fs::path(*dir_) / "holdout").string();
  const nlohmann::json rescored = nlohmann::json::parse(RunEvaluation(request));
  EXPECT_EQ(rescored["metrics"]["lidar_holdout"], holdout);
}

// optimizer.prior_radius_px keeps E_gcp near the GCPs only (one GCP per 8×8 block here).
TEST_F(TinyScene, PriorRadiusLimitsTheGcpEnergyToPixelsNearGcps) {
  const nlohmann::json everywhere = Run({}, "radius0");
  const nlohmann::json near = Run({"optimizer.prior_radius_px=1.5"}, "radius1");
  const double all = everywhere["stages"]["cost_and_optimization"]["gcp_energy_pixels_percent"];
  const double some = near["stages"]["cost_and_optimization"]["gcp_energy_pixels_percent"];
  EXPECT_GT(all, 99.0);
  // Within 1.5 px: at most the 3×3 block around each GCP, ≤ 9 of every 64 pixels.
  EXPECT_GT(some, 1.0);
  EXPECT_LE(some, 100.0 * 9 / 64 + 0.5);
}

// optimizer.prior_segment_k keeps E_gcp in the colour segments that hold a GCP: with one segment
// (huge k) that is every pixel; with the finest segmentation (k 1, segments of ≥ 20 px against
// one GCP per 64 px) many segments hold none.
TEST_F(TinyScene, PriorSegmentsLimitTheGcpEnergyToSegmentsWithGcps) {
  const nlohmann::json whole = Run({"optimizer.prior_segment_k=1e9"}, "segments_whole");
  const nlohmann::json fine = Run({"optimizer.prior_segment_k=1"}, "segments_fine");
  const double all = whole["stages"]["cost_and_optimization"]["gcp_energy_pixels_percent"];
  const double some = fine["stages"]["cost_and_optimization"]["gcp_energy_pixels_percent"];
  std::cout << "[ measured ] GCP energy on " << all << " % (one segment) and " << some
            << " % (k 1) of the pixels\n";
  EXPECT_GT(all, 99.0);
  EXPECT_LT(some, all - 10.0);
  EXPECT_GT(some, 10.0);
}

TEST_F(TinyScene, BadReferenceNameFailsWithoutOutputs) {
  ExpectRunFails<Error>("dataset.reference=0099", "bad");
}

// A GCP file that is not there stops the run before the data set is loaded, naming its key.
TEST_F(TinyScene, MissingGcpFileNamesItsKey) {
  ExpectRunFails<IoError>("gcp.lidar.path=" + *dir_ + "/no/laser.ply", "no_scan");
  LoadedConfig config;
  std::vector<std::string> overrides = Overrides();
  const std::string missing = *dir_ + "/no/depth.pfm";
  overrides.insert(overrides.end(), {"gcp.sources=[depth_map]", "gcp.depth_map.path=" + missing});
  config.Load("", overrides);
  try {
    RunPipeline(config, *dir_ + "/no_depth", "(test)");
    ADD_FAILURE() << "no error";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), missing);
    EXPECT_NE(std::string(e.what()).find("gcp.depth_map.path"), std::string::npos) << e.what();
  }
}

// The left-right check solves the pair again from the neighbour: only for rectified pairs.
TEST_F(TinyScene, LeftRightCheckNeedsARectifiedPair) {
  ExpectRunFails<ConfigError>("optimizer.left_right_check=true", "lr");
}

// Planes are fitted in disparity: only for rectified data.
TEST_F(TinyScene, PlaneFitNeedsRectifiedData) {
  ExpectRunFails<ConfigError>("optimizer.plane_fit=true", "plane_fit");
}

// The shipped configs/<config_name> with `overrides` (after `base`), run into `out`.
nlohmann::json RunShippedConfig(const std::string& config_name, const std::string& out,
                                std::vector<std::string> base,
                                const std::vector<std::string>& overrides) {
  base.push_back("runtime.log_level=warn");
  base.insert(base.end(), overrides.begin(), overrides.end());
  LoadedConfig config;
  config.Load((fs::path(GCPSTEREO_SOURCE_DIR) / "configs" / config_name).string(), base);
  return nlohmann::json::parse(RunPipeline(config, out, "(test)").report_json);
}
// configs/middlebury_stereo.yaml on tsukuba's ground-truth pair.
nlohmann::json RunTsukuba(const std::string& tsukuba, const std::string& out,
                          const std::vector<std::string>& overrides) {
  return RunShippedConfig(
      "middlebury_stereo.yaml", out,
      {"dataset.path=" + tsukuba, "dataset.reference=scene1.row3.col3",
       "dataset.neighbors=[scene1.row3.col4]", "labels.min=0", "labels.max=15", "labels.count=16"},
      overrides);
}
double Bad1(const nlohmann::json& report, const char* mask) {
  return report["metrics"]["middlebury"]["result"][mask]["bad_percent"][1].get<double>();
}

// configs/strecha.yaml runs a Strecha-layout scene it was not written for with nothing set but
// the folder and the view (and the scale: the tiny scene's 160 px would be 80 px at the config's
// 0.5): the label range, the neighbours and the GCPs come from the data, and the report says so.
TEST_F(TinyScene, StrechaConfigRunsAnotherSceneUnattended) {
  const nlohmann::json report = RunShippedConfig(
      "strecha.yaml", *dir_ + "/strecha",
      {"dataset.path=" + *dir_ + "/data", "dataset.reference=0005", "dataset.scale=1"}, {});
  EXPECT_EQ(report["labels"]["range_source"], "gcps+matching");  // not "config"
  const auto& neighbors = report["dataset"]["neighbor_selection"]["neighbors"];
  ASSERT_GE(neighbors.size(), 2u);
  EXPECT_LE(neighbors.size(), 6u);
  for (const auto& name : neighbors) EXPECT_NE(name.get<std::string>(), "0005");
  EXPECT_EQ(report["gcps"]["sources"][0]["source"], "stereo");
  EXPECT_GT(report["gcps"]["count"].get<int>(), 0);
  // The truth (the tiny scene spans ≈ 5–12 m) lies inside the automatic range.
  EXPECT_LT(report["labels"]["min"].get<double>(), 5.0);
  EXPECT_GT(report["labels"]["max"].get<double>(), 11.0);
  // The stereo result improves on its own sparse prior D̂.
  const auto& metrics = report["metrics"]["depth_sigma"];
  EXPECT_GT(metrics["result"]["within_n_sigma_percent"][2].get<double>(),
            metrics["propagated"]["within_n_sigma_percent"][2].get<double>());
  EXPECT_TRUE(fs::exists(*dir_ + "/strecha/depth.pfm"));
}

// labels.min/max/count omitted on a rectified pair with stereo GCPs: the pair's matched
// disparities (OpenCV's semi-global matcher over every disparity below the width) bound the
// stereo GCPs' search and, with the GCPs, the labels: one per pixel from 0 up. The matches alone
// miss tsukuba's nearest surfaces (the lamp), which the range must still reach. Half-size tsukuba
// and a small adaptive-weight window keep it fast.
TEST(MiddleburyRun, AutomaticLabelRangeOfARectifiedPair) {
  GCPSTEREO_REQUIRE_SHARED_DATA(tsukuba, "middlebury/tsukuba");
  const std::string dir = testing::MakeTempDir("gcpstereo-auto");
  const nlohmann::json report =
      RunShippedConfig("middlebury_stereo.yaml", dir + "/out",
                       {"dataset.path=" + tsukuba, "dataset.reference=scene1.row3.col3",
                        "dataset.neighbors=[scene1.row3.col4]", "dataset.scale=0.5",
                        "labels.min=auto", "labels.max=auto", "labels.count=auto"},
                       {"gcp.stereo.aw_window_px=9", "output.previews=false", "output.mesh=false"});
  const nlohmann::json& labels = report["labels"];
  EXPECT_EQ(labels["range_source"], "gcps+matching");
  // Half-size tsukuba's disparities are 2.5…7 (the ground truth's 5…14 halved).
  EXPECT_EQ(labels["min"].get<double>(), 0.0);
  EXPECT_GE(labels["max"].get<double>(), 7.0);
  EXPECT_LE(labels["max"].get<double>(), 10.0);
  EXPECT_EQ(labels["step"].get<double>(), 1.0);
  EXPECT_EQ(labels["count"].get<int>(), labels["max"].get<int>() + 1);
  EXPECT_EQ(labels["gcps_outside_range"].get<int>(), 0);
}

// optimizer.gcp_spread (eq. 10) reaches the energy: the tiny scene's laser GCPs spread about a
// plane across its depth edges, so a smaller τ lowers more of the prior; the factor is reported
// and drawn, and it lowers the GCP energy's share of the optimum.
TEST_F(TinyScene, GcpSpreadWeightsThePrior) {
  const nlohmann::json plain = Run({"optimizer.refinement=none"}, "spread-off");
  const nlohmann::json tight =
      Run({"optimizer.refinement=none", "optimizer.gcp_spread=0.5"}, "spread-tight");
  const nlohmann::json loose =
      Run({"optimizer.refinement=none", "optimizer.gcp_spread=4"}, "spread-loose");
  const nlohmann::json& off = plain["stages"]["cost_and_optimization"];
  const nlohmann::json& on = tight["stages"]["cost_and_optimization"];
  EXPECT_EQ(off["gcp_spread_weight_mean"].get<double>(), 1.0);
  const double mean_tight = on["gcp_spread_weight_mean"].get<double>();
  const double mean_loose =
      loose["stages"]["cost_and_optimization"]["gcp_spread_weight_mean"].get<double>();
  EXPECT_GT(mean_tight, 0.0);
  EXPECT_LT(mean_tight, mean_loose);
  EXPECT_LT(mean_loose, 1.0);
  EXPECT_FALSE(fs::exists(*dir_ + "/spread-off/gcp_weight.png"));
  const cv::Mat picture = io::ReadImage(*dir_ + "/spread-tight/gcp_weight.png");
  EXPECT_FALSE(picture.empty());
  double gcp_off = 0.0, gcp_on = 0.0;
  for (const auto& tile : off["tiles"]) gcp_off += tile["energy"]["gcp"].get<double>();
  for (const auto& tile : on["tiles"]) gcp_on += tile["energy"]["gcp"].get<double>();
  EXPECT_LT(gcp_on, gcp_off);
}

// On tsukuba, the check fills the half-occluded bands left of the foreground objects with
// background: bad-1 over all pixels with a ground truth drops (measured 3.72 % → 2.29 %) and the
// unoccluded pixels do not get worse (1.69 % → 1.42 %). Without the plane fit, which acts after it.
TEST(MiddleburyRun, LeftRightCheckFillsHalfOccludedBands) {
  GCPSTEREO_REQUIRE_SHARED_DATA(tsukuba, "middlebury/tsukuba");
  const std::string dir = testing::MakeTempDir("gcpstereo-lr");
  const nlohmann::json without = RunTsukuba(
      tsukuba, dir + "/without", {"optimizer.plane_fit=false", "optimizer.left_right_check=false"});
  const nlohmann::json with = RunTsukuba(
      tsukuba, dir + "/with", {"optimizer.plane_fit=false", "optimizer.left_right_check=true"});
  EXPECT_LT(Bad1(with, "all"), Bad1(without, "all") - 0.5);
  EXPECT_LE(Bad1(with, "nonocc"), Bad1(without, "nonocc"));
  const nlohmann::json& stage = with["stages"]["left_right_check"];
  EXPECT_GT(stage["inconsistent_percent"].get<double>(), 1.0);
  EXPECT_LT(stage["inconsistent_percent"].get<double>(), 20.0);
  EXPECT_EQ(stage["max_fill_run_px"].get<int>(), 15);
  EXPECT_TRUE(fs::exists(dir + "/with/left_right_check.png"));
  EXPECT_FALSE(without["stages"].contains("left_right_check"));
}

// The plane fit of configs/middlebury_stereo.yaml on tsukuba: foreground fattened over background
// segments (and a dark, textureless patch matched at the wrong disparity) takes its segment's
// plane. Measured bad-1 nonocc 1.45 % → 1.13 %, all 2.07 % → 1.75 %.
TEST(MiddleburyRun, PlaneFitRemovesFattening) {
  GCPSTEREO_REQUIRE_SHARED_DATA(tsukuba, "middlebury/tsukuba");
  const std::string dir = testing::MakeTempDir("gcpstereo-planes");
  const nlohmann::json without =
      RunTsukuba(tsukuba, dir + "/without", {"optimizer.plane_fit=false"});
  const nlohmann::json with = RunTsukuba(tsukuba, dir + "/with", {"optimizer.plane_fit=true"});
  EXPECT_LT(Bad1(with, "nonocc"), Bad1(without, "nonocc") - 0.2);
  EXPECT_LT(Bad1(with, "all"), Bad1(without, "all"));
  const nlohmann::json& stage = with["stages"]["plane_fit"];
  EXPECT_GT(stage["changed_pixels"].get<int>(), 0);
  EXPECT_LT(stage["changed_percent"].get<double>(), 5.0);
  EXPECT_GT(stage["fitted_segments"].get<int>(), stage["segments"].get<int>() / 2);
  EXPECT_TRUE(fs::exists(dir + "/with/plane_fit.png"));
  EXPECT_FALSE(without["stages"].contains("plane_fit"));
}

// A KITTI raw drive of two 80×30 frames, 0000000010 and 0000000020, each with a Velodyne scan of
// a few points (synthetic calibration, as tests/io/dataset_io_test.cpp); returns the drive folder.
std::string WriteTinyKittiDrive(const fs::path& root) {
  const fs::path drive = root / "2011_01_01_drive_0001_sync";
  std::ofstream(root / "calib_cam_to_cam.txt")
      << "S_rect_02: 8.000000e+01 3.000000e+01\nR_rect_00: 1 0 0 0 1 0 0 0 1\n"
         "P_rect_02: 100 0 40 10 0 100 15 0 0 0 1 0\nP_rect_03: 100 0 40 -40 0 100 15 0 0 0 1 0\n";
  std::ofstream(root / "calib_velo_to_cam.txt") << "R: 0 -1 0 0 0 -1 1 0 0\nT: 0 0 0.1\n";
  for (const char* folder : {"image_02/data", "image_03/data", "velodyne_points/data"}) {
    fs::create_directories(drive / folder);
  }
  for (const std::string frame : {"0000000010", "0000000020"}) {
    for (const char* camera : {"image_02", "image_03"}) {
      cv::Mat image(30, 80, CV_8UC3);
      cv::randu(image, 0, 255);
      io::WritePng((drive / camera / "data" / (frame + ".png")).string(), image);
    }
    // x forward, y left, z up (Velodyne): 10 m ahead, spread across the view.
    std::ofstream scan(drive / "velodyne_points" / "data" / (frame + ".bin"), std::ios::binary);
    for (int i = 0; i < 5; ++i) {
      const float point[4] = {10.0f, 1.0f - 0.5f * i, 0.0f, 0.5f};
      scan.write(reinterpret_cast<const char*>(point), sizeof(point));
    }
  }
  return drive.string();
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// gcp.lidar.path of KITTI raw names one frame's scan and nothing tied it to dataset.reference:
// a run of frame 20 with frame 10's scan went on silently. Now it warns (run.log, stderr) naming
// both frames and report.json records the scan's frame; the same frame or a file name that is not
// a frame number (a renamed file) gives no warning.
TEST(KittiRun, ScanOfAnotherFrameIsWarnedAndReported) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-kitti-scan");
  const std::string drive = WriteTinyKittiDrive(dir);
  fs::copy_file(drive + "/velodyne_points/data/0000000010.bin", dir / "renamed.bin");
  auto run = [&](const std::string& frame, const std::string& scan, const std::string& out) {
    LoadedConfig config;
    config.Load("", {"dataset.format=kitti_raw", "dataset.path=" + drive,
                     "dataset.reference=" + frame, "gcp.sources=[lidar]", "gcp.lidar.path=" + scan,
                     "runtime.stop_after=load", "runtime.log_level=warn"});
    return nlohmann::json::parse(RunPipeline(config, (dir / out).string(), "(test)").report_json);
  };
  const std::string scan_10 = drive + "/velodyne_points/data/0000000010.bin";
  const nlohmann::json other = run("0000000020", scan_10, "other");
  EXPECT_EQ(other["dataset"]["lidar_scan"],
            nlohmann::json(
                {{"path", scan_10}, {"frame", "0000000010"}, {"same_frame_as_reference", false}}));
  const std::string log = ReadText(dir / "other" / "run.log");
  EXPECT_NE(log.find("[warning] gcp.lidar.path " + scan_10 +
                     " is by its name the Velodyne scan of frame 0000000010, but "
                     "dataset.reference is frame 0000000020"),
            std::string::npos)
      << log;

  const nlohmann::json same = run("0000000010", scan_10, "same");
  EXPECT_TRUE(same["dataset"]["lidar_scan"]["same_frame_as_reference"].get<bool>());
  EXPECT_EQ(ReadText(dir / "same" / "run.log").find("[warning]"), std::string::npos);
  const nlohmann::json renamed = run("0000000020", (dir / "renamed.bin").string(), "renamed");
  EXPECT_FALSE(renamed["dataset"].contains("lidar_scan"));
  EXPECT_EQ(ReadText(dir / "renamed" / "run.log").find("[warning]"), std::string::npos);
}

// KITTI frame 10 at half size (5 s a run): the weighted-median D̂ of kitti_lidar.yaml against the
// paper's linear-system D̂, and its colour floor and edge stretch against plain joint-bilateral
// weights (σs 4, σc 20), on the motion-compensated scan. Measured held-out bad-3: 1.76 % against
// 3.62 % (linear system) and 2.13 % (plain weights); D̂ alone 1.44 / 3.33 / 1.81 % (full size: see
// the config).
TEST(KittiRun, MedianPriorFollowsTheScan) {
  GCPSTEREO_REQUIRE_SHARED_DATA(drive, "kitti/2011_09_26/2011_09_26_drive_0009_sync");
  const std::string dir = testing::MakeTempDir("gcpstereo-kitti");
  auto run = [&](const std::string& name, const std::vector<std::string>& extra) {
    return RunShippedConfig(
        "kitti_lidar.yaml", dir + "/" + name,
        {"dataset.path=" + drive, "dataset.reference=0000000010",
         "gcp.lidar.path=" + drive + "/velodyne_points/data/0000000010.bin",
         "eval.lidar_holdout=true", "dataset.scale=0.5", "labels.max=63", "labels.count=64"},
        extra);
  };
  const nlohmann::json shipped = run("shipped", {});
  const nlohmann::json paper = run("linear", {"propagation.method=linear_system"});
  const nlohmann::json plain =
      run("plain", {"propagation.median_colour_floor=0", "propagation.median_edge_stretch=1",
                    "propagation.median_sigma_px=4", "propagation.median_sigma_colour=20"});
  auto bad3 = [](const nlohmann::json& report, const char* map) {
    return report["metrics"]["lidar_holdout"][map]["bad3_percent"].get<double>();
  };
  EXPECT_LT(bad3(shipped, "result"), bad3(paper, "result") - 1.0);
  EXPECT_LT(bad3(shipped, "propagated"), bad3(paper, "propagated") - 1.0);
  EXPECT_LT(bad3(shipped, "result"), bad3(plain, "result") - 0.3);
  EXPECT_LT(bad3(shipped, "propagated"), bad3(plain, "propagated") - 0.3);
  EXPECT_EQ(shipped["stages"]["propagation"]["solver"], "weighted median");
  EXPECT_FALSE(shipped["stages"].contains("left_right_check"));
}

}  // namespace
}  // namespace gcpstereo::pipeline
