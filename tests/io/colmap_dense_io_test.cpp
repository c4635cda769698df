// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// COLMAP dense arrays (depth and normal maps): the byte layout COLMAP's Mat<float> reads, written
// out by hand here; round trips to the byte; and clear errors for broken headers and lengths.
#include "gcpstereo/io/colmap_dense_io.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

using gcpstereo::testing::ErrorOf;
using gcpstereo::testing::ReadFile;

void WriteRaw(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string FloatBytesLittleEndian(float value) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &value, 4);
  std::string bytes(4, '\0');
  for (int i = 0; i < 4; ++i) bytes[i] = static_cast<char>((bits >> (8 * i)) & 0xff);
  return bytes;
}

// A value that names its position: channel · 100 + row · 10 + col.
float Tag(int row, int col, int channel) { return 100.0f * channel + 10.0f * row + col; }

// The file COLMAP's Mat<float>::Write makes of a width × height × channels array: the header
// "W&H&C&", then element channel · W · H + row · W + col (src/mvs/mat.h), built without the
// writer under test.
std::string ColmapBytes(int width, int height, int channels) {
  std::string bytes =
      std::to_string(width) + "&" + std::to_string(height) + "&" + std::to_string(channels) + "&";
  std::string data(static_cast<std::size_t>(width) * height * channels * 4, '\0');
  for (int c = 0; c < channels; ++c) {
    for (int r = 0; r < height; ++r) {
      for (int x = 0; x < width; ++x) {
        const std::size_t index = (static_cast<std::size_t>(c) * width * height) +
                                  static_cast<std::size_t>(r) * width + x;
        data.replace(index * 4, 4, FloatBytesLittleEndian(Tag(r, x, c)));
      }
    }
  }
  return bytes + data;
}

cv::Mat TaggedArray(int width, int height, int channels) {
  cv::Mat array(height, width, CV_32FC(channels));
  for (int r = 0; r < height; ++r) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) array.ptr<float>(r)[x * channels + c] = Tag(r, x, c);
    }
  }
  return array;
}

TEST(ColmapDenseIo, WritesColmapsLayout) {
  const std::string dir = testing::MakeTempDir("gcpstereo-colmap-dense");
  for (int channels : {1, 3}) {
    const std::string path = dir + "/a" + std::to_string(channels) + ".geometric.bin";
    WriteColmapArray(path, TaggedArray(5, 3, channels));
    EXPECT_EQ(ReadFile(path), ColmapBytes(5, 3, channels)) << channels << " channels";
  }
}

TEST(ColmapDenseIo, ReadsColmapsLayout) {
  const std::string dir = testing::MakeTempDir("gcpstereo-colmap-dense");
  const std::string path = dir + "/n.geometric.bin";
  WriteRaw(path, ColmapBytes(4, 6, 3));
  const cv::Mat array = ReadColmapArray(path);
  ASSERT_EQ(array.type(), CV_32FC3);
  ASSERT_EQ(array.cols, 4);
  ASSERT_EQ(array.rows, 6);
  for (int r = 0; r < 6; ++r) {
    for (int x = 0; x < 4; ++x) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(array.at<cv::Vec3f>(r, x)[c], Tag(r, x, c)) << r << " " << x << " " << c;
      }
    }
  }
}

TEST(ColmapDenseIo, RoundTripIsByteExact) {
  const std::string dir = testing::MakeTempDir("gcpstereo-colmap-dense");
  cv::RNG rng(11);
  for (int channels : {1, 3}) {
    cv::Mat array(37, 53, CV_32FC(channels));
    rng.fill(array, cv::RNG::UNIFORM, -1e3, 1e3);
    array.ptr<float>(0)[0] = 0.0f;
    array.ptr<float>(1)[0] = -0.0f;
    array.ptr<float>(2)[0] = std::numeric_limits<float>::denorm_min();
    array.ptr<float>(3)[0] = std::numeric_limits<float>::quiet_NaN();
    array.ptr<float>(4)[0] = std::numeric_limits<float>::infinity();
    const std::string first = dir + "/first.bin", second = dir + "/second.bin";
    WriteColmapArray(first, array);
    const cv::Mat read = ReadColmapArray(first);
    ASSERT_EQ(read.type(), array.type());
    ASSERT_EQ(read.size(), array.size());
    for (int r = 0; r < array.rows; ++r) {
      EXPECT_EQ(std::memcmp(read.ptr(r), array.ptr(r), array.cols * array.elemSize()), 0) << r;
    }
    WriteColmapArray(second, read);
    EXPECT_EQ(ReadFile(first), ReadFile(second));
  }
}

TEST(ColmapDenseIo, BrokenFilesGiveClearErrors) {
  const std::string dir = testing::MakeTempDir("gcpstereo-colmap-dense");
  const std::string path = dir + "/x.geometric.bin";
  auto error_of = [&](const std::string& bytes) {
    WriteRaw(path, bytes);
    return ErrorOf([&] { ReadColmapArray(path); });
  };
  const std::string good = ColmapBytes(3, 2, 1);
  EXPECT_EQ(error_of(good.substr(0, good.size() - 3)),
            path +
                ": truncated: a 3x2x1 float32 array needs 24 bytes after the header, the file "
                "has 21");
  EXPECT_EQ(error_of(good + "xy"),
            path +
                ": trailing bytes: a 3x2x1 float32 array needs 24 bytes after the header, the "
                "file has 26");
  EXPECT_EQ(error_of("3&2&"),
            path +
                ": bad COLMAP array header: expected the channel count as a decimal number "
                "followed by '&' at byte 4, found '' (the header is "
                "<width>&<height>&<channels>&)");
  EXPECT_EQ(error_of("Pf\n3 2\n-1.0\n"),
            path +
                ": bad COLMAP array header: expected the width as a decimal number followed "
                "by '&' at byte 0, found 'Pf?3 2?-1.0?' (the header is "
                "<width>&<height>&<channels>&)");
  EXPECT_EQ(error_of("3&-2&1&"),
            path +
                ": bad COLMAP array header: expected the height as a decimal number followed "
                "by '&' at byte 2, found '-2&1&' (the header is <width>&<height>&<channels>&)");
  EXPECT_EQ(error_of("0&2&1&"), path + ": bad COLMAP array header: size 0x2 outside 1…100000");
  EXPECT_EQ(error_of("3&2&5&" + std::string(120, '\0')),
            path + ": bad COLMAP array header: 5 channels, expected 1 to 4");
  EXPECT_EQ(error_of(""),
            path +
                ": bad COLMAP array header: expected the width as a decimal number followed "
                "by '&' at byte 0, found '' (the header is <width>&<height>&<channels>&)");
  EXPECT_EQ(ErrorOf([&] { ReadColmapArray(dir + "/missing.bin"); }),
            dir + "/missing.bin: file not found");
  // A huge declared size is refused from the header, before anything is allocated.
  EXPECT_EQ(error_of("99999&99999&4&"),
            path +
                ": truncated: a 99999x99999x4 float32 array needs 159996800016 bytes after the "
                "header, the file has 0");
}

TEST(ColmapDenseIo, WriterRefusesOtherTypes) {
  const std::string dir = testing::MakeTempDir("gcpstereo-colmap-dense");
  EXPECT_EQ(ErrorOf([&] { WriteColmapArray(dir + "/a.bin", cv::Mat(2, 2, CV_8UC1)); }),
            dir + "/a.bin: a COLMAP array needs a CV_32FC1 … CV_32FC4 image, got type CV_8UC1");
  EXPECT_EQ(ErrorOf([&] { WriteColmapArray(dir + "/a.bin", cv::Mat()); }),
            dir + "/a.bin: cannot write an empty array in COLMAP's format");
}

TEST(ColmapDenseIo, DepthConventions) {
  cv::Mat depth(1, 6, CV_32F);
  const float values[6] = {2.5f, kInvalidDepth, std::numeric_limits<float>::quiet_NaN(),
                           0.0f, -1.0f,         7.0f};
  for (int i = 0; i < 6; ++i) depth.at<float>(0, i) = values[i];
  const cv::Mat colmap = ColmapDepthFromDepthMap(depth);
  const float expected[6] = {2.5f, 0.0f, 0.0f, 0.0f, 0.0f, 7.0f};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(colmap.at<float>(0, i), expected[i]) << i;
  EXPECT_EQ(depth.at<float>(0, 1), kInvalidDepth);  // the input is not modified
  const cv::Mat back = DepthMapFromColmapDepth(colmap);
  const float round_trip[6] = {2.5f,          kInvalidDepth, kInvalidDepth,
                               kInvalidDepth, kInvalidDepth, 7.0f};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(back.at<float>(0, i), round_trip[i]) << i;
}

}  // namespace
}  // namespace gcpstereo::io
