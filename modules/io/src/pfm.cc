// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/pfm.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"
#include "little_endian.h"

namespace gcpstereo::io {
namespace {

using internal::HostIsLittleEndian;

// Reads one whitespace-delimited token of the header starting at *pos and consumes exactly one
// whitespace character after it (the PFM header rule).
bool NextToken(const std::string& bytes, std::size_t* pos, std::string* token) {
  std::size_t p = *pos;
  while (p < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[p]))) ++p;
  const std::size_t start = p;
  while (p < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[p])) &&
         p - start < 64) {
    ++p;
  }
  if (p == start || p >= bytes.size()) return false;
  *token = bytes.substr(start, p - start);
  *pos = p + 1;  // the single whitespace after the token
  return true;
}

bool ParsePositiveInt(const std::string& token, int* value) {
  if (token.empty() || token.size() > 9) return false;
  for (char c : token) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  *value = std::stoi(token);
  return *value > 0;
}

}  // namespace

cv::Mat ReadPfm(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  std::size_t pos = 0;
  std::string magic, width_text, height_text, scale_text;
  if (!NextToken(bytes, &pos, &magic) || (magic != "Pf" && magic != "PF")) {
    throw IoError(
        path, "bad PFM header: expected 'Pf' or 'PF' magic, found '" + magic.substr(0, 16) + "'");
  }
  const int channels = magic == "PF" ? 3 : 1;
  int width = 0, height = 0;
  if (!NextToken(bytes, &pos, &width_text) || !NextToken(bytes, &pos, &height_text) ||
      !ParsePositiveInt(width_text, &width) || !ParsePositiveInt(height_text, &height)) {
    throw IoError(path, "bad PFM header: expected a positive width and height after '" + magic +
                            "', found '" + width_text + " " + height_text + "'");
  }
  double scale = 0.0;
  {
    bool ok = NextToken(bytes, &pos, &scale_text);
    if (ok) {
      std::istringstream s(scale_text);
      s.imbue(std::locale::classic());
      ok = static_cast<bool>(s >> scale) && s.eof();
    }
    if (!ok || !std::isfinite(scale) || scale == 0.0) {
      throw IoError(path,
                    "bad PFM header: expected a non-zero scale (negative = little-endian), "
                    "found '" +
                        scale_text + "'");
    }
  }
  const std::size_t expected = static_cast<std::size_t>(width) * height * channels * 4;
  const std::size_t available = bytes.size() - pos;
  if (available != expected) {
    std::ostringstream s;
    s << "PFM data of " << width << "x" << height << "x" << channels << " float32 needs "
      << expected << " bytes after the header, file has " << available;
    throw IoError(path, s.str());
  }
  const bool file_little_endian = scale < 0.0;
  const bool swap = file_little_endian != HostIsLittleEndian();
  cv::Mat image(height, width, channels == 3 ? CV_32FC3 : CV_32FC1);
  const std::size_t row_bytes = static_cast<std::size_t>(width) * channels * 4;
  for (int stored_row = 0; stored_row < height; ++stored_row) {
    // Rows are stored bottom to top.
    auto* dst = image.ptr<std::uint8_t>(height - 1 - stored_row);
    std::memcpy(dst, bytes.data() + pos + stored_row * row_bytes, row_bytes);
    if (swap) {
      for (std::size_t i = 0; i < row_bytes; i += 4) {
        std::swap(dst[i], dst[i + 3]);
        std::swap(dst[i + 1], dst[i + 2]);
      }
    }
  }
  if (channels == 3) cv::cvtColor(image, image, cv::COLOR_RGB2BGR);
  return image;
}

void WritePfm(const std::string& path, const cv::Mat& image) {
  if (image.empty()) throw IoError(path, "cannot write an empty image as PFM");
  if (image.type() != CV_32FC1 && image.type() != CV_32FC3) {
    throw IoError(
        path, "PFM needs a CV_32FC1 or CV_32FC3 image, got type " + cv::typeToString(image.type()));
  }
  cv::Mat data;  // a new buffer for colour images: never modify the caller's image
  if (image.channels() == 3) {
    cv::cvtColor(image, data, cv::COLOR_BGR2RGB);
  } else {
    data = image;
  }
  std::ostringstream header;
  header << (data.channels() == 3 ? "PF" : "Pf") << "\n"
         << data.cols << " " << data.rows << "\n"
         << "-1.0\n";
  const std::string head = header.str();
  const std::size_t row_bytes = static_cast<std::size_t>(data.cols) * data.channels() * 4;
  std::string bytes(head.size() + row_bytes * data.rows, '\0');
  std::memcpy(&bytes[0], head.data(), head.size());
  const bool swap = !HostIsLittleEndian();
  for (int stored_row = 0; stored_row < data.rows; ++stored_row) {
    char* dst = &bytes[head.size() + stored_row * row_bytes];
    std::memcpy(dst, data.ptr<char>(data.rows - 1 - stored_row), row_bytes);
    if (swap) {
      for (std::size_t i = 0; i < row_bytes; i += 4) {
        std::swap(dst[i], dst[i + 3]);
        std::swap(dst[i + 1], dst[i + 2]);
      }
    }
  }
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

}  // namespace gcpstereo::io
