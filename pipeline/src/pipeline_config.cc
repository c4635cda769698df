// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/pipeline_config.h"

#include <algorithm>
#include <sstream>

#include "gcpstereo/core/error.h"

namespace gcpstereo::pipeline {

using config::KeyDoc;
using config::Range;

void PipelineConfig::Register(config::Schema* s) {
  s->Add("dataset.format", &dataset.format, {"strecha", "middlebury", "kitti_raw"},
         {"data set layout: strecha (images/ + cameras/*.camera; also the synthetic sets), "
          "middlebury (official file names), kitti_raw (a drive folder)"});
  s->Add("dataset.path", &dataset.path, {},
         {"the data set's folder (kitti_raw: <date>/<date>_drive_NNNN_sync); relative paths are "
          "relative to the working directory"});
  s->Add("dataset.reference", &dataset.reference, {},
         {"reference view: strecha 0005; middlebury im2, scene1.row3.col3, view1; kitti_raw the "
          "frame 0000000010"});
  s->Add("dataset.neighbors", &dataset.neighbors, {},
         {"views used for matching; empty = all other views (ignored for kitti_raw)"});
  s->Add("dataset.scale", &dataset.scale, Range{0.0, 1.0, false, true},
         {"image scale before processing (fountain-P11 in the paper: 0.5)"});

  s->Add("labels.space", &labels.space, {"depth", "inverse_depth", "disparity"},
         {"spacing of the discrete hypotheses; disparity only for rectified data"});
  s->Add("labels.count", &labels.count, Range::Between(2, 4096),
         {"number of discrete hypotheses (paper: 360 depth levels)"});
  s->Add("labels.min", &labels.min, Range::AtLeast(0.0),
         {"lowest hypothesis in the space's unit (depth: data set unit; disparity: px in the "
          "ground truth's convention); auto = from the GCPs or the views' overlap"});
  s->Add("labels.max", &labels.max, Range::AtLeast(0.0), {"highest hypothesis; auto as labels.min"});

  s->Add("gcp.sources", &gcp.sources, {"lidar", "depth_map", "stereo"},
         {"GCP sources; empty list = no GCP energy (the paper's baseline)"});
  s->Add("gcp.lidar.path", &gcp.lidar_path, {},
         {"point cloud (.ply, .pcd, KITTI .bin): world frame for strecha, sensor frame for "
          "kitti_raw"});
  s->Add("gcp.depth_map.path", &gcp.depth_map.path, {},
         {"depth or disparity image of the reference view (PFM, 8/16-bit PNG/PGM; 0 or non-finite "
          "= no measurement)"});
  s->Add("gcp.depth_map.kind", &gcp.depth_map.kind, {"depth", "disparity"},
         {"what gcp.depth_map.path holds"});
  s->Add("gcp.depth_map.scale", &gcp.depth_map.scale, Range::GreaterThan(0.0),
         {"integer images: value = stored / scale"});
  s->Add("gcp.depth_map.sigma", &gcp.depth_map.sigma, Range::AtLeast(0.0),
         {"standard deviation of the depth-map measurements (depth unit); 0 = unknown", "m"});
  s->Add("gcp.downsample", &gcp.downsample, Range::Between(1, 1024),
         {"keep one measurement per s×s pixel block, nearest the block centre (paper: 16, i.e. "
          "≈0.4 %)",
          "px", "s"});

  s->Add("optimizer.tiles", &tiling.tiles, 2, Range::Between(1, 64),
         {"[rows, cols] of tiles for graph cuts (paper: [2, 2])"});
  s->Add("optimizer.tile_overlap", &tiling.tile_overlap, Range::Between(0, 1024),
         {"overlap between neighbouring tiles (paper: 16)", "px"});

  s->Add("runtime.threads", &runtime.threads, Range::Between(0, 1024),
         {"worker threads; 0 = all cores. Results do not depend on it"});
  s->Add("runtime.log_level", &runtime.log_level,
         {"trace", "debug", "info", "warn", "error", "off"}, {"terminal log level"});

  s->Add("output.previews", &output.previews, {"write the PNG previews and index.html"});
  s->Add("output.mesh", &output.mesh, {"write mesh.ply and mesh.obj"});
}

void PipelineConfig::Check() const {
  if (dataset.path.empty()) {
    throw ConfigError("dataset.path is required (the data set's folder)");
  }
  if (dataset.reference.empty()) {
    throw ConfigError("dataset.reference is required (the reference view's name)");
  }
  if (labels.min && labels.max && !(*labels.min < *labels.max)) {
    std::ostringstream s;
    s << *labels.min << ", " << *labels.max;
    throw ConfigError(ViolatedConstraint("labels.min, labels.max", s.str(), "min < max"));
  }
  if (labels.space == "depth" && labels.min && !(*labels.min > 0.0)) {
    throw ConfigError(ViolatedConstraint("labels.min", std::to_string(*labels.min),
                                         "labels.min > 0 for depth labels"));
  }
  if (labels.space == "disparity" && dataset.format == "strecha") {
    throw ConfigError(ViolatedConstraint("labels.space", "disparity",
                                         "depth or inverse_depth for calibrated (strecha) data; "
                                         "disparity needs rectified data"));
  }
  std::vector<std::string> seen;
  for (const auto& source : gcp.sources) {
    if (std::find(seen.begin(), seen.end(), source) != seen.end()) {
      throw ConfigError(ViolatedConstraint("gcp.sources", source, "each source listed once"));
    }
    seen.push_back(source);
    if (source == "lidar" && gcp.lidar_path.empty()) {
      throw ConfigError("gcp.sources lists lidar but gcp.lidar.path is not set");
    }
    if (source == "depth_map" && gcp.depth_map.path.empty()) {
      throw ConfigError("gcp.sources lists depth_map but gcp.depth_map.path is not set");
    }
  }
}

LoadedConfig::LoadedConfig() : schema_(std::make_unique<config::Schema>()) {
  options_.Register(schema_.get());
}

void LoadedConfig::Load(const std::string& path, const std::vector<std::string>& overrides) {
  if (!path.empty()) schema_->LoadFile(path);
  for (const auto& o : overrides) schema_->ApplyOverride(o);
  options_.Check();
}

}  // namespace gcpstereo::pipeline
