// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// `gcpstereo run`: load → GCPs → labels → propagation (D̂) → cost + graph cuts per tile →
// depth/disparity → mesh → evaluation → outputs (../shared/CONTRACT.md). The stages are in
// view_stages.h; this file calls them in order and is the only one that writes the outputs.
#include "gcpstereo/pipeline/run.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "colmap_export.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/mesh_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/io/preview.h"
#include "gcpstereo/mesh/meshing.h"
#include "gcpstereo/pipeline/memory_estimate.h"
#include "gcpstereo/pipeline/output_folder.h"
#include "gcpstereo/pipeline/scene.h"
#include "scene_internal.h"
#include "stage_clock.h"
#include "thread_limit.h"
#include "view_run.h"
#include "view_stages.h"

namespace gcpstereo::pipeline {
namespace internal {
namespace {

using nlohmann::json;
using NamedImages = std::vector<std::pair<std::string, cv::Mat>>;

void WriteText(const std::string& path, const std::string& text) {
  io::WriteBytesAtomically(path, text.data(), text.size());
}

// Depth preview with a range shared by every depth picture of the run.
cv::Mat DepthPreview(const cv::Mat& depth, double lo, double hi) {
  return io::RenderDepthPreview(depth, lo, hi, "m");
}

// Writes D̂'s maps (when there is a D̂) and the GCPs.
void WritePriorAndGcps(OutputFolder& out, const DepthMaps& propagated, const GcpSet& gcps,
                       const Camera& camera) {
  if (!propagated.depth.empty()) io::WritePfm(out.Path("propagated_depth.pfm"), propagated.depth);
  if (!propagated.disparity.empty()) {
    io::WritePfm(out.Path("propagated_disparity.pfm"), propagated.disparity);
  }
  io::WriteGcpsPly(out.Path("gcps.ply"), gcps, camera);
}

// Writes mesh.obj (with vertex normals) and returns the seconds it took: run in the background,
// it overlaps the evaluation and the other outputs (a few seconds for the 3 M faces of a
// fountain-size map).
double WriteMeshObj(const std::string& path, const TriangleMesh* triangles) {
  Timer timer;
  io::WriteMeshObj(path, *triangles, mesh::VertexNormals(*triangles));
  return timer.ElapsedSeconds();
}

// Writes mesh.ply (output.mesh) and points.ply (output.points); the mesh's picture is added to
// `previews` (output.previews).
void WriteMeshOutputs(OutputFolder& out, const PipelineConfig& options, const View& reference,
                      const TriangleMesh& triangles, const cv::Mat& depth, NamedImages* previews) {
  if (options.output.mesh) {
    io::WriteMeshPly(out.Path("mesh.ply"), triangles);
    if (options.output.previews && !triangles.faces.empty()) {
      previews->emplace_back("mesh.png", RenderMeshPicture(options, reference, triangles));
    }
  }
  if (options.output.points) {
    io::WriteMeshPly(out.Path("points.ply"),
                     mesh::ColoredPointsFromDepthMap(depth, reference.image, reference.camera,
                                                     options.mesh.meshing.stride_px));
  }
}

// Writes the previews (when output.previews is on): the result's depth (if any), D̂, the GCPs,
// the ground truth, then `more` in order (empty images skipped); returns the names written.
std::vector<std::string> WritePreviews(OutputFolder& out, const PipelineConfig& options,
                                       const Dataset& dataset, const LabelSpace& labels,
                                       const GcpSet& gcps, const cv::Mat& depth,
                                       const cv::Mat& prior_depth, const NamedImages& more) {
  std::vector<std::string> images;
  if (!options.output.previews) return images;
  double lo = labels.DepthOfLabel(0), hi = labels.DepthOfLabel(labels.count() - 1);
  if (lo > hi) std::swap(lo, hi);
  if (!std::isfinite(hi)) io::RobustValueRange(depth.empty() ? prior_depth : depth, &lo, &hi);
  auto add = [&](const std::string& name, const cv::Mat& image) {
    if (image.empty()) return;
    io::WritePng(out.Path(name), image);
    images.push_back(name);
  };
  if (!depth.empty()) add("depth.png", DepthPreview(depth, lo, hi));
  if (!prior_depth.empty()) add("propagated.png", DepthPreview(prior_depth, lo, hi));
  add("gcps.png", RenderGcpOverlay(dataset.reference.image, gcps));
  if (dataset.ground_truth.HasDepth()) {
    add("ground_truth.png", DepthPreview(dataset.ground_truth.depth, lo, hi));
  }
  for (const auto& [name, image] : more) add(name, image);
  return images;
}

// Writes the report, index.html and the effective configuration and moves every output into
// place.
RunSummary Finish(const LoadedConfig& config, OutputFolder& out, const Timer& total, json* report,
                  const std::vector<std::string>& images) {
  (*report)["peak_memory_bytes"] = PeakResidentMemoryBytes();
  (*report)["total_seconds"] = total.ElapsedSeconds();
  if (config.options().output.previews && !images.empty()) {
    WriteText(out.Path("index.html"), MakeIndexHtml(*report, images));
  }
  WriteText(out.Path("effective_config.yaml"), config.schema().ToYaml());
  const std::string report_text = report->dump(2) + "\n";
  WriteText(out.Path("report.json"), report_text);
  out.Commit();
  RunSummary summary;
  summary.output_dir = out.final_dir();
  summary.total_seconds = total.ElapsedSeconds();
  summary.peak_memory_bytes = PeakResidentMemoryBytes();
  summary.report_json = report_text;
  summary.terminal_summary = TerminalSummary(*report);
  return summary;
}

// What one view's run writes besides the report (WriteViewOutputs).
struct ViewOutputs {
  const DepthMaps& result;      // empty when the run stopped after the propagation
  const DepthMaps& propagated;  // D̂; empty without GCPs
  const GcpSet& gcps;
  const MeshResult& mesh;
  const NamedImages& stage_previews;       // left-right check, plane fit
  const NamedImages& evaluation_previews;  // after the mesh's picture
};

// Writes the maps, D̂ and the GCPs, then (timed as the "mesh" stage) the mesh and point cloud,
// then (the "write" stage) the previews, joining `obj_export` (mesh.obj written in the
// background); returns the names of the previews written.
std::vector<std::string> WriteViewOutputs(OutputFolder& out, json& stages,
                                          const PipelineConfig& options, const Dataset& dataset,
                                          const LabelSpace& labels, const ViewOutputs& outputs,
                                          std::future<double>* obj_export) {
  const View& reference = dataset.reference;
  const cv::Mat& depth = outputs.result.depth;
  if (!depth.empty()) io::WritePfm(out.Path("depth.pfm"), depth);
  if (!outputs.result.disparity.empty()) {
    io::WritePfm(out.Path("disparity.pfm"), outputs.result.disparity);
  }
  WritePriorAndGcps(out, outputs.propagated, outputs.gcps, reference.camera);
  NamedImages previews = outputs.stage_previews;
  if (!depth.empty() && (options.output.mesh || options.output.points)) {
    StageClock clock(&stages, "mesh");
    WriteMeshOutputs(out, options, reference, outputs.mesh.triangles, depth, &previews);
    clock.Done(outputs.mesh.stage_report);
  }
  StageClock write_clock(&stages, "write");
  previews.insert(previews.end(), outputs.evaluation_previews.begin(),
                  outputs.evaluation_previews.end());
  const std::vector<std::string> images = WritePreviews(out, options, dataset, labels, outputs.gcps,
                                                        depth, outputs.propagated.depth, previews);
  json write_report = json::object();
  if (obj_export->valid()) write_report["mesh_obj_export_seconds"] = obj_export->get();
  write_clock.Done(write_report);
  return images;
}

// output.colmap (colmap_export.h): the reference's depth map — D̂ when the run stopped after the
// propagation — with its neighbours' images and cameras as the source images, as a COLMAP
// workspace in colmap/ (staged and committed whole with the other outputs). Timed as the
// "colmap_export" stage; returns report.json's "colmap".
json WriteColmapOutput(OutputFolder& out, json& stages, const PipelineConfig& options,
                       const Dataset& dataset, const DepthMaps& result,
                       const DepthMaps& propagated) {
  const bool own = !result.depth.empty();
  const cv::Mat& depth = own ? result.depth : propagated.depth;
  if (depth.empty()) return nullptr;
  StageClock clock(&stages, "colmap_export");
  std::vector<ColmapExportView> views = {
      {dataset.reference.name, dataset.reference.camera, dataset.reference.image, depth, {}}};
  for (const View& neighbor : dataset.neighbors) {
    views.front().sources.push_back(neighbor.name);
    views.push_back({neighbor.name, neighbor.camera, neighbor.image, cv::Mat(), {}});
  }
  json summary = WriteColmapWorkspace(out.Path("colmap"), views, ColmapExportOptionsOf(options));
  summary["depth"] = own ? "depth.pfm" : "propagated_depth.pfm";
  clock.Done(summary);
  return summary;
}

// The label map after the optimisation and the stages that refine it.
struct OptimizedLabels {
  cv::Mat labels;
  NamedImages previews;  // left_right_check.png, plane_fit.png (empty when not run)
};

// 4–5c. The prior of the GCP energy, matching costs and global optimisation tile by tile (memory
// follows the tile), then the left-right check and the plane fit, each refining the label map of
// the one before.
OptimizedLabels OptimizeLabels(json& stages, const PipelineConfig& options, const LoadResult& load,
                               const LabelSpace& labels, const GcpSet& gcps,
                               const cv::Mat& propagated, const PairLabels& pair,
                               std::future<PartnerSolve> partner) {
  const Dataset& dataset = load.dataset;
  const EnergyPrior prior = EnergyPriorStage(options, dataset.reference, gcps, labels, propagated);
  const OptimizeInputs inputs{options, dataset, load.cost_method, labels, gcps, prior, pair};
  OptimizeResult optimized =
      Timed(stages, "cost_and_optimization", [&] { return OptimizeStage(inputs); });
  optimized.partner = std::move(partner);
  OptimizedLabels result{optimized.optimized.labels, {}};
  LeftRightCheckResult left_right;
  if (options.optimizer.left_right_check) {
    left_right = Timed(stages, "left_right_check", [&] {
      return LeftRightCheckStage(options, dataset, labels, gcps, pair, optimized);
    });
    result.labels = left_right.labels;
  }
  PlaneFitResult plane_fit;
  if (options.optimizer.plane_fit) {
    plane_fit = Timed(stages, "plane_fit", [&] {
      return PlaneFitStage(options, dataset, labels, result.labels, left_right);
    });
    result.labels = plane_fit.labels;
  }
  result.previews = {{"gcp_weight.png", GcpWeightPreview(prior, dataset.reference.image)},
                     {"left_right_check.png", left_right.preview},
                     {"plane_fit.png", plane_fit.preview}};
  return result;
}

}  // namespace

RunSummary RunViewInFolder(const LoadedConfig& config, OutputFolder& out,
                           const std::string& config_path) {
  const PipelineConfig& options = config.options();
  const std::string& stop_after = options.runtime.stop_after;
  Timer total;
  json report;
  report["gcpstereo_version"] = GCPSTEREO_VERSION;
  report["config"] = config_path;
  json& stages = report["stages"];
  stages = json::object();

  // 1. Load the data set (the GCP sources' files are checked first: a wrong path stops at once).
  CheckGcpInputFilesExist(options);
  const LoadResult load = Timed(stages, "load", [&] { return LoadStage(options); });
  const Dataset& dataset = load.dataset;
  const View& reference = dataset.reference;
  report["dataset"] = load.dataset_report;
  if (!load.alignment_report.is_null()) report["alignment"] = load.alignment_report;
  if (!config.neighbor_selection().is_null()) {
    report["dataset"]["neighbor_selection"] = config.neighbor_selection();
  }
  if (stop_after == "load") {
    // The range data named by the configuration is read too, so that it is validated.
    if (json lidar = LidarInputReport(options); !lidar.is_null()) report["lidar"] = lidar;
    return Finish(config, out, total, &report, {});
  }

  // 2. Ground control points, then the labels (from the configuration, the GCPs or the views).
  const GcpsResult gcp_stage = Timed(stages, "gcps", [&] { return GcpsStage(options, dataset); });
  const GcpSet& gcps = gcp_stage.gcp.gcps;
  const LabelsResult label_stage = LabelsStage(options, dataset, gcp_stage);
  const LabelSpace& labels = label_stage.labels;
  report["gcps"] = gcp_stage.gcp.report;
  if (!label_stage.gcp_outliers.is_null()) report["gcps"]["outliers"] = label_stage.gcp_outliers;
  report["labels"] = label_stage.report;
  if (stop_after == "gcps") {
    io::WriteGcpsPly(out.Path("gcps.ply"), gcps, reference.camera);
    return Finish(config, out, total, &report, {});
  }

  // The peak memory, estimated before D̂'s system, the cost volumes and the graphs are allocated:
  // a view larger than the machine (or runtime.max_memory_gb) is refused here, not killed later.
  ViewMemoryInput memory_input =
      ViewMemoryInputOf(options, reference.image.cols, reference.image.rows, labels.count(),
                        static_cast<int>(dataset.neighbors.size()));
  ReleaseFreedHeapMemory();
  memory_input.resident_bytes = ResidentMemoryBytes();
  const MemoryEstimate memory = EstimateViewMemory(memory_input);
  report["memory_estimate"] = memory.ToJson();
  spdlog::info("memory: estimated peak {:.0f} MB", memory.total_bytes() / 1e6);
  CheckMemoryBudget(memory, options.runtime.max_memory_gb);

  // 4b. With the left-right check, the neighbour's own solve starts now and runs alongside D̂ and
  // the reference's solve (it needs neither).
  const PairLabels pair = PairLabelsOf(dataset, labels, load.cost_method);
  const PartnerInputs partner_inputs{options, dataset, labels, gcps, pair};
  std::future<PartnerSolve> partner;
  if (stop_after != "propagation" && options.optimizer.left_right_check) {
    partner = StartPartnerSolve(partner_inputs);
  }

  // 3. Adaptive propagation of the GCPs (eq. 5): D̂, the prior of the GCP energy. In the data
  // set's units it is an output of every run with GCPs, and the product of one stopped here
  // (LiDAR depth completion without stereo).
  PropagationStageResult propagation;
  if (!gcps.empty()) {
    propagation = Timed(stages, "propagation",
                        [&] { return PropagationStage(options, reference, gcps, labels); });
  }
  const DepthMaps propagated = ToDepthMaps(propagation.prior, labels, dataset);

  // 4–6. Costs and optimisation, then the depth (and disparity) maps and the mesh, whose OBJ
  // export runs in the background while the evaluation, the previews and the other files are
  // produced (joined, and any error rethrown, before the outputs move).
  OptimizedLabels optimized;
  DepthMaps result;
  MeshResult mesh;
  std::future<double> obj_export;
  if (stop_after != "propagation") {
    optimized = OptimizeLabels(stages, options, load, labels, gcps, propagation.prior, pair,
                               std::move(partner));
    result = DepthMapsStage(optimized.labels, labels, dataset);
    mesh = MeshStage(options, reference, result.depth);
    if (options.output.mesh) {
      obj_export =
          std::async(std::launch::async, WriteMeshObj, out.Path("mesh.obj"), &mesh.triangles);
    }
  }

  // 7. Evaluation against whatever ground truth the data set carries.
  const EvaluationResult evaluation = Timed(stages, "evaluation", [&] {
    return EvaluationStage(dataset, gcp_stage.gcp, result, propagated);
  });
  report["metrics"] = evaluation.metrics;

  // 8. Outputs, staged and moved into place at the end.
  const std::vector<std::string> images = WriteViewOutputs(
      out, stages, options, dataset, labels,
      {result, propagated, gcps, mesh, optimized.previews, evaluation.previews}, &obj_export);
  if (options.output.colmap) {
    json colmap = WriteColmapOutput(out, stages, options, dataset, result, propagated);
    if (!colmap.is_null()) report["colmap"] = std::move(colmap);
  }
  return Finish(config, out, total, &report, images);
}

}  // namespace internal

RunSummary RunPipeline(const LoadedConfig& config, const std::string& output_dir,
                       const std::string& config_path) {
  // A whole scene composes this per-view run (scene.cc); neighbours chosen automatically become
  // the configuration's list before the view runs.
  if (config.options().dataset.IsScene()) return RunScene(config, output_dir);
  if (config.options().dataset.AutoNeighbors()) {
    const std::unique_ptr<LoadedConfig> chosen = ConfigWithChosenNeighbors(config);
    return RunPipeline(*chosen, output_dir, config_path);
  }
  const ScopedThreadLimit thread_limit(config.options().runtime.threads);
  OutputFolder out(output_dir);
  const ScopedLogFile log_file(out.FinalPath("run.log"));
  try {
    return internal::RunViewInFolder(config, out, config_path);
  } catch (const std::exception& e) {
    // The error ends the run: run.log says so too (stderr has it from the caller).
    LogToFilesOnly("run failed: " + std::string(e.what()));
    throw;
  }
}

}  // namespace gcpstereo::pipeline
