// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// dataset.align: the similarity that puts a COLMAP model into the scan's frame (align module),
// estimated from the configuration's files and applied wherever the pipeline reads the model —
// the views' cameras (io::DatasetRequest::world_from_model), the SfM GCPs, the scene's neighbour
// selection and the fusion — so that every stage works in the scan's frame and unit.
#pragma once

#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "gcpstereo/io/colmap_io.h"
#include "gcpstereo/pipeline/pipeline_config.h"

namespace gcpstereo::pipeline::internal {

struct ModelAlignment {
  bool active = false;  // dataset.align is not none
  Eigen::Matrix4d world_from_model = Eigen::Matrix4d::Identity();
  nlohmann::json report;  // report.json "alignment"; null when not active
};

// The alignment dataset.align asks for (identity for none). Estimated once per process for the
// same inputs — model folder, method, target file (by path, size and modification time) and
// dataset.align_* options — so that a scene's views, its neighbour selection and its fusion share
// one estimate; the estimate is deterministic, so a view run alone (a cluster job) finds the same.
// Logs the result. Throws Error with the residuals when the alignment is refused
// (align::CheckAlignment), IoError for unreadable files, ConfigError for centres naming images
// the model does not have.
ModelAlignment ModelAlignmentOf(const PipelineConfig& options);

// The COLMAP model of dataset.path (colmap), moved into the aligned frame.
io::ColmapModel ReadAlignedColmapModel(const PipelineConfig& options);

}  // namespace gcpstereo::pipeline::internal
