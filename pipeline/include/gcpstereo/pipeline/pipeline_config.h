// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gcpstereo/align/similarity_alignment.h"
#include "gcpstereo/config/schema.h"
#include "gcpstereo/cost/birchfield_tomasi.h"
#include "gcpstereo/cost/label_range.h"
#include "gcpstereo/cost/plane_sweep.h"
#include "gcpstereo/cost/view_selection.h"
#include "gcpstereo/fusion/fusion.h"
#include "gcpstereo/gcp/gcp_sources.h"
#include "gcpstereo/gcp/sfm_gcps.h"
#include "gcpstereo/gcp/stereo_gcps.h"
#include "gcpstereo/gcp/sweep_motion.h"
#include "gcpstereo/mesh/meshing.h"
#include "gcpstereo/mesh/render.h"
#include "gcpstereo/mesh/surface_reconstruction.h"
#include "gcpstereo/optimize/alpha_expansion.h"
#include "gcpstereo/optimize/energy.h"
#include "gcpstereo/optimize/plane_fit.h"
#include "gcpstereo/optimize/refinement.h"
#include "gcpstereo/propagation/propagation.h"

namespace gcpstereo::pipeline {

// Keys of the `dataset:` section (../shared/CONTRACT.md).
struct DatasetOptions {
  std::string format = "strecha";  // strecha | middlebury | kitti_raw | colmap
  std::string path;                // the data set's folder (required)
  // dataset.reference: one view name, a list of names or `all` (a whole scene: every reference's
  // depth map into OUT/views/<name>/, fused into OUT/). `reference` is the single reference's name
  // (LoadedConfig::Load sets it; empty for a scene).
  std::vector<std::string> references;
  std::string reference;
  // Views used for matching; empty = all others; {"auto"} = chosen per reference from the cameras
  // (and the scan's points) by cost::SelectNeighbors, `neighbor_count` of them.
  std::vector<std::string> neighbors;
  cost::ViewSelectionOptions
      neighbor_selection;  // dataset.neighbor_count, dataset.neighbor_selection.*
  double scale = 1.0;      // image scale before processing, (0, 1]
  // dataset.align (colmap only): none = the model's own frame; scan = the similarity registering
  // the model's 3D points to the scan gcp.lidar.path; centres = the similarity fitted to the
  // known camera centres of dataset.align_centres. Every camera and 3D point is moved by it on
  // load (pipeline/src/model_alignment.h).
  std::string align = "none";
  std::string align_centres;              // dataset.align_centres: "<image name> X Y Z" lines
  align::AlignmentOptions align_options;  // dataset.align_max_residual, ..._min_inlier_share, ...

  bool AutoNeighbors() const { return neighbors.size() == 1 && neighbors.front() == "auto"; }
  // More than one reference, or `all`.
  bool IsScene() const {
    return references.size() > 1 || (references.size() == 1 && references.front() == "all");
  }
};

// Keys of the `eval.scene.` section: the ground truth of a whole scene's model.
struct SceneEvalOptions {
  // A mesh (PLY) and/or a point cloud (PLY/PCD: a laser scan) of the true surface in world
  // coordinates; empty = <dataset.path>/gt/mesh.ply and gt/laser.ply when they exist (the
  // synthetic sets).
  std::string gt_mesh;
  std::string gt_points;
  bool view_histograms = true;  // the σ-histogram of the scene mesh in every view with GT depth
  int max_samples = 1'000'000;  // eval.scene.max_samples: samples per surface compared
};

// Keys of the `labels:` section.
struct LabelOptions {
  std::string space = "depth";  // depth | inverse_depth | disparity
  // Number of discrete hypotheses (the paper: 360 depth levels); absent = one per disparity pixel
  // (labels.space disparity only).
  std::optional<int> count = 360;
  std::optional<double> min;  // in the space's unit; absent = automatic
  std::optional<double> max;
};

struct DepthMapGcpOptions {
  std::string path;            // PFM, or 8/16-bit PNG/PGM of the reference view
  std::string kind = "depth";  // depth | disparity
  double scale = 1.0;          // integer images: value = stored / scale
  double sigma = 0.0;          // measurement standard deviation (depth unit); 0 = unknown
};

// Keys of the `gcp:` section.
struct GcpOptions {
  std::vector<std::string> sources;      // lidar | depth_map | stereo | sfm; empty = no GCP energy
  std::string lidar_path;                // gcp.lidar.path
  DepthMapGcpOptions depth_map;          // gcp.depth_map.*
  int downsample = 16;                   // s: one GCP per s×s block (paper: 16 → ≈0.4 %)
  gcp::LidarGcpOptions lidar;            // gcp.lidar.*
  gcp::LidarMotionOptions lidar_motion;  // gcp.lidar.motion.*: the sweep's motion compensation
  gcp::StereoGcpOptions stereo;          // gcp.stereo.*
  gcp::SfmGcpOptions sfm;                // gcp.sfm.*: a COLMAP model's points (colmap)
};

// Keys of the `cost:` section.
struct CostOptions {
  // auto = Birchfield–Tomasi for a rectified pair (one neighbour), plane sweep otherwise.
  std::string method = "auto";  // auto | plane_sweep | birchfield_tomasi
  cost::PlaneSweepOptions plane_sweep;
  cost::BirchfieldTomasiOptions birchfield_tomasi;
};

// Keys of the `optimizer:` section handed to the optimize module.
struct OptimizerOptions {
  // graph_cuts = the global energy (the paper); wta = winner-take-all of the costs alone (the
  // simplest result, for comparison and for measuring the cost stage).
  std::string method = "graph_cuts";
  optimize::EnergyOptions energy;
  optimize::ExpansionOptions expansion;
  optimize::RefinementOptions refinement;
  std::string candidate_labels = "local";  // all | local | prior
  std::string initialization = "wta";      // wta | prior
  std::string refinement_method = "irls";  // none | parabola | ceres | irls
  std::string blend = "mean";              // mean | feather
  // optimizer.prior_radius_px: E_gcp only where a GCP lies within this distance (pixels of the
  // processing resolution); elsewhere D̂ is an extrapolation over textureless areas and the data
  // and smoothness terms decide. 0 = everywhere (the paper). Range >= 0.
  double prior_radius_px = 0.0;
  // optimizer.prior_segment_k: E_gcp only in the colour segments (graph-based segmentation of the
  // reference with this scale k, as the plane fit's) that hold a GCP; in the others D̂ is an
  // extrapolation across a colour edge. 0 = off (the paper). Range >= 0.
  double prior_segment_k = 0.0;
  // optimizer.left_right_check: rectified pairs only (Birchfield–Tomasi cost). Solves the pair a
  // second time with the neighbour as reference and replaces the reference pixels whose two
  // disparities differ by more than left_right_max_difference_px by the background side of their
  // row: removes the foreground fattening into half-occluded bands. Doubles the optimisation time.
  bool left_right_check = false;
  double left_right_max_difference_px = 1.0;
  // Before the median: a filled pixel takes back its optimised value when the nearest GCP within
  // this radius is closer to it than to the fill (optimize::RestoreGcpConfirmed); 0 = off.
  int left_right_gcp_radius_px = 0;
  // Then a colour-weighted median over the filled pixels (optimize::WeightedMedianOfFilled):
  // window half-size (0 = off) and colour sigma (intensities in [0, 1]).
  int left_right_median_radius_px = 0;
  double left_right_median_sigma = 0.1;
  // optimizer.plane_fit: rectified data only. After the optimisation (and the left-right check),
  // the reference image is over-segmented by colour and the pixels of a segment that lie nearer
  // than the segment's robustly fitted disparity plane take the plane's value
  // (optimize/plane_fit.h).
  bool plane_fit = false;
  optimize::PlaneFitOptions plane_fit_options;
};

// Keys of the `optimizer:` section that the pipeline itself reads.
struct TilingOptions {
  std::vector<int> tiles{2, 2};  // [rows, cols] (paper: 2 × 2)
  int tile_overlap = 16;         // pixels (paper: 16)
};

struct RuntimeOptions {
  int threads = 0;  // worker threads; 0 = all cores
  std::string log_level = "info";
  std::string stop_after = "all";  // load | gcps | propagation | all
  double max_memory_gb = 0.0;      // refuse a view estimated above this; 0 = the memory available
};

// Keys of the `eval:` section.
struct EvalOptions {
  // Split the LiDAR scan by an 8×8-pixel checkerboard of blocks: one half are GCPs, the other
  // half scores the result (KITTI-style bad-3), as no dense ground truth exists.
  bool lidar_holdout = false;
  // The same split of the reference's structure-from-motion points (COLMAP data sets): one half
  // may feed the sfm GCP source, the other half scores the depth map by relative depth error.
  bool sfm_holdout = false;
  int holdout_block_px = 8;
  SceneEvalOptions scene;  // eval.scene.*
};

struct OutputOptions {
  bool previews = true;  // write the *.png previews and index.html
  bool mesh = true;      // write mesh.ply and mesh.obj
  bool points = false;   // also write points.ply (one coloured point per valid pixel)
  // also write colmap/: a COLMAP dense workspace holding the depth maps (colmap_export.h)
  bool colmap = false;
};

// Keys of the `mesh:` section.
struct MeshOptions {
  mesh::MeshingOptions meshing;
  mesh::MeshRenderOptions preview;
  double preview_yaw_deg = 30.0;  // viewpoint of mesh.png, rotated about the median vertex
  double preview_pitch_deg = 15.0;
};

// The whole configuration of `gcpstereo run`.
struct PipelineConfig {
  DatasetOptions dataset;
  LabelOptions labels;
  GcpOptions gcp;
  TilingOptions tiling;
  CostOptions cost;
  cost::LabelRangeOptions label_range;  // labels.auto.*
  propagation::PropagationOptions propagation;
  OptimizerOptions optimizer;
  MeshOptions mesh;
  EvalOptions eval;
  RuntimeOptions runtime;
  OutputOptions output;
  fusion::FusionOptions fusion;      // fusion.*: the scene's depth-map fusion
  bool fusion_include_gcps = false;  // fusion.include_gcps: the views' GCPs join the fused cloud
  // fusion.input: the views' depth.pfm (depth), or their propagated_depth.pfm (propagated: D̂
  // alone, e.g. views run with runtime.stop_after: propagation).
  std::string fusion_input = "depth";
  mesh::SurfaceOptions scene_mesh;  // scene_mesh.*: the scene's surface reconstruction

  // Registers every key with `schema` (bound to this object's fields, which must outlive it).
  void Register(config::Schema* schema);
  // Cross-key checks after loading (required keys present, min < max, …); throws ConfigError.
  void Check() const;
};

// A loaded configuration: the options and the schema that filled them (for effective_config.yaml).
class LoadedConfig {
 public:
  LoadedConfig();
  // The schema points into options_: neither copied nor moved.
  LoadedConfig(const LoadedConfig&) = delete;
  LoadedConfig& operator=(const LoadedConfig&) = delete;
  // Applies the file (if not empty) and then each KEY=VALUE override, then Check()s.
  void Load(const std::string& path, const std::vector<std::string>& overrides);
  const PipelineConfig& options() const { return options_; }
  PipelineConfig& mutable_options() { return options_; }
  const config::Schema& schema() const { return *schema_; }
  // The same file and overrides, then `more` overrides: a view's configuration in a scene.
  std::unique_ptr<LoadedConfig> WithOverrides(const std::vector<std::string>& more) const;
  const std::string& path() const { return path_; }
  const std::vector<std::string>& overrides() const { return overrides_; }
  // dataset.neighbors: auto: how the neighbours were chosen (cost::ViewSelection::ToJson), for
  // the view's report.json (dataset.neighbor_selection); null otherwise.
  const nlohmann::json& neighbor_selection() const { return neighbor_selection_; }
  void set_neighbor_selection(nlohmann::json selection) {
    neighbor_selection_ = std::move(selection);
  }

 private:
  PipelineConfig options_;
  std::unique_ptr<config::Schema> schema_;
  std::string path_;
  std::vector<std::string> overrides_;
  nlohmann::json neighbor_selection_;
};

}  // namespace gcpstereo::pipeline
