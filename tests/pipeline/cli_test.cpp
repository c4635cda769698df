// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Runs the gcpstereo executable as a user would and checks exit status and messages.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "cli_runner.h"
#include "gcpstereo/core/camera.h"
#include "gcpstereo/io/camera_io.h"
#include "test_data.h"

namespace gcpstereo {
namespace {

namespace fs = std::filesystem;

using Result = testing::CliResult;
using testing::RunCli;
using testing::WriteFile;

TEST(Cli, HelpListsTheCommands) {
  const Result r = RunCli("--help", true);
  EXPECT_EQ(r.status, 0);
  for (const char* command : {"run", "fuse", "views", "synth", "eval", "demo"}) {
    EXPECT_NE(r.output.find(command), std::string::npos) << command << " missing in:\n" << r.output;
  }
}

TEST(Cli, UnknownConfigKeyIsOneLineNamingTheKey) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli");
  const std::string config =
      WriteFile(dir / "bad.yaml", "dataset:\n  path: /x\n  reference: a\nlabels:\n  cuont: 3\n");
  const Result r = RunCli("run " + config + " -o " + (dir / "out").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "gcpstereo: error: " + config +
                          ":5: unknown configuration key 'labels.cuont' (did you mean "
                          "'labels.count'?)\n");
  EXPECT_FALSE(fs::exists(dir / "out" / "report.json"));
}

TEST(Cli, OutOfRangeOverrideNamesKeyAndBound) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli");
  const std::string config = WriteFile(dir / "ok.yaml", "dataset:\n  path: /x\n  reference: a\n");
  const Result r =
      RunCli("run " + config + " -o " + (dir / "out").string() + " --set dataset.scale=2");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output,
            "gcpstereo: error: --set: dataset.scale = 2. Violated constraint: 0 < dataset.scale "
            "<= 1\n");
}

TEST(Cli, MissingDatasetFailsWithoutOutputs) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli");
  const std::string config = WriteFile(
      dir / "ok.yaml", "dataset:\n  path: " + (dir / "nothing").string() + "\n  reference: a\n");
  const Result r = RunCli("run " + config + " -o " + (dir / "out").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output.rfind("gcpstereo: error: ", 0), 0u) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "report.json"));
  EXPECT_FALSE(fs::exists(dir / "out" / "effective_config.yaml"));
}

// Command-line mistakes are one line on stderr too, with the same prefix as every other error.
TEST(Cli, BadCommandLineIsOneLine) {
  for (const char* args : {"frobnicate", "eval --foo 3"}) {
    const Result r = RunCli(args);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(r.output.rfind("gcpstereo: error: ", 0), 0u) << r.output;
    EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << r.output;
  }
}

// -o '' (an empty variable in a script) is no folder: run failed with ": cannot create output
// folder: Invalid argument", synth and demo wrote into the working folder. One line naming the
// option, and nothing is created.
TEST(Cli, EmptyOutputPathIsOneLineNamingTheOption) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli");
  const std::string config = WriteFile(dir / "ok.yaml", "dataset:\n  path: /x\n  reference: a\n");
  const fs::path work = dir / "work";
  fs::create_directories(work);
  for (const std::string& args :
       {"run " + config + " -o ''", std::string("synth --preset tiny -o ''"),
        std::string("demo -o ''")}) {
    const Result r = RunCli(args, false, work.string());
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(r.output,
              "gcpstereo: error: --output: the output folder path is empty (gcpstereo --help "
              "lists the commands and options)\n")
        << args;
    EXPECT_TRUE(fs::is_empty(work)) << args;
  }
}

// eval refuses what would read as a perfect score over no pixel, a non-positive --gt-scale, and
// a figures folder it cannot create (a file is in the way), each in one line naming the fault.
TEST(Cli, EvalRefusesToScoreNothing) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli");
  // A 2×2 PFM disparity (ones) and a ground truth of zeros (= unknown).
  const std::string header = "Pf\n2 2\n-1.0\n";
  std::string ones = header, zeros = header;
  for (int i = 0; i < 4; ++i) {
    const float one = 1.0f, zero = 0.0f;
    ones.append(reinterpret_cast<const char*>(&one), 4);
    zeros.append(reinterpret_cast<const char*>(&zero), 4);
  }
  const std::string map = WriteFile(dir / "d.pfm", ones);
  const std::string none = WriteFile(dir / "gt0.pfm", zeros);
  Result r = RunCli("eval --disparity " + map + " --gt-disparity " + none);
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output,
            "gcpstereo: error: eval: no pixel has a valid ground truth to score (all zero, "
            "non-finite or masked out; check the ground-truth file and --gt-scale)\n");
  r = RunCli("eval --disparity " + map + " --gt-disparity " + map + " --gt-scale 0");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "gcpstereo: error: eval: --gt-scale must be > 0, got 0\n");
  const std::string file = WriteFile(dir / "a_file", "x");
  r = RunCli("eval --disparity " + map + " --gt-disparity " + map + " --figures " + file);
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output,
            "gcpstereo: error: " + file + ": cannot create the figures folder: Not a directory\n");
  r = RunCli("eval --disparity " + map + " --gt-disparity " + map, true);
  EXPECT_EQ(r.status, 0) << r.output;
}

TEST(Cli, KeysListsContractKeys) {
  const Result r = RunCli("keys", true);
  EXPECT_EQ(r.status, 0);
  for (const char* key :
       {"dataset.format", "dataset.path", "dataset.reference", "dataset.neighbors", "dataset.scale",
        "labels.space", "labels.count", "labels.min", "labels.max", "gcp.sources", "gcp.lidar.path",
        "gcp.depth_map.path", "gcp.depth_map.kind", "gcp.depth_map.scale", "gcp.downsample",
        "optimizer.tiles", "optimizer.tile_overlap"}) {
    EXPECT_NE(r.output.find(std::string("  ") + key + "  ("), std::string::npos) << key;
  }
}

TEST(Cli, FountainAtHalfScaleReportsElevenViews) {
  GCPSTEREO_REQUIRE_SHARED_DATA(fountain, "strecha/fountain-P11");
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli");
  const Result r = RunCli(std::string("run ") + GCPSTEREO_SOURCE_DIR +
                          "/configs/fountain_p11.yaml -o " + (dir / "out").string() +
                          " --set dataset.path=" + fountain + " --set dataset.neighbors=[]" +
                          " --set runtime.log_level=warn --set runtime.stop_after=load");
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(dir / "out" / "report.json");
  const std::string report((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(report.find("\"num_views\": 11"), std::string::npos) << report;
  EXPECT_NE(report.find("\"width\": 1536"), std::string::npos);
  EXPECT_NE(report.find("\"height\": 1024"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "out" / "effective_config.yaml"));
}

// eval --camera with a camera of another size than the depth map: one of the full-size image (twice
// the map's size, also with an odd height that halves to 107.5 rows) is scaled to the map and
// scores as the view's own camera; one of another aspect ratio is refused naming both sizes. (The
// odd height was refused before, and the refusal named the camera scaled by the width ratio,
// 160x120, a size its file does not have.)
TEST(Cli, EvalCameraOfAnotherAspectRatioIsRefused) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli");
  const fs::path data = dir / "tiny";
  ASSERT_EQ(RunCli("synth --preset tiny -q -o " + data.string()).status, 0);
  const Camera own = io::ReadStrechaCamera((data / "cameras" / "0005.png.camera").string());
  ASSERT_EQ(own.width, 160);
  ASSERT_EQ(own.height, 107);
  auto camera_twice_the_size = [&](int height) {
    Camera camera = own.Rescaled(2.0);
    camera.height = height;
    const std::string path = (dir / ("320x" + std::to_string(height) + ".camera")).string();
    io::WriteStrechaCamera(path, camera);
    return path;
  };
  const std::string depth = (data / "gt" / "0005.depth.pfm").string();
  auto eval = [&](const std::string& camera) {
    return RunCli("eval --depth " + depth + " --gt-mesh " + (data / "gt" / "mesh.ply").string() +
                      " --sigma 0.01 --camera " + camera,
                  true);
  };
  const Result reference = eval((data / "cameras" / "0005.png.camera").string());
  ASSERT_EQ(reference.status, 0) << reference.output;
  for (const int height : {214, 215}) {
    const Result r = eval(camera_twice_the_size(height));
    EXPECT_EQ(r.status, 0) << height << ": " << r.output;
    EXPECT_EQ(r.output, reference.output) << height;
  }
  const std::string other = camera_twice_the_size(240);
  const Result r = eval(other);
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "gcpstereo: error: eval: --camera " + other +
                          " is 320x240 and the depth map " + depth +
                          " 160x107: another aspect ratio (scaled to the map's width, x0.5, the "
                          "camera is 120 px high, not 107); the camera is of another image\n");
}

// synth --views N: N views in arc order around the reference 0005, which gt/scene.json names
// and the scene's views list; a count out of range is one line naming the option, nothing
// written.
TEST(Cli, SynthViewsWritesThatManyViews) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli-synth-views");
  for (const char* bad : {"2", "100", "-1", "7x"}) {
    const Result r = RunCli("synth --preset tiny --views " + std::string(bad) + " -q -o " +
                            (dir / "bad").string());
    EXPECT_NE(r.status, 0) << bad;
    EXPECT_EQ(r.output, "gcpstereo: error: --views: 0 (the preset's cameras) or 3..99, got " +
                            std::string(bad) +
                            " (gcpstereo --help lists the commands and options)\n")
        << bad;
    EXPECT_FALSE(fs::exists(dir / "bad")) << bad;
  }
  const fs::path data = dir / "data";
  const Result r = RunCli("synth --preset tiny --views 6 -q -o " + data.string());
  ASSERT_EQ(r.status, 0) << r.output;
  // tiny's arc −20.5° … +21.4° in steps of 8.4°: the third camera (−3.7°) is the head-on one.
  for (const char* name : {"0003", "0004", "0005", "0006", "0007", "0008"}) {
    EXPECT_TRUE(fs::exists(data / "images" / (std::string(name) + ".png"))) << name;
    EXPECT_TRUE(fs::exists(data / "cameras" / (std::string(name) + ".png.camera"))) << name;
    EXPECT_TRUE(fs::exists(data / "gt" / (std::string(name) + ".depth.pfm"))) << name;
  }
  EXPECT_FALSE(fs::exists(data / "images" / "0002.png"));
  EXPECT_FALSE(fs::exists(data / "images" / "0009.png"));
  std::ifstream in(data / "gt" / "scene.json");
  const std::string scene((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(scene.find("\"reference\": \"0005\""), std::string::npos) << scene;
  EXPECT_NE(scene.find("\"0008\""), std::string::npos) << scene;
  const std::string config = WriteFile(
      dir / "c.yaml", "dataset:\n  format: strecha\n  path: " + data.string() +
                          "\n  reference: all\n  neighbors: auto\nlabels:\n  count: 32\n");
  const Result views = RunCli("views " + config, /*with_stdout=*/true);
  ASSERT_EQ(views.status, 0) << views.output;
  for (const char* name : {"0003", "0004", "0005", "0006", "0007", "0008"}) {
    EXPECT_NE(views.output.find("\"name\": \"" + std::string(name) + "\""), std::string::npos)
        << name << " in\n"
        << views.output;
  }
}

TEST(Cli, FuseOfAFolderThatIsNoViewIsOneLineNamingTheFile) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli-fuse");
  fs::create_directories(dir / "not_a_view");
  const Result r =
      RunCli("fuse '" + (dir / "not_a_view").string() + "' -o '" + (dir / "out").string() + "'");
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(r.output,
            "gcpstereo: error: " + (dir / "not_a_view" / "effective_config.yaml").string() +
                ": not found: the folder is not a finished per-view run of gcpstereo\n");
  EXPECT_FALSE(fs::exists(dir / "out" / "fused.ply"));
}

// `views` prints the jobs of a scene as JSON on stdout alone (the workflow parses it), and
// `run --fuse-only` of a single reference is refused in one line.
TEST(Cli, ViewsPrintsTheSceneAsJsonAndFuseOnlyNeedsAScene) {
  const fs::path dir = testing::MakeTempDir("gcpstereo-cli-views");
  const fs::path data = dir / "data";
  ASSERT_EQ(RunCli("synth --preset tiny -q -o " + data.string()).status, 0);
  const std::string config =
      WriteFile(dir / "c.yaml", "dataset:\n  format: strecha\n  path: " + data.string() +
                                    "\n  reference: all\nlabels:\n  count: 32\n");
  const Result views = RunCli("views " + config + " --set 'dataset.reference=[\"0004\", \"0006\"]'",
                              /*with_stdout=*/true);
  EXPECT_EQ(views.status, 0) << views.output;
  ASSERT_FALSE(views.output.empty());
  EXPECT_EQ(views.output.front(), '{') << views.output;
  for (const char* expected :
       {"\"scene\": true", "\"labels\": 32", "\"name\": \"0004\"", "\"name\": \"0006\"",
        "\"width_px\": 160", "\"memory_estimate_mb\": ", "\"dataset.reference=\\\"0006\\\"\""}) {
    EXPECT_NE(views.output.find(expected), std::string::npos) << expected << " in\n"
                                                              << views.output;
  }
  EXPECT_EQ(views.output.find("\"name\": \"0005\""), std::string::npos) << views.output;
  const Result single = RunCli("run " + config + " -o " + (dir / "out").string() +
                               " --set dataset.reference=0005 --fuse-only");
  EXPECT_NE(single.status, 0);
  EXPECT_EQ(single.output,
            "gcpstereo: error: --fuse-only: dataset.reference is one view, not a scene (a list of "
            "views or all): there is nothing to fuse\n");
}

}  // namespace
}  // namespace gcpstereo
