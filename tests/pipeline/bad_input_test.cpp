// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The bad-input catalogue (issue 24): every kind of bad input the program refuses, each through
// the gcpstereo executable as a user meets it, with the exact one line it prints on stderr, exit
// status 1, and no output under its final name in the output folder (run.log, which records the
// failure, is the only file a refused run may leave). Some of these cases are also tested where
// their reader is (tests/io, cli_test.cpp, run_test.cpp); this file is the one place that lists
// them all. Inputs are the synthetic `tiny` set, damaged copies of its files, and small files
// written here.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_runner.h"
#include "test_data.h"
#include "tiny_data.h"

namespace gcpstereo {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunCli;
using testing::WriteFile;

class BadInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::WriteTinyData("gcpstereo-bad-input"));
    // A valid, fast configuration: the cases below break one thing in it.
    WriteFile(*dir_ / "ok.yaml", "dataset:\n  format: strecha\n  path: " + Data().string() +
                                     "\n  reference: '0005'\nlabels:\n  count: 16\ngcp:\n"
                                     "  sources: [lidar]\n  lidar:\n    path: " +
                                     (Data() / "gt" / "laser.ply").string() +
                                     "\noptimizer:\n  tiles: [1, 1]\n  refinement: parabola\n"
                                     "runtime:\n  stop_after: propagation\n");
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  static fs::path Data() { return *dir_ / "data"; }
  static std::string Config() { return (*dir_ / "ok.yaml").string(); }
  // A copy of the tiny data set, to be damaged.
  static fs::path CopyOfData(const std::string& name) {
    const fs::path copy = *dir_ / name;
    fs::copy(Data(), copy, fs::copy_options::recursive);
    return copy;
  }
  // A small COLMAP workspace of two of the tiny set's views (text model, one PINHOLE camera).
  static fs::path ColmapWorkspace(const std::string& name) {
    const fs::path ws = *dir_ / name;
    fs::create_directories(ws / "images");
    fs::create_directories(ws / "sparse");
    for (const char* view : {"0005.png", "0006.png"}) {
      fs::copy_file(Data() / "images" / view, ws / "images" / view);
    }
    WriteFile(ws / "sparse" / "cameras.txt", "1 PINHOLE 160 107 150 150 80 53\n");
    WriteFile(ws / "sparse" / "images.txt",
              "1 1 0 0 0 0 0 0 1 0005.png\n\n2 1 0 0 0 -0.1 0 0 1 0006.png\n\n");
    WriteFile(ws / "sparse" / "points3D.txt", "");
    return ws;
  }
  static std::string ColmapConfig(const fs::path& ws) {
    return WriteFile(*dir_ / "colmap.yaml",
                     "dataset:\n  format: colmap\n  path: " + ws.string() +
                         "\n  reference: 0005.png\nlabels:\n  count: 16\n  min: 2\n  max: 9\n"
                         "gcp:\n  sources: [sfm]\nruntime:\n  stop_after: propagation\n");
  }

  // `gcpstereo ARGS -o <dir>/<out>` must fail with exit status 1 and exactly the line
  // "gcpstereo: error: MESSAGE" on stderr, and leave nothing but run.log in the output folder.
  static void ExpectRefused(const std::string& args, const std::string& out,
                            const std::string& message) {
    const fs::path out_dir = *dir_ / out;
    const testing::CliResult r = RunCli(args + " -q -o '" + out_dir.string() + "'");
    EXPECT_EQ(r.status, 1) << args;
    EXPECT_EQ(r.output, "gcpstereo: error: " + message + "\n") << args;
    std::error_code ec;
    for (const auto& entry : fs::recursive_directory_iterator(out_dir, ec)) {
      EXPECT_EQ(entry.path().filename(), "run.log")
          << args << ": a refused run left " << entry.path();
    }
  }

  static fs::path* dir_;
};
fs::path* BadInput::dir_ = nullptr;

// ---- point clouds (gcp.lidar.path) -------------------------------------------------------------

TEST_F(BadInput, TruncatedPly) {
  const std::string cut =
      WriteFile(*dir_ / "cut.ply", ReadFile((Data() / "gt" / "laser.ply").string()).substr(0, 300));
  ExpectRefused("run " + Config() + " --set gcp.lidar.path=" + cut, "out_ply",
                cut +
                    ": not a valid PLY file: its header declares 21207 records of at least 16 "
                    "bytes, more than the file's 300 bytes (truncated or corrupt)");
}

TEST_F(BadInput, TruncatedPcd) {
  const std::string cut =
      WriteFile(*dir_ / "cut.pcd",
                "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                "COUNT 1 1 1\nWIDTH 10\nHEIGHT 1\nPOINTS 10\nDATA binary\n"
                "0123456789ab");
  ExpectRefused("run " + Config() + " --set gcp.lidar.path=" + cut, "out_pcd",
                cut +
                    ": not a valid PCD file: the data its header declares (120 bytes) is "
                    "longer than the 12 bytes after the header (truncated?)");
}

TEST_F(BadInput, TruncatedKittiBin) {
  const std::string cut = WriteFile(*dir_ / "cut.bin", std::string(17, '\0'));
  ExpectRefused("run " + Config() + " --set gcp.lidar.path=" + cut, "out_bin",
                cut +
                    ": KITTI Velodyne file length 17 bytes is not a multiple of 16 (float32 x, "
                    "y, z, reflectance)");
}

// Found by fuzzing (tools/fuzz.sh): PCL aborted on the first and allocated 6 GB for the second.
TEST_F(BadInput, PlyWithAListPropertyOfVertices) {
  const std::string ply = WriteFile(*dir_ / "list.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                    "property float y\nproperty float z\n"
                                    "property list uchar int vertex_indices\nend_header\n"
                                    "0 0 1 2 0 1\n");
  ExpectRefused("run " + Config() + " --set gcp.lidar.path=" + ply, "out_ply_list",
                ply +
                    ": not a valid PLY file: a list property in element 'vertex' (only scalar "
                    "vertex properties are read)");
}

TEST_F(BadInput, PcdWithAnAbsurdFieldSize) {
  const std::string pcd = WriteFile(*dir_ / "size.pcd",
                                    "VERSION 0.7\nFIELDS x y z\nSIZE 8 4 444444444444444\n"
                                    "TYPE F F F\nPOINTS 1\nDATA ascii\n0 0 1\n");
  ExpectRefused("run " + Config() + " --set gcp.lidar.path=" + pcd, "out_pcd_size",
                pcd + ": not a valid PCD file: SIZE 4.44444e+14 (expected 1, 2, 4 or 8)");
}

TEST_F(BadInput, MissingPointCloud) {
  const std::string missing = (*dir_ / "no" / "laser.ply").string();
  ExpectRefused("run " + Config() + " --set gcp.lidar.path=" + missing, "out_no_ply",
                missing +
                    ": file not found (gcp.lidar.path; a relative path is relative to the working "
                    "directory)");
}

// ---- data set files ----------------------------------------------------------------------------

TEST_F(BadInput, NanInStrechaCamera) {
  const fs::path data = CopyOfData("nan_camera");
  const fs::path camera = data / "cameras" / "0005.png.camera";
  std::string text = ReadFile(camera.string());
  const std::size_t line2 = text.find('\n') + 1;
  text.replace(line2, text.find('\n', line2) - line2, "0 nan 100");
  WriteFile(camera, text);
  ExpectRefused("run " + Config() + " --set dataset.path=" + data.string(), "out_nan",
                camera.string() + ": line 2: non-finite value 'nan'");
}

TEST_F(BadInput, CorruptPng) {
  const fs::path data = CopyOfData("corrupt_png");
  const fs::path image = data / "images" / "0005.png";
  WriteFile(image, "\x89PNG\r\n\x1a\ngarbage");
  ExpectRefused("run " + Config() + " --set dataset.path=" + data.string(), "out_png",
                image.string() + ": cannot decode image (unsupported or corrupt file: Read Error)");
}

TEST_F(BadInput, TruncatedPfm) {
  const std::string cut = WriteFile(
      *dir_ / "cut.pfm", ReadFile((Data() / "gt" / "0005.depth.pfm").string()).substr(0, 40));
  ExpectRefused(
      "run " + Config() + " --set gcp.sources=[depth_map] --set gcp.depth_map.path=" + cut,
      "out_pfm",
      cut +
          ": PFM data of 160x107x1 float32 needs 68480 bytes after the header, file "
          "has 24");
}

TEST_F(BadInput, MissingDatasetPath) {
  const std::string missing = (*dir_ / "nothing").string();
  ExpectRefused("run " + Config() + " --set dataset.path=" + missing, "out_no_data",
                missing + ": data set folder not found");
}

TEST_F(BadInput, UnknownReferenceView) {
  ExpectRefused("run " + Config() + " --set dataset.reference=0099", "out_ref",
                "dataset.reference = '0099'. Violated constraint: a view of " + Data().string() +
                    " (valid names: 0003, 0004, 0005, 0006, 0007)");
}

// ---- the configuration file and --set ----------------------------------------------------------

TEST_F(BadInput, BrokenYaml) {
  const std::string config = WriteFile(*dir_ / "broken.yaml", "dataset:\n  path: [unclosed\n");
  ExpectRefused("run " + config, "out_yaml",
                config + ":3: YAML syntax error: end of sequence flow not found");
}

TEST_F(BadInput, WrongTypeForAKey) {
  const std::string config = WriteFile(
      *dir_ / "type.yaml", "dataset:\n  path: /x\n  reference: a\nlabels:\n  count: many\n");
  ExpectRefused("run " + config, "out_type",
                config + ":5: labels.count = many. Violated constraint: an integer or auto");
}

TEST_F(BadInput, OutOfRangeValue) {
  const std::string config =
      WriteFile(*dir_ / "range.yaml", "dataset:\n  path: /x\n  reference: a\n  scale: 7\n");
  ExpectRefused("run " + config, "out_range",
                config + ":4: dataset.scale = 7. Violated constraint: 0 < dataset.scale <= 1");
}

TEST_F(BadInput, UnknownKey) {
  const std::string config = WriteFile(
      *dir_ / "unknown.yaml", "dataset:\n  path: /x\n  reference: a\nlabels:\n  cuont: 3\n");
  ExpectRefused("run " + config, "out_unknown",
                config +
                    ":5: unknown configuration key 'labels.cuont' (did you mean "
                    "'labels.count'?)");
}

TEST_F(BadInput, SetWithoutEquals) {
  ExpectRefused("run " + Config() + " --set labels.count", "out_set",
                "--set labels.count: expected KEY=VALUE");
}

TEST_F(BadInput, SetOfWrongType) {
  ExpectRefused("run " + Config() + " --set labels.count=many", "out_set_type",
                "--set: labels.count = many. Violated constraint: an integer or auto");
}

TEST_F(BadInput, SetOutOfRange) {
  ExpectRefused("run " + Config() + " --set dataset.scale=2", "out_set_range",
                "--set: dataset.scale = 2. Violated constraint: 0 < dataset.scale <= 1");
}

// ---- whole scenes and fuse ---------------------------------------------------------------------

TEST_F(BadInput, SceneListNamingAMissingView) {
  ExpectRefused("run " + Config() + " --set dataset.reference=[0005,0099]", "out_scene_list",
                "dataset.reference: no view named 0099 in " + Data().string() +
                    " (views: 0003, 0004, 0005, 0006, 0007)");
}

TEST_F(BadInput, AutomaticNeighboursWithOneView) {
  const fs::path one = *dir_ / "one_view";
  fs::create_directories(one / "images");
  fs::create_directories(one / "cameras");
  fs::copy_file(Data() / "images" / "0005.png", one / "images" / "0005.png");
  fs::copy_file(Data() / "cameras" / "0005.png.camera", one / "cameras" / "0005.png.camera");
  const std::string message = "dataset.neighbors: " + one.string() +
                              " has no view besides the reference '0005' (a depth map needs at "
                              "least one neighbour view)";
  ExpectRefused(
      "run " + Config() + " --set dataset.path=" + one.string() + " --set dataset.neighbors=auto",
      "out_one_view", message);
  ExpectRefused("run " + Config() + " --set dataset.path=" + one.string() +
                    " --set dataset.reference=all --set dataset.neighbors=auto",
                "out_one_view_scene", message);
}

TEST_F(BadInput, FuseOfAViewWithoutDepthMap) {
  // A view run stopped after propagation: finished, but with D̂ only.
  const fs::path view = *dir_ / "view_propagated";
  ASSERT_EQ(RunCli("run " + Config() + " -q -o '" + view.string() + "'").status, 0);
  ExpectRefused("fuse '" + view.string() + "'", "out_fuse_propagated",
                (view / "depth.pfm").string() +
                    ": not found, but propagated_depth.pfm is (a view run with "
                    "runtime.stop_after: propagation? --set fusion.input=propagated fuses that)");
  // The same folder without either map.
  fs::remove(view / "propagated_depth.pfm");
  ExpectRefused("fuse '" + view.string() + "'", "out_fuse",
                (view / "depth.pfm").string() +
                    ": not found: the folder is not a finished per-view run of gcpstereo");
}

TEST_F(BadInput, AlignmentOfAModelThatIsNotColmap) {
  ExpectRefused("run " + Config() + " --set dataset.align=scan", "out_align_strecha",
                "dataset.align = scan. Violated constraint: none unless dataset.format is colmap "
                "(only a COLMAP model lives in a frame of its own; here: strecha)");
}

TEST_F(BadInput, AlignmentToCentresWithoutTheirFile) {
  const fs::path ws = ColmapWorkspace("colmap_align_nofile");
  ExpectRefused("run " + ColmapConfig(ws) + " --set dataset.align=centres", "out_align_nofile",
                "dataset.align = centres needs dataset.align_centres (a file of '<image name> X "
                "Y Z' lines)");
}

TEST_F(BadInput, AlignmentCentresNamingAnImageTheModelLacks) {
  const fs::path ws = ColmapWorkspace("colmap_align_name");
  const std::string centres =
      WriteFile(*dir_ / "centres_name.txt", "0005.png 0 0 0\n0006.png 0.1 0 0\n0099.png 1 2 3\n");
  ExpectRefused("run " + ColmapConfig(ws) + " --set dataset.align=centres" +
                    " --set dataset.align_centres=" + centres,
                "out_align_name",
                "dataset.align_centres: " + centres +
                    " names image '0099.png', which the COLMAP model " + (ws / "sparse").string() +
                    " does not have (its images: 0005.png, 0006.png)");
}

TEST_F(BadInput, AlignmentCentresWithANonNumericCoordinate) {
  const fs::path ws = ColmapWorkspace("colmap_align_value");
  const std::string centres =
      WriteFile(*dir_ / "centres_value.txt", "0005.png 0 0 0\n0006.png 0.1 0 zero\n");
  ExpectRefused("run " + ColmapConfig(ws) + " --set dataset.align=centres" +
                    " --set dataset.align_centres=" + centres,
                "out_align_value", centres + ": line 2: 'zero' is not a finite coordinate");
}

TEST_F(BadInput, ColmapOutputOfMiddlebury) {
  ExpectRefused("run " + Config() + " --set dataset.format=middlebury --set output.colmap=true",
                "out_colmap_output",
                "output.colmap = true. Violated constraint: false for middlebury (it publishes no "
                "camera calibration: its cameras and depths are in arbitrary units, so a COLMAP "
                "workspace of them would not be the scene)");
}

// ---- COLMAP workspaces -------------------------------------------------------------------------

TEST_F(BadInput, ColmapWithoutCamerasFile) {
  const fs::path ws = ColmapWorkspace("colmap_no_cameras");
  fs::remove(ws / "sparse" / "cameras.txt");
  ExpectRefused("run " + ColmapConfig(ws), "out_colmap_cameras",
                (ws / "sparse").string() +
                    ": no cameras.bin or cameras.txt (a COLMAP sparse model folder holds cameras, "
                    "images and points3D)");
}

TEST_F(BadInput, ColmapUnsupportedCameraModel) {
  const fs::path ws = ColmapWorkspace("colmap_fisheye");
  WriteFile(ws / "sparse" / "cameras.txt", "1 OPENCV_FISHEYE 160 107 150 150 80 53 0 0 0 0\n");
  ExpectRefused("run " + ColmapConfig(ws), "out_colmap_model",
                (ws / "sparse").string() +
                    ": camera 1 has model OPENCV_FISHEYE, which gcpstereo does not support "
                    "(supported: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, "
                    "FULL_OPENCV)");
}

TEST_F(BadInput, ColmapTruncatedImagesBin) {
  const fs::path ws = ColmapWorkspace("colmap_truncated");
  fs::remove(ws / "sparse" / "images.txt");
  // The number of images (uint64 2), then the first image's id and nothing more.
  const std::string bytes("\x02\0\0\0\0\0\0\0\x01\0\0\0", 12);
  WriteFile(ws / "sparse" / "images.bin", bytes);
  ExpectRefused("run " + ColmapConfig(ws), "out_colmap_truncated",
                (ws / "sparse" / "images.bin").string() +
                    ": corrupt or truncated: the number of images = 2 needs at least 74 bytes "
                    "each, but only 4 bytes follow (at byte 0 of 12)");
}

// Found with the COLMAP fuzz harness: a distorting camera of 100000x100000 px had its undistortion
// maps (80 GB) allocated before its image was read.
TEST_F(BadInput, ColmapCameraOfAbsurdSize) {
  const fs::path ws = ColmapWorkspace("colmap_huge");
  WriteFile(ws / "sparse" / "cameras.txt",
            "1 OPENCV 100000 100000 150 150 80 53 0.01 -0.002 0.001 0.0005\n");
  ExpectRefused("run " + ColmapConfig(ws), "out_colmap_huge",
                (ws / "images" / "0005.png").string() +
                    ": image is 160x107 but its COLMAP camera 1 is 100000x100000 (resized images "
                    "need a model of their size)");
}

}  // namespace
}  // namespace gcpstereo
