// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/run.h"

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/pipeline/output_folder.h"

namespace gcpstereo::pipeline {
namespace {

using nlohmann::json;

json ViewJson(const View& v) {
  return {{"name", v.name}, {"width", v.image.cols}, {"height", v.image.rows}};
}

void WriteText(const std::string& path, const std::string& text) {
  io::WriteBytesAtomically(path, text.data(), text.size());
}

// Records one stage's wall time and the process's peak memory after it.
class StageClock {
 public:
  StageClock(json* stages, std::string name) : stages_(stages), name_(std::move(name)) {
    spdlog::info("stage {}: started", name_);
  }
  void Done(json extra = json::object()) {
    extra["seconds"] = timer_.ElapsedSeconds();
    extra["peak_memory_bytes_after"] = PeakResidentMemoryBytes();
    (*stages_)[name_] = extra;
    spdlog::info("stage {}: {:.2f} s", name_, extra["seconds"].get<double>());
  }

 private:
  json* stages_;
  std::string name_;
  Timer timer_;
};

}  // namespace

RunSummary RunPipeline(const LoadedConfig& config, const std::string& output_dir,
                       const std::string& config_path) {
  const PipelineConfig& options = config.options();
  Timer total;
  OutputFolder out(output_dir);
  json report;
  report["gcpstereo_version"] = GCPSTEREO_VERSION;
  report["config"] = config_path;
  json& stages = report["stages"];
  stages = json::object();

  // 1. Load the data set.
  StageClock load_clock(&stages, "load");
  io::DatasetRequest request;
  request.format = options.dataset.format;
  request.path = options.dataset.path;
  request.reference = options.dataset.reference;
  request.neighbors = options.dataset.neighbors;
  request.scale = options.dataset.scale;
  const Dataset dataset = io::LoadDataset(request);
  json views = json::array();
  for (const auto& n : dataset.neighbors) views.push_back(ViewJson(n));
  report["dataset"] = {{"format", dataset.format},
                       {"path", dataset.path},
                       {"rectified", dataset.rectified},
                       {"reference", ViewJson(dataset.reference)},
                       {"neighbors", views},
                       {"num_views", 1 + dataset.neighbors.size()},
                       {"ground_truth",
                        {{"depth", dataset.ground_truth.HasDepth()},
                         {"disparity", dataset.ground_truth.HasDisparity()}}}};
  spdlog::info("loaded {} views: reference {} ({}x{}) and {} neighbours", 1 + dataset.neighbors.size(),
               dataset.reference.name, dataset.reference.image.cols, dataset.reference.image.rows,
               dataset.neighbors.size());

  // Range sensors named by the configuration.
  PointCloud lidar;
  for (const auto& source : options.gcp.sources) {
    if (source == "lidar") {
      lidar = io::ReadPointCloud(options.gcp.lidar_path);
      report["lidar"] = {{"path", options.gcp.lidar_path}, {"num_points", lidar.size()},
                         {"has_sigma", !lidar.sigma.empty()}};
      spdlog::info("loaded {} LiDAR points from {}", lidar.size(), options.gcp.lidar_path);
    }
  }
  load_clock.Done();

  report["peak_memory_bytes"] = PeakResidentMemoryBytes();
  report["total_seconds"] = total.ElapsedSeconds();

  WriteText(out.Path("effective_config.yaml"), config.schema().ToYaml());
  const std::string report_text = report.dump(2) + "\n";
  WriteText(out.Path("report.json"), report_text);
  out.Commit();

  RunSummary summary;
  summary.output_dir = output_dir;
  summary.total_seconds = total.ElapsedSeconds();
  summary.peak_memory_bytes = PeakResidentMemoryBytes();
  summary.report_json = report_text;
  return summary;
}

}  // namespace gcpstereo::pipeline
