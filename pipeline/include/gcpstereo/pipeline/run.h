// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include "gcpstereo/pipeline/pipeline_config.h"

namespace gcpstereo::pipeline {

// What a run prints at the end and what the demo compares.
struct RunSummary {
  std::string output_dir;
  double total_seconds = 0.0;
  std::size_t peak_memory_bytes = 0;
  std::string report_json;       // the report.json text
  std::string terminal_summary;  // GCP counts and metrics tables for the terminal
};

// Runs the pipeline described by `config` and writes the outputs into `output_dir`
// (../shared/CONTRACT.md, "Output files"). Throws Error on bad input; on any error no output
// file is left under its final name.
RunSummary RunPipeline(const LoadedConfig& config, const std::string& output_dir,
                       const std::string& config_path);

}  // namespace gcpstereo::pipeline
