// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/point_cloud_io.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

PointCloud RandomCloud(int n, bool sigma, bool intensity, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-20.0f, 20.0f);
  PointCloud cloud;
  for (int i = 0; i < n; ++i) {
    cloud.points.emplace_back(uniform(rng), uniform(rng), uniform(rng));
    if (sigma) cloud.sigma.push_back(0.001f * (1 + i % 7));
    if (intensity) cloud.intensity.push_back(0.01f * (i % 100));
  }
  return cloud;
}

void WriteRaw(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string ErrorOf(const std::string& path) {
  try {
    ReadPointCloud(path);
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PointCloudIo, PlyRoundTripWithSigmaAndIntensity) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  const PointCloud cloud = RandomCloud(1000, true, true, 5);
  WritePointCloudPly(dir + "/laser.ply", cloud);
  const PointCloud back = ReadPointCloud(dir + "/laser.ply");
  ASSERT_EQ(back.size(), cloud.size());
  ASSERT_EQ(back.sigma.size(), cloud.size());
  ASSERT_EQ(back.intensity.size(), cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(back.points[i], cloud.points[i]) << i;
    ASSERT_EQ(back.sigma[i], cloud.sigma[i]) << i;
    ASSERT_EQ(back.intensity[i], cloud.intensity[i]) << i;
  }
}

TEST(PointCloudIo, PlyWithoutOptionalChannels) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  const PointCloud cloud = RandomCloud(10, false, false, 6);
  WritePointCloudPly(dir + "/xyz.ply", cloud);
  const PointCloud back = ReadPointCloud(dir + "/xyz.ply");
  ASSERT_EQ(back.size(), 10u);
  EXPECT_TRUE(back.sigma.empty());
  EXPECT_TRUE(back.intensity.empty());
  EXPECT_EQ(back.points[9], cloud.points[9]);
}

TEST(PointCloudIo, ReadsAsciiPcdWithSigma) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  WriteRaw(dir + "/c.pcd",
           "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z sigma\nSIZE 4 4 4 4\nTYPE F F F F\n"
           "COUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
           "1 2 3 0.5\n-4 5.5 6 0.25\n");
  const PointCloud cloud = ReadPointCloud(dir + "/c.pcd");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(-4.0f, 5.5f, 6.0f));
  ASSERT_EQ(cloud.sigma.size(), 2u);
  EXPECT_EQ(cloud.sigma[1], 0.25f);
}

TEST(PointCloudIo, KittiBinRoundTrip) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  const float values[8] = {1.0f, 2.0f, 3.0f, 0.5f, -7.25f, 8.0f, 0.125f, 0.0f};
  std::string bytes(sizeof(values), '\0');
  std::memcpy(&bytes[0], values, sizeof(values));
  WriteRaw(dir + "/0000000010.bin", bytes);
  const PointCloud cloud = ReadPointCloud(dir + "/0000000010.bin");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(-7.25f, 8.0f, 0.125f));
  ASSERT_EQ(cloud.intensity.size(), 2u);
  EXPECT_EQ(cloud.intensity[0], 0.5f);
}

TEST(PointCloudIo, BinLengthNotDivisibleBy16) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  const std::string path = dir + "/bad.bin";
  WriteRaw(path, std::string(36, '\0'));
  EXPECT_EQ(ErrorOf(path), path +
                               ": KITTI Velodyne file length 36 bytes is not a multiple of 16 "
                               "(float32 x, y, z, reflectance)");
}

// Headers are checked before PCL reads the file: PCL crashed on an empty or headerless PCD and
// allocated whatever a PLY header declared (10⁹ vertices: 16 GB before it failed).
TEST(PointCloudIo, CorruptPly) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  const std::string path = dir + "/corrupt.ply";
  auto vertices = [](const std::string& count) {
    return "ply\nformat binary_little_endian 1.0\nelement vertex " + count +
           "\nproperty float x\nproperty float y\nproperty float z\nend_header\n0123456789";
  };
  WriteRaw(path, vertices("5"));
  EXPECT_EQ(ErrorOf(path), path +
                               ": not a valid PLY file: the data its header declares (60 bytes) "
                               "is longer than the 10 bytes after the header (truncated?)");
  WriteRaw(path, vertices("999999999"));
  EXPECT_EQ(ErrorOf(path), path +
                               ": not a valid PLY file: its header declares 999999999 records "
                               "of at least 12 bytes, more than the file's " +
                               std::to_string(vertices("999999999").size()) +
                               " bytes (truncated or corrupt)");
  WriteRaw(path, "this is not a ply file\n");
  EXPECT_EQ(ErrorOf(path), path + ": not a valid PLY file: it does not begin with 'ply'");
  WriteRaw(path, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n");
  EXPECT_EQ(ErrorOf(path), path + ": not a valid PLY file: no 'end_header' line");
  WriteRaw(path, "");
  EXPECT_EQ(ErrorOf(path), path + ": point cloud file is empty");
}

TEST(PointCloudIo, CorruptPcd) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  const std::string path = dir + "/corrupt.pcd";
  WriteRaw(path, "");
  EXPECT_EQ(ErrorOf(path), path + ": point cloud file is empty");
  WriteRaw(path, "garbage\n");
  EXPECT_EQ(ErrorOf(path), path + ": not a valid PCD file: unexpected header line 'garbage'");
  const std::string header =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1000\nHEIGHT 1\n"
      "POINTS 1000\n";
  WriteRaw(path, header);
  EXPECT_EQ(ErrorOf(path), path + ": not a valid PCD file: no 'DATA' line");
  WriteRaw(path, header + "DATA binary\n0123456789");
  EXPECT_EQ(ErrorOf(path), path +
                               ": not a valid PCD file: its header declares 1000 points of at "
                               "least 12 bytes, more than the file's " +
                               std::to_string(header.size() + 22) +
                               " bytes (truncated or corrupt)");
  WriteRaw(path, header + "DATA ascii\n1 2 3\n");
  EXPECT_NE(ErrorOf(path).find("not a valid PCD file"), std::string::npos) << ErrorOf(path);
}

// Inputs tools/fuzz.sh found (reduced but the last): PCL 1.13 aborts on a list property of the
// vertex element, allocates SIZE × COUNT bytes per point (also for ASCII data) before reading any,
// and can return a cloud whose fields lie outside its records; counts beyond 2^64 overflowed the
// header check's integers. Each is refused, naming the file.
TEST(PointCloudIo, FuzzerFindingsAreRefusedBeforePcl) {
  const std::string dir = testing::MakeTempDir("io-cloud-fuzz");
  const std::string ply = dir + "/list.ply";
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nproperty list uchar int vertex_indices\nend_header\n";
  bytes += std::string(12, '\0') + std::string("\x01\x02\0\0\0", 5);
  WriteRaw(ply, bytes);
  EXPECT_EQ(ErrorOf(ply), ply +
                              ": not a valid PLY file: a list property in element 'vertex' (only "
                              "scalar vertex properties are read)");
  const std::string pcd = dir + "/size.pcd";
  const std::string head = "VERSION 0.7\nFIELDS x y z\n";
  const std::string tail = "TYPE F F F\nPOINTS 3\nDATA ascii\n0 0 1\n1 0 2\n-1 0 3\n";
  WriteRaw(pcd, head + "SIZE 8 4 444444444444444\n" + tail);
  EXPECT_EQ(ErrorOf(pcd), pcd + ": not a valid PCD file: SIZE 4.44444e+14 (expected 1, 2, 4 or 8)");
  WriteRaw(pcd, head + "SIZE 4 4 4\nCOUNT 1 1 4000000000\n" + tail);
  EXPECT_EQ(ErrorOf(pcd), pcd + ": not a valid PCD file: COUNT 4e+09 (expected 1 to the file's " +
                              std::to_string(head.size() + tail.size() + 32) + " bytes)");
  // A count that does not fit an integer (UBSan: float-cast overflow).
  WriteRaw(ply, "ply\nformat ascii 1.0\nelement vertex 88888888888888888888\nend_header\n");
  EXPECT_EQ(ErrorOf(ply),
            ply + ": not a valid PLY file: element 'vertex' declares 8.88889e+19 records");
  WriteRaw(pcd, head + "WIDTH 1e30\nHEIGHT 1\n" + tail);
  EXPECT_EQ(ErrorOf(pcd), pcd + ": not a valid PCD file: WIDTH 1e+30");
  // Two FIELDS lines and a broken SIZE line: PCL returned a cloud whose data disagreed with its
  // fields, and pcl::fromPCLPointCloud2 indexed an empty cloud (the fuzzer's input, as found).
  const std::string fields(
      "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensityDNT 7\nFIELDS x y z intensit\x82\n"
      "SIZE 4 4 inten\0IEWPOINTS 3\nDATA binary\n\0\0\0CD v0..7\nVERSION "
      "0\x8d\x8d\x8d\x8d@\0\0\xa0@",
      144);
  WriteRaw(pcd, fields);
  EXPECT_EQ(ErrorOf(pcd), pcd +
                              ": cannot read point cloud: inconsistent fields or sizes (field 'z' "
                              "outside the 8-byte point record)");
  // No point at all: pcl::fromPCLPointCloud2 referenced element 0 of the empty cloud.
  WriteRaw(ply,
           "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
           "property float z\nend_header\n");
  EXPECT_EQ(ErrorOf(ply), ply + ": point cloud is empty");
  WriteRaw(pcd, head + "SIZE 4 4 4\nTYPE F F F\nWIDTH 0\nHEIGHT 1\nDATA ascii\n");
  EXPECT_EQ(ErrorOf(pcd), pcd + ": point cloud is empty");
  // A header line of only "\r": PCL read through a null pointer.
  WriteRaw(pcd, "\r\n" + head + "SIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n");
  EXPECT_EQ(ErrorOf(pcd),
            pcd + ": not a valid PCD file: a header line holding only a carriage return");
  // An ASCII value count larger than the file can hold.
  WriteRaw(pcd, head + "SIZE 4 4 4\nCOUNT 1 1 30\n" + tail);
  EXPECT_NE(ErrorOf(pcd).find(": not a valid PCD file: its header declares 3 points of at least 64 "
                              "bytes"),
            std::string::npos)
      << ErrorOf(pcd);
}

TEST(PointCloudIo, NonFiniteEmptyAndUnknownExtension) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  PointCloud cloud = RandomCloud(5, false, false, 7);
  cloud.points[3].y() = std::numeric_limits<float>::quiet_NaN();
  WritePointCloudPly(dir + "/nan.ply", cloud);
  EXPECT_EQ(ErrorOf(dir + "/nan.ply"), dir + "/nan.ply: point 3 has a non-finite coordinate");
  WriteRaw(dir + "/empty.bin", "");
  EXPECT_EQ(ErrorOf(dir + "/empty.bin"), dir + "/empty.bin: point cloud is empty");
  WriteRaw(dir + "/c.xyz", "1 2 3\n");
  EXPECT_EQ(ErrorOf(dir + "/c.xyz"),
            dir + "/c.xyz: unknown point cloud extension '.xyz' (expected .ply, .pcd or .bin)");
  EXPECT_EQ(ErrorOf(dir + "/none.ply"), dir + "/none.ply: point cloud file not found");
}

TEST(PointCloudIo, ChannelLengthMismatchIsRejected) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  PointCloud cloud = RandomCloud(5, true, false, 8);
  cloud.sigma.pop_back();
  EXPECT_THROW(WritePointCloudPly(dir + "/m.ply", cloud), IoError);
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.ply"));
}

TEST(PointCloudIo, GcpsPlyHoldsWorldPointsAndSigma) {
  const std::string dir = testing::MakeTempDir("io-cloud");
  Camera camera;
  camera.K << 500.0, 0.0, 80.0, 0.0, 500.0, 50.0, 0.0, 0.0, 1.0;
  camera.world_from_camera_rotation =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  camera.center_world = Eigen::Vector3d(1.0, 2.0, 3.0);
  camera.width = 160;
  camera.height = 107;
  GcpSet gcps;
  gcps.points.push_back({10, 20, 5.0, 0.01, GcpSource::kLidar});
  gcps.points.push_back({100, 7, 7.5, 0.02, GcpSource::kDepthMap});
  gcps.points.push_back({159, 106, 3.25, 0.0, GcpSource::kStereo});
  WriteGcpsPly(dir + "/gcps.ply", gcps, camera);
  const PointCloud back = ReadPointCloud(dir + "/gcps.ply");
  ASSERT_EQ(back.size(), 3u);
  ASSERT_EQ(back.sigma.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const Gcp& g = gcps.points[i];
    Eigen::Vector2d pixel;
    double depth = 0.0;
    ASSERT_TRUE(camera.Project(back.points[i].cast<double>(), &pixel, &depth));
    EXPECT_NEAR(pixel.x(), g.col, 1e-3);
    EXPECT_NEAR(pixel.y(), g.row, 1e-3);
    EXPECT_NEAR(depth, g.depth, 1e-5);
    EXPECT_FLOAT_EQ(back.sigma[i], static_cast<float>(g.sigma));
  }
  // The header declares the source property (not read back by ReadPointCloud).
  std::ifstream in(dir + "/gcps.ply", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(bytes.find("property uchar source\n"), std::string::npos);
  EXPECT_NE(bytes.find("property uchar red\n"), std::string::npos);
}

OrientedPointCloud RandomOrientedCloud(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-20.0f, 20.0f);
  OrientedPointCloud cloud;
  for (int i = 0; i < n; ++i) {
    cloud.points.emplace_back(uniform(rng), uniform(rng), uniform(rng));
    cloud.normals.push_back(Eigen::Vector3f(uniform(rng), uniform(rng), uniform(rng)).normalized());
    cloud.colors.emplace_back(static_cast<std::uint8_t>(i % 256),
                              static_cast<std::uint8_t>((7 * i) % 256),
                              static_cast<std::uint8_t>(255 - i % 256));
    cloud.num_views.push_back(static_cast<std::uint16_t>(i % 3 == 0 ? 0 : 1 + i % 11));
    cloud.sigma.push_back(i % 3 == 0 ? 0.001f * (1 + i % 5) : 0.0f);
  }
  cloud.num_views[1] = 65535;  // the whole ushort range
  return cloud;
}

std::string OrientedErrorOf(const std::string& path) {
  try {
    ReadOrientedPointCloudPly(path);
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(OrientedPointCloudIo, PlyRoundTripIsExact) {
  const std::string dir = testing::MakeTempDir("io-fused");
  const OrientedPointCloud cloud = RandomOrientedCloud(1000, 3);
  const std::string path = dir + "/fused.ply";
  WriteOrientedPointCloudPly(path, cloud);
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  const OrientedPointCloud back = ReadOrientedPointCloudPly(path);
  ASSERT_EQ(back.size(), cloud.size());
  ASSERT_EQ(back.normals.size(), cloud.size());
  ASSERT_EQ(back.colors.size(), cloud.size());
  ASSERT_EQ(back.num_views.size(), cloud.size());
  ASSERT_EQ(back.sigma.size(), cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(back.points[i], cloud.points[i]) << i;
    ASSERT_EQ(back.normals[i], cloud.normals[i]) << i;
    ASSERT_EQ(back.colors[i], cloud.colors[i]) << i;
    ASSERT_EQ(back.num_views[i], cloud.num_views[i]) << i;
    ASSERT_EQ(back.sigma[i], cloud.sigma[i]) << i;
  }
  // 33 bytes per vertex after the header; the general reader sees the positions too.
  const std::string bytes = ReadFileBytes(path);
  const size_t header_end = bytes.find("end_header\n") + std::strlen("end_header\n");
  EXPECT_EQ(bytes.size() - header_end, 33u * cloud.size());
  const PointCloud positions = ReadPointCloud(path);
  ASSERT_EQ(positions.size(), cloud.size());
  EXPECT_EQ(positions.points[17], cloud.points[17]);

  // An empty cloud round-trips too.
  WriteOrientedPointCloudPly(dir + "/empty.ply", OrientedPointCloud());
  EXPECT_TRUE(ReadOrientedPointCloudPly(dir + "/empty.ply").empty());
}

TEST(OrientedPointCloudIo, TruncatedAndForeignFilesAreRejected) {
  const std::string dir = testing::MakeTempDir("io-fused-bad");
  const std::string path = dir + "/fused.ply";
  WriteOrientedPointCloudPly(path, RandomOrientedCloud(10, 4));
  const std::string bytes = ReadFileBytes(path);

  WriteRaw(dir + "/truncated.ply", bytes.substr(0, bytes.size() - 5));
  EXPECT_EQ(
      OrientedErrorOf(dir + "/truncated.ply"),
      dir + "/truncated.ply: truncated: 10 vertices need 330 bytes of data, the file has 325");

  WriteRaw(dir + "/long.ply", bytes + "xy");
  EXPECT_EQ(OrientedErrorOf(dir + "/long.ply"),
            dir + "/long.ply: 2 bytes after the 10 vertices the header announces");

  WriteRaw(dir + "/header.ply", bytes.substr(0, bytes.find("end_header")));
  EXPECT_EQ(OrientedErrorOf(dir + "/header.ply"),
            dir + "/header.ply: PLY header without end_header (truncated or not a PLY file)");

  WriteRaw(dir + "/not.ply", "hello\n");
  EXPECT_EQ(OrientedErrorOf(dir + "/not.ply"), dir + "/not.ply: not a PLY file (no 'ply' line)");

  // A plain point cloud is not a fused cloud.
  WritePointCloudPly(dir + "/xyz.ply", RandomCloud(5, true, false, 1));
  EXPECT_EQ(OrientedErrorOf(dir + "/xyz.ply"),
            dir +
                "/xyz.ply: not a fused-cloud PLY: header line 'property float sigma' where "
                "'property float nx' was expected");

  std::string ascii = bytes;
  ascii.replace(ascii.find("binary_little_endian"), std::strlen("binary_little_endian"), "ascii");
  WriteRaw(dir + "/ascii.ply", ascii);
  EXPECT_EQ(OrientedErrorOf(dir + "/ascii.ply"),
            dir +
                "/ascii.ply: not a fused-cloud PLY: header line 'format ascii 1.0' where "
                "'format binary_little_endian 1.0' was expected");

  std::string count = bytes;
  count.replace(count.find("element vertex 10"), std::strlen("element vertex 10"),
                "element vertex -3");
  WriteRaw(dir + "/count.ply", count);
  EXPECT_EQ(OrientedErrorOf(dir + "/count.ply"),
            dir +
                "/count.ply: not a fused-cloud PLY: header line 'element vertex -3' where "
                "'element vertex <count>' was expected");

  EXPECT_NE(OrientedErrorOf(dir + "/missing.ply").find(dir + "/missing.ply: "), std::string::npos);
}

TEST(OrientedPointCloudIo, ChannelLengthMismatchIsRejected) {
  const std::string dir = testing::MakeTempDir("io-fused-mismatch");
  OrientedPointCloud cloud = RandomOrientedCloud(4, 5);
  cloud.num_views.pop_back();
  try {
    WriteOrientedPointCloudPly(dir + "/fused.ply", cloud);
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              dir + "/fused.ply: oriented point cloud has 4 points but 3 view counts");
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/fused.ply"));
}

}  // namespace
}  // namespace gcpstereo::io
