// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include <opencv2/core/mat.hpp>

namespace gcpstereo::io {

// Portable Float Map in the Middlebury 2014 convention: a header "Pf" (one channel, CV_32F) or
// "PF" (three channels, CV_32FC3, stored R G B and returned in OpenCV's B G R order), then
// "W H", then a scale whose sign gives the byte order (negative = little-endian), each followed by
// one whitespace character; then the float32 samples, rows stored bottom to top.
// +inf (unknown depth / disparity) round-trips.

// Reads either byte order. Validates the magic, the size, the scale (non-zero, finite) and the file
// length; throws IoError naming the file and the problem.
cv::Mat ReadPfm(const std::string& path);

// Writes CV_32F or CV_32FC3 little-endian (scale -1.0), atomically. Throws IoError for other types
// or an empty image.
void WritePfm(const std::string& path, const cv::Mat& image);

}  // namespace gcpstereo::io
