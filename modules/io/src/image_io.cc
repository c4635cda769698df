// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/image_io.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <mutex>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"

namespace gcpstereo::io {

namespace {

// Runs `read` with the process's stderr (file descriptor 2) sent to a temporary file and returns
// what was written there: OpenCV's imread and libpng print their own lines about a corrupt file
// before returning an empty image, and the contract allows one line per error. Serialised, since
// the descriptor is process-wide.
std::string WithStderrCaptured(const std::function<void()>& read) {
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  std::FILE* capture = std::tmpfile();
  if (capture == nullptr) {
    read();
    return std::string();
  }
  std::cerr.flush();
  std::fflush(stderr);
  const int saved = dup(2);
  dup2(fileno(capture), 2);
  struct Restore {
    int saved;
    ~Restore() {
      std::cerr.flush();
      std::fflush(stderr);
      dup2(saved, 2);
      close(saved);
    }
  };
  {
    Restore restore{saved};
    read();
  }
  std::string text;
  std::rewind(capture);
  char buffer[512];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), capture)) > 0) text.append(buffer, n);
  std::fclose(capture);
  return text;
}

// The decoder's own reason from its captured lines ("… error: (-2:…) Unexpected end of input
// stream in function 'readBlock'" → "Unexpected end of input stream"; "libpng error: Read Error"
// → "Read Error"), or "" when there is none.
std::string DecoderReason(const std::string& captured) {
  std::string line = captured.substr(0, captured.find('\n'));
  const size_t paren = line.find(") ", line.find("error: ("));
  if (line.find("error: (") != std::string::npos && paren != std::string::npos) {
    line = line.substr(paren + 2);
    const size_t in_function = line.find(" in function");
    if (in_function != std::string::npos) line = line.substr(0, in_function);
  } else if (line.rfind("libpng error: ", 0) == 0) {
    line = line.substr(14);
  }
  if (line.size() > 120) line = line.substr(0, 120);
  return line;
}

}  // namespace

cv::Mat ReadImage(const std::string& path, int flags) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "image file not found");
  cv::Mat image;
  std::string error;
  const std::string captured = WithStderrCaptured([&] {
    try {
      image = cv::imread(path, flags);
    } catch (const cv::Exception& e) {
      error = e.what();
    }
  });
  if (!error.empty()) throw IoError(path, "cannot decode image: " + error);
  if (image.empty()) {
    const std::string reason = DecoderReason(captured);
    throw IoError(path, "cannot decode image (unsupported or corrupt file" +
                            (reason.empty() ? std::string() : ": " + reason) + ")");
  }
  if (!captured.empty()) std::fputs(captured.c_str(), stderr);  // a decoder's warning: keep it
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
