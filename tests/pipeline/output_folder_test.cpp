// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/output_folder.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
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
  EXPECT_TRUE(fs::exists(dir / OutputFolder::kManifestName));
  EXPECT_EQ(CountEntries(dir), 2u);  // the staging folder is gone
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

// A folder reused by a run with other options: the previous run's files that this run does not
// write again go, files the user put there stay, and a failed run changes nothing.
TEST(OutputFolder, ReusedFolderHoldsOneRunsOutputs) {
  const fs::path dir = fs::path(testing::MakeTempDir("gcpstereo-out")) / "run";
  {
    OutputFolder out(dir.string());
    for (const char* name : {"depth.pfm", "mesh.ply", "depth.png"}) {
      std::ofstream(out.Path(name)) << "first";
    }
    out.Commit();
  }
  std::ofstream(dir / "notes.txt") << "mine";
  {
    OutputFolder out(dir.string());
    std::ofstream(out.Path("depth.pfm")) << "failed";
  }  // no Commit()
  EXPECT_TRUE(fs::exists(dir / "mesh.ply"));
  {
    OutputFolder out(dir.string());
    std::ofstream(out.Path("depth.pfm")) << "second";
    out.Path("planned_but_not_written.png");
    out.Commit();
  }
  std::ifstream depth(dir / "depth.pfm");
  std::string text;
  depth >> text;
  EXPECT_EQ(text, "second");
  EXPECT_FALSE(fs::exists(dir / "mesh.ply"));
  EXPECT_FALSE(fs::exists(dir / "depth.png"));
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  std::ifstream manifest(dir / OutputFolder::kManifestName);
  std::string listed;
  std::getline(manifest, listed, '\0');
  EXPECT_EQ(listed, "depth.pfm\n");
}

// A folder output (colmap/) is committed whole, replaced whole by the next run that writes it,
// and removed by the next run that does not.
TEST(OutputFolder, FolderOutputsAreCommittedAndReplacedWhole) {
  const fs::path dir = fs::path(testing::MakeTempDir("gcpstereo-out")) / "run";
  auto write_folder = [](OutputFolder& out, const char* file) {
    const fs::path colmap = out.Path("colmap");
    fs::create_directories(colmap / "stereo");
    std::ofstream(colmap / "stereo" / file) << file;
  };
  {
    OutputFolder out(dir.string());
    write_folder(out, "first.bin");
    EXPECT_FALSE(fs::exists(dir / "colmap"));
    out.Commit();
  }
  EXPECT_TRUE(fs::exists(dir / "colmap" / "stereo" / "first.bin"));
  {
    OutputFolder out(dir.string());
    write_folder(out, "second.bin");
    out.Commit();
  }
  EXPECT_FALSE(fs::exists(dir / "colmap" / "stereo" / "first.bin"));
  EXPECT_TRUE(fs::exists(dir / "colmap" / "stereo" / "second.bin"));
  {
    OutputFolder out(dir.string());
    std::ofstream(out.Path("depth.pfm")) << "third";
    out.Commit();
  }
  EXPECT_FALSE(fs::exists(dir / "colmap"));
  EXPECT_TRUE(fs::exists(dir / "depth.pfm"));
}

// A run killed by a signal leaves its staging folder (no destructor runs); the next run into the
// folder removes it, since its process is gone. A live process's folder is left alone.
TEST(OutputFolder, StagingOfAKilledRunIsRemoved) {
  const fs::path dir = fs::path(testing::MakeTempDir("gcpstereo-out")) / "run";
  fs::create_directories(dir / ".gcpstereo-staging-999999999");
  std::ofstream(dir / ".gcpstereo-staging-999999999" / "depth.pfm") << "partial";
  fs::create_directories(dir / ".gcpstereo-staging-1");  // pid 1 (init) is alive
  { OutputFolder out(dir.string()); }
  EXPECT_FALSE(fs::exists(dir / ".gcpstereo-staging-999999999"));
  EXPECT_TRUE(fs::exists(dir / ".gcpstereo-staging-1"));
}

// An empty path is no folder: a clear error (std::filesystem's own is ": Invalid argument"), and
// nothing appears in the working folder.
TEST(OutputFolder, EmptyPathIsRefused) {
  const fs::path work = testing::MakeTempDir("gcpstereo-out");
  const fs::path previous = fs::current_path();
  fs::current_path(work);
  std::string message = "no error";
  try {
    OutputFolder out("");
  } catch (const Error& e) {
    message = e.what();
  }
  fs::current_path(previous);
  EXPECT_EQ(message, "the output folder path is empty");
  EXPECT_EQ(CountEntries(work), 0u);
}

}  // namespace
}  // namespace gcpstereo::pipeline
