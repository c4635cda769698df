// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Yoon–Kweon adaptive-support-weight matching of a rectified pair, both views in one pass (private
// to the gcp module; stereo_gcps.h documents the cost).
#pragma once

#include <opencv2/core/mat.hpp>

#include "gcpstereo/gcp/stereo_gcps.h"

namespace gcpstereo::gcp::internal {

// Uniqueness u = (c₂ − c₁) / c₂ of a cost curve: c₁ = cost[best], c₂ the lowest cost among the
// valid entries more than 1 px from best. 0 when there is no such entry or c₂ <= 0.
float UniquenessOfCurve(const double* cost, const bool* valid, int count, int best);

// The adaptive-weight WTA, its uniqueness and its parabola vertex (wta_aw, uniqueness_aw,
// subpixel_aw) of the left view (partner pixel x − d) and of the right view (partner x + d), each
// in its own image's coordinates, d ∈ [dmin, dmax]. The right view's costs are those of the left
// formula applied to both images mirrored left–right (its window offsets summed in that order),
// bit for bit; the two views share their support weights and truncated differences, which is
// why they are computed together. Ties go to the smallest disparity.
void AdaptiveWeightEvidence(const cv::Mat& left_bgr, const cv::Mat& right_bgr, int dmin, int dmax,
                            const StereoGcpOptions& options, StereoViewEvidence* left,
                            StereoViewEvidence* right);

}  // namespace gcpstereo::gcp::internal
