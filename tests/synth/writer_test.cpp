// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/camera_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"

namespace gcpstereo::synth {
namespace {

namespace fs = std::filesystem;

std::string FileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(SynthWriterTest, WritesTheStrechaLayoutDeterministically) {
  SynthOptions options;
  options.preset = "tiny";
  options.supersampling = 1;
  const SyntheticScene scene = GenerateScene(options);
  const std::string dir_a = testing::MakeTempDir("synth_a");
  const std::string dir_b = testing::MakeTempDir("synth_b");
  WriteScene(scene, options, dir_a);
  WriteScene(GenerateScene(options), options, dir_b);

  std::vector<std::string> files = {"gt/laser.ply", "gt/mesh.ply", "gt/scene.json"};
  for (const View& v : scene.views) {
    files.push_back("images/" + v.name + ".png");
    files.push_back("cameras/" + v.name + ".png.camera");
    files.push_back("gt/" + v.name + ".depth.pfm");
    files.push_back("gt/" + v.name + ".sigma.pfm");
  }
  for (const std::string& f : files) {
    ASSERT_TRUE(fs::exists(fs::path(dir_a) / f)) << f;
    EXPECT_EQ(FileBytes(fs::path(dir_a) / f), FileBytes(fs::path(dir_b) / f)) << f;
  }
  for (const auto& entry : fs::recursive_directory_iterator(dir_a)) {
    EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos) << entry.path();
  }

  // Read back through the io module.
  const int ref = scene.reference_index;
  const cv::Mat depth = io::ReadPfm(dir_a + "/gt/0005.depth.pfm");
  ASSERT_EQ(depth.size(), scene.depth[ref].size());
  EXPECT_EQ(cv::norm(depth != scene.depth[ref], cv::NORM_L1), 0.0);
  const Camera camera = io::ReadStrechaCamera(dir_a + "/cameras/0005.png.camera");
  EXPECT_LT((camera.K - scene.views[ref].camera.K).norm(), 1e-6);
  EXPECT_LT((camera.center_world - scene.views[ref].camera.center_world).norm(), 1e-6);
  const PointCloud laser = io::ReadPointCloud(dir_a + "/gt/laser.ply");
  ASSERT_EQ(laser.size(), scene.laser.size());
  ASSERT_EQ(laser.sigma.size(), scene.laser.size());
  EXPECT_EQ(laser.points[10], scene.laser.points[10]);
  EXPECT_EQ(laser.sigma[10], scene.laser.sigma[10]);
}

// A folder this command wrote before is replaced whole: views of the earlier set (here a stray
// view the tiny preset does not have) do not stay behind to break a later run. A folder holding a
// data set it did not write is refused and left as it was.
TEST(SynthWriterTest, ReplacesItsOwnEarlierSetAndRefusesOthers) {
  SynthOptions options;
  options.preset = "tiny";
  options.supersampling = 1;
  const SyntheticScene scene = GenerateScene(options);
  const fs::path dir = testing::MakeTempDir("synth_again");
  WriteScene(scene, options, dir.string());
  std::ofstream(dir / "images" / "0009.png") << "an earlier set's view";
  std::ofstream(dir / "cameras" / "0009.png.camera") << "its camera";
  WriteScene(scene, options, dir.string());
  EXPECT_FALSE(fs::exists(dir / "images" / "0009.png"));
  EXPECT_FALSE(fs::exists(dir / "cameras" / "0009.png.camera"));
  EXPECT_TRUE(fs::exists(dir / "images" / "0005.png"));

  const fs::path other = testing::MakeTempDir("synth_foreign");
  fs::create_directories(other / "images");
  std::ofstream(other / "images" / "0000.jpg") << "a user's photo";
  EXPECT_THROW(WriteScene(scene, options, other.string()), IoError);
  EXPECT_TRUE(fs::exists(other / "images" / "0000.jpg"));
  EXPECT_FALSE(fs::exists(other / "gt"));
}

// An empty folder path would put the data set into the working folder: refused, nothing written.
TEST(SynthWriterTest, EmptyFolderPathIsRefused) {
  SynthOptions options;
  options.preset = "tiny";
  options.supersampling = 1;
  const SyntheticScene scene = GenerateScene(options);
  const fs::path work = testing::MakeTempDir("synth_empty_path");
  const fs::path previous = fs::current_path();
  fs::current_path(work);
  std::string message = "no error";
  try {
    WriteScene(scene, options, "");
  } catch (const Error& e) {
    message = e.what();
  }
  fs::current_path(previous);
  EXPECT_EQ(message, "the synthetic data set's folder path is empty");
  EXPECT_TRUE(fs::is_empty(work));
}

}  // namespace
}  // namespace gcpstereo::synth
