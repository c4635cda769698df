// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The parts of the scene layer (scene.cc) that run.cc and the tests reach.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gcpstereo/pipeline/output_folder.h"
#include "gcpstereo/pipeline/pipeline_config.h"

namespace gcpstereo::pipeline {

// dataset.neighbors: auto for one reference: the same configuration with the chosen neighbours
// as a list, the choice (cost::ViewSelection) attached for the view's report.json.
std::unique_ptr<LoadedConfig> ConfigWithChosenNeighbors(const LoadedConfig& config);

namespace internal {

// Fusion, scene mesh and scene evaluation of finished view folders, written into `out` (staged):
// fused.ply, mesh.ply, mesh.obj and the pictures (their names appended to `images`). Returns the
// report's fields (dataset, fusion, scene_mesh, metrics, stages).
nlohmann::json FuseMeshEvaluate(const std::vector<std::string>& view_dirs,
                                const PipelineConfig& options, OutputFolder& out,
                                std::vector<std::string>* images);
// A view's line in the scene's report, from its report.json.
nlohmann::json ViewSummary(const std::string& name, const std::string& dir,
                           const std::string& status);
std::string SceneHtml(const nlohmann::json& report, const std::vector<std::string>& images,
                      const std::string& output_dir);
std::string SceneTerminalSummary(const nlohmann::json& report);

}  // namespace internal
}  // namespace gcpstereo::pipeline
