// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The stages of one reference view's run, in the order run.cc calls them: load → GCPs → labels →
// propagation (D̂) → the energy's prior → cost + graph cuts → left-right check → plane fit → depth
// maps → mesh → evaluation. Each is a function from in-memory inputs to a typed result; a timed
// stage's `stage_report` is its entry of report.json's "stages" (StageClock adds the time and
// memory). None of them writes a file: the orchestrator (run.cc) does (STYLE item 2).
#pragma once

#include <future>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/labels.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/cost/label_range.h"
#include "gcpstereo/mesh/meshing.h"
#include "gcpstereo/optimize/plane_fit.h"
#include "gcpstereo/optimize/tiling.h"
#include "gcpstereo/pipeline/pipeline_config.h"
#include "gcpstereo/propagation/propagation.h"
#include "stages.h"

namespace gcpstereo::pipeline::internal {

// 1. The data set, checked against the options that depend on it (cost method, left-right check,
// plane fit), a COLMAP model moved into the scan's frame first when dataset.align asks for it.
// Throws ConfigError when the data set cannot serve the configuration, Error for a refused
// alignment.
struct LoadResult {
  Dataset dataset;
  std::string cost_method;          // cost.method resolved: "birchfield_tomasi" or "plane_sweep"
  nlohmann::json dataset_report;    // report["dataset"]
  nlohmann::json alignment_report;  // report["alignment"] (dataset.align); null without one
  nlohmann::json stage_report = nlohmann::json::object();
};
LoadResult LoadStage(const PipelineConfig& options);

// The GCP sources' input files exist before the data set is loaded: a wrong path stops the run at
// once and names its key.
void CheckGcpInputFilesExist(const PipelineConfig& options);

// What report.json's "lidar" says of the scan gcp.lidar.path names (null without one); reads the
// scan, so that a run stopped after the load still validates it.
nlohmann::json LidarInputReport(const PipelineConfig& options);

// 2. The GCPs of every configured source (RunGcpStage), their label space's kind, and the views'
// matched depth range the stereo GCPs' provisional labels computed (reused by the labels).
struct GcpsResult {
  GcpStageResult gcp;
  LabelSpaceKind kind = LabelSpaceKind::kDepth;
  cost::MatchedDepthRange matched_range;
  nlohmann::json stage_report = nlohmann::json::object();  // {"count"}
};
GcpsResult GcpsStage(const PipelineConfig& options, const Dataset& dataset);

// 2b. The label space of the run (from the configuration, the GCPs or the views) and the GCPs'
// quality against the ground truth the data set carries (the paper's Table 1). Untimed.
struct LabelsResult {
  LabelSpace labels;
  nlohmann::json report;        // report["labels"]
  nlohmann::json gcp_outliers;  // report["gcps"]["outliers"]; null when not evaluated
};
LabelsResult LabelsStage(const PipelineConfig& options, const Dataset& dataset,
                         const GcpsResult& gcps);

// 3. Adaptive propagation of the GCPs (eq. 5): D̂, the prior of the GCP energy, in labels. Run
// only with GCPs.
struct PropagationStageResult {
  cv::Mat prior;  // CV_32F labels, NaN where no GCP reaches; empty when not run
  nlohmann::json stage_report = nlohmann::json::object();
};
PropagationStageResult PropagationStage(const PipelineConfig& options, const View& reference,
                                        const GcpSet& gcps, const LabelSpace& labels);

// D̂ (eq. 5 or another propagation.method) from GCP labels, in labels. The local planes are fitted
// to a quantity affine over a scene plane: depth labels are propagated as inverse depth and
// converted back; inverse-depth and disparity labels already are affine.
propagation::PropagationResult PropagateLabels(const cv::Mat& image_bgr,
                                               const cv::Mat& sparse_labels,
                                               const LabelSpace& labels,
                                               const propagation::PropagationOptions& options);

// A label map in the data set's units: depth, and disparity for rectified data (empty otherwise
// and when `label_map` is empty).
struct DepthMaps {
  cv::Mat depth;      // CV_32F metres, +inf where unknown
  cv::Mat disparity;  // CV_32F, the ground truth's convention
};
DepthMaps ToDepthMaps(const cv::Mat& label_map, const LabelSpace& labels, const Dataset& dataset);

// 4. The prior the GCP energy uses: D̂, optionally only within optimizer.prior_radius_px of a GCP
// and only in the colour segments that hold one (optimizer.prior_segment_k). Untimed.
struct EnergyPrior {
  cv::Mat prior;                // labels, NaN where the GCP energy does not act; empty without D̂
  cv::Mat weight;               // ρ_p of eq. (10) (optimizer.gcp_spread > 0), else empty
  double weight_mean = 1.0;     // mean ρ_p over the pixels where the prior acts
  double pixels_percent = 0.0;  // share of the pixels where it acts
  std::optional<optimize::SegmentationOptions> segmentation;  // prior_segment_k > 0
};
EnergyPrior EnergyPriorStage(const PipelineConfig& options, const View& reference,
                             const GcpSet& gcps, const LabelSpace& labels,
                             const cv::Mat& propagated);

// gcp_weight.png: ρ_p of eq. (10) in grey (white 1, black 0) where the prior acts, the reference
// image dimmed elsewhere; empty without the weights.
cv::Mat GcpWeightPreview(const EnergyPrior& prior, const cv::Mat& image_bgr);

// The rectified pair Birchfield–Tomasi matches (cost method "birchfield_tomasi"; empty
// otherwise): the neighbour and the pair disparity of each label.
struct PairLabels {
  const View* neighbor = nullptr;
  std::vector<double> disparities;
};
PairLabels PairLabelsOf(const Dataset& dataset, const LabelSpace& labels,
                        const std::string& cost_method);

// 4b. The left-right check's second solve (optimizer.left_right_check, rectified pairs): the
// neighbour as reference, on mirrored images, with D̂ of the GCPs it sees as its prior. It needs
// nothing from the reference's D̂ or solve, so it starts before them and runs alongside (D̂'s
// solve and one tile's α-expansion are mostly single-threaded: the two share the cores).
// `seconds` is its wall time from the start. `inputs` must outlive the future.
struct PartnerSolve {
  optimize::TiledResult result;
  double seconds = 0.0;
};
struct PartnerInputs {
  const PipelineConfig& options;
  const Dataset& dataset;
  const LabelSpace& labels;
  const GcpSet& gcps;
  const PairLabels& pair;
};
std::future<PartnerSolve> StartPartnerSolve(const PartnerInputs& inputs);

// 5. Matching costs and global optimisation (or winner-take-all), tile by tile.
struct OptimizeInputs {
  const PipelineConfig& options;
  const Dataset& dataset;
  const std::string& cost_method;
  const LabelSpace& labels;
  const GcpSet& gcps;
  const EnergyPrior& prior;
  const PairLabels& pair;
};
struct OptimizeResult {
  optimize::TiledResult optimized;
  std::future<PartnerSolve> partner;  // StartPartnerSolve's, with optimizer.left_right_check
  nlohmann::json stage_report = nlohmann::json::object();
};
OptimizeResult OptimizeStage(const OptimizeInputs& inputs);

// 5b. Left-right check (optimizer.left_right_check, rectified pairs): pixels whose disparities
// from the two solves disagree are filled from the background side of their row
// (optimize/left_right.h). Waits for the neighbour's solve.
struct LeftRightCheckResult {
  cv::Mat labels;   // the optimised labels, checked and filled
  cv::Mat support;  // for the plane fit: consistent or GCP-confirmed pixels (with plane_fit)
  cv::Mat frozen;   // for the plane fit: pixels occluded in the right view (with plane_fit)
  cv::Mat preview;  // left_right_check.png
  nlohmann::json stage_report = nlohmann::json::object();
};
LeftRightCheckResult LeftRightCheckStage(const PipelineConfig& options, const Dataset& dataset,
                                         const LabelSpace& labels, const GcpSet& gcps,
                                         const PairLabels& pair, OptimizeResult& optimized);

// 5c. Segment planes (optimizer.plane_fit, rectified data): the pixels of a colour segment that
// lie nearer than its robustly fitted disparity plane take the plane's value.
struct PlaneFitResult {
  cv::Mat labels;   // `label_map` with the fitted pixels changed
  cv::Mat preview;  // plane_fit.png
  nlohmann::json stage_report = nlohmann::json::object();
};
PlaneFitResult PlaneFitStage(const PipelineConfig& options, const Dataset& dataset,
                             const LabelSpace& labels, const cv::Mat& label_map,
                             const LeftRightCheckResult& left_right);

// 6. The result's depth (and disparity) maps; warns when the labels sit at the range's ends.
DepthMaps DepthMapsStage(const cv::Mat& label_map, const LabelSpace& labels,
                         const Dataset& dataset);

// 6b. The triangle mesh of the depth map (output.mesh; empty otherwise). Untimed: report.json's
// "mesh" entry, as before this stage was split out, times the mesh's outputs (run.cc).
struct MeshResult {
  TriangleMesh triangles;
  nlohmann::json stage_report = nlohmann::json::object();  // vertices, faces, dropped counts
};
MeshResult MeshStage(const PipelineConfig& options, const View& reference, const cv::Mat& depth);
// The picture of the mesh from an orbit around it (mesh.png): empty without faces.
cv::Mat RenderMeshPicture(const PipelineConfig& options, const View& reference,
                          const TriangleMesh& triangles);

// 7. The result (empty maps when the run stopped before it) and D̂ scored against the data set's
// ground truth (report["metrics"]), with the error previews.
struct EvaluationResult {
  nlohmann::json metrics;
  std::vector<std::pair<std::string, cv::Mat>> previews;
  nlohmann::json stage_report = nlohmann::json::object();
};
EvaluationResult EvaluationStage(const Dataset& dataset, const GcpStageResult& gcps,
                                 const DepthMaps& result, const DepthMaps& propagated);

}  // namespace gcpstereo::pipeline::internal
