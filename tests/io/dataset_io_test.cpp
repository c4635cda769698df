// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Data set loaders on small synthetic folders written by the tests themselves (real data in
// dataset_real_test.cpp).
#include "gcpstereo/io/dataset_io.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/camera_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/pfm.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

using gcpstereo::testing::ErrorOf;

namespace fs = std::filesystem;

cv::Mat RandomImage(int rows, int cols, int type, unsigned seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

// ---------------------------------------------------------------------------------------------
// Strecha layout

constexpr int kWidth = 40;
constexpr int kHeight = 30;

Camera StrechaTestCamera(int index) {
  Camera c;
  c.K << 50.0, 0.0, 19.5, 0.0, 50.0, 14.5, 0.0, 0.0, 1.0;
  c.world_from_camera_rotation =
      Eigen::AngleAxisd(0.1 * (index - 1), Eigen::Vector3d::UnitY()).toRotationMatrix();
  c.center_world = Eigen::Vector3d(0.5 * index, 0.0, 0.0);
  c.width = kWidth;
  c.height = kHeight;
  return c;
}

class StrechaDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("io-strecha");
    fs::create_directories(dir_ + "/images");
    fs::create_directories(dir_ + "/cameras");
    fs::create_directories(dir_ + "/gt");
    for (int i = 0; i < 3; ++i) {
      const std::string name = "000" + std::to_string(i);
      images_.push_back(RandomImage(kHeight, kWidth, CV_8UC3, 10 + i));
      WritePng(dir_ + "/images/" + name + ".png", images_.back());
      WriteStrechaCamera(dir_ + "/cameras/" + name + ".png.camera", StrechaTestCamera(i));
    }
    depth_ = cv::Mat(kHeight, kWidth, CV_32F);
    for (int r = 0; r < kHeight; ++r) {
      for (int c = 0; c < kWidth; ++c) depth_.at<float>(r, c) = 5.0f + 0.01f * (r * kWidth + c);
    }
    depth_.at<float>(0, 0) = kInvalidDepth;
    WritePfm(dir_ + "/gt/0001.depth.pfm", depth_);
    WritePfm(dir_ + "/gt/0001.sigma.pfm", cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(0.01f)));
  }
  DatasetRequest Request(const std::string& reference = "0001") const {
    DatasetRequest r;
    r.format = "strecha";
    r.path = dir_;
    r.reference = reference;
    return r;
  }
  std::string dir_;
  std::vector<cv::Mat> images_;
  cv::Mat depth_;
};

TEST_F(StrechaDataset, LoadsAllViewsCamerasAndGroundTruth) {
  const Dataset d = LoadDataset(Request());
  EXPECT_EQ(d.format, "strecha");
  EXPECT_FALSE(d.rectified);
  EXPECT_TRUE(d.world_from_lidar.isIdentity());
  EXPECT_EQ(d.reference.name, "0001");
  ASSERT_EQ(d.neighbors.size(), 2u);
  EXPECT_EQ(d.neighbors[0].name, "0000");
  EXPECT_EQ(d.neighbors[1].name, "0002");
  EXPECT_EQ(cv::norm(d.reference.image, images_[1], cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(d.neighbors[1].image, images_[2], cv::NORM_INF), 0.0);
  EXPECT_EQ(d.neighbors[1].camera.center_world, StrechaTestCamera(2).center_world);
  ASSERT_TRUE(d.ground_truth.HasDepth());
  EXPECT_EQ(d.ground_truth.depth.at<float>(3, 4), depth_.at<float>(3, 4));
  EXPECT_TRUE(std::isinf(d.ground_truth.depth.at<float>(0, 0)));
  ASSERT_FALSE(d.ground_truth.sigma.empty());
  EXPECT_FLOAT_EQ(d.ground_truth.sigma.at<float>(5, 5), 0.01f);
}

TEST_F(StrechaDataset, NeighboursInRequestedOrder) {
  DatasetRequest r = Request("0000");
  r.neighbors = {"0002", "0001"};
  const Dataset d = LoadDataset(r);
  ASSERT_EQ(d.neighbors.size(), 2u);
  EXPECT_EQ(d.neighbors[0].name, "0002");
  EXPECT_EQ(d.neighbors[1].name, "0001");
  EXPECT_FALSE(d.ground_truth.HasDepth());  // no gt/0000.depth.pfm
}

TEST_F(StrechaDataset, ScaleResizesImagesCamerasAndGroundTruth) {
  DatasetRequest r = Request();
  r.scale = 0.5;
  const Dataset d = LoadDataset(r);
  EXPECT_EQ(d.reference.image.size(), cv::Size(20, 15));
  const Camera expected = StrechaTestCamera(1).Rescaled(0.5);
  EXPECT_EQ(d.reference.camera.K, expected.K);
  EXPECT_EQ(d.reference.camera.width, 20);
  EXPECT_EQ(d.ground_truth.depth.size(), cv::Size(20, 15));
  // Nearest-neighbour: every value is one of the original depths.
  const float v = d.ground_truth.depth.at<float>(7, 9);
  bool found = false;
  for (int rr = 0; rr < kHeight && !found; ++rr) {
    for (int cc = 0; cc < kWidth && !found; ++cc) found = depth_.at<float>(rr, cc) == v;
  }
  EXPECT_TRUE(found);
}

TEST_F(StrechaDataset, UnknownViewNameListsValidNames) {
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request("0005")); }),
            "dataset.reference = '0005'. Violated constraint: a view of " + dir_ +
                " (valid names: 0000, 0001, 0002)");
  DatasetRequest r = Request();
  r.neighbors = {"0000", "0009"};
  EXPECT_NE(ErrorOf([&] { LoadDataset(r); }).find("dataset.neighbors = '0009'"), std::string::npos);
  r.neighbors = {"0001"};
  EXPECT_NE(ErrorOf([&] { LoadDataset(r); }).find("must differ from dataset.reference"),
            std::string::npos);
}

TEST_F(StrechaDataset, ImageSizeMismatch) {
  WritePng(dir_ + "/images/0002.png", RandomImage(kHeight, kWidth + 1, CV_8UC3, 99));
  DatasetRequest r = Request();
  EXPECT_EQ(ErrorOf([&] { LoadDataset(r); }), dir_ + "/images/0002.png: image is 41x30 but " +
                                                  dir_ + "/cameras/0002.png.camera declares 40x30");
}

TEST_F(StrechaDataset, MissingCameraAndCorruptImage) {
  fs::remove(dir_ + "/cameras/0000.png.camera");
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            dir_ + "/cameras/0000.png.camera: file not found");
  WriteStrechaCamera(dir_ + "/cameras/0000.png.camera", StrechaTestCamera(0));
  std::ofstream(dir_ + "/images/0000.png", std::ios::trunc) << "garbage";
  EXPECT_NE(
      ErrorOf([&] { LoadDataset(Request()); }).find(dir_ + "/images/0000.png: cannot decode image"),
      std::string::npos);
}

TEST_F(StrechaDataset, MissingImageFolderAndBadRequest) {
  DatasetRequest r = Request();
  r.path = dir_ + "/nothing";
  EXPECT_EQ(ErrorOf([&] { LoadDataset(r); }), dir_ + "/nothing: data set folder not found");
  r = Request();
  r.path = dir_ + "/gt";
  EXPECT_EQ(ErrorOf([&] { LoadDataset(r); }),
            dir_ + "/gt/images: Strecha image folder not found (expected <path>/images/)");
  r = Request();
  r.scale = 0.0;
  EXPECT_EQ(ErrorOf([&] { LoadDataset(r); }),
            "dataset.scale = 0. Violated constraint: 0 < dataset.scale <= 4");
  r = Request();
  r.format = "bundler";
  EXPECT_EQ(ErrorOf([&] { LoadDataset(r); }),
            "dataset.format = 'bundler'. Violated constraint: one of strecha, middlebury, "
            "kitti_raw, colmap");
}

TEST_F(StrechaDataset, GroundTruthOfWrongSize) {
  WritePfm(dir_ + "/gt/0001.depth.pfm", cv::Mat(10, 10, CV_32F, cv::Scalar(1.0f)));
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            dir_ + "/gt/0001.depth.pfm: ground-truth map is 10x10, the image is 40x30");
}

// ---------------------------------------------------------------------------------------------
// Middlebury layout (a 2001-style im0…im8 scene in miniature)

class MiddleburyDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("io-middlebury");
    for (int i = 0; i < 9; ++i) {
      cv::imwrite(dir_ + "/im" + std::to_string(i) + ".ppm", RandomImage(10, 20, CV_8UC3, i));
    }
    // disp2.pgm: I = 80 → disparity 10 px for the im2↔im6 pair; one pixel unknown.
    cv::Mat disp(10, 20, CV_8UC1, cv::Scalar(80));
    disp.at<std::uint8_t>(1, 1) = 0;
    cv::imwrite(dir_ + "/disp2.pgm", disp);
    cv::imwrite(dir_ + "/disp6.pgm", cv::Mat(10, 20, CV_8UC1, cv::Scalar(40)));
    cv::imwrite(dir_ + "/nonocc.png", cv::Mat(10, 20, CV_8UC1, cv::Scalar(255)));
  }
  DatasetRequest Request(const std::string& reference = "im2") const {
    DatasetRequest r;
    r.format = "middlebury";
    r.path = dir_;
    r.reference = reference;
    return r;
  }
  std::string dir_;
};

TEST_F(MiddleburyDataset, CamerasAndDisparityConvention) {
  DatasetRequest r = Request();
  r.neighbors = {"im3", "im6", "im1"};
  const Dataset d = LoadDataset(r);
  EXPECT_TRUE(d.rectified);
  // f = width = 20 px, one unit per view step, GT pair 4 steps apart.
  EXPECT_DOUBLE_EQ(d.disparity_numerator, 80.0);
  EXPECT_DOUBLE_EQ(d.reference.camera.center_world.x(), 2.0);
  EXPECT_DOUBLE_EQ(d.neighbors[1].camera.center_world.x(), 6.0);
  ASSERT_TRUE(d.ground_truth.HasDisparity());
  EXPECT_FLOAT_EQ(d.ground_truth.disparity.at<float>(5, 5), 10.0f);
  EXPECT_TRUE(std::isinf(d.ground_truth.disparity.at<float>(1, 1)));
  EXPECT_FLOAT_EQ(d.ground_truth.depth.at<float>(5, 5), 8.0f);
  EXPECT_TRUE(std::isinf(d.ground_truth.depth.at<float>(1, 1)));
  EXPECT_FLOAT_EQ(d.ground_truth.disparity_right.at<float>(0, 0), 5.0f);
  EXPECT_FALSE(d.ground_truth.mask_nonocc.empty());
  EXPECT_TRUE(d.ground_truth.mask_disc.empty());
  // A point at the GT depth moves by disparity / 4 per view step: check it with the cameras.
  const Eigen::Vector3d X = d.reference.camera.BackProject(Eigen::Vector2d(12.0, 4.0), 8.0);
  Eigen::Vector2d pixel;
  double depth = 0.0;
  ASSERT_TRUE(d.neighbors[0].camera.Project(X, &pixel, &depth));  // im3, one step right
  EXPECT_NEAR(pixel.x(), 12.0 - 10.0 / 4, 1e-9);
  ASSERT_TRUE(d.neighbors[1].camera.Project(X, &pixel, &depth));  // im6, the GT pair's right view
  EXPECT_NEAR(pixel.x(), 12.0 - 10.0, 1e-9);
}

TEST_F(MiddleburyDataset, ScaleScalesDisparitiesNotDepths) {
  DatasetRequest r = Request();
  r.scale = 0.5;
  const Dataset d = LoadDataset(r);
  EXPECT_EQ(d.reference.image.size(), cv::Size(10, 5));
  EXPECT_DOUBLE_EQ(d.disparity_numerator, 40.0);
  EXPECT_FLOAT_EQ(d.ground_truth.disparity.at<float>(2, 2), 5.0f);
  EXPECT_FLOAT_EQ(d.ground_truth.depth.at<float>(2, 2), 8.0f);
  EXPECT_EQ(d.ground_truth.mask_nonocc.size(), cv::Size(10, 5));
  EXPECT_EQ(d.neighbors.size(), 8u);
}

TEST_F(MiddleburyDataset, RightViewOfThePairAndUnknownNames) {
  const Dataset d = LoadDataset(Request("im6"));
  EXPECT_FLOAT_EQ(d.ground_truth.disparity.at<float>(0, 0), 5.0f);
  EXPECT_TRUE(d.ground_truth.mask_nonocc.empty());
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request("view1")); }),
            "dataset.reference = 'view1'. Violated constraint: a view of " + dir_ +
                " (valid names: im0, im1, im2, im3, im4, im5, im6, im7, im8)");
}

TEST_F(MiddleburyDataset, MismatchedSizesAndEmptyFolder) {
  cv::imwrite(dir_ + "/im4.ppm", RandomImage(11, 20, CV_8UC3, 4));
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            dir_ +
                "/im4.ppm: image is 20x11, the reference im2.ppm is 20x10 (views of a "
                "rectified set must match)");
  const std::string empty = testing::MakeTempDir("io-middlebury-empty");
  DatasetRequest r = Request();
  r.path = empty;
  EXPECT_NE(ErrorOf([&] { LoadDataset(r); }).find(empty + ": not a Middlebury scene folder"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// KITTI raw layout with synthetic calibration

class KittiDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = testing::MakeTempDir("io-kitti");
    drive_ = root_ + "/2011_01_01_drive_0001_sync";
    fs::create_directories(drive_ + "/image_02/data");
    fs::create_directories(drive_ + "/image_03/data");
    WritePng(drive_ + "/image_02/data/0000000010.png", RandomImage(30, 80, CV_8UC3, 1));
    WritePng(drive_ + "/image_03/data/0000000010.png", RandomImage(30, 80, CV_8UC3, 2));
    cam_lines_ = {
        "calib_time: 01-Jan-2011 00:00:00",
        "S_rect_02: 8.000000e+01 3.000000e+01",
        "R_rect_00: 1 0 0 0 1 0 0 0 1",
        "P_rect_02: 100 0 40 10 0 100 15 0 0 0 1 0",
        "P_rect_03: 100 0 40 -40 0 100 15 0 0 0 1 0",
    };
    velo_lines_ = {"R: 0 -1 0 0 0 -1 1 0 0", "T: 0 0 0.1"};
    WriteCalibration();
  }
  void WriteCalibration() {
    std::ofstream cam(root_ + "/calib_cam_to_cam.txt", std::ios::trunc);
    for (const auto& l : cam_lines_) cam << l << "\n";
    std::ofstream velo(root_ + "/calib_velo_to_cam.txt", std::ios::trunc);
    for (const auto& l : velo_lines_) velo << l << "\n";
  }
  DatasetRequest Request() const {
    DatasetRequest r;
    r.format = "kitti_raw";
    r.path = drive_;
    r.reference = "0000000010";
    return r;
  }
  std::string root_, drive_;
  std::vector<std::string> cam_lines_, velo_lines_;
};

TEST_F(KittiDataset, CamerasBaselineAndLidarTransform) {
  const Dataset d = LoadDataset(Request());
  EXPECT_TRUE(d.rectified);
  ASSERT_EQ(d.neighbors.size(), 1u);
  EXPECT_EQ(d.reference.camera.center_world, Eigen::Vector3d(-0.1, 0.0, 0.0));
  EXPECT_EQ(d.neighbors[0].camera.center_world, Eigen::Vector3d(0.4, 0.0, 0.0));
  EXPECT_DOUBLE_EQ(d.disparity_numerator, 50.0);  // f = 100 px, baseline 0.5
  // A Velodyne point 10 m ahead (velodyne x forward) lands 10.1 m in front of the cameras.
  const Eigen::Vector4d X = d.world_from_lidar * Eigen::Vector4d(10.0, 0.0, 0.0, 1.0);
  Eigen::Vector2d left, right;
  double depth = 0.0;
  ASSERT_TRUE(d.reference.camera.Project(X.head<3>(), &left, &depth));
  ASSERT_TRUE(d.neighbors[0].camera.Project(X.head<3>(), &right, &depth));
  EXPECT_NEAR(depth, 10.1, 1e-12);
  EXPECT_NEAR(left.x() - right.x(), d.disparity_numerator / depth, 1e-9);
  EXPECT_EQ(KittiVelodynePath(drive_, "0000000010"),
            drive_ + "/velodyne_points/data/0000000010.bin");
}

TEST_F(KittiDataset, MissingCalibrationKey) {
  cam_lines_.pop_back();  // P_rect_03
  WriteCalibration();
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            root_ + "/calib_cam_to_cam.txt: missing calibration key 'P_rect_03'");
  cam_lines_.push_back("P_rect_03: 100 0 40 -40 0 100 15 0 0 0 1");
  WriteCalibration();
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            root_ + "/calib_cam_to_cam.txt: key 'P_rect_03': expected 12 numbers, found 11");
  velo_lines_ = {"R: 0 -1 0 0 0 -1 1 0 0"};
  cam_lines_.back() += " 0";
  WriteCalibration();
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            root_ + "/calib_velo_to_cam.txt: missing calibration key 'T'");
}

TEST_F(KittiDataset, MissingRightImage) {
  fs::remove(drive_ + "/image_03/data/0000000010.png");
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            drive_ + "/image_03/data/0000000010.png: image file not found");
}

TEST_F(KittiDataset, UnknownFrameAndWrongImageSize) {
  DatasetRequest r = Request();
  r.reference = "0000000011";
  EXPECT_EQ(ErrorOf([&] { LoadDataset(r); }),
            "dataset.reference = '0000000011'. Violated constraint: a frame of " + drive_ +
                " (valid names: 0000000010)");
  WritePng(drive_ + "/image_03/data/0000000010.png", RandomImage(31, 80, CV_8UC3, 2));
  EXPECT_EQ(ErrorOf([&] { LoadDataset(Request()); }),
            drive_ + "/image_03/data/0000000010.png: image is 80x31 but " + root_ +
                "/calib_cam_to_cam.txt declares S_rect_02 = 80x30");
}

TEST_F(KittiDataset, NeighbourScansNearestOnEitherSideWithinTheGap) {
  fs::create_directories(drive_ + "/velodyne_points/data");
  for (const char* f : {"0000000000", "0000000005", "0000000010", "0000000030", "notaframe"}) {
    std::ofstream(drive_ + "/velodyne_points/data/" + f + ".bin");
  }
  // No timestamps.txt: frame numbers at 10 Hz.
  std::vector<KittiScanTime> scans = KittiNeighbourScans(drive_, "0000000010", 2.0);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[0].frame, "0000000005");
  EXPECT_NEAR(scans[0].seconds_after_reference, -0.5, 1e-9);
  EXPECT_EQ(scans[0].path, KittiVelodynePath(drive_, "0000000005"));
  EXPECT_EQ(scans[1].frame, "0000000030");
  EXPECT_NEAR(scans[1].seconds_after_reference, 2.0, 1e-9);
  scans = KittiNeighbourScans(drive_, "0000000010", 1.5);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].frame, "0000000005");
  EXPECT_TRUE(KittiNeighbourScans(drive_, "0000000030", 1.0).empty());

  // With timestamps.txt (line k = frame k), its times count: frame 30 only 0.4 s after frame 10.
  {
    std::ofstream stamps(drive_ + "/velodyne_points/timestamps.txt");
    for (int k = 0; k <= 30; ++k) {
      const double t = k <= 10 ? 0.1 * k : 1.0 + 0.02 * (k - 10);
      char line[64];
      std::snprintf(line, sizeof line, "2011-01-01 12:00:%012.9f\n", 10.0 + t);
      stamps << line;
    }
  }
  scans = KittiNeighbourScans(drive_, "0000000010", 1.0);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_NEAR(scans[1].seconds_after_reference, 0.4, 1e-6);

  {
    std::ofstream stamps(drive_ + "/velodyne_points/timestamps.txt", std::ios::trunc);
    stamps << "2011-01-01 12:00:10.000000000\nyesterday\n";
  }
  const std::string message = ErrorOf([&] { KittiNeighbourScans(drive_, "0000000001", 1.0); });
  EXPECT_NE(message.find("timestamps.txt"), std::string::npos) << message;
  EXPECT_NE(message.find("line 2 is not a timestamp"), std::string::npos) << message;
}

}  // namespace
}  // namespace gcpstereo::io
