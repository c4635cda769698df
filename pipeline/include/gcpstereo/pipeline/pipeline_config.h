// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gcpstereo/config/schema.h"

namespace gcpstereo::pipeline {

// Keys of the `dataset:` section (../shared/CONTRACT.md).
struct DatasetOptions {
  std::string format = "strecha";        // strecha | middlebury | kitti_raw
  std::string path;                      // the data set's folder (required)
  std::string reference;                 // reference view name (required)
  std::vector<std::string> neighbors;    // views used for matching; empty = all others
  double scale = 1.0;                    // image scale before processing, (0, 1]
};

// Keys of the `labels:` section.
struct LabelOptions {
  std::string space = "depth";   // depth | inverse_depth | disparity
  int count = 360;               // number of discrete hypotheses (the paper: 360 depth levels)
  std::optional<double> min;     // in the space's unit; absent = automatic
  std::optional<double> max;
};

struct DepthMapGcpOptions {
  std::string path;            // PFM, or 8/16-bit PNG/PGM of the reference view
  std::string kind = "depth";  // depth | disparity
  double scale = 1.0;          // integer images: value = stored / scale
  double sigma = 0.0;          // measurement standard deviation (depth unit); 0 = unknown
};

// Keys of the `gcp:` section.
struct GcpOptions {
  std::vector<std::string> sources;  // lidar | depth_map | stereo; empty = no GCP energy
  std::string lidar_path;            // gcp.lidar.path
  DepthMapGcpOptions depth_map;      // gcp.depth_map.*
  int downsample = 16;               // s: one GCP per s×s block (paper: 16 → ≈0.4 %)
};

// Keys of the `optimizer:` section that the pipeline itself reads.
struct TilingOptions {
  std::vector<int> tiles{2, 2};  // [rows, cols] (paper: 2 × 2)
  int tile_overlap = 16;         // pixels (paper: 16)
};

struct RuntimeOptions {
  int threads = 0;              // worker threads; 0 = all cores
  std::string log_level = "info";
};

struct OutputOptions {
  bool previews = true;  // write the *.png previews and index.html
  bool mesh = true;      // write mesh.ply and mesh.obj
};

// The whole configuration of `gcpstereo run`.
struct PipelineConfig {
  DatasetOptions dataset;
  LabelOptions labels;
  GcpOptions gcp;
  TilingOptions tiling;
  RuntimeOptions runtime;
  OutputOptions output;

  // Registers every key with `schema` (bound to this object's fields, which must outlive it).
  void Register(config::Schema* schema);
  // Cross-key checks after loading (required keys present, min < max, …); throws ConfigError.
  void Check() const;
};

// A loaded configuration: the options and the schema that filled them (for effective_config.yaml).
class LoadedConfig {
 public:
  LoadedConfig();
  // Applies the file (if not empty) and then each KEY=VALUE override, then Check()s.
  void Load(const std::string& path, const std::vector<std::string>& overrides);
  const PipelineConfig& options() const { return options_; }
  PipelineConfig& mutable_options() { return options_; }
  const config::Schema& schema() const { return *schema_; }

 private:
  PipelineConfig options_;
  std::unique_ptr<config::Schema> schema_;
};

}  // namespace gcpstereo::pipeline
