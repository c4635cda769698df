// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The view's peak memory is estimated before the big allocations, recorded in report.json beside
// the measured peak, and a run whose estimate exceeds runtime.max_memory_gb is refused with one
// line naming the keys that lower it.
#include "gcpstereo/pipeline/memory_estimate.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/pipeline/run.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"
#include "tiny_data.h"

namespace gcpstereo::pipeline {
namespace {

using gcpstereo::testing::ErrorOf;
namespace fs = std::filesystem;

ViewMemoryInput Fountain() {
  ViewMemoryInput in;
  in.width_px = 1536;
  in.height_px = 1024;
  in.labels = 360;
  in.neighbors = 6;
  in.tile_rows = in.tile_cols = 2;
  in.tile_overlap_px = 16;
  in.threads = 2;
  in.refinement = "parabola";
  return in;
}

TEST(MemoryEstimate, GrowsWithLabelsAndPixelsAndShrinksWithTiles) {
  const MemoryEstimate base = EstimateViewMemory(Fountain());
  ViewMemoryInput more_labels = Fountain();
  more_labels.labels = 720;
  // 4 more bytes per label and pixel of the tiles solved at once: the cost volume and its copy.
  EXPECT_DOUBLE_EQ(EstimateViewMemory(more_labels).optimization_bytes - base.optimization_bytes,
                   base.concurrent_tiles * base.tile_pixels * 4.0 * 360);
  ViewMemoryInput one_tile = Fountain();
  one_tile.tile_rows = one_tile.tile_cols = 1;
  EXPECT_GT(EstimateViewMemory(one_tile).total_bytes(), base.total_bytes());
  ViewMemoryInput more_tiles = Fountain();
  more_tiles.tile_rows = more_tiles.tile_cols = 4;
  EXPECT_LT(EstimateViewMemory(more_tiles).total_bytes(), base.total_bytes());
  ViewMemoryInput smaller = Fountain();
  smaller.width_px /= 2;
  smaller.height_px /= 2;
  EXPECT_LT(EstimateViewMemory(smaller).total_bytes(), base.total_bytes());
  // The Ceres refinement needs more per pixel than the expansion at 360 labels.
  ViewMemoryInput ceres = Fountain();
  ceres.refinement = "ceres";
  EXPECT_GT(EstimateViewMemory(ceres).optimization_bytes, base.optimization_bytes);
  // Two tiles at once with two threads, one with one.
  EXPECT_EQ(base.concurrent_tiles, 2);
  ViewMemoryInput one_thread = Fountain();
  one_thread.threads = 1;
  EXPECT_EQ(EstimateViewMemory(one_thread).concurrent_tiles, 1);
}

// The left-right check's partner solve runs alongside the reference's D̂ and tiles: as much again
// as the larger of the two, and nothing when the run stops after D̂.
TEST(MemoryEstimate, LeftRightPartnerCountsAsASecondSolve) {
  const MemoryEstimate base = EstimateViewMemory(Fountain());
  EXPECT_EQ(base.partner_bytes, 0.0);
  ViewMemoryInput checked = Fountain();
  checked.left_right_check = true;
  const MemoryEstimate with_partner = EstimateViewMemory(checked);
  EXPECT_GT(with_partner.partner_bytes, 0.0);
  EXPECT_DOUBLE_EQ(with_partner.partner_bytes,
                   std::max(base.propagation_bytes, base.optimization_bytes));
  EXPECT_DOUBLE_EQ(with_partner.total_bytes() - base.total_bytes(), with_partner.partner_bytes);
  checked.optimize = false;
  EXPECT_EQ(EstimateViewMemory(checked).partner_bytes, 0.0);
}

TEST(MemoryEstimate, BudgetIsTheKeyOrTheMachinesAvailableMemory) {
  EXPECT_GT(AvailableMemoryBytes(), 0.0);
  EXPECT_EQ(MemoryBudgetBytes(2.5), 2.5e9);
  MemoryEstimate e;
  e.base_bytes = 3e9;
  EXPECT_EQ(ErrorOf([&] { CheckMemoryBudget(e, 4.0); }), "(no error)");
  EXPECT_EQ(ErrorOf([&] { CheckMemoryBudget(e, 2.0); }),
            "this view needs an estimated 3000 MB, more than runtime.max_memory_gb = 2 (2000 MB): "
            "lower it with more optimizer.tiles, a smaller dataset.scale or fewer labels.count");
}

class TinyMemory : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::WriteTinyData("gcpstereo-memory"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static void Load(LoadedConfig* config, const std::string& extra) {
    const std::string data = *dir_ + "/data";
    config->Load("", {"dataset.path=" + data, "dataset.reference=0005", "labels.count=48",
                      "gcp.sources=[lidar]", "gcp.lidar.path=" + data + "/gt/laser.ply",
                      "gcp.downsample=8", "optimizer.tiles=[1, 1]", "optimizer.refinement=parabola",
                      "output.previews=false", "runtime.log_level=warn", extra});
  }
  static std::string* dir_;
};
std::string* TinyMemory::dir_ = nullptr;

TEST_F(TinyMemory, RefusedBeforeAllocatingWhenOverMaxMemory) {
  const std::string out = *dir_ + "/refused";
  LoadedConfig config;
  Load(&config, "runtime.max_memory_gb=0.01");
  const std::string error = ErrorOf([&] { RunPipeline(config, out, "(test)"); });
  EXPECT_EQ(error.rfind("this view needs an estimated ", 0), 0u) << error;
  EXPECT_NE(error.find("more than runtime.max_memory_gb = 0.01 (10 MB): lower it with more "
                       "optimizer.tiles, a smaller dataset.scale or fewer labels.count"),
            std::string::npos)
      << error;
  EXPECT_EQ(error.find('\n'), std::string::npos);
  EXPECT_FALSE(fs::exists(out + "/report.json"));
  EXPECT_FALSE(fs::exists(out + "/depth.pfm"));
}

TEST_F(TinyMemory, EstimateIsInTheReportBesideTheMeasuredPeak) {
  LoadedConfig config;
  Load(&config, "runtime.max_memory_gb=0");
  const RunSummary summary = RunPipeline(config, *dir_ + "/estimated", "(test)");
  const nlohmann::json report = nlohmann::json::parse(summary.report_json);
  ASSERT_TRUE(report.contains("memory_estimate"));
  const double estimate = report["memory_estimate"]["total_bytes"].get<double>();
  const double peak = report["peak_memory_bytes"].get<double>();
  EXPECT_GT(estimate, 0.0);
  EXPECT_GT(peak, 0.0);
  // In this test process (gtest and the other tests' memory add to the peak) only the order of
  // magnitude can be checked; the shipped configurations' figures are in the README.
  EXPECT_LT(estimate, 4.0 * peak);
  EXPECT_GT(estimate, 0.25 * peak);
}

}  // namespace
}  // namespace gcpstereo::pipeline
