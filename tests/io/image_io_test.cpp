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

}  // namespace
}  // namespace gcpstereo::io
