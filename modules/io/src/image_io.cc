// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/image_io.h"

#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"

namespace gcpstereo::io {

cv::Mat ReadImage(const std::string& path, int flags) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "image file not found");
  cv::Mat image;
  try {
    image = cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    throw IoError(path, std::string("cannot decode image: ") + e.what());
  }
  if (image.empty()) throw IoError(path, "cannot decode image (unsupported or corrupt file)");
  return image;
}

cv::Mat ReadColorImage(const std::string& path) {
  cv::Mat image = ReadImage(path, cv::IMREAD_UNCHANGED);
  if (image.depth() != CV_8U) {
    throw IoError(path, "expected an 8-bit image, got type " + cv::typeToString(image.type()));
  }
  switch (image.channels()) {
    case 1:
      cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
      break;
    case 3:
      break;
    case 4:
      cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
      break;
    default:
      throw IoError(path, "unsupported channel count " + std::to_string(image.channels()));
  }
  return image;
}

void WritePng(const std::string& path, const cv::Mat& image) {
  if (image.empty()) throw IoError(path, "cannot write an empty image as PNG");
  const int type = image.type();
  if (type != CV_8UC1 && type != CV_8UC3 && type != CV_8UC4 && type != CV_16UC1) {
    throw IoError(path, "PNG writer accepts CV_8UC1, CV_8UC3, CV_8UC4 or CV_16UC1, got " +
                            cv::typeToString(type));
  }
  // Encode in memory: cv::imwrite picks the format from the extension, which the temporary
  // ".partial" name hides.
  std::vector<std::uint8_t> buffer;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, buffer, {cv::IMWRITE_PNG_COMPRESSION, 3});
  } catch (const cv::Exception& e) {
    throw IoError(path, std::string("PNG encoding failed: ") + e.what());
  }
  if (!ok) throw IoError(path, "PNG encoding failed");
  WriteBytesAtomically(path, buffer.data(), buffer.size());
}

}  // namespace gcpstereo::io
