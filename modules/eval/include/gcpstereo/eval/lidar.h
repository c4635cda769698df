// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::eval {

// Held-out LiDAR evaluation for data without dense ground truth (KITTI raw): the projected scan
// points are split by a fixed block pattern into a part that may be used as GCPs and a part that is
// only scored, so no scored point ever fed the optimisation.

// One scan point seen in the reference view.
struct ProjectedPoint {
  Eigen::Vector2d pixel;  // sub-pixel position (pixel-centre convention of Camera)
  double depth = 0.0;     // along the reference camera's z
  int index = -1;         // index of the point in the input cloud
};

// Projects every point of `cloud` (in its own frame; world_from_cloud maps it to the world frame
// of `camera`) into the camera, keeping those in front of it and inside the image. With
// keep_nearest_per_pixel, only the nearest point of each pixel (nearest pixel centre) is kept
// (ties: the lower index). Output order: by input index.
std::vector<ProjectedPoint> ProjectPointCloud(
    const PointCloud& cloud, const Camera& camera,
    const Eigen::Matrix4d& world_from_cloud = Eigen::Matrix4d::Identity(),
    bool keep_nearest_per_pixel = true);

// The fixed split pattern: with (c, r) the nearest pixel of a point (c = floor(x + 0.5),
// r = floor(y + 0.5)) and the block (bc, br) = (floor(c / block_px), floor(r / block_px)),
// points in blocks with (bc + br) even go to `gcp_indices`, odd to `score_indices` — a
// checkerboard of block_px × block_px squares whose top-left square (0, 0) is a GCP square.
// Indices refer to the input vector and are ascending.
struct LidarSplit {
  std::vector<int> gcp_indices;
  std::vector<int> score_indices;
};

// Throws ConfigError (key eval.lidar.block_px) unless block_px >= 1.
LidarSplit CheckerboardSplit(const std::vector<Eigen::Vector2d>& pixels, int block_px = 8);

// A reference measurement: pixel and true value in the SAME convention as the evaluated map
// (disparity in px for rectified data, as KITTI scores; depth otherwise).
struct ReferencePoint {
  Eigen::Vector2d pixel;
  double value = 0.0;
};

struct LidarScoreOptions {
  // KITTI 2015 outlier: |e| > bad_abs_px AND |e| > bad_rel * |reference| (paper-independent;
  // Menze & Geiger, CVPR 2015). Range: > 0. YAML: eval.lidar.bad_abs_px.
  double bad_abs_px = 3.0;
  // Range: >= 0. YAML: eval.lidar.bad_rel.
  double bad_rel = 0.05;
  // Second, stricter rate: |e| > bad1_abs_px (absolute only). Range: > 0. YAML:
  // eval.lidar.bad1_abs_px.
  double bad1_abs_px = 1.0;

  void Check() const;
};

// Definitions: the estimate at a point is the map's value at its nearest pixel (as in the split).
//   outside  : the nearest pixel is outside the map — not scored (no estimate exists there);
//   invalid_reference: the reference value is non-finite or <= 0 — not scored;
//   counted  : all other points;
//   missing  : counted points whose estimate is non-finite or <= 0 — bad in both rates;
//   bad3 / bad1: as in LidarScoreOptions, percent of counted (0 when counted = 0);
//   mean_abs_error / rms_error: over counted points with a valid estimate (map units).
struct LidarScore {
  std::int64_t counted = 0;
  std::int64_t outside = 0;
  std::int64_t invalid_reference = 0;
  std::int64_t missing = 0;
  std::int64_t bad3_count = 0;
  std::int64_t bad1_count = 0;
  double bad3_percent = 0.0;
  double bad1_percent = 0.0;
  double mean_abs_error = 0.0;
  double rms_error = 0.0;

  nlohmann::json ToJson() const;
};

// `map`: CV_32F disparity or depth (non-finite = no estimate). Throws Error on a wrong type.
LidarScore EvaluateAgainstPoints(const cv::Mat& map, const std::vector<ReferencePoint>& points,
                                 const LidarScoreOptions& options = {});

// Scale-free score of a DEPTH map against reference depths (eval.sfm_holdout: the held-out points
// of a structure-from-motion model, whose unit is arbitrary). Same nearest-pixel estimate and
// outside / invalid_reference / counted / missing definitions as LidarScore; per counted point the
// relative error r = |estimate − reference| / reference, a missing estimate counting as r = ∞:
//   above_percent[i]: percent of counted points with r > thresholds[i] (0 when counted = 0);
//   median_percent:   100 · the median of r over the counted points (∞ → null in JSON;
//                     NaN when counted = 0).
struct RelativeDepthScore {
  std::vector<double> thresholds;  // fractions, e.g. 0.01 for 1 %
  std::int64_t counted = 0;
  std::int64_t outside = 0;
  std::int64_t invalid_reference = 0;
  std::int64_t missing = 0;
  std::vector<double> above_percent;
  double median_percent = 0.0;

  nlohmann::json ToJson() const;
};

// `depth`: CV_32F (non-finite or <= 0 = no estimate). Throws Error on a wrong type and
// ConfigError for a threshold that is not positive.
RelativeDepthScore EvaluateRelativeDepth(const cv::Mat& depth,
                                         const std::vector<ReferencePoint>& points,
                                         const std::vector<double>& thresholds = {0.01, 0.02,
                                                                                  0.05});

// The reference points on the darkened reference image, coloured by the same definitions: green
// |e| <= bad1_abs_px, yellow bad-1 only, red bad-3, magenta no estimate (outside / invalid
// reference points are not drawn). image_bgr: CV_8UC3 of the map's size. Throws Error otherwise.
cv::Mat RenderPointErrors(const cv::Mat& image_bgr, const cv::Mat& map,
                          const std::vector<ReferencePoint>& points,
                          const LidarScoreOptions& options = {});

}  // namespace gcpstereo::eval
