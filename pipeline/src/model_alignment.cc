// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "model_alignment.h"

#include <filesystem>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

#include "gcpstereo/align/similarity_alignment.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/io/point_cloud_io.h"

namespace gcpstereo::pipeline::internal {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// A file as the cache tells versions apart: path, size and modification time.
std::string FileIdentity(const std::string& path) {
  std::error_code ec;
  std::ostringstream s;
  s << fs::weakly_canonical(path, ec).string() << '|' << fs::file_size(path, ec) << '|'
    << fs::last_write_time(path, ec).time_since_epoch().count();
  return s.str();
}

std::string CacheKey(const PipelineConfig& o, const std::string& target) {
  const align::AlignmentOptions& a = o.dataset.align_options;
  std::ostringstream s;
  s.precision(17);
  s << o.dataset.align << '|' << FileIdentity(o.dataset.path + "/sparse/images.bin") << '|'
    << FileIdentity(o.dataset.path + "/sparse/images.txt") << '|'
    << FileIdentity(o.dataset.path + "/sparse/points3D.bin") << '|'
    << FileIdentity(o.dataset.path + "/sparse/points3D.txt") << '|' << FileIdentity(target) << '|'
    << a.max_residual << '|' << a.min_inlier_share << '|' << a.max_relative_residual << '|'
    << a.ransac_iterations << '|' << a.seed << '|' << a.max_model_points;
  return s.str();
}

json ReportOf(const align::AlignmentResult& r, const std::string& target,
              const align::AlignmentOptions& options, const std::vector<io::KnownCentre>* centres) {
  const align::Similarity& s = r.world_from_model;
  const Eigen::Matrix4d m = s.Matrix();
  json matrix = json::array();
  for (int row = 0; row < 4; ++row) {
    matrix.push_back({m(row, 0), m(row, 1), m(row, 2), m(row, 3)});
  }
  json report = {{"method", r.method},
                 {"target", target},
                 {"scale", s.scale},
                 {"rotation_deg", s.RotationAngleDeg()},
                 {"translation", {s.translation.x(), s.translation.y(), s.translation.z()}},
                 {"world_from_model", matrix},
                 {"residual_median", r.median_residual},
                 {"residual_p90", r.p90_residual},
                 {"residual_rms", r.rms_residual},
                 {"residual_median_relative", r.relative_median_residual},
                 {"model_spread", r.model_spread},
                 {"correspondences", r.num_correspondences},
                 {"inliers", r.num_inliers},
                 {"inlier_share", r.inlier_share},
                 {"hypotheses", r.hypotheses},
                 {"iterations", r.iterations},
                 {"seconds", r.seconds},
                 {"max_residual", options.max_residual},
                 {"min_inlier_share", options.min_inlier_share}};
  if (r.method == "scan") {
    report["max_relative_residual"] = options.max_relative_residual;
    report["restarts"] = r.restarts;
    report["restarts_alike"] = r.restarts_alike;
    report["ambiguity"] = r.ambiguity;
    report["ambiguity_probes"] = r.ambiguity_probes;
  }
  if (centres) {
    json per_centre = json::array();
    for (size_t i = 0; i < centres->size() && i < r.residuals.size(); ++i) {
      per_centre.push_back({{"name", (*centres)[i].name}, {"residual", r.residuals[i]}});
    }
    report["centres"] = per_centre;
  }
  return report;
}

ModelAlignment Estimate(const PipelineConfig& o) {
  const io::ColmapModel model = io::ReadColmapModel(io::ColmapSparseDir(o.dataset.path));
  const align::AlignmentOptions& options = o.dataset.align_options;
  align::AlignmentResult result;
  std::string target;
  std::vector<io::KnownCentre> centres;
  if (o.dataset.align == "centres") {
    target = o.dataset.align_centres;
    centres = io::ReadKnownCentres(target);
    std::vector<Eigen::Vector3d> from, to;
    for (const io::KnownCentre& c : centres) {
      const io::ColmapImage* image = model.FindImage(c.name);
      if (!image) {
        std::string names;
        for (const std::string& n : model.ImageNames()) {
          if (names.size() > 200) {
            names += ", ...";
            break;
          }
          names += (names.empty() ? "" : ", ") + n;
        }
        throw ConfigError("dataset.align_centres: " + target + " names image '" + c.name +
                          "', which the COLMAP model " + model.sparse_dir +
                          " does not have (its images: " + names + ")");
      }
      from.push_back(image->CenterWorld());
      to.push_back(c.center_world);
    }
    try {
      result = align::AlignToKnownPoints(from, to, options);
    } catch (const Error& e) {
      throw Error("dataset.align_centres: " + target + ": " + e.what());
    }
  } else {
    target = o.gcp.lidar_path;
    std::vector<Eigen::Vector3d> points;
    points.reserve(model.points3d.size());
    for (const auto& [id, point] : model.points3d) points.push_back(point.xyz_world);
    std::vector<Eigen::Vector3d> model_centres;
    for (const auto& [id, image] : model.images) model_centres.push_back(image.CenterWorld());
    const PointCloud scan = io::ReadPointCloud(target);
    try {
      result = align::AlignToScan(points, scan, options, model_centres);
    } catch (const Error& e) {
      throw Error("dataset.align = scan: " + target + ": " + e.what());
    }
  }
  spdlog::info("dataset.align {} ({}): {}, {:.2f} s", o.dataset.align, target, result.Describe(),
               result.seconds);
  align::CheckAlignment(result, options,
                        "dataset.align = " + o.dataset.align + " (" + target + ")");
  ModelAlignment alignment;
  alignment.active = true;
  alignment.world_from_model = result.world_from_model.Matrix();
  alignment.report =
      ReportOf(result, target, options, o.dataset.align == "centres" ? &centres : nullptr);
  return alignment;
}

}  // namespace

ModelAlignment ModelAlignmentOf(const PipelineConfig& o) {
  if (o.dataset.align == "none" || o.dataset.format != "colmap") return ModelAlignment();
  static std::mutex mutex;
  static std::map<std::string, ModelAlignment> cache;
  const std::string key =
      CacheKey(o, o.dataset.align == "centres" ? o.dataset.align_centres : o.gcp.lidar_path);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto found = cache.find(key);
    if (found != cache.end()) return found->second;
  }
  ModelAlignment alignment = Estimate(o);
  const std::lock_guard<std::mutex> lock(mutex);
  cache.emplace(key, alignment);
  return alignment;
}

io::ColmapModel ReadAlignedColmapModel(const PipelineConfig& o) {
  io::ColmapModel model = io::ReadColmapModel(io::ColmapSparseDir(o.dataset.path));
  const ModelAlignment alignment = ModelAlignmentOf(o);
  if (alignment.active) io::TransformColmapModel(alignment.world_from_model, &model);
  return model;
}

}  // namespace gcpstereo::pipeline::internal
