// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/evaluate.h"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/eval/json.h"
#include "gcpstereo/gcp/lidar_holdout.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/camera_io.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/mesh_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/pipeline/lidar_scan.h"
#include "gcpstereo/pipeline/pipeline_config.h"
#include "model_alignment.h"
#include "stages.h"

namespace fs = std::filesystem;

namespace gcpstereo::pipeline {
namespace {

using nlohmann::json;

// A single-channel float map from PFM, or an integer image divided by `scale` (0 = unknown).
// Ground truth (`zero_is_unknown`): 0, negative and NaN mean unknown; an estimate keeps 0 (a
// disparity of 0 is a valid estimate) and only non-finite values mean "no estimate".
cv::Mat ReadMap(const std::string& path, double scale, bool zero_is_unknown) {
  const std::string ext = fs::path(path).extension().string();
  cv::Mat map;
  if (ext == ".pfm" || ext == ".PFM") {
    map = io::ReadPfm(path);
    if (map.channels() != 1) throw IoError(path, "expected a single-channel PFM");
  } else {
    const cv::Mat raw = io::ReadImage(path, cv::IMREAD_UNCHANGED);
    if (raw.channels() != 1) throw IoError(path, "expected a single-channel image");
    raw.convertTo(map, CV_32F, 1.0 / scale);
    map.setTo(kInvalidDepth, raw == 0);
  }
  if (zero_is_unknown) {
    map.setTo(kInvalidDepth, ~(map > 0));
  } else {
    map.setTo(kInvalidDepth, map != map);  // NaN
  }
  return map;
}

cv::Mat ReadMask(const std::string& path, cv::Size size) {
  if (path.empty()) return {};
  cv::Mat mask = io::ReadImage(path, cv::IMREAD_GRAYSCALE);
  if (mask.size() != size) throw IoError(path, "mask size differs from the ground truth's");
  return mask;
}

void RequireSameSize(const cv::Mat& a, const std::string& a_name, const cv::Mat& b,
                     const std::string& b_name) {
  if (a.size() != b.size()) {
    throw Error(a_name + " is " + std::to_string(a.cols) + "x" + std::to_string(a.rows) + " but " +
                b_name + " is " + std::to_string(b.cols) + "x" + std::to_string(b.rows));
  }
}

// The --camera of a depth map, at the map's size. A camera of the full-size image serves a map
// computed at a fraction of it (dataset.scale): it is scaled by the width ratio. The height this
// predicts may differ from the map's by less than a pixel (however the map's size was rounded);
// the camera then takes the map's height. A pixel or more is another aspect ratio: the camera is
// of another image, and the ground truth rendered through it would not be the map's view.
Camera CameraOfMap(const std::string& camera_path, const cv::Mat& map,
                   const std::string& map_path) {
  const Camera camera = io::ReadStrechaCamera(camera_path);
  if (camera.width == map.cols && camera.height == map.rows) return camera;
  const double scale = static_cast<double>(map.cols) / camera.width;
  const double predicted_rows = camera.height * scale;
  if (!(std::abs(predicted_rows - map.rows) < 1.0)) {
    throw Error("eval: --camera " + camera_path + " is " + std::to_string(camera.width) + "x" +
                std::to_string(camera.height) + " and the depth map " + map_path + " " +
                std::to_string(map.cols) + "x" + std::to_string(map.rows) +
                ": another aspect ratio (scaled to the map's width, x" + FormatNumber(scale) +
                ", the camera is " + FormatNumber(predicted_rows) + " px high, not " +
                std::to_string(map.rows) + "); the camera is of another image");
  }
  Camera scaled = camera.Rescaled(scale);
  scaled.width = map.cols;
  scaled.height = map.rows;
  return scaled;
}

// The largest "counted" anywhere in a metrics object (-1 when none is there).
long long MostCounted(const nlohmann::json& j) {
  long long most = -1;
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "counted" && it.value().is_number()) {
        most = std::max(most, it.value().get<long long>());
      } else {
        most = std::max(most, MostCounted(it.value()));
      }
    }
  } else if (j.is_array()) {
    for (const auto& v : j) most = std::max(most, MostCounted(v));
  }
  return most;
}

}  // namespace

std::string RunEvaluation(const EvalRequest& r) {
  const int estimates = !r.run_folder.empty() + !r.depth.empty() + !r.disparity.empty();
  if (estimates != 1) {
    throw ConfigError("eval: give exactly one of --run, --depth, --disparity");
  }
  Dataset dataset;  // only its ground truth is used
  internal::EvaluationInputs inputs;
  std::vector<eval::ReferencePoint> held_out;      // eval.lidar_holdout runs: the scored points
  std::vector<eval::ReferencePoint> sfm_held_out;  // eval.sfm_holdout runs: the scored points
  json report;

  if (!r.run_folder.empty()) {
    const std::string config_path = (fs::path(r.run_folder) / "effective_config.yaml").string();
    if (!fs::exists(config_path)) {
      throw IoError(r.run_folder, "not a finished gcpstereo run (no effective_config.yaml)");
    }
    LoadedConfig config;
    config.Load(config_path, {});
    const PipelineConfig& o = config.options();
    io::DatasetRequest request{o.dataset.format, o.dataset.path, o.dataset.reference,
                               o.dataset.neighbors, o.dataset.scale};
    // The cameras in the frame the run worked in (dataset.align).
    request.world_from_model = internal::ModelAlignmentOf(o).world_from_model;
    dataset = io::LoadDataset(request);
    // The result and D̂, as far as the run wrote them (a run stopped after the propagation has
    // only D̂).
    struct RunMap {
      const char* name;
      const char* file_prefix;
    };
    for (const RunMap map : {RunMap{"result", ""}, RunMap{"propagated", "propagated_"}}) {
      const fs::path prefix = fs::path(r.run_folder) / map.file_prefix;
      const std::string depth_path = prefix.string() + "depth.pfm";
      if (fs::exists(depth_path)) inputs.depth_maps.emplace_back(map.name, io::ReadPfm(depth_path));
      const std::string disparity_path = prefix.string() + "disparity.pfm";
      if (fs::exists(disparity_path)) {
        inputs.disparity_maps.emplace_back(map.name, io::ReadPfm(disparity_path));
      }
    }
    if (inputs.depth_maps.empty()) {
      throw IoError(r.run_folder, "a run folder without depth.pfm or propagated_depth.pfm");
    }
    // A run scored on held-out LiDAR points: the split is a deterministic function of the scan
    // and the configuration, so it is made again here (as the GCP stage made it).
    if (o.eval.lidar_holdout && !o.gcp.lidar_path.empty()) {
      gcp::LidarHoldout holdout = gcp::SplitScanForHoldout(
          LoadLidarScan(o.gcp.lidar_path, o.dataset.path, o.dataset.reference, o.gcp.lidar_motion),
          dataset.world_from_lidar, dataset.reference.camera, o.gcp.lidar, o.eval.holdout_block_px,
          dataset.rectified ? dataset.disparity_numerator : 0.0);
      held_out = std::move(holdout.scored);
      inputs.lidar_holdout = &held_out;
      inputs.holdout_in_disparity = dataset.rectified;
      inputs.holdout_not_visible = holdout.not_visible;
    }
    if (o.eval.sfm_holdout) {  // likewise a function of the model and the configuration
      sfm_held_out =
          internal::SplitSfmPointsForHoldout(o, dataset.reference.name, dataset.reference.camera)
              .scored;
      inputs.sfm_holdout = &sfm_held_out;
    }
    report["run"] = r.run_folder;
  } else if (!r.depth.empty()) {
    const cv::Mat depth = ReadMap(r.depth, 1.0, false);
    inputs.depth_maps.emplace_back("result", depth);
    GroundTruth& gt = dataset.ground_truth;
    if (!r.gt_depth.empty()) {
      gt.depth = ReadMap(r.gt_depth, 1.0, true);
      RequireSameSize(depth, r.depth, gt.depth, r.gt_depth);
    } else if (!r.gt_mesh.empty() || !r.gt_points.empty()) {
      if (r.camera.empty()) throw ConfigError("eval: --gt-mesh/--gt-points need --camera");
      const Camera camera = CameraOfMap(r.camera, depth, r.depth);
      gt.depth = !r.gt_mesh.empty()
                     ? eval::RenderMeshDepth(io::ReadMeshPly(r.gt_mesh), camera).depth
                     : eval::RenderPointDepth(io::ReadPointCloud(r.gt_points), camera).depth;
    } else {
      throw ConfigError("eval: --depth needs --gt-depth, --gt-mesh or --gt-points");
    }
    if (!r.gt_sigma.empty()) {
      gt.sigma = ReadMap(r.gt_sigma, 1.0, true);
      RequireSameSize(depth, r.depth, gt.sigma, r.gt_sigma);
    } else if (r.sigma > 0.0) {
      gt.sigma = cv::Mat(depth.size(), CV_32F, cv::Scalar(r.sigma));
    } else {
      throw ConfigError("eval: give the laser's sigma (--gt-sigma map or --sigma value)");
    }
  } else {
    if (!(r.gt_scale > 0.0)) {
      throw ConfigError("eval: --gt-scale must be > 0, got " + FormatNumber(r.gt_scale));
    }
    const cv::Mat disparity = ReadMap(r.disparity, 1.0, false);
    inputs.disparity_maps.emplace_back("result", disparity);
    if (r.gt_disparity.empty()) throw ConfigError("eval: --disparity needs --gt-disparity");
    GroundTruth& gt = dataset.ground_truth;
    gt.disparity = ReadMap(r.gt_disparity, r.gt_scale, true);
    RequireSameSize(disparity, r.disparity, gt.disparity, r.gt_disparity);
    if (!r.gt_disparity_right.empty()) {
      gt.disparity_right = ReadMap(r.gt_disparity_right, r.gt_scale, true);
    }
    gt.mask_nonocc = ReadMask(r.mask_nonocc, gt.disparity.size());
    gt.mask_all = ReadMask(r.mask_all, gt.disparity.size());
    gt.mask_disc = ReadMask(r.mask_disc, gt.disparity.size());
    inputs.border_px = r.border_px;
  }

  std::vector<std::pair<std::string, cv::Mat>> figures;
  report["metrics"] = internal::Evaluate(dataset, inputs, &figures);
  if (report["metrics"].empty()) {
    throw Error(r.run_folder.empty()
                    ? "eval: no ground truth to compare with"
                    : "eval: " + r.run_folder +
                          ": no ground truth to compare with (the data set has none and the run "
                          "held out no LiDAR points)");
  }
  // Scores over no pixel at all would read as a perfect result.
  if (MostCounted(report["metrics"]) == 0) {
    throw Error(
        "eval: no pixel has a valid ground truth to score (all zero, non-finite or masked "
        "out; check the ground-truth file and --gt-scale)");
  }
  if (!r.figures.empty()) {
    std::error_code ec;
    fs::create_directories(r.figures, ec);
    if (ec) throw IoError(r.figures, "cannot create the figures folder: " + ec.message());
    for (const auto& [name, image] : figures) {
      io::WritePng((fs::path(r.figures) / name).string(), image);
    }
  }
  const std::string text = report.dump(2) + "\n";
  if (!r.report.empty()) io::WriteBytesAtomically(r.report, text.data(), text.size());
  std::cout << internal::TerminalSummary(report);
  return text;
}

}  // namespace gcpstereo::pipeline
