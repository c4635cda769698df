// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "commands.h"

#include <cstdio>
#include <iostream>

#include <CLI/CLI.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/pipeline/pipeline_config.h"
#include "gcpstereo/pipeline/run.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"

namespace gcpstereo::cli {

int Run(const RunArgs& args, bool log_level_from_command_line) {
  pipeline::LoadedConfig config;
  config.Load(args.config_path, args.overrides);
  if (!log_level_from_command_line) SetLogLevel(config.options().runtime.log_level);
  const pipeline::RunSummary summary =
      pipeline::RunPipeline(config, args.output_dir, args.config_path);
  std::printf("gcpstereo run: done in %.1f s, peak memory %.0f MB; outputs in %s\n",
              summary.total_seconds, summary.peak_memory_bytes / 1e6, summary.output_dir.c_str());
  return 0;
}

int Synth(const SynthArgs& args) {
  synth::SynthOptions options;
  options.preset = args.preset;
  options.seed = args.seed;
  options.Check();
  synth::SyntheticScene scene;
  {
    ProgressBar bar("synth " + args.preset, 1000);
    scene = synth::GenerateScene(options, bar.AsCallback());
  }
  synth::WriteScene(scene, options, args.output_dir);
  const synth::SynthSummary& s = scene.summary;
  std::printf(
      "gcpstereo synth: %d views of %dx%d (reference %s, depth %.2f…%.2f m), %lld laser points, "
      "%lld mesh faces in %.1f s -> %s\n",
      s.num_views, s.width, s.height, s.reference_name.c_str(), s.reference_depth_min_m,
      s.reference_depth_max_m, static_cast<long long>(s.laser_points),
      static_cast<long long>(s.mesh_faces), s.total_seconds, args.output_dir.c_str());
  return 0;
}

int Demo(const DemoArgs& args) {
  throw Error("demo: needs the synthetic scene generator, which is not built into this version yet");
}

int Keys() {
  pipeline::LoadedConfig config;
  std::cout << "Configuration keys (YAML, dotted; set in a file or with --set KEY=VALUE):\n"
            << config.schema().Describe();
  return 0;
}

void AddEvalOptions(CLI::App* eval, EvalArgs* args) {
  eval->add_option("--output-folder", args->output_folder, "a finished gcpstereo run's folder");
}

int Eval(const EvalArgs& args) {
  throw Error("eval: the evaluation module is not built into this version yet");
}

}  // namespace gcpstereo::cli
