// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The stages of `gcpstereo run`, each a function from in-memory inputs to results plus a JSON
// summary for report.json. Only run.cc touches the output folder.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/labels.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/eval/lidar.h"
#include "gcpstereo/gcp/sfm_gcps.h"
#include "gcpstereo/pipeline/pipeline_config.h"

namespace gcpstereo::pipeline::internal {

// The neighbour used with the reference as a rectified pair (Birchfield–Tomasi cost, stereo GCPs):
// the first neighbour. `numerator` = f · (C_neighbour.x − C_reference.x): its pair disparity is
// numerator / depth (a reference pixel x matches x − d in the neighbour). Throws ConfigError when
// the data set is not rectified or has no neighbour, or that neighbour is left of the reference.
struct RectifiedPair {
  const View* neighbor = nullptr;
  double numerator = 0.0;
};
RectifiedPair FindRectifiedPair(const Dataset& dataset, const std::string& purpose);

struct GcpStageResult {
  GcpSet gcps;                                      // merged and downsampled
  nlohmann::json report;                            // per-source counts, density
  std::vector<eval::ReferencePoint> lidar_holdout;  // disparity/depth reference values of the
                                                    // held-out scan points (eval.lidar_holdout)
  bool holdout_in_disparity = false;                // values are disparities (rectified data)
  int lidar_holdout_not_visible = 0;  // held-out points failing the visibility test: not scored
  std::vector<eval::ReferencePoint> sfm_holdout;  // depths of the held-out SfM points
                                                  // (eval.sfm_holdout)
};
// The label space stereo GCPs search, given the GCPs of the other sources (empty when there are
// none): an automatic range then comes from those GCPs instead of the views' overlap.
using ProvisionalLabels = std::function<LabelSpace(const GcpSet& other_gcps)>;
// Builds the GCPs of every configured source; stereo comes last so that its search range can use
// the other sources' GCPs. The report lists the sources in the configuration's order.
GcpStageResult RunGcpStage(const PipelineConfig& config, const Dataset& dataset,
                           const ProvisionalLabels& provisional_labels);

// eval.sfm_holdout: the COLMAP model's points that the reference observes, projected into
// `reference` and split by eval::CheckerboardSplit(eval.holdout_block_px): the points of the GCP
// squares (for the sfm source; with gcp.sfm.projected also every point the reference does not
// observe, wherever it projects) and the depths of the scoring squares' observed points. Points
// behind the camera or outside the image are in neither part.
struct SfmHoldout {
  std::vector<gcp::SfmPoint> gcp_part;
  std::vector<eval::ReferencePoint> scored;
};
SfmHoldout SplitSfmPointsForHoldout(const PipelineConfig& config, const std::string& reference_name,
                                    const Camera& reference);

// Continuous labels of the GCPs on the reference grid (NaN elsewhere), for propagation.
cv::Mat SparseGcpLabels(const GcpSet& gcps, const LabelSpace& labels, cv::Size size);
// Disparities of the GCPs on the reference grid, numerator / depth (NaN elsewhere): the
// ground-truth convention of rectified data sets (Dataset::disparity_numerator).
cv::Mat SparseGcpDisparity(const GcpSet& gcps, double numerator, cv::Size size);

// Converts continuous labels (CV_32F or CV_32S) to depth (CV_32F, +inf where invalid). Labels
// below kLabelZeroSnap count as label 0: a sub-label refinement that ends a rounding error above
// label 0 of a disparity or inverse-depth range starting at 0 would otherwise give depths of
// 10²⁷ m instead of +inf (KITTI frame 10: 63 pixels).
constexpr float kLabelZeroSnap = 1e-3f;
cv::Mat LabelMapToDepth(const cv::Mat& labels, const LabelSpace& space);
// Disparity in the data set's ground-truth convention: the label value itself for disparity
// labels, numerator / depth otherwise (+inf where unknown); labels snapped as above.
cv::Mat LabelMapToDisparity(const cv::Mat& labels, const LabelSpace& space, double numerator);
// The inverse: continuous labels (CV_32F, clamped to the label range; NaN where the disparity is
// not finite or, for depth labels, not positive).
cv::Mat DisparityMapToLabels(const cv::Mat& disparity, const LabelSpace& space, double numerator);

// Evaluation against whatever ground truth the data set carries. `maps` are named depth maps
// ("final", "propagated", …); figures are added to `previews` (name → image).
struct EvaluationInputs {
  std::vector<std::pair<std::string, cv::Mat>> depth_maps;      // first = the result
  std::vector<std::pair<std::string, cv::Mat>> disparity_maps;  // rectified data; same order
  const std::vector<eval::ReferencePoint>* lidar_holdout = nullptr;
  bool holdout_in_disparity = false;
  int holdout_not_visible = 0;  // held-out scan points not scored (not visible from the camera)
  const std::vector<eval::ReferencePoint>* sfm_holdout = nullptr;  // depths (eval.sfm_holdout)
  int border_px = 0;  // ignored border of masks derived from a left-right check
};
nlohmann::json Evaluate(const Dataset& dataset, const EvaluationInputs& inputs,
                        std::vector<std::pair<std::string, cv::Mat>>* previews);

// The picture of the GCPs over the reference image (colour per source).
cv::Mat RenderGcpOverlay(const cv::Mat& image_bgr, const GcpSet& gcps);

// index.html of the output folder: the previews and the metrics table.
std::string MakeIndexHtml(const nlohmann::json& report, const std::vector<std::string>& images);

// A few lines for the terminal at the end of a run.
std::string TerminalSummary(const nlohmann::json& report);

}  // namespace gcpstereo::pipeline::internal
