// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/lidar_scan.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/io/point_cloud_io.h"
#include "test_data.h"

namespace gcpstereo::pipeline {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A KITTI .bin (float32 x, y, z, reflectance) of points on a circle of radius 10 around the
// scanner.
std::string WriteRingScan(const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  for (int i = 0; i < 360; ++i) {
    const float a = static_cast<float>(i * kPi / 180.0);
    const float values[4] = {10.0f * std::cos(a), 10.0f * std::sin(a), -1.0f, 0.5f};
    out.write(reinterpret_cast<const char*>(values), sizeof values);
  }
  return path;
}

TEST(LidarScanTest, GivenMotionIsTheCompensationOfTheScanAsRead) {
  const std::string drive = testing::MakeTempDir("lidar-scan-given");
  const std::string path = WriteRingScan(drive + "/0000000003.bin");
  gcp::LidarMotionOptions options;
  options.mode = "given";
  options.speed_mps = 8.0;
  options.yaw_rate_deg_s = 10.0;
  LidarScanSummary summary;
  const PointCloud scan = LoadLidarScan(path, drive, "0000000003", options, &summary);
  EXPECT_TRUE(summary.compensated);
  EXPECT_EQ(summary.mode, "given");
  EXPECT_DOUBLE_EQ(summary.motion.velocity.x(), 8.0);
  EXPECT_NEAR(summary.motion.yaw_rate_rad_s, 10.0 * kPi / 180.0, 1e-12);

  gcp::SweepMotion motion;
  motion.velocity = Eigen::Vector3d(8.0, 0.0, 0.0);
  motion.yaw_rate_rad_s = 10.0 * kPi / 180.0;
  const PointCloud raw = io::ReadPointCloud(path);
  const PointCloud expected = gcp::CompensateSweepMotion(raw, motion, options.sweep);
  ASSERT_EQ(scan.size(), expected.size());
  double moved = 0.0;
  for (size_t i = 0; i < scan.size(); ++i) {
    EXPECT_EQ(scan.points[i], expected.points[i]);
    moved = std::max(moved, static_cast<double>((scan.points[i] - raw.points[i]).norm()));
  }
  EXPECT_GT(moved, 0.3);  // up to 8 m/s · 0.05 s = 0.4 m behind the scanner
}

TEST(LidarScanTest, RegistrationWithoutOtherScansKeepsTheScanAndSaysWhy) {
  const std::string drive = testing::MakeTempDir("lidar-scan-alone");
  std::filesystem::create_directories(drive + "/velodyne_points/data");
  const std::string path = WriteRingScan(drive + "/velodyne_points/data/0000000007.bin");
  gcp::LidarMotionOptions options;
  options.mode = "registration";
  LidarScanSummary summary;
  const PointCloud scan = LoadLidarScan(path, drive, "0000000007", options, &summary);
  EXPECT_FALSE(summary.compensated);
  EXPECT_EQ(summary.message,
            "the sweep's motion is not compensated: no other scan of the drive within 2 s "
            "(gcp.lidar.motion.max_gap_s) of frame 0000000007");
  EXPECT_EQ(scan.points, io::ReadPointCloud(path).points);
}

// KITTI drive 0009 (residential street, ≈ 40 km/h): the scans of frames 30 and 50, one second
// before and after frame 40's, register to the same speed.
TEST(LidarScanTest, KittiDriveSpeedFromTheScansBeforeAndAfter) {
  GCPSTEREO_REQUIRE_SHARED_DATA(drive, "kitti/2011_09_26/2011_09_26_drive_0009_sync");
  gcp::LidarMotionOptions options;
  options.mode = "registration";
  LidarScanSummary summary;
  LoadLidarScan(drive + "/velodyne_points/data/0000000040.bin", drive, "0000000040", options,
                &summary);
  ASSERT_TRUE(summary.compensated) << summary.message;
  ASSERT_EQ(summary.registrations.size(), 2u);
  EXPECT_EQ(summary.registrations[0].name, "0000000030");
  EXPECT_EQ(summary.registrations[1].name, "0000000050");
  double speeds[2];
  for (int i = 0; i < 2; ++i) {
    const gcp::ScanRegistrationSummary& r = summary.registrations[i];
    EXPECT_TRUE(r.used);
    speeds[i] = r.reference_from_other(0, 3) / r.seconds_after_reference;
    EXPECT_NEAR(r.reference_from_other(1, 3), 0.0, 0.5);  // straight ahead
  }
  EXPECT_GT(speeds[0], 9.5);
  EXPECT_LT(speeds[0], 12.5);
  EXPECT_NEAR(speeds[0], speeds[1], 1.0);  // a steady speed over two seconds
  EXPECT_NEAR(summary.motion.velocity.x(), 0.5 * (speeds[0] + speeds[1]), 1e-9);
}

}  // namespace
}  // namespace gcpstereo::pipeline
