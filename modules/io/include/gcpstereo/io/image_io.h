// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include <opencv2/core/mat.hpp>
#include <opencv2/imgcodecs.hpp>

namespace gcpstereo::io {

// Reads an image with cv::imread(path, flags) (PNG, JPEG, PPM/PGM, …; default: unchanged depth
// and channels). Throws IoError naming the path when the file is missing or cannot be decoded.
cv::Mat ReadImage(const std::string& path, int flags = cv::IMREAD_UNCHANGED);

// Reads an 8-bit colour image as CV_8UC3 BGR (grey images are expanded to three channels; 16-bit
// images are rejected). Throws IoError.
cv::Mat ReadColorImage(const std::string& path);

// Writes a lossless PNG atomically. Accepts CV_8UC1, CV_8UC3 (BGR), CV_8UC4 (BGRA) and CV_16UC1;
// throws IoError (naming the path and the type) for anything else or an empty image.
void WritePng(const std::string& path, const cv::Mat& image);

}  // namespace gcpstereo::io
