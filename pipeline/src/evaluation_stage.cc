// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Stage 6b: evaluation against the ground truth a data set carries (dense depth + laser sigma,
// Middlebury disparities and masks, or held-out LiDAR points), with the figures a person reads.

#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/logging.h"
#include "gcpstereo/eval/json.h"
#include "stages.h"

namespace gcpstereo::pipeline::internal {

using nlohmann::json;

json Evaluate(const Dataset& dataset, const EvaluationInputs& inputs,
              std::vector<std::pair<std::string, cv::Mat>>* previews) {
  json metrics = json::object();
  const GroundTruth& gt = dataset.ground_truth;

  if (gt.HasDepth() && !gt.sigma.empty() && !inputs.depth_maps.empty()) {
    std::vector<eval::NamedHistogram> series;
    json& out = metrics["depth_sigma"];
    for (const auto& [name, depth] : inputs.depth_maps) {
      const eval::SigmaHistogram h = eval::EvaluateDepthSigma(depth, gt.depth, gt.sigma);
      out[name] = h.ToJson();
      series.push_back({name, h});
    }
    previews->emplace_back("sigma_histogram.png", eval::RenderSigmaHistogram(series));
    previews->emplace_back(
        "error_sigma.png",
        eval::RenderDepthErrorMap(inputs.depth_maps.front().second, gt.depth, gt.sigma));
  }

  if (gt.HasDisparity() && !inputs.disparity_maps.empty()) {
    eval::MiddleburyMasks masks;
    std::string mask_source;
    if (!gt.mask_nonocc.empty() || !gt.mask_all.empty() || !gt.mask_disc.empty()) {
      masks.nonocc = gt.mask_nonocc;
      masks.all = gt.mask_all;
      masks.disc = gt.mask_disc;
      mask_source = "files";
    } else if (!gt.disparity_right.empty()) {
      eval::DeriveMasksOptions derive;
      derive.border_px = inputs.border_px;
      masks = eval::DeriveMasks(gt.disparity, gt.disparity_right, derive);
      mask_source = "derived from a left-right check of the two ground-truth maps";
    } else {
      masks.all = cv::Mat(gt.disparity.size(), CV_8U, cv::Scalar(255));
      mask_source = "none (all pixels with ground truth)";
    }
    json& out = metrics["middlebury"];
    out["masks"] = mask_source;
    for (const auto& [name, disparity] : inputs.disparity_maps) {
      out[name] = eval::EvaluateDisparity(disparity, gt.disparity, masks).ToJson();
    }
    const cv::Mat& region = !masks.nonocc.empty() ? masks.nonocc : masks.all;
    previews->emplace_back("error_disparity.png",
                           eval::RenderDisparityErrorMap(inputs.disparity_maps.front().second,
                                                         gt.disparity, region, 1.0));
  }

  if (inputs.lidar_holdout && !inputs.lidar_holdout->empty()) {
    const auto& maps = inputs.holdout_in_disparity ? inputs.disparity_maps : inputs.depth_maps;
    json& out = metrics["lidar_holdout"];
    out["unit"] = inputs.holdout_in_disparity ? "disparity px" : "depth";
    out["split"] =
        "checkerboard of eval.holdout_block_px blocks: half of the scan feeds the GCPs, "
        "the other half is scored";
    out["not_visible_not_scored"] = inputs.holdout_not_visible;
    for (const auto& [name, map] : maps) {
      out[name] = eval::EvaluateAgainstPoints(map, *inputs.lidar_holdout).ToJson();
    }
    if (!maps.empty()) {
      previews->emplace_back("error_holdout.png",
                             eval::RenderPointErrors(dataset.reference.image, maps.front().second,
                                                     *inputs.lidar_holdout));
    }
  }
  if (inputs.sfm_holdout && !inputs.sfm_holdout->empty()) {
    json& out = metrics["sfm_holdout"];
    out["unit"] = "relative depth";
    out["split"] =
        "checkerboard of eval.holdout_block_px blocks over the structure-from-motion points the "
        "reference observes: one half may feed the sfm GCPs, the other half is scored";
    for (const auto& [name, map] : inputs.depth_maps) {
      out[name] = eval::EvaluateRelativeDepth(map, *inputs.sfm_holdout).ToJson();
    }
  }
  return metrics;
}

cv::Mat RenderGcpOverlay(const cv::Mat& image_bgr, const GcpSet& gcps) {
  cv::Mat grey, out;
  cv::cvtColor(image_bgr, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
  const int radius = std::max(1, image_bgr.cols / 400);
  for (const Gcp& g : gcps.points) {
    cv::Scalar color;
    switch (g.source) {
      case GcpSource::kLidar:
        color = cv::Scalar(0, 0, 255);
        break;  // red
      case GcpSource::kDepthMap:
        color = cv::Scalar(0, 200, 0);
        break;  // green
      case GcpSource::kStereo:
        color = cv::Scalar(255, 128, 0);
        break;  // blue
      case GcpSource::kSfm:
        color = cv::Scalar(255, 0, 255);
        break;  // magenta
    }
    cv::circle(out, cv::Point(g.col, g.row), radius, color, cv::FILLED, cv::LINE_AA);
  }
  return out;
}

}  // namespace gcpstereo::pipeline::internal
