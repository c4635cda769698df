// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The wall time and peak memory of each stage of a run, as report.json's "stages" lists them.
#pragma once

#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/system.h"

namespace gcpstereo::pipeline::internal {

// Records one stage's wall time and the process's peak memory after it: Done(extra) sets
// (*stages)[name] to `extra` plus "seconds" and "peak_memory_bytes_after".
class StageClock {
 public:
  StageClock(nlohmann::json* stages, std::string name) : stages_(stages), name_(std::move(name)) {
    spdlog::info("{} …", name_);
  }
  void Done(nlohmann::json extra = nlohmann::json::object()) {
    extra["seconds"] = timer_.ElapsedSeconds();
    extra["peak_memory_bytes_after"] = PeakResidentMemoryBytes();
    (*stages_)[name_] = extra;
    spdlog::info("{}: {:.2f} s", name_, extra["seconds"].get<double>());
  }

 private:
  nlohmann::json* stages_;
  std::string name_;
  Timer timer_;
};

// Runs `stage` (a callable returning a result with a `stage_report`) under a StageClock: the
// result's stage_report becomes report["stages"][name] with the time and memory added.
template <typename Stage>
auto Timed(nlohmann::json& stages, const std::string& name, Stage&& stage) {
  StageClock clock(&stages, name);
  auto result = stage();
  clock.Done(result.stage_report);
  return result;
}

}  // namespace gcpstereo::pipeline::internal
