// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// One reference view's run, for the layers that compose it (`gcpstereo run`, a whole scene).
#pragma once

#include <string>

#include "gcpstereo/pipeline/output_folder.h"
#include "gcpstereo/pipeline/pipeline_config.h"
#include "gcpstereo/pipeline/run.h"

namespace gcpstereo::pipeline::internal {

// Runs one reference view's pipeline into `out` (committing it), as `gcpstereo run` does for a
// single reference: the stages of view_stages.h, then the outputs (../shared/CONTRACT.md) and
// report.json. Throws Error on bad input; `out` is then left uncommitted. Logging to a file is
// the caller's (RunPipeline adds run.log).
RunSummary RunViewInFolder(const LoadedConfig& config, OutputFolder& out,
                           const std::string& config_path);

}  // namespace gcpstereo::pipeline::internal
