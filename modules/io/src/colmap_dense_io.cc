// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// COLMAP dense-workspace arrays (colmap_dense_io.h).
#include "gcpstereo/io/colmap_dense_io.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/io/atomic_file.h"
#include "little_endian.h"

namespace gcpstereo::io {
namespace {

constexpr std::uint64_t kMaxSide = 100000;  // px: far beyond any camera, well inside size_t
constexpr int kMaxChannels = 4;             // COLMAP writes 1 (depth) and 3 (normals)

// Parses "<digits>&" at bytes[*pos]; returns the number and moves *pos past the '&'.
std::uint64_t HeaderNumber(const std::string& path, const std::string& bytes, std::size_t* pos,
                           const char* what) {
  const std::size_t start = *pos;
  std::uint64_t value = 0;
  std::size_t p = start;
  while (p < bytes.size() && p - start < 12 && bytes[p] >= '0' && bytes[p] <= '9') {
    value = value * 10 + static_cast<std::uint64_t>(bytes[p] - '0');
    ++p;
  }
  if (p == start || p >= bytes.size() || bytes[p] != '&') {
    const std::string found = bytes.substr(start, std::min<std::size_t>(16, bytes.size() - start));
    std::string printable;
    for (char c : found) printable += (c >= 32 && c < 127) ? c : '?';
    throw IoError(path, std::string("bad COLMAP array header: expected the ") + what +
                            " as a decimal number followed by '&' at byte " +
                            std::to_string(start) + ", found '" + printable +
                            "' (the header is <width>&<height>&<channels>&)");
  }
  *pos = p + 1;
  return value;
}

}  // namespace

cv::Mat ReadColmapArray(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  std::size_t pos = 0;
  const std::uint64_t width = HeaderNumber(path, bytes, &pos, "width");
  const std::uint64_t height = HeaderNumber(path, bytes, &pos, "height");
  const std::uint64_t channels = HeaderNumber(path, bytes, &pos, "channel count");
  if (width == 0 || height == 0 || width > kMaxSide || height > kMaxSide) {
    throw IoError(path, "bad COLMAP array header: size " + std::to_string(width) + "x" +
                            std::to_string(height) + " outside 1…" + std::to_string(kMaxSide));
  }
  if (channels == 0 || channels > static_cast<std::uint64_t>(kMaxChannels)) {
    throw IoError(path, "bad COLMAP array header: " + std::to_string(channels) +
                            " channels, expected 1 to " + std::to_string(kMaxChannels));
  }
  const std::uint64_t plane = width * height;
  const std::uint64_t expected = plane * channels * sizeof(float);
  const std::uint64_t available = bytes.size() - pos;
  if (available != expected) {
    throw IoError(path, std::string(available < expected ? "truncated" : "trailing bytes") +
                            ": a " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                            std::to_string(channels) + " float32 array needs " +
                            std::to_string(expected) + " bytes after the header, the file has " +
                            std::to_string(available));
  }
  const int rows = static_cast<int>(height), cols = static_cast<int>(width);
  const int n = static_cast<int>(channels);
  cv::Mat array(rows, cols, CV_32FC(n));
  const bool swap = !internal::HostIsLittleEndian();
  const char* data = bytes.data() + pos;
  for (int c = 0; c < n; ++c) {
    for (int r = 0; r < rows; ++r) {
      float* row = array.ptr<float>(r);
      for (int x = 0; x < cols; ++x) {
        char raw[sizeof(float)];
        std::memcpy(raw, data + ((c * plane) + static_cast<std::uint64_t>(r) * width + x) * 4,
                    sizeof(float));
        if (swap) std::reverse(raw, raw + sizeof(float));
        std::memcpy(&row[x * n + c], raw, sizeof(float));
      }
    }
  }
  return array;
}

void WriteColmapArray(const std::string& path, const cv::Mat& array) {
  if (array.empty()) throw IoError(path, "cannot write an empty array in COLMAP's format");
  if (array.depth() != CV_32F || array.channels() > kMaxChannels) {
    throw IoError(path, "a COLMAP array needs a CV_32FC1 … CV_32FC4 image, got type " +
                            cv::typeToString(array.type()));
  }
  const int rows = array.rows, cols = array.cols, n = array.channels();
  std::string bytes =
      std::to_string(cols) + "&" + std::to_string(rows) + "&" + std::to_string(n) + "&";
  bytes.reserve(bytes.size() + static_cast<std::size_t>(rows) * cols * n * sizeof(float));
  for (int c = 0; c < n; ++c) {
    for (int r = 0; r < rows; ++r) {
      const float* row = array.ptr<float>(r);
      for (int x = 0; x < cols; ++x) internal::AppendLittleEndian(&bytes, row[x * n + c]);
    }
  }
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

cv::Mat ColmapDepthFromDepthMap(const cv::Mat& depth) {
  if (depth.type() != CV_32FC1) {
    throw Error("ColmapDepthFromDepthMap: expected a CV_32FC1 depth map, got type " +
                cv::typeToString(depth.type()));
  }
  cv::Mat out = depth.clone();
  out.forEach<float>([](float& d, const int*) {
    if (!IsValidDepth(d)) d = 0.0f;
  });
  return out;
}

cv::Mat DepthMapFromColmapDepth(const cv::Mat& colmap_depth) {
  if (colmap_depth.type() != CV_32FC1) {
    throw Error("DepthMapFromColmapDepth: expected a CV_32FC1 depth array, got type " +
                cv::typeToString(colmap_depth.type()));
  }
  cv::Mat out = colmap_depth.clone();
  out.forEach<float>([](float& d, const int*) {
    if (!IsValidDepth(d)) d = kInvalidDepth;
  });
  return out;
}

}  // namespace gcpstereo::io
