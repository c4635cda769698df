// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/types.h"

namespace gcpstereo::cost {

// A calibrated reference–neighbour pair made rectified, with the reference as the left image.
struct RectifiedCalibratedPair {
  // True when cv::stereoRectify puts the neighbour above or below the reference: the pair is then
  // not usable for horizontal matching and the other fields are unset.
  bool vertical = false;
  // The neighbour is left of the reference: both rectified images are mirrored left-right, so that
  // disparities d = x_left − x_right stay positive.
  bool mirrored = false;
  cv::Mat left, right;              // rectified (and mirrored) reference and neighbour images
  cv::Mat left_valid, right_valid;  // CV_8U, 255 = a source pixel (eroded by 1 px), same layout
  double focal_px = 0.0;            // f of the rectified cameras
  double cx = 0.0, cy = 0.0;        // principal point of the rectified reference (not mirrored)
  double baseline = 0.0;            // rectified baseline, data set unit: z_rect = f·B / d
  // Rotation from the rectified reference camera's frame to the reference camera's frame.
  Eigen::Matrix3d ref_from_rect = Eigen::Matrix3d::Identity();
};

// Rectifies (reference, neighbor) with cv::stereoRectify: zero distortion, alpha = 1, the input
// size, CALIB_ZERO_DISPARITY; relative pose from the Cameras, R = R_nᵀ R_ref, T = R_nᵀ (C_ref −
// C_n) (R = camera-to-world rotation). Images are remapped bilinearly (black outside the source).
// Both views must have images of their cameras' size.
RectifiedCalibratedPair RectifyCalibratedPair(const View& reference, const View& neighbor);

// Indices of `neighbors` from the nearest to the reference to the farthest (distance of the camera
// centres; ties: list order): the pairs to rectify first.
std::vector<std::size_t> NeighborsByDistance(const View& reference,
                                             const std::vector<View>& neighbors);

}  // namespace gcpstereo::cost
