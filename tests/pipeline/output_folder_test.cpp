// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/output_folder.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "test_data.h"

namespace gcpstereo::pipeline {
namespace {

namespace fs = std::filesystem;

size_t CountEntries(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

TEST(OutputFolder, NothingAppearsUntilCommit) {
  const fs::path dir = fs::path(testing::MakeTempDir("gcpstereo-out")) / "run";
  {
    OutputFolder out(dir.string());
    std::ofstream(out.Path("report.json")) << "{}";
    EXPECT_FALSE(fs::exists(dir / "report.json"));
    out.Commit();
  }
  EXPECT_TRUE(fs::exists(dir / "report.json"));
  EXPECT_EQ(CountEntries(dir), 1u);  // the staging folder is gone
}

TEST(OutputFolder, AbandonedRunLeavesNoFiles) {
  const fs::path dir = fs::path(testing::MakeTempDir("gcpstereo-out")) / "run";
  {
    OutputFolder out(dir.string());
    std::ofstream(out.Path("depth.pfm")) << "partial";
  }  // no Commit(): as when a later stage throws
  EXPECT_TRUE(fs::is_directory(dir));
  EXPECT_EQ(CountEntries(dir), 0u);
}

}  // namespace
}  // namespace gcpstereo::pipeline
