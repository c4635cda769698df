// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The arrays of a COLMAP dense workspace (Schönberger et al., "Pixelwise View Selection for
// Unstructured Multi-View Stereo", ECCV 2016): stereo/depth_maps/<image>.<type>.bin (one channel)
// and stereo/normal_maps/<image>.<type>.bin (three), which `colmap stereo_fusion` and
// `colmap delaunay_mesher` read. Written after COLMAP's own reader and writer (src/mvs/mat.h,
// scripts/python/read_write_dense.py):
//
//   header   the ASCII text "<width>&<height>&<channels>&" (decimal, no spaces, no newline)
//   data     width · height · channels float32, little-endian, channel after channel, each
//            channel row after row from the top, each row left to right: the value of (row, col,
//            channel) is element  channel · width · height + row · width + col
//            (numpy: reshape((width, height, channels), order="F"), then transposed).
//
// Depth is along the camera's z axis in the model's unit; COLMAP treats depth <= 0 as no
// estimate (its own maps hold 0 there). Normals are unit vectors in the camera frame, pointing
// towards the camera.
#pragma once

#include <string>

#include <opencv2/core/mat.hpp>

namespace gcpstereo::io {

// Reads a COLMAP array as a CV_32FC(channels) image (channels 1 to 4; OpenCV's channel order is
// COLMAP's slice order: channel 0 = slice 0). Values are returned as stored. Throws IoError naming
// the file for: a missing or unreadable file, a header that is not three positive decimal numbers
// each followed by '&' ("bad COLMAP array header: …"), a size beyond 100000 px a side or a channel
// count outside 1…4, and data whose length is not width · height · channels · 4 bytes ("truncated"
// or "trailing bytes", with both counts).
cv::Mat ReadColmapArray(const std::string& path);

// Writes a CV_32FC1 … CV_32FC4 image as a COLMAP array, atomically (WriteFileAtomically), the
// values as they are. Throws IoError naming the path for an empty image or another type.
void WriteColmapArray(const std::string& path, const cv::Mat& array);

// The depth map in COLMAP's convention: a copy of a CV_32FC1 depth map (kInvalidDepth = +inf or
// any value that is not a positive finite number = no estimate) with 0 wherever there is no
// estimate. Throws Error for another type.
cv::Mat ColmapDepthFromDepthMap(const cv::Mat& depth);

// The depth map of a COLMAP depth array (CV_32FC1) in the project's convention: +inf
// (kInvalidDepth) wherever COLMAP has no estimate (depth <= 0 or not finite).
cv::Mat DepthMapFromColmapDepth(const cv::Mat& colmap_depth);

}  // namespace gcpstereo::io
