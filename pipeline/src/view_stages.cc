// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The stages of one view's run around the optimisation: load, GCPs and labels, propagation, depth
// maps, mesh and evaluation (view_stages.h; the optimisation's stages are in optimize_stage.cc).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/gcp/gcp_sources.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/mesh/render.h"
#include "model_alignment.h"
#include "view_stages.h"

namespace gcpstereo::pipeline::internal {
namespace {

using nlohmann::json;

json ViewJson(const View& v) {
  json view = {{"name", v.name}, {"width", v.image.cols}, {"height", v.image.rows}};
  if (!v.source_camera_model.empty()) {
    view["camera_model"] = v.source_camera_model;
    view["undistorted"] = v.undistorted;
  }
  return view;
}

// KITTI raw: gcp.lidar.path is velodyne_points/data/NNNNNNNNNN.bin of one frame, and nothing ties
// it to dataset.reference, so a config edited for another frame (or a --set of one key but not
// the other) would take its GCPs from a scan of another moment of the drive. Warns when the scan's
// file name is a frame number other than the reference's (a warning: the file may have been
// renamed; a name that is not a number is not checked). Returns what report.json records
// (dataset.lidar_scan), null when there is nothing to check.
json WarnOfScanOfAnotherFrame(const PipelineConfig& options) {
  const std::vector<std::string>& sources = options.gcp.sources;
  if (options.dataset.format != "kitti_raw" ||
      std::find(sources.begin(), sources.end(), "lidar") == sources.end()) {
    return nullptr;
  }
  const std::string scan = std::filesystem::path(options.gcp.lidar_path).stem().string();
  const std::string& frame = options.dataset.reference;
  auto is_number = [](const std::string& name) {
    return !name.empty() && std::all_of(name.begin(), name.end(),
                                        [](unsigned char c) { return std::isdigit(c) != 0; });
  };
  if (!is_number(scan) || !is_number(frame)) return nullptr;
  // The same number however many leading zeros (0000000010 = 10).
  auto without_zeros = [](const std::string& digits) {
    const size_t first = digits.find_first_not_of('0');
    return first == std::string::npos ? std::string("0") : digits.substr(first);
  };
  const bool same = without_zeros(scan) == without_zeros(frame);
  if (!same) {
    spdlog::warn(
        "gcp.lidar.path {} is by its name the Velodyne scan of frame {}, but dataset.reference is "
        "frame {}: the LiDAR GCPs come from another moment of the drive (set gcp.lidar.path to "
        "the scan of frame {}, unless the file was renamed)",
        options.gcp.lidar_path, scan, frame, frame);
  }
  return {{"path", options.gcp.lidar_path}, {"frame", scan}, {"same_frame_as_reference", same}};
}

// The configuration's demands on the data set: a neighbour, and for the left-right check and the
// plane fit a rectified pair. Returns the cost method (cost.method, "auto" resolved).
std::string CheckDatasetServesOptions(const PipelineConfig& options, const Dataset& dataset) {
  if (dataset.neighbors.empty()) {
    throw ConfigError("dataset.neighbors: no neighbour view to match the reference against");
  }
  const std::string cost_method =
      options.cost.method != "auto"
          ? options.cost.method
          : (dataset.rectified && dataset.neighbors.size() == 1 ? "birchfield_tomasi"
                                                                : "plane_sweep");
  if (options.optimizer.left_right_check && cost_method != "birchfield_tomasi") {
    throw ConfigError(
        "optimizer.left_right_check = true needs a rectified pair matched with cost.method = "
        "birchfield_tomasi (here: " +
        cost_method + ")");
  }
  if (options.optimizer.plane_fit && !dataset.rectified) {
    throw ConfigError(
        "optimizer.plane_fit = true needs a rectified data set (its planes are fitted in "
        "disparity)");
  }
  if (!options.optimizer.left_right_check && (options.optimizer.left_right_gcp_radius_px > 0 ||
                                              options.optimizer.left_right_median_radius_px > 0)) {
    spdlog::warn(
        "optimizer.left_right_gcp_radius_px and left_right_median_radius_px act on the left-right "
        "check's fill: without optimizer.left_right_check they have no effect");
  }
  if (cost_method == "plane_sweep" && options.cost.plane_sweep.measure != "zncc" &&
      options.cost.plane_sweep.zncc_flat_fallback) {
    spdlog::warn(
        "cost.zncc_flat_fallback acts on the zncc sweep only: with cost.sweep_measure = {} it has "
        "no effect",
        options.cost.plane_sweep.measure);
  }
  return cost_method;
}

// GCPs the labels cannot reach: the range misses the scene (a frequent configuration slip).
// Warns when they are 10 % of the GCPs or more; returns their number.
int WarnOfGcpsOutsideLabels(const GcpSet& gcps, const LabelSpace& labels) {
  int outside = 0;
  for (const Gcp& g : gcps.points) {
    const double l = labels.LabelOfDepth(g.depth);
    if (!(l >= -0.5 && l <= labels.count() - 0.5)) ++outside;
  }
  if (outside > 0 && outside * 10 >= static_cast<int>(gcps.size())) {
    spdlog::warn(
        "{} of the {} GCPs ({:.0f} %) lie outside the label range [{}, {}] ({}): check "
        "labels.min, labels.max and labels.space",
        outside, gcps.size(), 100.0 * outside / gcps.size(), FormatNumber(labels.min()),
        FormatNumber(labels.max()), LabelSpaceKindName(labels.kind()));
  }
  return outside;
}

// GCP quality against the ground truth (the paper's Table 1: outliers = |error| > 1 px, or one
// label step against a depth ground truth); null without GCPs or ground truth.
json GcpOutliers(const GcpSet& gcps, const LabelSpace& labels, const Dataset& dataset) {
  const cv::Size size = dataset.reference.image.size();
  if (!gcps.empty() && dataset.ground_truth.HasDisparity()) {
    const cv::Mat sparse = SparseGcpDisparity(gcps, dataset.disparity_numerator, size);
    const gcp::GcpOutlierStats stats =
        gcp::ComputeOutlierStats(sparse, dataset.ground_truth.disparity, 1.0);
    return {{"definition", "|disparity - gt| > 1 px"},
            {"evaluated", stats.num_evaluated},
            {"outliers", stats.num_outliers},
            {"percent", stats.outlier_percent}};
  }
  if (!gcps.empty() && dataset.ground_truth.HasDepth()) {
    cv::Mat sparse(size, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
    cv::Mat gt_labels(size, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
    int within_3_sigma = 0, with_sigma = 0;
    for (const Gcp& g : gcps.points) {
      sparse.at<float>(g.row, g.col) = static_cast<float>(labels.LabelOfDepth(g.depth));
      const float gt = dataset.ground_truth.depth.at<float>(g.row, g.col);
      if (!IsValidDepth(gt)) continue;
      gt_labels.at<float>(g.row, g.col) = static_cast<float>(labels.LabelOfDepth(gt));
      if (!dataset.ground_truth.sigma.empty()) {
        const float sigma = dataset.ground_truth.sigma.at<float>(g.row, g.col);
        if (std::isfinite(sigma) && sigma > 0) {
          ++with_sigma;
          within_3_sigma += std::abs(g.depth - gt) <= 3.0 * sigma;
        }
      }
    }
    const gcp::GcpOutlierStats stats = gcp::ComputeOutlierStats(sparse, gt_labels, 1.0);
    return {{"definition", "|label - gt label| > 1 label step"},
            {"evaluated", stats.num_evaluated},
            {"outliers", stats.num_outliers},
            {"percent", stats.outlier_percent},
            {"within_3_sigma_percent", with_sigma ? 100.0 * within_3_sigma / with_sigma : 0.0}};
  }
  return nullptr;
}

// Warns when most estimated pixels of `label_map` took the first or last label: the range is
// likely to miss the scene.
void WarnOfLabelsAtTheRangeEnds(const cv::Mat& label_map, const LabelSpace& labels) {
  int at_ends = 0, estimated = 0;
  const float top = static_cast<float>(labels.count() - 1);
  for (int r = 0; r < label_map.rows; ++r) {
    const float* row = label_map.ptr<float>(r);
    for (int c = 0; c < label_map.cols; ++c) {
      if (!std::isfinite(row[c])) continue;
      ++estimated;
      at_ends += (row[c] <= 0.5f || row[c] >= top - 0.5f) ? 1 : 0;
    }
  }
  if (estimated > 0 && at_ends * 2 > estimated) {
    spdlog::warn(
        "{:.0f} % of the pixels took the first or last label of [{}, {}] ({}): the label range "
        "probably misses the scene; check labels.min, labels.max and labels.space",
        100.0 * at_ends / estimated, FormatNumber(labels.min()), FormatNumber(labels.max()),
        LabelSpaceKindName(labels.kind()));
  }
}

}  // namespace

void CheckGcpInputFilesExist(const PipelineConfig& options) {
  const auto& sources = options.gcp.sources;
  auto check = [&](const char* source, const char* key, const std::string& path) {
    std::error_code ec;
    if (std::find(sources.begin(), sources.end(), source) == sources.end() ||
        std::filesystem::is_regular_file(path, ec)) {
      return;
    }
    throw IoError(path, std::string("file not found (") + key +
                            "; a relative path is relative to the working directory)");
  };
  // A `--set dataset.path=…` override does not move the other paths.
  check("lidar", "gcp.lidar.path", options.gcp.lidar_path);
  check("depth_map", "gcp.depth_map.path", options.gcp.depth_map.path);
}

LoadResult LoadStage(const PipelineConfig& options) {
  io::DatasetRequest request;
  request.format = options.dataset.format;
  request.path = options.dataset.path;
  request.reference = options.dataset.reference;
  request.neighbors = options.dataset.neighbors;
  request.scale = options.dataset.scale;
  LoadResult result;
  const ModelAlignment alignment = ModelAlignmentOf(options);
  request.world_from_model = alignment.world_from_model;
  result.alignment_report = alignment.report;
  result.dataset = io::LoadDataset(request);
  const Dataset& dataset = result.dataset;
  const View& reference = dataset.reference;
  json views = json::array();
  for (const auto& n : dataset.neighbors) views.push_back(ViewJson(n));
  result.dataset_report = {{"format", dataset.format},
                           {"path", dataset.path},
                           {"rectified", dataset.rectified},
                           {"reference", ViewJson(reference)},
                           {"neighbors", views},
                           {"num_views", 1 + dataset.neighbors.size()},
                           {"ground_truth",
                            {{"depth", dataset.ground_truth.HasDepth()},
                             {"sigma", !dataset.ground_truth.sigma.empty()},
                             {"disparity", dataset.ground_truth.HasDisparity()}}}};
  spdlog::info("loaded {} views: reference {} ({}x{}) and {} neighbours",
               1 + dataset.neighbors.size(), reference.name, reference.image.cols,
               reference.image.rows, dataset.neighbors.size());
  if (json scan = WarnOfScanOfAnotherFrame(options); !scan.is_null()) {
    result.dataset_report["lidar_scan"] = std::move(scan);
  }
  result.cost_method = CheckDatasetServesOptions(options, dataset);
  return result;
}

json LidarInputReport(const PipelineConfig& options) {
  if (options.gcp.lidar_path.empty()) return nullptr;
  return {{"path", options.gcp.lidar_path},
          {"num_points", io::ReadPointCloud(options.gcp.lidar_path).size()}};
}

GcpsResult GcpsStage(const PipelineConfig& options, const Dataset& dataset) {
  GcpsResult result;
  result.kind = ParseLabelSpaceKind(options.labels.space);
  if (result.kind == LabelSpaceKind::kDisparity && !dataset.rectified) {
    throw ConfigError("labels.space = disparity needs rectified data (middlebury, kitti_raw)");
  }
  // Stereo GCPs search the label range before their own GCPs exist: it comes from the
  // configuration, the other sources' GCPs, the pair's matched disparities or the views' overlap
  // then. The views' matched range is computed once for both label spaces (LabelsStage).
  const ProvisionalLabels provisional = [&](const GcpSet& other_gcps) {
    return cost::MakeLabelSpace(result.kind, options.labels.count, options.labels.min,
                                options.labels.max, other_gcps, dataset.reference,
                                dataset.neighbors, dataset.disparity_numerator, dataset.rectified,
                                options.label_range, nullptr, &result.matched_range);
  };
  result.gcp = RunGcpStage(options, dataset, provisional);
  result.stage_report = {{"count", result.gcp.gcps.size()}};
  return result;
}

LabelsResult LabelsStage(const PipelineConfig& options, const Dataset& dataset,
                         const GcpsResult& gcps_result) {
  const GcpSet& gcps = gcps_result.gcp.gcps;
  cost::MatchedDepthRange matched_range = gcps_result.matched_range;
  cost::LabelRangeSummary range_summary;
  LabelsResult result;
  result.labels = cost::MakeLabelSpace(
      gcps_result.kind, options.labels.count, options.labels.min, options.labels.max, gcps,
      dataset.reference, dataset.neighbors, dataset.disparity_numerator, dataset.rectified,
      options.label_range, &range_summary, &matched_range);
  const LabelSpace& labels = result.labels;
  result.report = {{"space", LabelSpaceKindName(labels.kind())},
                   {"count", labels.count()},
                   {"min", labels.min()},
                   {"max", labels.max()},
                   {"step", labels.step()},
                   {"range_source", range_summary.source},
                   {"depth_of_first_label", labels.DepthOfLabel(0)},
                   {"depth_of_last_label", labels.DepthOfLabel(labels.count() - 1)}};
  result.report["gcps_outside_range"] = WarnOfGcpsOutsideLabels(gcps, labels);
  result.gcp_outliers = GcpOutliers(gcps, labels, dataset);
  spdlog::info("labels: {} {} from {} to {} (range from {})", labels.count(),
               LabelSpaceKindName(labels.kind()), labels.min(), labels.max(), range_summary.source);
  return result;
}

propagation::PropagationResult PropagateLabels(const cv::Mat& image_bgr,
                                               const cv::Mat& sparse_labels,
                                               const LabelSpace& labels,
                                               const propagation::PropagationOptions& options) {
  if (options.method != "local_plane" || labels.kind() != LabelSpaceKind::kDepth) {
    return propagation::Propagate(image_bgr, sparse_labels, options);
  }
  cv::Mat inverse_depth = sparse_labels.clone();
  inverse_depth.forEach<float>([&](float& v, const int*) {
    if (std::isfinite(v)) v = static_cast<float>(1.0 / labels.DepthOfLabel(v));
  });
  propagation::PropagationResult result = propagation::Propagate(image_bgr, inverse_depth, options);
  result.values.forEach<float>([&](float& v, const int*) {
    v = std::isfinite(v) && v > 0.0f ? static_cast<float>(labels.LabelOfDepth(1.0 / v))
                                     : std::numeric_limits<float>::quiet_NaN();
  });
  // The GCPs keep their labels exactly, not after a round trip through inverse depth.
  sparse_labels.copyTo(result.values, sparse_labels == sparse_labels);
  return result;
}

PropagationStageResult PropagationStage(const PipelineConfig& options, const View& reference,
                                        const GcpSet& gcps, const LabelSpace& labels) {
  const cv::Size size = reference.image.size();
  const cv::Mat sparse = SparseGcpLabels(gcps, labels, size);
  const propagation::PropagationResult propagated =
      PropagateLabels(reference.image, sparse, labels, options.propagation);
  const double unreached_percent = 100.0 * propagated.num_unreached_pixels / size.area();
  if (propagated.num_unreached_pixels > 0) {
    spdlog::warn("propagation: {} pixels ({:.1f} %) in {} regions no GCP reaches have no prior",
                 propagated.num_unreached_pixels, unreached_percent,
                 propagated.num_unreached_regions);
  }
  PropagationStageResult result;
  result.prior = propagated.values;
  result.stage_report = {{"solver", propagated.solver},
                         {"gcps", propagated.num_gcps},
                         {"unknowns", propagated.num_unknowns},
                         {"unreached_pixels", propagated.num_unreached_pixels},
                         {"unreached_percent", unreached_percent},
                         {"unreached_regions", propagated.num_unreached_regions},
                         {"setup_seconds", propagated.setup_seconds},
                         {"solve_seconds", propagated.solve_seconds},
                         {"residual", propagated.residual}};
  return result;
}

DepthMaps ToDepthMaps(const cv::Mat& label_map, const LabelSpace& labels, const Dataset& dataset) {
  DepthMaps maps;
  if (label_map.empty()) return maps;
  maps.depth = LabelMapToDepth(label_map, labels);
  if (dataset.rectified) {
    maps.disparity = LabelMapToDisparity(label_map, labels, dataset.disparity_numerator);
  }
  return maps;
}

DepthMaps DepthMapsStage(const cv::Mat& label_map, const LabelSpace& labels,
                         const Dataset& dataset) {
  WarnOfLabelsAtTheRangeEnds(label_map, labels);
  return ToDepthMaps(label_map, labels, dataset);
}

MeshResult MeshStage(const PipelineConfig& options, const View& reference, const cv::Mat& depth) {
  MeshResult result;
  if (!options.output.mesh) return result;
  mesh::MeshingSummary meshing;
  result.triangles = mesh::MeshFromDepthMap(depth, reference.image, reference.camera,
                                            options.mesh.meshing, &meshing);
  result.stage_report = {{"vertices", meshing.vertices},
                         {"faces", meshing.faces},
                         {"dropped_invalid", meshing.dropped_invalid},
                         {"dropped_depth_ratio", meshing.dropped_depth_ratio},
                         {"dropped_view_angle", meshing.dropped_view_angle}};
  return result;
}

cv::Mat RenderMeshPicture(const PipelineConfig& options, const View& reference,
                          const TriangleMesh& triangles) {
  if (triangles.faces.empty()) return cv::Mat();
  // Small images are rendered larger so that the picture stays legible.
  const double enlarge = std::max(1.0, 960.0 / reference.camera.width);
  const Camera view =
      mesh::OrbitCamera(reference.camera.Rescaled(enlarge), options.mesh.preview_yaw_deg,
                        options.mesh.preview_pitch_deg, mesh::MedianVertex(triangles));
  return mesh::RenderMeshPreview(triangles, view, options.mesh.preview);
}

EvaluationResult EvaluationStage(const Dataset& dataset, const GcpStageResult& gcps,
                                 const DepthMaps& result, const DepthMaps& propagated) {
  EvaluationInputs inputs;
  if (!result.depth.empty()) inputs.depth_maps.emplace_back("result", result.depth);
  if (!propagated.depth.empty()) inputs.depth_maps.emplace_back("propagated", propagated.depth);
  if (!result.disparity.empty()) inputs.disparity_maps.emplace_back("result", result.disparity);
  if (!propagated.disparity.empty()) {
    inputs.disparity_maps.emplace_back("propagated", propagated.disparity);
  }
  inputs.lidar_holdout = &gcps.lidar_holdout;
  inputs.holdout_in_disparity = gcps.holdout_in_disparity;
  inputs.holdout_not_visible = gcps.lidar_holdout_not_visible;
  inputs.sfm_holdout = &gcps.sfm_holdout;
  EvaluationResult evaluation;
  evaluation.metrics = Evaluate(dataset, inputs, &evaluation.previews);
  return evaluation;
}

}  // namespace gcpstereo::pipeline::internal
