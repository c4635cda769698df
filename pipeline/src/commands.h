// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The subcommands of the gcpstereo executable. Each returns the process exit status and throws
// gcpstereo::Error for bad input (main() prints it as one line).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gcpstereo/pipeline/evaluate.h"

namespace CLI {
class App;
}

namespace gcpstereo::cli {

struct RunArgs {
  std::string config_path;
  std::string output_dir;
  std::vector<std::string> overrides;
  bool fuse_only = false;  // a scene run that computes no view (SceneRunOptions::compute_views)
};
int Run(const RunArgs& args, bool log_level_from_command_line);

// `gcpstereo views CONFIG [--set]...`: the run's views as jobs of their own (PlanViewJobs), one
// JSON document on stdout.
struct ViewsArgs {
  std::string config_path;
  std::vector<std::string> overrides;
};
int Views(const ViewsArgs& args);

struct FuseArgs {
  std::vector<std::string> view_dirs;
  std::string output_dir;
  std::vector<std::string> overrides;
};
int Fuse(const FuseArgs& args);

struct SynthArgs {
  std::string preset;
  std::string output_dir;
  std::uint64_t seed = 1;
  int views = 0;  // 0 = the preset's cameras (synth::SynthOptions::views)
};
int Synth(const SynthArgs& args);

struct DemoArgs {
  std::string output_dir = "gcpstereo-demo";
};
int Demo(const DemoArgs& args);

int Keys();

using EvalArgs = pipeline::EvalRequest;
void AddEvalOptions(CLI::App* eval, EvalArgs* args);
int Eval(const EvalArgs& args);

}  // namespace gcpstereo::cli
