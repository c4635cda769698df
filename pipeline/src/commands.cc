// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "commands.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <CLI/CLI.hpp>

#include <nlohmann/json.hpp>
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/pipeline/memory_estimate.h"
#include "gcpstereo/pipeline/pipeline_config.h"
#include "gcpstereo/pipeline/run.h"
#include "gcpstereo/pipeline/scene.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"

namespace gcpstereo::cli {

int Run(const RunArgs& args, bool log_level_from_command_line) {
  pipeline::LoadedConfig config;
  config.Load(args.config_path, args.overrides);
  if (!log_level_from_command_line) SetLogLevel(config.options().runtime.log_level);
  if (args.fuse_only && !config.options().dataset.IsScene()) {
    throw ConfigError(
        "--fuse-only: dataset.reference is one view, not a scene (a list of views or all): there "
        "is nothing to fuse");
  }
  const pipeline::RunSummary summary =
      args.fuse_only ? pipeline::RunScene(config, args.output_dir, {/*compute_views=*/false})
                     : pipeline::RunPipeline(config, args.output_dir, args.config_path);
  std::printf("%s", summary.terminal_summary.c_str());
  std::printf("gcpstereo run: done in %.1f s, peak memory %.0f MB; outputs in %s\n",
              summary.total_seconds, summary.peak_memory_bytes / 1e6, summary.output_dir.c_str());
  return 0;
}

int Views(const ViewsArgs& args) {
  pipeline::LoadedConfig config;
  config.Load(args.config_path, args.overrides);
  const pipeline::PipelineConfig& o = config.options();
  const std::vector<pipeline::ViewJob> jobs = pipeline::PlanViewJobs(config);
  nlohmann::json views = nlohmann::json::array();
  for (const pipeline::ViewJob& job : jobs) {
    // The run's own estimate of the view's peak (memory_estimate.h): labels not known before the
    // run (labels.count auto: one per pixel of disparity) count as a quarter of the image's width,
    // neighbours not chosen yet as dataset.neighbor_count (or every other view).
    const int labels = o.labels.count ? *o.labels.count : std::max(2, job.width_px / 4);
    int neighbors = static_cast<int>(jobs.size()) - 1;
    if (o.dataset.AutoNeighbors()) {
      neighbors = o.dataset.neighbor_selection.count;
    } else if (!o.dataset.neighbors.empty()) {
      neighbors = static_cast<int>(o.dataset.neighbors.size());
    }
    const pipeline::MemoryEstimate memory = pipeline::EstimateViewMemory(
        pipeline::ViewMemoryInputOf(o, job.width_px, job.height_px, labels, neighbors));
    views.push_back({{"name", job.name},
                     {"width_px", job.width_px},
                     {"height_px", job.height_px},
                     {"memory_estimate_mb", std::ceil(memory.total_bytes() / 1e6)},
                     {"overrides", job.overrides}});
  }
  // What a job's memory and time scale with (pipeline/workflow/Snakefile): the label count
  // (null = one per pixel of disparity, known only when the view runs), the neighbours (null =
  // every other view of the data set) and the Poisson octree depth of the scene mesh.
  nlohmann::json labels = nullptr;
  if (o.labels.count) labels = *o.labels.count;
  nlohmann::json neighbors = nullptr;
  if (o.dataset.AutoNeighbors()) {
    neighbors = o.dataset.neighbor_selection.count;
  } else if (!o.dataset.neighbors.empty()) {
    neighbors = o.dataset.neighbors.size();
  }
  const nlohmann::json document = {
      {"scene", o.dataset.IsScene()}, {"labels", labels},
      {"neighbors", neighbors},       {"scene_mesh_depth", o.scene_mesh.depth},
      {"threads", o.runtime.threads}, {"views", views}};
  std::printf("%s\n", document.dump(2).c_str());
  return 0;
}

int Fuse(const FuseArgs& args) {
  pipeline::FuseRequest request;
  request.view_dirs = args.view_dirs;
  request.output_dir = args.output_dir;
  request.overrides = args.overrides;
  const pipeline::RunSummary summary = pipeline::FuseViewFolders(request);
  std::printf("%s", summary.terminal_summary.c_str());
  std::printf("gcpstereo fuse: done in %.1f s, peak memory %.0f MB; outputs in %s\n",
              summary.total_seconds, summary.peak_memory_bytes / 1e6, summary.output_dir.c_str());
  return 0;
}

int Synth(const SynthArgs& args) {
  synth::SynthOptions options;
  options.preset = args.preset;
  options.seed = args.seed;
  options.views = args.views;
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
  namespace fs = std::filesystem;
  Timer timer;
  const std::string data_dir = (fs::path(args.output_dir) / "data").string();
  std::printf("gcpstereo demo: generating the synthetic 'small' scene in %s …\n", data_dir.c_str());
  SynthArgs synth{"small", data_dir, 1};
  Synth(synth);

  // The same pipeline twice: with the GCP energy (laser GCPs at s = 16, the paper's Fountain
  // setting in miniature) and without it (the paper's baseline D). Only E_gcp differs.
  const std::vector<std::string> common = {
      "dataset.format=strecha",
      "dataset.path=" + data_dir,
      "dataset.reference=0005",
      "labels.space=depth",
      "labels.count=128",
      "gcp.sources=[lidar]",
      "gcp.lidar.path=" + (fs::path(data_dir) / "gt" / "laser.ply").string(),
      "gcp.downsample=16",
      "propagation.method=local_plane",  // as configs/synthetic_fountain.yaml
      "optimizer.tiles=[1, 1]",
      "optimizer.tile_overlap=0"};
  struct Variant {
    std::string name, title;
    bool use_gcp_energy;
  };
  const std::vector<Variant> variants = {{"with_gcps", "with the GCP energy", true},
                                         {"without_gcps", "without the GCP energy", false}};
  std::vector<nlohmann::json> reports;
  for (const Variant& v : variants) {
    std::vector<std::string> overrides = common;
    overrides.push_back(std::string("optimizer.use_gcp_energy=") +
                        (v.use_gcp_energy ? "true" : "false"));
    pipeline::LoadedConfig config;
    config.Load("", overrides);
    const std::string out = (fs::path(args.output_dir) / v.name).string();
    std::printf("gcpstereo demo: running the pipeline %s → %s\n", v.title.c_str(), out.c_str());
    const pipeline::RunSummary summary = pipeline::RunPipeline(config, out, "(demo)");
    reports.push_back(nlohmann::json::parse(summary.report_json));
  }

  std::printf(
      "\nDepth error of the reference view against the exact ground truth, in units of "
      "the simulated laser's sigma:\n");
  std::printf("  %-24s %10s %10s %10s %12s %14s\n", "", "within 1σ", "within 3σ", "within 10σ",
              "mean |err| m", "time s");
  auto row = [](const char* name, const nlohmann::json& h, double seconds) {
    const auto& w = h["within_n_sigma_percent"];
    std::printf("  %-24s %9.2f%% %9.2f%% %9.2f%% %12.4f %14s\n", name, w[0].get<double>(),
                w[2].get<double>(), w[9].get<double>(), h["mean_abs_error"].get<double>(),
                seconds > 0 ? std::to_string(seconds).substr(0, 5).c_str() : "");
  };
  row("without the GCP energy", reports[1]["metrics"]["depth_sigma"]["result"],
      reports[1]["total_seconds"].get<double>());
  row("with the GCP energy", reports[0]["metrics"]["depth_sigma"]["result"],
      reports[0]["total_seconds"].get<double>());
  row("propagated GCPs (D̂)", reports[0]["metrics"]["depth_sigma"]["propagated"], 0.0);
  std::printf("\nPictures and reports: %s/with_gcps/index.html and %s/without_gcps/index.html\n",
              args.output_dir.c_str(), args.output_dir.c_str());
  std::printf("gcpstereo demo: done in %.1f s\n", timer.ElapsedSeconds());
  return 0;
}

int Keys() {
  pipeline::LoadedConfig config;
  std::cout << "Configuration keys (YAML, dotted; set in a file or with --set KEY=VALUE):\n"
            << config.schema().Describe();
  return 0;
}

void AddEvalOptions(CLI::App* eval, EvalArgs* a) {
  eval->footer(
      "Examples:\n"
      "  gcpstereo eval --run out/fountain\n"
      "  gcpstereo eval --depth out/depth.pfm --gt-depth gt/0005.depth.pfm --gt-sigma "
      "gt/0005.sigma.pfm\n"
      "  gcpstereo eval --depth out/depth.pfm --gt-mesh laser_mesh.ply --camera 0005.jpg.camera "
      "--sigma 0.005\n"
      "  gcpstereo eval --disparity out/disparity.pfm --gt-disparity "
      "tsukuba/truedisp.row3.col3.pgm "
      "--gt-scale 16 --nonocc tsukuba/nonocc.png --all tsukuba/all.png --disc tsukuba/disc.png");
  eval->add_option("--run", a->run_folder,
                   "a finished gcpstereo run folder: scores its depth.pfm/disparity.pfm and "
                   "propagated_*.pfm (D̂) against the ground truth of its data set, and against "
                   "the held-out LiDAR points when the run held some out (eval.lidar_holdout)");
  eval->add_option("--depth", a->depth, "a depth map (PFM) to score");
  eval->add_option("--disparity", a->disparity, "a disparity map (PFM) to score");
  eval->add_option("--gt-depth", a->gt_depth, "ground-truth depth (PFM)");
  eval->add_option("--gt-sigma", a->gt_sigma, "per-pixel laser sigma (PFM)");
  eval->add_option("--sigma", a->sigma, "constant laser sigma when there is no --gt-sigma map");
  eval->add_option("--gt-mesh", a->gt_mesh, "ground-truth surface mesh (PLY, world coordinates)");
  eval->add_option("--gt-points", a->gt_points, "ground-truth point cloud (PLY/PCD, world)");
  eval->add_option("--camera", a->camera,
                   "Strecha .camera of the depth map's view (one of a larger or smaller image of "
                   "the same aspect ratio is scaled to the map; another aspect ratio is an error)");
  eval->add_option("--gt-disparity", a->gt_disparity,
                   "ground-truth disparity (PFM, or PNG/PGM divided by --gt-scale; 0 = unknown)");
  eval->add_option("--gt-disparity-right", a->gt_disparity_right,
                   "the right view's ground truth, to derive occlusion masks");
  eval->add_option("--gt-scale", a->gt_scale,
                   "divisor of integer ground-truth images "
                   "(tsukuba 16, venus 8, 2005/2006 third size 3)")
      ->capture_default_str();
  eval->add_option("--nonocc", a->mask_nonocc, "Middlebury nonocc mask (255 = counted)");
  eval->add_option("--all", a->mask_all, "Middlebury all mask");
  eval->add_option("--disc", a->mask_disc, "Middlebury disc mask");
  eval->add_option("--border", a->border_px, "ignored border of derived masks, px")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  eval->add_option("--report", a->report, "write the metrics as JSON to this file");
  eval->add_option("--figures", a->figures,
                   "write error maps and histograms (PNG) into this folder");
}

int Eval(const EvalArgs& args) {
  pipeline::RunEvaluation(args);
  return 0;
}

}  // namespace gcpstereo::cli
