// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The gcpstereo command line (../shared/CONTRACT.md): run, fuse, views, synth, eval, demo, keys.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/propagation/sparse_solver.h"
#include "gcpstereo/synth/generator.h"

namespace {

// Errors are one line on stderr: flatten any newline a message may contain.
std::string OneLine(std::string s) {
  for (char& c : s) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return s;
}

// The -o/--output of run, synth and demo. An empty path ("-o ''", an unset shell variable) is no
// folder: run failed with ": cannot create output folder: Invalid argument", and synth and demo
// wrote their files into the working folder. "." names that folder when it is meant.
const CLI::Validator kOutputFolder(
    [](std::string& path) {
      return path.empty() ? std::string("the output folder path is empty") : std::string();
    },
    "");

}  // namespace

int main(int argc, char** argv) {
  // Progress messages to stdout, warnings and errors to stderr.
  gcpstereo::InstallConsoleLogger();
  gcpstereo::propagation::UseHugePagesInSuiteSparse();  // before any thread uses SuiteSparse

  CLI::App app{
      "gcpstereo — dense depth maps and meshes from calibrated images and sparse ground control "
      "points\n(Wang & Yang, \"Global Stereo Matching Leveraged by Sparse Ground Control Points\", "
      "CVPR 2011)"};
  app.require_subcommand(1);
  app.fallthrough();  // -q and --log-level may follow the subcommand too
  app.set_version_flag("--version", std::string("gcpstereo ") + GCPSTEREO_VERSION);
  bool quiet = false;
  std::string log_level;
  app.add_flag("-q,--quiet", quiet, "no progress bars, warnings and errors only");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off (default info)");

  gcpstereo::cli::RunArgs run_args;
  CLI::App* run = app.add_subcommand("run", "run the pipeline described by a YAML configuration");
  run->add_option("config", run_args.config_path, "configuration file (YAML); see configs/")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("-o,--output", run_args.output_dir, "output folder (created if missing)")
      ->required()
      ->check(kOutputFolder);
  run->add_option("--set", run_args.overrides,
                  "override one dotted key, KEY=VALUE with VALUE parsed as YAML "
                  "(e.g. --set dataset.neighbors=[im1,im3]); repeatable");
  run->add_flag("--fuse-only", run_args.fuse_only,
                "scene runs: compute no view; fuse the complete folders under OUTDIR/views/ "
                "(computed apart, e.g. by pipeline/workflow/Snakefile) and report the others as "
                "failed");
  run->footer(
      "Every configuration key, with its default, range and unit: gcpstereo keys\n"
      "Outputs: depth.pfm, disparity.pfm (rectified data), gcps.ply, mesh.ply, mesh.obj, "
      "report.json,\neffective_config.yaml, *.png previews, index.html and run.log.");

  gcpstereo::cli::ViewsArgs views_args;
  CLI::App* views = app.add_subcommand(
      "views",
      "print, as JSON, the views a run's configuration stands for, each with its image size and "
      "the --set overrides that run it alone (one job per view: pipeline/workflow/Snakefile)");
  views->add_option("config", views_args.config_path, "configuration file (YAML); see configs/")
      ->required()
      ->check(CLI::ExistingFile);
  views->add_option("--set", views_args.overrides,
                    "override one dotted key, KEY=VALUE, as for run; repeatable");

  gcpstereo::cli::FuseArgs fuse_args;
  CLI::App* fuse = app.add_subcommand(
      "fuse",
      "fuse finished per-view output folders into one scene model (what a scene run does after "
      "its views)");
  fuse->add_option("views", fuse_args.view_dirs, "per-view output folders (OUT/views/NAME)")
      ->required()
      ->check(CLI::ExistingDirectory);
  fuse->add_option("-o,--output", fuse_args.output_dir, "output folder (created if missing)")
      ->required()
      ->check(kOutputFolder);
  fuse->add_option("--set", fuse_args.overrides,
                   "override one dotted key of the first view's configuration, KEY=VALUE "
                   "(fusion.*, scene_mesh.*, eval.scene.*); repeatable");
  fuse->footer(
      "Outputs: fused.ply, mesh.ply, mesh.obj, report.json, effective_config.yaml, index.html, "
      "*.png\npictures and run.log. Folders of different scenes or cameras are refused.");

  gcpstereo::cli::SynthArgs synth_args;
  CLI::App* synth =
      app.add_subcommand("synth", "write a synthetic data set with exact ground truth");
  synth
      ->add_option("--preset", synth_args.preset,
                   "tiny (5 views, 160x107), small (7 views, 640x427) or fountain "
                   "(11 views, 1536x1024)")
      ->required()
      ->check(CLI::IsMember({"tiny", "small", "fountain"}));
  synth->add_option("-o,--output", synth_args.output_dir, "output folder")
      ->required()
      ->check(kOutputFolder);
  synth->add_option("--seed", synth_args.seed, "random seed (same seed, same bytes)")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const bool digits = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
              return c >= '0' && c <= '9';
            });
            if (!digits) return "a non-negative integer, got " + text;
            try {
              (void)std::stoull(text);
            } catch (const std::out_of_range&) {
              return "at most 18446744073709551615, got " + text;
            }
            return std::string();
          },
          "UINT64"));

  synth
      ->add_option("--views", synth_args.views,
                   "number of views: 0 = the preset's cameras; N = " +
                       std::to_string(gcpstereo::synth::kMinSynthViews) + ".." +
                       std::to_string(gcpstereo::synth::kMaxSynthViews) +
                       " cameras evenly spaced over the preset's arc, named in arc order, the "
                       "reference 0005 the head-on one or, past 5 left of it, the sixth")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            int views = -1;
            try {
              size_t used = 0;
              views = std::stoi(text, &used);
              if (used != text.size()) views = -1;
            } catch (const std::exception&) {
              views = -1;
            }
            if (gcpstereo::synth::IsValidSynthViews(views)) return std::string();
            return "0 (the preset's cameras) or " +
                   std::to_string(gcpstereo::synth::kMinSynthViews) + ".." +
                   std::to_string(gcpstereo::synth::kMaxSynthViews) + ", got " + text;
          },
          "INT"));

  gcpstereo::cli::DemoArgs demo_args;
  CLI::App* demo = app.add_subcommand(
      "demo",
      "generate the synthetic small scene and run the full pipeline on it, with evaluation");
  demo->add_option("-o,--output", demo_args.output_dir, "output folder")
      ->capture_default_str()
      ->check(kOutputFolder);

  CLI::App* keys = app.add_subcommand("keys",
                                      "list every configuration key with its default, "
                                      "range, unit and meaning");

  gcpstereo::cli::EvalArgs eval_args;
  CLI::App* eval = app.add_subcommand(
      "eval", "score a depth or disparity map (or a finished output folder) against ground truth");
  gcpstereo::cli::AddEvalOptions(eval, &eval_args);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help: usage on stdout
    // One line on stderr, as for every other error.
    std::fprintf(stderr, "gcpstereo: error: %s (gcpstereo --help lists the commands and options)\n",
                 OneLine(e.what()).c_str());
    return e.get_exit_code();
  }

  try {
    gcpstereo::SetProgressBarsEnabled(!quiet);
    gcpstereo::SetLogLevel(!log_level.empty() ? log_level : (quiet ? "warn" : "info"));
    if (run->parsed()) return gcpstereo::cli::Run(run_args, !log_level.empty() || quiet);
    if (fuse->parsed()) return gcpstereo::cli::Fuse(fuse_args);
    if (views->parsed()) {
      // stdout carries the JSON alone: info messages and progress bars off.
      gcpstereo::SetProgressBarsEnabled(false);
      if (log_level.empty()) gcpstereo::SetLogLevel("warn");
      return gcpstereo::cli::Views(views_args);
    }
    if (synth->parsed()) return gcpstereo::cli::Synth(synth_args);
    if (demo->parsed()) return gcpstereo::cli::Demo(demo_args);
    if (keys->parsed()) return gcpstereo::cli::Keys();
    if (eval->parsed()) return gcpstereo::cli::Eval(eval_args);
  } catch (const gcpstereo::Error& e) {
    std::fprintf(stderr, "gcpstereo: error: %s\n", OneLine(e.what()).c_str());
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // A folder or file the user named cannot be created or moved: name it.
    std::fprintf(stderr, "gcpstereo: error: %s: %s\n", e.path1().string().c_str(),
                 e.code().message().c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gcpstereo: internal error: %s\n", OneLine(e.what()).c_str());
    return 2;
  }
  return 0;
}
