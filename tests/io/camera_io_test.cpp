// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/camera_io.h"

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

Camera MakeCamera() {
  Camera c;
  c.K << 1234.5678, 0.0, 321.25, 0.0, 1236.125, 243.75, 0.0, 0.0, 1.0;
  c.world_from_camera_rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -1.0, 0.2).normalized()).toRotationMatrix();
  c.center_world = Eigen::Vector3d(-14.1604, -3.32084, 0.0862032);
  c.width = 640;
  c.height = 427;
  return c;
}

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

void WriteLines(const std::string& path, const std::vector<std::string>& lines) {
  std::ofstream out(path);
  for (const auto& l : lines) out << l << "\n";
}

std::string ErrorOf(const std::string& path) {
  try {
    ReadStrechaCamera(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(StrechaCamera, RoundTripIsExact) {
  const std::string dir = testing::MakeTempDir("io-camera");
  const Camera c = MakeCamera();
  WriteStrechaCamera(dir + "/0000.png.camera", c);
  EXPECT_EQ(Lines(dir + "/0000.png.camera").size(), 9u);
  const Camera back = ReadStrechaCamera(dir + "/0000.png.camera");
  EXPECT_EQ(back.K, c.K);
  EXPECT_EQ(back.world_from_camera_rotation, c.world_from_camera_rotation);
  EXPECT_EQ(back.center_world, c.center_world);
  EXPECT_EQ(back.width, 640);
  EXPECT_EQ(back.height, 427);
}

TEST(StrechaCamera, ReadsTheOriginalLayout) {
  // fountain-P11's 0005.jpg.camera (trailing spaces and all), as published by Strecha et al.
  const std::string dir = testing::MakeTempDir("io-camera");
  WriteLines(dir + "/c.camera",
             {"2759.48 0 1520.69 ", "0 2764.16 1006.81 ", "0 0 1 ", "0 0 0",
              "0.962742 -0.0160548 -0.269944 ", "-0.270399 -0.0444283 -0.961723 ",
              "0.00344709 0.998884 -0.0471142 ", "-14.1604 -3.32084 0.0862032 ", "3072 2048"});
  const Camera c = ReadStrechaCamera(dir + "/c.camera");
  EXPECT_EQ(c.K(0, 0), 2759.48);
  // R is snapped to the nearest rotation: within the file's 6 digits, and exactly orthonormal.
  EXPECT_NEAR(c.world_from_camera_rotation(2, 1), 0.998884, 2e-6);
  const Eigen::Matrix3d& R = c.world_from_camera_rotation;
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
  EXPECT_EQ(c.center_world.x(), -14.1604);
  EXPECT_EQ(c.width, 3072);
  EXPECT_EQ(c.height, 2048);
}

class StrechaCameraBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("io-camera-bad");
    WriteStrechaCamera(dir_ + "/good.camera", MakeCamera());
    lines_ = Lines(dir_ + "/good.camera");
    ASSERT_EQ(lines_.size(), 9u);
  }
  std::string Write(const std::vector<std::string>& lines) {
    const std::string path = dir_ + "/bad.camera";
    WriteLines(path, lines);
    return path;
  }
  std::string dir_;
  std::vector<std::string> lines_;
};

TEST_F(StrechaCameraBadInput, Truncated) {
  const std::vector<std::string> truncated(lines_.begin(), lines_.begin() + 6);
  const std::string path = Write(truncated);
  EXPECT_EQ(ErrorOf(path), path + ": expected 9 lines (K, distortion, R, C, size), found 6");
}

TEST_F(StrechaCameraBadInput, NaN) {
  auto lines = lines_;
  lines[4] = "nan 0 0";
  const std::string path = Write(lines);
  EXPECT_EQ(ErrorOf(path), path + ": line 5: non-finite value 'nan'");
}

TEST_F(StrechaCameraBadInput, WrongNumberCountAndGarbage) {
  auto lines = lines_;
  lines[7] = "1 2";
  std::string path = Write(lines);
  EXPECT_EQ(ErrorOf(path), path + ": line 8: expected 3 numbers, found 2");
  lines = lines_;
  lines[0] = "1000 0 abc";
  path = Write(lines);
  EXPECT_EQ(ErrorOf(path), path + ": line 1: cannot parse 'abc' as a number");
  lines = lines_;
  lines[8] = "640.5 427";
  path = Write(lines);
  EXPECT_EQ(ErrorOf(path),
            path + ": line 9: image size must be two positive integers, found '640.5 427'");
}

TEST_F(StrechaCameraBadInput, NonOrthonormalRotation) {
  auto lines = lines_;
  lines[4] = "1 0 0";
  lines[5] = "0 1 0";
  lines[6] = "0 0.5 1";
  const std::string path = Write(lines);
  EXPECT_NE(ErrorOf(path).find(path + ": rotation is not orthonormal"), std::string::npos)
      << ErrorOf(path);
}

TEST_F(StrechaCameraBadInput, ReflectionAndNegativeFocal) {
  auto lines = lines_;
  lines[4] = "-1 0 0";
  lines[5] = "0 1 0";
  lines[6] = "0 0 1";
  std::string path = Write(lines);
  EXPECT_NE(ErrorOf(path).find(path + ": rotation determinant is -1"), std::string::npos)
      << ErrorOf(path);
  lines = lines_;
  lines[0] = "-1000 0 320";
  path = Write(lines);
  EXPECT_NE(ErrorOf(path).find(path + ": focal lengths must be positive"), std::string::npos)
      << ErrorOf(path);
}

TEST_F(StrechaCameraBadInput, MissingFile) {
  EXPECT_EQ(ErrorOf(dir_ + "/none.camera"), dir_ + "/none.camera: file not found");
}

TEST_F(StrechaCameraBadInput, NonZeroDistortionIsAccepted) {
  auto lines = lines_;
  lines[3] = "0.01 0 0";
  const Camera c = ReadStrechaCamera(Write(lines));
  EXPECT_EQ(c.width, 640);
}

}  // namespace
}  // namespace gcpstereo::io
