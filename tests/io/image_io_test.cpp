// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/image_io.h"

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

cv::Mat RandomImage(int rows, int cols, int type, unsigned seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 65536 : 256);
  return image;
}

TEST(ImageIo, Png16RoundTrip) {
  const std::string dir = testing::MakeTempDir("io-image");
  const cv::Mat image = RandomImage(13, 17, CV_16UC1, 3);
  WritePng(dir + "/d.png", image);
  const cv::Mat back = ReadImage(dir + "/d.png");
  ASSERT_EQ(back.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(image, back, cv::NORM_INF), 0.0);
  EXPECT_FALSE(std::filesystem::exists(dir + "/d.png.partial"));
}

TEST(ImageIo, Png8ColorAndGrayRoundTrip) {
  const std::string dir = testing::MakeTempDir("io-image");
  for (int type : {CV_8UC1, CV_8UC3}) {
    const cv::Mat image = RandomImage(9, 11, type, 4);
    WritePng(dir + "/c.png", image);
    const cv::Mat back = ReadImage(dir + "/c.png");
    ASSERT_EQ(back.type(), type);
    EXPECT_EQ(cv::norm(image, back, cv::NORM_INF), 0.0);
  }
  // ReadColorImage expands grey to BGR.
  const cv::Mat color = ReadColorImage(dir + "/c.png");
  EXPECT_EQ(color.type(), CV_8UC3);
}

TEST(ImageIo, ErrorsNameTheFile) {
  const std::string dir = testing::MakeTempDir("io-image");
  try {
    ReadImage(dir + "/missing.png");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), dir + "/missing.png: image file not found");
  }
  std::ofstream(dir + "/junk.png") << "not a png at all";
  try {
    ReadImage(dir + "/junk.png");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("junk.png: cannot decode image"), std::string::npos)
        << e.what();
  }
  try {
    WritePng(dir + "/f.png", cv::Mat(2, 2, CV_32FC1));
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("got CV_32FC1"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/f.png"));
}

// A truncated file: the decoder's own lines (OpenCV's imread, libpng) no longer reach stderr
// ahead of the error; their reason is part of the one error message instead.
TEST(ImageIo, TruncatedFilesGiveOneMessageWithTheDecodersReason) {
  const std::string dir = testing::MakeTempDir("io-image");
  WritePng(dir + "/whole.png", RandomImage(40, 40, CV_8UC3, 3));
  std::ifstream in(dir + "/whole.png", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir + "/cut.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::ofstream(dir + "/cut.ppm", std::ios::binary) << "P6\n40 40\n255\n" << bytes.substr(0, 100);
  ::testing::internal::CaptureStderr();
  std::string png_error, ppm_error;
  try {
    ReadImage(dir + "/cut.png");
  } catch (const IoError& e) {
    png_error = e.what();
  }
  try {
    ReadImage(dir + "/cut.ppm");
  } catch (const IoError& e) {
    ppm_error = e.what();
  }
  const std::string printed = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "");
  EXPECT_EQ(png_error,
            dir + "/cut.png: cannot decode image (unsupported or corrupt file: Read Error)");
  EXPECT_EQ(ppm_error, dir +
                           "/cut.ppm: cannot decode image (unsupported or corrupt file: "
                           "Unexpected end of input stream)");
  // A good file still reads, and reading it prints nothing.
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(ReadImage(dir + "/whole.png").size(), cv::Size(40, 40));
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace gcpstereo::io
