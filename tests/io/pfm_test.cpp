// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/pfm.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

cv::Mat RandomFloatImage(int rows, int cols, int channels, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-100.0f, 100.0f);
  cv::Mat image(rows, cols, CV_MAKETYPE(CV_32F, channels));
  for (int r = 0; r < rows; ++r) {
    float* p = image.ptr<float>(r);
    for (int i = 0; i < cols * channels; ++i) p[i] = uniform(rng);
  }
  return image;
}

bool BitwiseEqual(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int r = 0; r < a.rows; ++r) {
    if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

void WriteRaw(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string ErrorOf(const std::string& path) {
  try {
    ReadPfm(path);
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Pfm, GrayRoundTripWithInfinity) {
  const std::string dir = testing::MakeTempDir("io-pfm");
  cv::Mat image = RandomFloatImage(7, 5, 1, 1);
  image.at<float>(0, 0) = std::numeric_limits<float>::infinity();
  image.at<float>(3, 4) = -std::numeric_limits<float>::infinity();
  image.at<float>(6, 2) = 0.0f;
  WritePfm(dir + "/a.pfm", image);
  const cv::Mat back = ReadPfm(dir + "/a.pfm");
  EXPECT_TRUE(BitwiseEqual(image, back));
  EXPECT_TRUE(std::isinf(back.at<float>(0, 0)));
}

TEST(Pfm, ColorRoundTripKeepsBgrOrder) {
  const std::string dir = testing::MakeTempDir("io-pfm");
  const cv::Mat image = RandomFloatImage(4, 6, 3, 2);
  WritePfm(dir + "/c.pfm", image);
  EXPECT_TRUE(BitwiseEqual(image, ReadPfm(dir + "/c.pfm")));
}

TEST(Pfm, FileLayoutIsMiddlebury2014) {
  // Header "Pf\nW H\n-1.0\n", little-endian floats, bottom row first.
  const std::string dir = testing::MakeTempDir("io-pfm");
  cv::Mat image = (cv::Mat_<float>(2, 3) << 1, 2, 3, 4, 5, 6);
  WritePfm(dir + "/l.pfm", image);
  std::ifstream in(dir + "/l.pfm", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = "Pf\n3 2\n-1.0\n";
  ASSERT_EQ(bytes.size(), header.size() + 24);
  EXPECT_EQ(bytes.substr(0, header.size()), header);
  float first = 0.0f;
  std::memcpy(&first, bytes.data() + header.size(), 4);
  EXPECT_EQ(first, 4.0f);  // first stored sample = bottom-left
}

TEST(Pfm, ReadsBigEndian) {
  const std::string dir = testing::MakeTempDir("io-pfm");
  // 2x2 big-endian file, rows bottom to top: bottom row (3, inf), top row (1, -2.5).
  const float values[4] = {3.0f, std::numeric_limits<float>::infinity(), 1.0f, -2.5f};
  std::string bytes = "Pf\n2 2\n1.0\n";
  for (float v : values) {
    char raw[4];
    std::memcpy(raw, &v, 4);
    std::swap(raw[0], raw[3]);
    std::swap(raw[1], raw[2]);
    bytes.append(raw, 4);
  }
  WriteRaw(dir + "/be.pfm", bytes);
  const cv::Mat image = ReadPfm(dir + "/be.pfm");
  ASSERT_EQ(image.type(), CV_32FC1);
  EXPECT_EQ(image.at<float>(0, 0), 1.0f);
  EXPECT_EQ(image.at<float>(0, 1), -2.5f);
  EXPECT_EQ(image.at<float>(1, 0), 3.0f);
  EXPECT_TRUE(std::isinf(image.at<float>(1, 1)));
}

TEST(Pfm, BadHeaderIsNamed) {
  const std::string dir = testing::MakeTempDir("io-pfm");
  const std::string path = dir + "/bad.pfm";
  WriteRaw(path, "P6\n2 2\n255\n123456789012");
  EXPECT_NE(ErrorOf(path).find(path + ": bad PFM header: expected 'Pf' or 'PF' magic, found 'P6'"),
            std::string::npos)
      << ErrorOf(path);
  WriteRaw(path, "Pf\n2 x\n-1.0\n0123456789abcdef");
  EXPECT_NE(ErrorOf(path).find("expected a positive width and height"), std::string::npos)
      << ErrorOf(path);
  WriteRaw(path, "Pf\n2 2\n0\n0123456789abcdef");
  EXPECT_NE(ErrorOf(path).find("expected a non-zero scale"), std::string::npos) << ErrorOf(path);
}

TEST(Pfm, TruncatedDataIsNamed) {
  const std::string dir = testing::MakeTempDir("io-pfm");
  const std::string path = dir + "/short.pfm";
  WriteRaw(path, "Pf\n2 2\n-1.0\n0123456789");
  EXPECT_NE(ErrorOf(path).find(path + ": PFM data of 2x2x1 float32 needs 16 bytes after the "
                                      "header, file has 10"),
            std::string::npos)
      << ErrorOf(path);
}

TEST(Pfm, MissingFileAndWrongTypeAreNamed) {
  const std::string dir = testing::MakeTempDir("io-pfm");
  EXPECT_NE(ErrorOf(dir + "/none.pfm").find("none.pfm: file not found"), std::string::npos);
  try {
    WritePfm(dir + "/u8.pfm", cv::Mat(2, 2, CV_8UC1, cv::Scalar(1)));
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(
        std::string(e.what()).find("PFM needs a CV_32FC1 or CV_32FC3 image, got type CV_8UC1"),
        std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace gcpstereo::io
