// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Whole scenes: per-view runs → fusion → scene mesh → scene evaluation (scene.h). The per-view
// run is RunPipeline itself, one call per reference; this file only composes it with the fusion
// stages, so a view computed here and one computed alone (a cluster job, then `gcpstereo fuse`)
// are the same bytes.
#include "gcpstereo/pipeline/scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "colmap_export.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/cost/view_selection.h"
#include "gcpstereo/eval/depth_sigma.h"
#include "gcpstereo/eval/mesh_accuracy.h"
#include "gcpstereo/eval/render.h"
#include "gcpstereo/fusion/fusion.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/colmap_io.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/mesh_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/mesh/meshing.h"
#include "gcpstereo/mesh/render.h"
#include "gcpstereo/mesh/surface_reconstruction.h"
#include "gcpstereo/pipeline/output_folder.h"
#include "model_alignment.h"
#include "scene_internal.h"
#include "stage_clock.h"
#include "thread_limit.h"

namespace gcpstereo::pipeline {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// A YAML double-quoted scalar: view names such as 0005 stay strings whatever the YAML parser.
std::string Quoted(const std::string& text) {
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

std::string FlowList(const std::vector<std::string>& names) {
  std::string list = "[";
  for (size_t i = 0; i < names.size(); ++i) list += (i ? ", " : "") + Quoted(names[i]);
  return list + "]";
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void WriteText(const std::string& path, const std::string& text) {
  io::WriteBytesAtomically(path, text.data(), text.size());
}

bool HasLidar(const PipelineConfig& o) {
  return std::find(o.gcp.sources.begin(), o.gcp.sources.end(), "lidar") != o.gcp.sources.end();
}

// ---- Per-view runs ---------------------------------------------------------------------------

// The camera of every view of the data set (at dataset.scale), for the view selection.
struct SceneCameras {
  std::vector<std::string> names;
  std::vector<Camera> cameras;
};

SceneCameras LoadSceneCameras(const PipelineConfig& o) {
  SceneCameras scene;
  scene.names = io::ListDatasetViews(o.dataset.format, o.dataset.path);
  for (const std::string& name : scene.names) {
    io::DatasetRequest request;
    request.format = o.dataset.format;
    request.path = o.dataset.path;
    request.reference = name;
    request.scale = o.dataset.scale;
    request.load_neighbors = false;
    request.world_from_model = internal::ModelAlignmentOf(o).world_from_model;
    scene.cameras.push_back(io::LoadDataset(request).reference.camera);
  }
  return scene;
}

// Where the scene is, for the view selection, in the world frame, at most kMaxPoints points
// (every k-th): a COLMAP model's own 3D points (colmap; the reference's visible share of them is
// what the selection scores), else the scan's points (strecha and colmap with a LiDAR source: the
// scan is in the world frame). Empty otherwise (the selection then uses the frustum basis).
std::vector<Eigen::Vector3d> SelectionPoints(const PipelineConfig& o) {
  constexpr size_t kMaxPoints = 20000;
  std::vector<Eigen::Vector3d> points;
  auto every_kth = [&points](size_t size, const auto& point_at) {
    const size_t step = std::max<size_t>(1, (size + kMaxPoints - 1) / kMaxPoints);
    for (size_t i = 0; i < size; i += step) points.push_back(point_at(i));
  };
  if (o.dataset.format == "colmap") {
    const io::ColmapModel model = internal::ReadAlignedColmapModel(o);
    std::vector<Eigen::Vector3d> all;
    for (const auto& [id, point] : model.points3d) all.push_back(point.xyz_world);
    if (!all.empty()) {
      every_kth(all.size(), [&all](size_t i) { return all[i]; });
      return points;
    }
  }
  if (!HasLidar(o) || (o.dataset.format != "strecha" && o.dataset.format != "colmap")) {
    return points;
  }
  const PointCloud cloud = io::ReadPointCloud(o.gcp.lidar_path);
  every_kth(cloud.size(), [&cloud](size_t i) { return cloud.points[i].cast<double>(); });
  return points;
}

struct NeighborChoice {
  std::vector<std::string> names;
  json report;
};

NeighborChoice ChooseNeighbors(const SceneCameras& scene, const std::string& reference,
                               const std::vector<Eigen::Vector3d>& points,
                               const cost::ViewSelectionOptions& options) {
  const auto it = std::find(scene.names.begin(), scene.names.end(), reference);
  if (it == scene.names.end()) {
    throw ConfigError("dataset.reference: no view named " + reference);
  }
  const int index = static_cast<int>(it - scene.names.begin());
  const cost::ViewSelection selection =
      cost::SelectNeighbors(scene.cameras, index, points, options);
  NeighborChoice choice;
  for (int n : selection.neighbors) choice.names.push_back(scene.names[n]);
  if (choice.names.empty()) {
    throw Error("dataset.neighbors = auto: no view shares enough of " + reference +
                "'s scene at a usable triangulation angle (" + selection.basis + " basis)");
  }
  choice.report = selection.ToJson(scene.names);
  spdlog::info("neighbours of {} ({} basis): {}", reference, selection.basis,
               FlowList(choice.names));
  return choice;
}

// The overrides that make the scene's configuration this view's, but for neighbours chosen
// automatically (ViewConfig adds those).
std::vector<std::string> ViewOverrides(const PipelineConfig& o, const std::string& name) {
  std::vector<std::string> overrides = {"dataset.reference=" + Quoted(name)};
  if (!o.dataset.AutoNeighbors() && !o.dataset.neighbors.empty()) {
    // An explicit list serves every reference: each uses the others of the list.
    std::vector<std::string> others;
    for (const std::string& n : o.dataset.neighbors) {
      if (n != name) others.push_back(n);
    }
    overrides.push_back("dataset.neighbors=" + FlowList(others));
  }
  return overrides;
}

// The per-view configuration: the scene's with this reference and its neighbours.
std::unique_ptr<LoadedConfig> ViewConfig(const LoadedConfig& scene_config, const std::string& name,
                                         const SceneCameras* cameras,
                                         const std::vector<Eigen::Vector3d>& points) {
  const PipelineConfig& o = scene_config.options();
  std::vector<std::string> overrides = ViewOverrides(o, name);
  json selection;
  if (o.dataset.AutoNeighbors()) {
    NeighborChoice choice = ChooseNeighbors(*cameras, name, points, o.dataset.neighbor_selection);
    overrides.push_back("dataset.neighbors=" + FlowList(choice.names));
    selection = std::move(choice.report);
  }
  std::unique_ptr<LoadedConfig> config = scene_config.WithOverrides(overrides);
  config->set_neighbor_selection(std::move(selection));
  return config;
}

// A view folder a previous run finished with the same configuration.
bool ViewFolderComplete(const fs::path& dir, const std::string& effective_yaml) {
  // report.json and effective_config.yaml are committed with the other outputs, all at once.
  std::error_code ec;
  if (!fs::is_regular_file(dir / "report.json", ec) ||
      !fs::is_regular_file(dir / "effective_config.yaml", ec)) {
    return false;
  }
  return ReadText(dir / "effective_config.yaml") == effective_yaml;
}

// Why a view folder a scene run did not compute is not complete: the error its own run.log ends
// on (RunPipeline logs "run failed: ..."), if it has one.
std::string MissingViewError(const fs::path& dir) {
  std::string error =
      "not computed by this run (--fuse-only) and no complete folder with this "
      "configuration in " +
      dir.string();
  std::ifstream log(dir / "run.log");
  std::string line, last_failure;
  const std::string marker = "run failed: ";
  while (std::getline(log, line)) {
    const size_t at = line.find(marker);
    if (at != std::string::npos) last_failure = line.substr(at + marker.size());
  }
  if (!last_failure.empty()) error += "; its run.log: " + last_failure;
  return error;
}

// ---- Fusion, meshing, evaluation
// -----------------------------------------------------------------

// A finished view folder, loaded: its view (image, camera and ground truth at the run's scale)
// and its depth map.
struct FinishedView {
  std::string dir;
  std::string name;
  View view;
  GroundTruth ground_truth;
  cv::Mat depth;
  std::vector<std::string> neighbors;  // its run's dataset.neighbors (empty: all other views)
};

// Throws IoError naming the first of `files` missing from `dir`.
void CheckViewFolder(const std::string& dir, const std::vector<std::string>& files) {
  for (const std::string& file : files) {
    std::error_code ec;
    if (!fs::is_regular_file(fs::path(dir) / file, ec)) {
      // A view run with runtime.stop_after: propagation is finished but has D̂ only.
      if (file == "depth.pfm" && fs::is_regular_file(fs::path(dir) / "propagated_depth.pfm", ec)) {
        throw IoError((fs::path(dir) / file).string(),
                      "not found, but propagated_depth.pfm is (a view run with runtime.stop_after: "
                      "propagation? --set fusion.input=propagated fuses that)");
      }
      throw IoError((fs::path(dir) / file).string(),
                    "not found: the folder is not a finished per-view run of gcpstereo");
    }
  }
}

struct SceneIdentity {
  std::string format, path;
  double scale = 1.0;
};

std::vector<FinishedView> LoadFinishedViews(const std::vector<std::string>& dirs,
                                            const std::string& depth_file,
                                            SceneIdentity* identity) {
  if (dirs.empty()) throw Error("fuse: no view folder given");
  std::vector<FinishedView> views;
  for (const std::string& dir : dirs) {
    CheckViewFolder(dir, {"effective_config.yaml", depth_file, "report.json"});
    LoadedConfig config;
    config.Load((fs::path(dir) / "effective_config.yaml").string(), {});
    const DatasetOptions& d = config.options().dataset;
    if (d.IsScene()) {
      throw Error(dir + ": a scene's folder, not a view's (fuse the folders under its views/)");
    }
    std::error_code ec;
    const std::string canonical = fs::weakly_canonical(d.path, ec).string();
    if (views.empty()) {
      *identity = {d.format, canonical, d.scale};
    } else if (d.format != identity->format || canonical != identity->path ||
               d.scale != identity->scale) {
      throw Error("fuse: " + dir + " is a view of " + d.format + " data set " + canonical +
                  " at scale " + FormatNumber(d.scale) + ", but " + views.front().dir + " is of " +
                  identity->format + " data set " + identity->path + " at scale " +
                  FormatNumber(identity->scale) +
                  ": only views of one scene with the same cameras can be fused");
    }
    for (const FinishedView& v : views) {
      if (v.name == d.reference) {
        throw Error("fuse: " + dir + " and " + v.dir + " are both view " + d.reference);
      }
    }
    io::DatasetRequest request;
    request.format = d.format;
    request.path = d.path;
    request.reference = d.reference;
    request.scale = d.scale;
    request.load_neighbors = false;
    // The cameras in the frame the view's depth map was computed in (dataset.align).
    request.world_from_model = internal::ModelAlignmentOf(config.options()).world_from_model;
    Dataset dataset = io::LoadDataset(request);
    FinishedView v;
    v.dir = dir;
    v.name = d.reference;
    v.view = std::move(dataset.reference);
    v.ground_truth = std::move(dataset.ground_truth);
    v.neighbors = d.neighbors;
    v.depth = io::ReadPfm((fs::path(dir) / depth_file).string());
    if (v.depth.size() != v.view.image.size()) {
      throw Error(dir + "/" + depth_file + ": " + std::to_string(v.depth.cols) + "x" +
                  std::to_string(v.depth.rows) + ", but view " + v.name + " is " +
                  std::to_string(v.view.image.cols) + "x" + std::to_string(v.view.image.rows) +
                  " at scale " + FormatNumber(d.scale));
    }
    views.push_back(std::move(v));
  }
  return views;
}

// The ground truth of the scene: the configured files, else the synthetic sets' gt/ files.
std::string GroundTruthFile(const std::string& configured, const SceneIdentity& scene,
                            const char* default_name) {
  if (!configured.empty()) return configured;
  std::error_code ec;
  const fs::path candidate = fs::path(scene.path) / "gt" / default_name;
  return fs::is_regular_file(candidate, ec) ? candidate.string() : std::string();
}

// The part of the true surface the views observed: a point counts when at least `min_views`
// views see it — in front, inside the image, and not behind that view's true surface there (its
// ground-truth depth map, or the GT mesh rendered into it; without either, the frustum alone
// decides). Completeness against the whole GT surface would count the far ground and the walls
// behind the cameras; against what fewer views see than the fusion requires (fusion.min_views),
// surface no fused point can stand for by construction.
class ObservedRegion {
 public:
  ObservedRegion(const std::vector<FinishedView>& views, const TriangleMesh* gt_mesh, int min_views)
      : min_views_(std::max(1, min_views)) {
    for (const FinishedView& v : views) {
      cv::Mat depth = v.ground_truth.depth;
      if (depth.empty() && gt_mesh != nullptr) {
        depth = eval::RenderMeshDepth(*gt_mesh, v.view.camera).depth;
      }
      cameras_.push_back(v.view.camera);
      depths_.push_back(depth);
    }
  }
  bool operator()(const Eigen::Vector3d& point) const {
    int seen = 0;
    for (size_t i = 0; i < cameras_.size() && seen < min_views_; ++i) {
      Eigen::Vector2d pixel;
      double z = 0.0;
      if (!cameras_[i].Project(point, &pixel, &z) || !cameras_[i].InImage(pixel)) continue;
      if (depths_[i].empty()) {
        ++seen;
        continue;
      }
      const int col = std::clamp(static_cast<int>(std::lround(pixel.x())), 0, depths_[i].cols - 1);
      const int row = std::clamp(static_cast<int>(std::lround(pixel.y())), 0, depths_[i].rows - 1);
      const float surface = depths_[i].at<float>(row, col);
      if (IsValidDepth(surface) && z <= surface * (1.0 + kDepthTolerance)) ++seen;
    }
    return seen >= min_views_;
  }
  // A point this much (relative) behind the surface seen at its pixel still counts as seen.
  static constexpr double kDepthTolerance = 0.01;

 private:
  int min_views_;
  std::vector<Camera> cameras_;
  std::vector<cv::Mat> depths_;
};

// The σ-histogram (Strecha; the paper's Figure 4) of each view's depth map and of the scene mesh
// rendered into the view, for the views with ground-truth depth and sigma; pooled over the views
// too (all their pixels in one histogram).
json ViewHistograms(const std::vector<FinishedView>& views, const TriangleMesh& mesh,
                    std::vector<std::pair<std::string, cv::Mat>>* figures) {
  json per_view = json::array();
  std::vector<cv::Mat> depth_maps, mesh_maps, gt_maps, sigma_maps;
  double sum_view = 0.0, sum_mesh = 0.0;
  for (const FinishedView& v : views) {
    const GroundTruth& gt = v.ground_truth;
    if (gt.depth.empty() || gt.sigma.empty()) continue;
    const cv::Mat rendered = eval::RenderMeshDepth(mesh, v.view.camera).depth;
    const eval::SigmaHistogram own = eval::EvaluateDepthSigma(v.depth, gt.depth, gt.sigma);
    const eval::SigmaHistogram of_mesh = eval::EvaluateDepthSigma(rendered, gt.depth, gt.sigma);
    per_view.push_back({{"view", v.name},
                        {"depth_map_within_3_sigma_percent", own.WithinPercent(3)},
                        {"scene_mesh_within_3_sigma_percent", of_mesh.WithinPercent(3)},
                        {"depth_map", own.ToJson()},
                        {"scene_mesh", of_mesh.ToJson()}});
    sum_view += own.WithinPercent(3);
    sum_mesh += of_mesh.WithinPercent(3);
    depth_maps.push_back(v.depth);
    mesh_maps.push_back(rendered);
    gt_maps.push_back(gt.depth);
    sigma_maps.push_back(gt.sigma);
  }
  if (per_view.empty()) return nullptr;
  // Views may differ in size: pool them as one column of maps of the widest width.
  auto pooled = [](const std::vector<cv::Mat>& maps) {
    int width = 0;
    for (const cv::Mat& m : maps) width = std::max(width, m.cols);
    std::vector<cv::Mat> padded;
    for (const cv::Mat& m : maps) {
      cv::Mat p(m.rows, width, CV_32F, cv::Scalar(kInvalidDepth));
      m.copyTo(p(cv::Rect(0, 0, m.cols, m.rows)));
      padded.push_back(p);
    }
    cv::Mat all;
    cv::vconcat(padded, all);
    return all;
  };
  const cv::Mat gt_all = pooled(gt_maps), sigma_all = pooled(sigma_maps);
  const eval::SigmaHistogram pooled_views =
      eval::EvaluateDepthSigma(pooled(depth_maps), gt_all, sigma_all);
  const eval::SigmaHistogram pooled_mesh =
      eval::EvaluateDepthSigma(pooled(mesh_maps), gt_all, sigma_all);
  const double n = static_cast<double>(per_view.size());
  eval::SigmaHistogramPlotOptions plot;
  plot.title = "Scene: |depth - gt| / sigma over " + std::to_string(per_view.size()) + " views";
  figures->emplace_back(
      "scene_sigma_histogram.png",
      eval::RenderSigmaHistogram(
          {{"views' depth maps", pooled_views}, {"scene mesh in the views", pooled_mesh}}, plot));
  return {{"views", per_view},
          {"mean_depth_map_within_3_sigma_percent", sum_view / n},
          {"mean_scene_mesh_within_3_sigma_percent", sum_mesh / n},
          {"pooled_depth_maps", pooled_views.ToJson()},
          {"pooled_scene_mesh", pooled_mesh.ToJson()}};
}

// Pictures of the scene mesh from a few viewpoints around it, seen from the middle view.
void ModelPictures(const std::vector<FinishedView>& views, const TriangleMesh& mesh,
                   const PipelineConfig& o, std::vector<std::pair<std::string, cv::Mat>>* out) {
  if (mesh.faces.empty()) return;
  const Camera& middle = views[views.size() / 2].view.camera;
  const double enlarge = std::max(1.0, 960.0 / middle.width);
  const Eigen::Vector3d pivot = mesh::MedianVertex(mesh);
  const std::vector<std::pair<double, double>> angles = {
      {0.0, 0.0}, {-35.0, 15.0}, {35.0, 15.0}, {0.0, 45.0}};
  for (size_t i = 0; i < angles.size(); ++i) {
    const Camera view =
        mesh::OrbitCamera(middle.Rescaled(enlarge), angles[i].first, angles[i].second, pivot);
    out->emplace_back("model_" + std::to_string(i + 1) + ".png",
                      mesh::RenderMeshPreview(mesh, view, o.mesh.preview));
  }
}

// output.colmap: every fused view's depth map (the fusion's input, `depth_file`) as one COLMAP
// workspace in colmap/ (colmap_export.h), each view's source images its run's neighbours among
// the fused views. Timed as the "colmap_export" stage; returns report.json's "colmap".
json WriteSceneColmap(const std::vector<FinishedView>& views, const PipelineConfig& o,
                      const std::string& depth_file, OutputFolder& out, json* stages) {
  internal::StageClock clock(stages, "colmap_export");
  std::vector<internal::ColmapExportView> inputs;
  for (const FinishedView& v : views) {
    std::vector<std::string> sources = v.neighbors;
    if (sources.empty()) {
      for (const FinishedView& other : views) sources.push_back(other.name);
    }
    inputs.push_back({v.name, v.view.camera, v.view.image, v.depth, sources});
  }
  json summary = internal::WriteColmapWorkspace(out.Path("colmap"), inputs,
                                                internal::ColmapExportOptionsOf(o));
  summary["depth"] = depth_file;
  clock.Done(summary);
  return summary;
}

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Percent(const json& v) {
  if (!v.is_number()) return "–";
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << v.get<double>();
  return s.str();
}

// index.html of a scene: the model's pictures, the accuracy tables, the views.
std::string SceneIndexHtml(const json& report, const std::vector<std::string>& images,
                           const std::vector<std::pair<std::string, std::string>>& view_pictures) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>gcpstereo scene</title>\n"
    << "<style>body{font-family:sans-serif;margin:2em;background:#fafafa}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:4px 10px;"
       "text-align:right}th{background:#eee}td:first-child{text-align:left}"
       "figure{display:inline-block;margin:0.5em;vertical-align:top}"
       "img{max-width:640px;border:1px solid #ccc}.small "
       "img{max-width:300px}</style></head><body>\n";
  h << "<h1>gcpstereo scene</h1>\n<p>Data set <code>" << Escape(report.value("dataset", ""))
    << "</code>; " << report["views"].size() << " views, " << report.value("fused_views", 0)
    << " fused; " << report["fusion"].value("points", 0) << " fused points, "
    << report["scene_mesh"].value("faces", 0) << " mesh faces.</p>\n";
  for (const std::string& image : images) {
    h << "<figure><img src=\"" << Escape(image) << "\"><figcaption>" << Escape(image)
      << "</figcaption></figure>\n";
  }
  if (report.contains("metrics")) {
    for (const auto& [what, metrics] : report["metrics"].items()) {
      if (!metrics.contains("thresholds")) continue;
      h << "<h2>" << Escape(what) << "</h2>\n<table><tr><th>threshold</th><th>accuracy %</th>"
        << "<th>completeness %</th><th>F-score %</th></tr>\n";
      for (size_t i = 0; i < metrics["thresholds"].size(); ++i) {
        h << "<tr><td>" << metrics["thresholds"][i].get<double>() << "</td><td>"
          << Percent(metrics["accuracy_percent"][i]) << "</td><td>"
          << Percent(metrics["completeness_percent"][i]) << "</td><td>"
          << Percent(metrics["f_score_percent"][i]) << "</td></tr>\n";
      }
      h << "</table>\n";
    }
    if (report["metrics"].contains("views_sigma")) {
      const json& s = report["metrics"]["views_sigma"];
      h << "<h2>Within 3σ per view</h2>\n<table><tr><th>view</th><th>its depth map %</th>"
        << "<th>scene mesh %</th></tr>\n";
      for (const json& v : s["views"]) {
        h << "<tr><td>" << Escape(v.value("view", "")) << "</td><td>"
          << Percent(v["depth_map_within_3_sigma_percent"]) << "</td><td>"
          << Percent(v["scene_mesh_within_3_sigma_percent"]) << "</td></tr>\n";
      }
      h << "<tr><td><b>mean</b></td><td>" << Percent(s["mean_depth_map_within_3_sigma_percent"])
        << "</td><td>" << Percent(s["mean_scene_mesh_within_3_sigma_percent"]) << "</td></tr>\n";
      h << "</table>\n";
    }
  }
  h << "<h2>Views</h2>\n<table><tr><th>view</th><th>status</th><th>seconds</th><th>neighbours</th>"
    << "<th>GCPs</th></tr>\n";
  for (const json& v : report["views"]) {
    h << "<tr><td>" << Escape(v.value("name", "")) << "</td><td>" << Escape(v.value("status", ""))
      << (v.contains("error") ? ": " + Escape(v["error"].get<std::string>()) : std::string())
      << "</td><td>" << Percent(v.value("seconds", json())) << "</td><td>"
      << Escape(v.value("neighbors", json::array()).dump()) << "</td><td>" << v.value("gcps", 0)
      << "</td></tr>\n";
  }
  h << "</table>\n<div class=\"small\">\n";
  for (const auto& [name, picture] : view_pictures) {
    h << "<figure><a href=\"" << Escape(picture) << "\"><img src=\"" << Escape(picture)
      << "\"></a><figcaption>" << Escape(name) << "</figcaption></figure>\n";
  }
  h << "</div>\n";
  if (report.contains("stages")) {
    h << "<h2>Stages</h2>\n<table><tr><th>stage</th><th>seconds</th><th>peak memory after "
         "(MB)</th></tr>\n";
    for (const auto& [name, stage] : report["stages"].items()) {
      h << "<tr><td>" << Escape(name) << "</td><td>" << Percent(stage.value("seconds", json()))
        << "</td><td>" << stage.value("peak_memory_bytes_after", 0.0) / 1e6 << "</td></tr>\n";
    }
    h << "</table>\n";
  }
  h << "</body></html>\n";
  return h.str();
}

}  // namespace

namespace internal {

json FuseMeshEvaluate(const std::vector<std::string>& view_dirs, const PipelineConfig& o,
                      OutputFolder& out, std::vector<std::string>* images) {
  json report = json::object();
  json& stages = report["stages"];
  stages = json::object();

  internal::StageClock load(&stages, "load_views");
  SceneIdentity scene;
  const std::string depth_file =
      o.fusion_input == "propagated" ? "propagated_depth.pfm" : "depth.pfm";
  const std::vector<FinishedView> views = LoadFinishedViews(view_dirs, depth_file, &scene);
  report["fusion_input"] = depth_file;
  report["dataset"] = scene.path;
  report["format"] = scene.format;
  report["scale"] = scene.scale;
  report["fused_views"] = views.size();
  load.Done({{"views", views.size()}});

  internal::StageClock fuse(&stages, "fusion");
  std::vector<fusion::FusionView> inputs;
  for (const FinishedView& v : views) {
    inputs.push_back({v.name, v.view.camera, v.depth, v.view.image});
  }
  fusion::FusionSummary fusion_summary;
  OrientedPointCloud cloud;
  {
    ProgressBar bar("fusion", 1000);
    cloud = fusion::FuseDepthMaps(inputs, o.fusion, &fusion_summary, bar.AsCallback());
  }
  const size_t fused_points = cloud.size();
  size_t gcp_points = 0;
  if (o.fusion_include_gcps) {
    for (const FinishedView& v : views) {
      const fs::path gcps = fs::path(v.dir) / "gcps.ply";
      std::error_code ec;
      if (!fs::is_regular_file(gcps, ec)) continue;
      const PointCloud points = io::ReadPointCloud(gcps.string());
      gcp_points += points.size();
      fusion::AppendGcpPoints(points, &cloud);
    }
  }
  if (cloud.empty()) {
    throw Error("fusion: no point is seen alike by fusion.min_views = " +
                std::to_string(o.fusion.min_views) + " of the " + std::to_string(views.size()) +
                " views: lower fusion.min_views or widen fusion.depth_tolerance");
  }
  io::WriteOrientedPointCloudPly(out.Path("fused.ply"), cloud);
  json fusion_report = fusion_summary.ToJson();
  fusion_report["points"] = cloud.size();
  fusion_report["fused_points"] = fused_points;
  fusion_report["gcp_points"] = gcp_points;
  fusion_report["include_gcps"] = o.fusion_include_gcps;
  report["fusion"] = fusion_report;
  fuse.Done({{"points", cloud.size()}});

  internal::StageClock meshing(&stages, "scene_mesh");
  mesh::SurfaceSummary surface_summary;
  mesh::SurfaceOptions surface_options = o.scene_mesh;
  surface_options.threads = o.runtime.threads;
  const TriangleMesh mesh = mesh::ReconstructSurface(cloud, surface_options, &surface_summary);
  io::WriteMeshPly(out.Path("mesh.ply"), mesh);
  io::WriteMeshObj(out.Path("mesh.obj"), mesh, mesh::VertexNormals(mesh));
  report["scene_mesh"] = surface_summary.ToJson();
  report["scene_mesh"]["faces"] = mesh.faces.size();
  report["scene_mesh"]["vertices"] = mesh.vertices.size();
  meshing.Done({{"faces", mesh.faces.size()}});

  internal::StageClock evaluation(&stages, "evaluation");
  std::vector<std::pair<std::string, cv::Mat>> figures;
  json metrics = json::object();
  const std::string gt_mesh_path = GroundTruthFile(o.eval.scene.gt_mesh, scene, "mesh.ply");
  const std::string gt_points_path = GroundTruthFile(o.eval.scene.gt_points, scene, "laser.ply");
  // Thresholds 1, 2, 5 and 10 cm (MeshAccuracyOptions' defaults).
  eval::MeshAccuracyOptions accuracy_options;
  accuracy_options.max_samples = o.eval.scene.max_samples;
  std::optional<TriangleMesh> gt_mesh;
  if (!gt_mesh_path.empty()) gt_mesh = io::ReadMeshPly(gt_mesh_path);
  const ObservedRegion observed(views, gt_mesh ? &*gt_mesh : nullptr, o.fusion.min_views);
  accuracy_options.gt_filter = [&observed](const Eigen::Vector3d& p) { return observed(p); };
  if (gt_mesh) {
    metrics["gt_mesh"] = gt_mesh_path;
    metrics["mesh_vs_gt_mesh"] =
        eval::EvaluateSurface({&mesh, nullptr}, {&*gt_mesh, nullptr}, accuracy_options).ToJson();
    metrics["fused_points_vs_gt_mesh"] =
        eval::EvaluateSurface({nullptr, &cloud.points}, {&*gt_mesh, nullptr}, accuracy_options)
            .ToJson();
  }
  if (!gt_points_path.empty()) {
    const PointCloud laser = io::ReadPointCloud(gt_points_path);
    metrics["gt_points"] = gt_points_path;
    metrics["mesh_vs_gt_points"] =
        eval::EvaluateSurface({&mesh, nullptr}, {nullptr, &laser.points}, accuracy_options)
            .ToJson();
    metrics["fused_points_vs_gt_points"] =
        eval::EvaluateSurface({nullptr, &cloud.points}, {nullptr, &laser.points}, accuracy_options)
            .ToJson();
  }
  if (gt_mesh || !gt_points_path.empty()) {
    metrics["ground_truth_region"] =
        "the part of the ground truth that at least fusion.min_views views observe (in their "
        "images, not behind their true surface)";
  }
  if (o.eval.scene.view_histograms) {
    json histograms = ViewHistograms(views, mesh, &figures);
    if (!histograms.is_null()) metrics["views_sigma"] = std::move(histograms);
  }
  if (!metrics.empty()) report["metrics"] = metrics;
  evaluation.Done();

  if (o.output.colmap) report["colmap"] = WriteSceneColmap(views, o, depth_file, out, &stages);

  if (o.output.previews) {
    internal::StageClock pictures(&stages, "pictures");
    std::vector<std::pair<std::string, cv::Mat>> model;
    ModelPictures(views, mesh, o, &model);
    model.insert(model.end(), figures.begin(), figures.end());
    for (const auto& [name, picture] : model) {
      io::WritePng(out.Path(name), picture);
      images->push_back(name);
    }
    pictures.Done();
  }
  return report;
}

std::string SceneHtml(const json& report, const std::vector<std::string>& images,
                      const std::string& output_dir) {
  std::vector<std::pair<std::string, std::string>> view_pictures;
  for (const json& v : report["views"]) {
    const std::string dir = v.value("dir", "");
    std::error_code ec;
    if (dir.empty() || !fs::is_regular_file(fs::path(dir) / "depth.png", ec)) continue;
    const fs::path relative =
        fs::relative(fs::absolute(fs::path(dir) / "depth.png"), fs::absolute(output_dir), ec);
    if (!ec) view_pictures.emplace_back(v.value("name", ""), relative.generic_string());
  }
  return SceneIndexHtml(report, images, view_pictures);
}

// A finished view's summary for the scene's report, from its report.json.
json ViewSummary(const std::string& name, const std::string& dir, const std::string& status) {
  json summary = {{"name", name}, {"dir", dir}, {"status", status}};
  std::ifstream in(fs::path(dir) / "report.json");
  json view = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (view.is_discarded()) return summary;
  summary["seconds"] = view.value("total_seconds", 0.0);
  summary["peak_memory_bytes"] = view.value("peak_memory_bytes", 0.0);
  if (view.contains("gcps")) summary["gcps"] = view["gcps"].value("count", 0);
  if (view.contains("dataset")) {
    json neighbors = json::array();
    for (const json& n : view["dataset"].value("neighbors", json::array())) {
      neighbors.push_back(n.value("name", ""));
    }
    summary["neighbors"] = neighbors;
  }
  return summary;
}

std::string SceneTerminalSummary(const json& report) {
  std::ostringstream t;
  int failed = 0;
  for (const json& v : report["views"]) failed += v.value("status", "") == "failed";
  t << "scene: " << report["views"].size() << " views (" << failed << " failed), "
    << report["fusion"].value("points", 0) << " fused points, "
    << report["scene_mesh"].value("faces", 0) << " mesh faces\n";
  if (report.contains("metrics")) {
    for (const auto& [what, m] : report["metrics"].items()) {
      if (!m.contains("thresholds")) continue;
      t << "  " << what << ": F-score";
      for (size_t i = 0; i < m["thresholds"].size(); ++i) {
        t << " " << m["f_score_percent"][i].get<double>() << " % @ "
          << m["thresholds"][i].get<double>();
      }
      t << "\n";
    }
    if (report["metrics"].contains("views_sigma")) {
      const json& s = report["metrics"]["views_sigma"];
      t << "  within 3σ, mean over " << s["views"].size() << " views: depth maps "
        << Percent(s["mean_depth_map_within_3_sigma_percent"]) << " %, scene mesh "
        << Percent(s["mean_scene_mesh_within_3_sigma_percent"]) << " %\n";
    }
  }
  for (const json& v : report["views"]) {
    if (v.value("status", "") == "failed") {
      t << "  view " << v.value("name", "") << " failed: " << v.value("error", "") << "\n";
    }
  }
  return t.str();
}

}  // namespace internal

namespace {

// Writes the scene's report.json, index.html and effective_config.yaml and commits the folder.
RunSummary CommitScene(json* report, const std::vector<std::string>& images,
                       const LoadedConfig& config, OutputFolder& out, const Timer& total) {
  (*report)["peak_memory_bytes"] = PeakResidentMemoryBytes();
  (*report)["total_seconds"] = total.ElapsedSeconds();
  if (config.options().output.previews) {
    WriteText(out.Path("index.html"), internal::SceneHtml(*report, images, out.final_dir()));
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
  summary.terminal_summary = internal::SceneTerminalSummary(*report);
  return summary;
}

}  // namespace

std::vector<std::string> SceneReferenceNames(const PipelineConfig& o) {
  const std::vector<std::string> available = io::ListDatasetViews(o.dataset.format, o.dataset.path);
  if (o.dataset.references.size() == 1 && o.dataset.references.front() == "all") return available;
  for (const std::string& name : o.dataset.references) {
    if (std::find(available.begin(), available.end(), name) == available.end()) {
      std::string valid;
      for (const std::string& a : available) valid += (valid.empty() ? "" : ", ") + a;
      throw ConfigError("dataset.reference: no view named " + name + " in " + o.dataset.path +
                        " (views: " + valid + ")");
    }
  }
  return o.dataset.references;
}

std::unique_ptr<LoadedConfig> ConfigWithChosenNeighbors(const LoadedConfig& config) {
  const PipelineConfig& o = config.options();
  const SceneCameras cameras = LoadSceneCameras(o);
  return ViewConfig(config, o.dataset.reference, &cameras, SelectionPoints(o));
}

std::vector<ViewJob> PlanViewJobs(const LoadedConfig& config) {
  const PipelineConfig& o = config.options();
  std::vector<ViewJob> jobs;
  const std::vector<std::string> names =
      o.dataset.IsScene() ? SceneReferenceNames(o) : std::vector<std::string>{o.dataset.reference};
  for (const std::string& name : names) {
    io::DatasetRequest request;
    request.format = o.dataset.format;
    request.path = o.dataset.path;
    request.reference = name;
    request.scale = o.dataset.scale;
    request.load_neighbors = false;
    const Camera camera = io::LoadDataset(request).reference.camera;
    ViewJob job;
    job.name = name;
    job.width_px = camera.width;
    job.height_px = camera.height;
    if (o.dataset.IsScene()) job.overrides = ViewOverrides(o, name);
    jobs.push_back(std::move(job));
  }
  return jobs;
}

RunSummary RunScene(const LoadedConfig& config, const std::string& output_dir,
                    const SceneRunOptions& options) {
  const PipelineConfig& o = config.options();
  const ScopedThreadLimit thread_limit(o.runtime.threads);
  Timer total;
  OutputFolder out(output_dir);
  const ScopedLogFile log_file(out.FinalPath("run.log"));

  json report;
  report["gcpstereo_version"] = GCPSTEREO_VERSION;
  report["config"] = config.path();
  json stages = json::object();

  const std::vector<std::string> names = SceneReferenceNames(o);
  spdlog::info("scene of {} views: {}", names.size(), FlowList(names));
  // dataset.align once for the scene (a refused alignment stops it here, not in every view).
  const internal::ModelAlignment alignment = internal::ModelAlignmentOf(o);
  if (alignment.active) report["alignment"] = alignment.report;
  internal::StageClock selection_stage(&stages, "view_selection");
  std::optional<SceneCameras> cameras;
  std::vector<Eigen::Vector3d> points;
  if (o.dataset.AutoNeighbors()) {
    cameras = LoadSceneCameras(o);
    points = SelectionPoints(o);
  }
  selection_stage.Done({{"points", points.size()}});

  internal::StageClock views_stage(&stages, "views");
  json views = json::array();
  std::vector<std::string> finished;
  std::string errors;
  int reused = 0;
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& name = names[i];
    const std::string dir = (fs::path(out.final_dir()) / "views" / name).string();
    spdlog::info("scene: view {} ({}/{})", name, i + 1, names.size());
    try {
      std::unique_ptr<LoadedConfig> view_config =
          ViewConfig(config, name, cameras ? &*cameras : nullptr, points);
      if (ViewFolderComplete(dir, view_config->schema().ToYaml())) {
        spdlog::info("scene: view {} is complete in {}: reused", name, dir);
        views.push_back(internal::ViewSummary(name, dir, "reused"));
        ++reused;
      } else if (!options.compute_views) {
        throw Error(MissingViewError(dir));
      } else {
        RunPipeline(*view_config, dir, config.path());
        views.push_back(internal::ViewSummary(name, dir, "done"));
      }
      finished.push_back(dir);
    } catch (const std::exception& e) {
      spdlog::error("scene: view {} failed: {}", name, e.what());
      views.push_back({{"name", name}, {"dir", dir}, {"status", "failed"}, {"error", e.what()}});
      errors += std::string(errors.empty() ? "" : "; ") + name + ": " + e.what();
    }
  }
  views_stage.Done({{"finished", finished.size()},
                    {"reused", reused},
                    {"failed", names.size() - finished.size()}});
  if (finished.empty()) {
    throw Error("scene: no view finished, nothing to fuse (" + errors + ")");
  }

  std::vector<std::string> images;
  json fused = internal::FuseMeshEvaluate(finished, o, out, &images);
  for (auto& [name, stage] : fused["stages"].items()) stages[name] = stage;
  fused.erase("stages");
  report.update(fused);
  report["views"] = views;
  report["stages"] = stages;
  return CommitScene(&report, images, config, out, total);
}

RunSummary FuseViewFolders(const FuseRequest& request) {
  if (request.view_dirs.empty()) throw Error("fuse: give at least one view folder");
  for (const std::string& dir : request.view_dirs) CheckViewFolder(dir, {"effective_config.yaml"});
  Timer total;
  // The configuration: the first view's, with the command line's overrides.
  LoadedConfig config;
  config.Load((fs::path(request.view_dirs.front()) / "effective_config.yaml").string(),
              request.overrides);
  const ScopedThreadLimit thread_limit(config.options().runtime.threads);
  OutputFolder out(request.output_dir);
  const ScopedLogFile log_file(out.FinalPath("run.log"));

  json report;
  report["gcpstereo_version"] = GCPSTEREO_VERSION;
  std::vector<std::string> images;
  json fused = internal::FuseMeshEvaluate(request.view_dirs, config.options(), out, &images);
  report.update(fused);
  json views = json::array();
  for (const std::string& dir : request.view_dirs) {
    LoadedConfig view;
    view.Load((fs::path(dir) / "effective_config.yaml").string(), {});
    views.push_back(internal::ViewSummary(view.options().dataset.reference, dir, "done"));
  }
  report["views"] = views;
  return CommitScene(&report, images, config, out, total);
}

}  // namespace gcpstereo::pipeline
