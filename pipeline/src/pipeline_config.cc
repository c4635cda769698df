// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/pipeline_config.h"

#include <algorithm>
#include <sstream>
#include <string>

#include "gcpstereo/core/error.h"
#include "gcpstereo/cost/cost_filter.h"

namespace gcpstereo::pipeline {

using config::KeyDoc;
using config::Range;

namespace {

// The keys <prefix>window_px, <prefix>window_filter, <prefix>guided_epsilon of one cost's window
// aggregation (the names CostFilterOptions::Check(prefix) reports); `what` names the cost.
void AddCostFilterKeys(config::Schema* s, const std::string& prefix, const std::string& what,
                       cost::CostFilterOptions* window) {
  s->Add(prefix + "window_px", &window->window_px, Range::Between(1, 101),
         {what + ": aggregation window side (odd; 1 = pixel-wise, the paper)", "px"});
  s->Add(prefix + "window_filter", &window->filter, {"box", "guided"},
         {what + ": window mean (box) or edge-preserving guided filter (He et al.)"});
  s->Add(prefix + "guided_epsilon", &window->guided_epsilon, Range::GreaterThan(0.0),
         {what + ": guided-filter regularisation ε of He et al. (not the paper's ε), "
                 "intensities in [0, 1]"});
}

}  // namespace

void PipelineConfig::Register(config::Schema* s) {
  s->Add("dataset.format", &dataset.format, {"strecha", "middlebury", "kitti_raw", "colmap"},
         {"data set layout: strecha (images/ + cameras/*.camera; also the synthetic sets), "
          "middlebury (official file names), kitti_raw (a drive folder), colmap (a COLMAP "
          "workspace: images/ + sparse/ with cameras, images, points3D as .bin or .txt; "
          "distorting camera models are undistorted on load)"});
  s->Add("dataset.path", &dataset.path, {},
         {"the data set's folder (kitti_raw: <date>/<date>_drive_NNNN_sync); relative paths are "
          "relative to the working directory"});
  s->AddListOrScalar(
      "dataset.reference", &dataset.references, {},
      {"reference view: strecha 0005; middlebury im2, scene1.row3.col3, view1; kitti_raw the "
       "frame 0000000010; colmap the model's image name, 0005.jpg. A list of names or all = a "
       "whole scene: each reference's depth map into OUT/views/<name>/, fused and meshed into "
       "OUT/ (strecha, middlebury, colmap)"});
  s->AddListOrScalar("dataset.neighbors", &dataset.neighbors, {"auto"},
                     {"views used for matching; empty = all other views; auto = the "
                      "dataset.neighbor_count best by triangulation angle and shared visible area, "
                      "scored on the laser scan's points, a COLMAP model's 3D points (colmap) or "
                      "the cameras' frusta (ignored for kitti_raw)"});
  s->Add("dataset.neighbor_count", &dataset.neighbor_selection.count, Range::Between(1, 64),
         {"dataset.neighbors: auto: how many neighbours each reference gets (fewer when fewer "
          "views see its scene)"});
  s->Add("dataset.neighbor_selection.min_angle_deg", &dataset.neighbor_selection.min_angle_deg,
         Range{0.0, 90.0, false, false},
         {"dataset.neighbors: auto: triangulation angle below which a shared point counts nothing "
          "(a near-duplicate view)",
          "deg", "θ_min"});
  s->Add("dataset.neighbor_selection.optimal_angle_deg",
         &dataset.neighbor_selection.optimal_angle_deg, Range{0.0, 90.0, false, false},
         {"dataset.neighbors: auto: triangulation angle from which a shared point counts fully",
          "deg", "θ_opt"});
  s->Add("dataset.neighbor_selection.max_angle_deg", &dataset.neighbor_selection.max_angle_deg,
         Range{0.0, 90.0, false, false},
         {"dataset.neighbors: auto: triangulation angle beyond which a shared point counts less "
          "and less (the views see the surface too differently)",
          "deg", "θ_max"});
  s->Add("dataset.neighbor_selection.grid_step_px", &dataset.neighbor_selection.grid_step_px,
         Range::Between(1, 1024),
         {"dataset.neighbors: auto without scan points: reference pixels sampled every n", "px"});
  s->Add("dataset.scale", &dataset.scale, Range{0.0, 1.0, false, true},
         {"image scale before processing (fountain-P11 in the paper: 0.5)"});
  s->Add("dataset.align", &dataset.align, {"none", "scan", "centres"},
         {"colmap: put the model (arbitrary frame and scale) into a scan's frame by a similarity "
          "(scale, rotation, translation) applied to every camera and 3D point on load: none = "
          "the model's own frame; scan = registered to the scan gcp.lidar.path (its 3D points: "
          "principal-axes hypotheses, then scale-aware trimmed ICP); centres = fitted (RANSAC, "
          "Umeyama) to the known camera centres of dataset.align_centres. Depths, labels.min/max, "
          "gcp.lidar.* and fusion distances are then in the scan's unit. A poor alignment is an "
          "error giving its residuals (dataset.align_max_residual, ...)"});
  s->Add("dataset.align_centres", &dataset.align_centres, {},
         {"dataset.align: centres: a text file of known camera centres in the target frame, one "
          "'<image name> X Y Z' per line (COLMAP model_aligner's convention; # comments); at "
          "least 3 non-collinear centres of the model's images"});
  s->Add("dataset.align_max_residual", &dataset.align_options.max_residual, Range::GreaterThan(0.0),
         {"dataset.align: a model point within this of its nearest scan point (a camera centre "
          "within this of its known position) is an inlier; the median residual must not exceed "
          "it; scan: nor may restarts from perturbed poses that fit as well move a camera centre "
          "further (ambiguity)",
          "m"});
  s->Add("dataset.align_min_inlier_share", &dataset.align_options.min_inlier_share,
         Range::Between(0.0, 1.0),
         {"dataset.align: refuse the alignment when fewer model points (centres) are inliers"});
  s->Add("dataset.align_max_relative_residual", &dataset.align_options.max_relative_residual,
         Range{0.0, 1.0, false, true},
         {"dataset.align: scan: refuse the alignment when the median residual exceeds this "
          "fraction of the aligned model's spread (RMS distance of its points from their "
          "centroid): a model shrunk onto a wrong scan fits in scan units, not relative to its "
          "size"});
  s->Add("dataset.align_ransac_iterations", &dataset.align_options.ransac_iterations,
         Range::Between(1, 1000000),
         {"dataset.align: centres: RANSAC samples of three centres (every triple when there are "
          "fewer)"});
  s->Add("dataset.align_max_model_points", &dataset.align_options.max_model_points,
         Range::Between(3, 10000000),
         {"dataset.align: scan: the model's 3D points registered, at most this many (every k-th)"});

  s->Add("labels.space", &labels.space, {"depth", "inverse_depth", "disparity"},
         {"spacing of the discrete hypotheses; disparity only for rectified data"});
  s->Add("labels.count", &labels.count, Range::Between(2, 4096),
         {"number of discrete hypotheses (paper: 360 depth levels); auto = one per pixel of "
          "disparity (labels.space disparity)"});
  s->Add("labels.min", &labels.min, Range::AtLeast(0.0),
         {"lowest hypothesis in the space's unit (depth: data set unit, the scan's after "
          "dataset.align; disparity: px in the ground truth's convention); auto = from a range "
          "sensor's GCPs, else from the views' "
          "matched disparities and stereo GCPs (disparity labels: 0), else the views' overlap"});
  s->Add("labels.max", &labels.max, Range::AtLeast(0.0),
         {"highest hypothesis; auto as labels.min"});

  s->Add("gcp.sources", &gcp.sources, {"lidar", "depth_map", "stereo", "sfm"},
         {"GCP sources; empty list = no GCP energy (the paper's baseline); sfm = the 3D points "
          "of a COLMAP model (dataset.format colmap) that the reference observes"});
  s->Add(
      "gcp.lidar.path", &gcp.lidar_path, {},
      {"point cloud (.ply, .pcd, KITTI .bin): world frame for strecha and colmap, sensor frame for "
       "kitti_raw (the scan of the dataset.reference frame: a file named after another frame "
       "warns)"});
  s->Add("gcp.depth_map.path", &gcp.depth_map.path, {},
         {"depth or disparity image of the reference view (PFM, 8/16-bit PNG/PGM; 0 or non-finite "
          "= no measurement)"});
  s->Add("gcp.depth_map.kind", &gcp.depth_map.kind, {"depth", "disparity"},
         {"what gcp.depth_map.path holds"});
  s->Add("gcp.depth_map.scale", &gcp.depth_map.scale, Range::GreaterThan(0.0),
         {"integer images: value = stored / scale"});
  s->Add("gcp.depth_map.sigma", &gcp.depth_map.sigma, Range::AtLeast(0.0),
         {"standard deviation of the depth-map measurements (depth unit); 0 = unknown", "m"});
  s->Add("gcp.downsample", &gcp.downsample, Range::Between(1, 1024),
         {"keep one measurement per s×s pixel block, nearest the block centre (paper: 16, i.e. "
          "≈0.4 %)",
          "px", "s"});

  s->Add("labels.auto.gcp_low_percentile", &label_range.gcp_low_percentile, Range::Between(0, 100),
         {"automatic range from GCPs: lower percentile of their depths", "%"});
  s->Add("labels.auto.gcp_high_percentile", &label_range.gcp_high_percentile,
         Range::Between(0, 100), {"automatic range from GCPs: upper percentile", "%"});
  s->Add("labels.auto.margin", &label_range.margin, Range::AtLeast(0.0),
         {"automatic range: widen the span by this fraction on each side"});
  s->Add("labels.auto.grid_step_px", &label_range.grid_step_px, Range::Between(1, 1024),
         {"automatic range from the views' overlap: reference rays sampled every n pixels", "px"});
  s->Add("labels.auto.min_neighbors", &label_range.min_neighbors, Range::AtLeast(1),
         {"automatic range from the views' overlap: depths seen by at least this many neighbours"});
  s->Add("labels.auto.max_depth", &label_range.max_depth, Range::GreaterThanOrInfinite(0.0),
         {"automatic range: never beyond this depth (data set unit)", "m"});
  s->Add("labels.auto.matching_far_percentile", &label_range.matching_far_percentile,
         Range::HalfOpen(0, 50),
         {"depth labels without GCPs: when the matched disparities reach 0 (an unbounded far end), "
          "the far end is taken at this percentile of them (0 = fail instead)",
          "%"});

  // gcp.lidar.* and gcp.stereo.*: the gcp module's options (see gcp_sources.h, stereo_gcps.h).
  s->Add("gcp.lidar.consistency_radius_px", &gcp.lidar.consistency_radius_px, Range::Between(0, 20),
         {"half-size of the window of the depth-consistency test (0 = z-buffer only)", "px"});
  s->Add("gcp.lidar.max_surface_slant_deg", &gcp.lidar.max_surface_slant_deg,
         Range{0.0, 90.0, false, false},
         {"steepest surface slant the consistency test tolerates", "deg"});
  s->Add("gcp.lidar.depth_tolerance", &gcp.lidar.depth_tolerance, Range::AtLeast(0.0),
         {"absolute depth tolerance of the consistency test", "m"});
  s->Add("gcp.lidar.sigma_multiplier", &gcp.lidar.sigma_multiplier, Range::AtLeast(0.0),
         {"multiple of a point's sigma added to the consistency tolerance"});
  s->Add("gcp.lidar.default_sigma", &gcp.lidar.default_sigma, Range::AtLeast(0.0),
         {"sigma of points whose cloud carries none (HDL-64E ≈ 0.02)", "m"});
  s->Add("gcp.lidar.min_depth", &gcp.lidar.min_depth, Range::AtLeast(0.0),
         {"ignore points nearer than this depth", "m"});
  s->Add("gcp.sfm.min_track_length", &gcp.sfm.min_track_length, Range::AtLeast(2),
         {"sfm: drop model points observed in fewer images (the reference included)"});
  s->Add("gcp.sfm.max_error_px", &gcp.sfm.max_error_px, Range::GreaterThan(0.0),
         {"sfm: drop model points whose mean reprojection error (COLMAP's ERROR, pixels of the "
          "model's images) is larger",
          "px"});
  s->Add("gcp.sfm.min_angle_deg", &gcp.sfm.min_angle_deg, Range{0.0, 90.0, false, false},
         {"sfm: drop model points whose widest triangulation angle with the reference's ray is "
          "smaller (ill-determined depth)",
          "deg"});
  s->Add("gcp.sfm.projected", &gcp.sfm.projected,
         {"sfm: also the model points the reference does not observe but that project into it "
          "and pass the lidar source's visibility tests (gcp.lidar.consistency_radius_px, ...); "
          "off: a sparse cloud does not hide what lies behind a nearer surface from those tests"});
  s->Add("gcp.sfm.min_error_px", &gcp.sfm.min_error_px, Range::GreaterThan(0.0),
         {"sfm: smallest image error the GCP sigma assumes, sigma = min over the other observers "
          "i of d_i (e / f) / sin(theta_i), e = max(ERROR, this)",
          "px"});
  s->Add("gcp.lidar.motion.mode", &gcp.lidar_motion.mode, {"off", "given", "registration"},
         {"motion compensation of a spinning scanner's sweep (kitti_raw): off; given = "
          "gcp.lidar.motion.speed_mps and yaw_rate_deg_s; registration = ego-motion from ICP "
          "with the drive's nearest earlier and later scans"});
  s->Add("gcp.lidar.motion.speed_mps", &gcp.lidar_motion.speed_mps, Range::Between(-100.0, 100.0),
         {"mode given: the sensor's speed along its +x (forward) axis", "m/s"});
  s->Add(
      "gcp.lidar.motion.yaw_rate_deg_s", &gcp.lidar_motion.yaw_rate_deg_s,
      Range::Between(-360.0, 360.0),
      {"mode given: the sensor's yaw rate, counter-clockwise seen from above positive", "deg/s"});
  s->Add("gcp.lidar.motion.max_gap_s", &gcp.lidar_motion.max_gap_s, Range::GreaterThan(0.0),
         {"mode registration: use scans at most this far in time from the reference's", "s"});
  s->Add("gcp.lidar.motion.min_inlier_fraction", &gcp.lidar_motion.registration.min_inlier_fraction,
         Range::Between(0.0, 1.0),
         {"mode registration: a registration with fewer points within 0.3 m of the other scan "
          "is not used"});
  s->Add("gcp.lidar.motion.sweep_period_s", &gcp.lidar_motion.sweep.period_s,
         Range::GreaterThan(0.0), {"duration of one revolution (HDL-64E in KITTI: 0.1)", "s"});
  s->Add("gcp.lidar.motion.clockwise", &gcp.lidar_motion.sweep.clockwise,
         {"the scanner turns clockwise seen from above (Velodyne scanners do)"});
  s->Add("gcp.lidar.motion.trigger_azimuth_deg", &gcp.lidar_motion.sweep.trigger_azimuth_deg,
         Range::Between(-180.0, 180.0),
         {"the scanner's azimuth when the camera exposes, from +x towards +y (KITTI: 0)", "deg"});
  s->Add("gcp.stereo.max_spread_px", &gcp.stereo.max_spread_px, Range::Between(0, 10),
         {"the three WTA disparities (BT, NCC, adaptive weights) must agree within this", "px"});
  s->Add("gcp.stereo.lr_tolerance_px", &gcp.stereo.lr_tolerance_px, Range::Between(0, 10),
         {"left-right check tolerance", "px"});
  s->Add("gcp.stereo.canny_low", &gcp.stereo.canny_low, Range::AtLeast(0.0),
         {"Canny lower threshold (grey levels)"});
  s->Add("gcp.stereo.canny_high", &gcp.stereo.canny_high, Range::AtLeast(0.0),
         {"Canny upper threshold (grey levels)"});
  s->Add("gcp.stereo.edge_margin_px", &gcp.stereo.edge_margin_px, Range::Between(0, 20),
         {"drop candidates within this distance of a Canny edge", "px"});
  s->Add("gcp.stereo.ncc_window_px", &gcp.stereo.ncc_window_px, Range::Between(3, 15),
         {"NCC window side, odd (paper: 5)", "px"});
  s->Add("gcp.stereo.aw_window_px", &gcp.stereo.aw_window_px, Range::Between(3, 71),
         {"adaptive-weight window side, odd", "px"});
  s->Add("gcp.stereo.aw_stride_px", &gcp.stereo.aw_stride_px, Range::Between(1, 4),
         {"adaptive-weight window sampling stride (speed approximation)", "px"});
  s->Add("gcp.stereo.aw_gamma_c", &gcp.stereo.aw_gamma_c, Range::GreaterThan(0.0),
         {"adaptive-weight colour bandwidth (Yoon & Kweon: 5)", "", "γc"});
  s->Add("gcp.stereo.aw_gamma_p", &gcp.stereo.aw_gamma_p, Range::GreaterThan(0.0),
         {"adaptive-weight spatial bandwidth (Yoon & Kweon: 17.5)", "px", "γp"});
  s->Add("gcp.stereo.aw_truncation", &gcp.stereo.aw_truncation, Range::GreaterThan(0.0),
         {"adaptive-weight cost truncation (Yoon & Kweon: 40)"});
  s->Add("gcp.stereo.sigma_px", &gcp.stereo.sigma_px, Range::AtLeast(0.0),
         {"standard deviation attributed to a stereo GCP", "px"});
  s->Add("gcp.stereo.min_uniqueness_aw", &gcp.stereo.min_uniqueness_aw,
         Range{0.0, 1.0, true, false},
         {"adaptive-weight WTA uniqueness (c2 - c1) / c2 must reach this (0 = off)"});
  s->Add("gcp.stereo.min_uniqueness_ncc", &gcp.stereo.min_uniqueness_ncc,
         Range{0.0, 1.0, true, false},
         {"NCC WTA uniqueness (cost 1 - ncc) must reach this (0 = off)"});
  s->Add("gcp.stereo.min_uniqueness_bt", &gcp.stereo.min_uniqueness_bt,
         Range{0.0, 1.0, true, false},
         {"Birchfield-Tomasi WTA uniqueness must reach this (0 = off)"});
  s->Add("gcp.stereo.min_texture_std", &gcp.stereo.min_texture_std, Range::Between(0.0, 128.0),
         {"grey-level standard deviation in the texture window must reach this (0 = off)",
          "grey levels"});
  s->Add("gcp.stereo.texture_window_px", &gcp.stereo.texture_window_px, Range::Between(3, 31),
         {"texture test window side, odd", "px"});
  s->Add("gcp.stereo.occlusion_margin_px", &gcp.stereo.occlusion_margin_px, Range::Between(-1, 50),
         {"drop matches in or within this margin of a band occluded in the other view (-1 = off)",
          "px"});
  s->Add("gcp.stereo.value", &gcp.stereo.value, {"median", "ncc"},
         {"disparity given to a GCP: median of the three WTAs or the NCC WTA"});
  s->Add("gcp.stereo.image_scale", &gcp.stereo.image_scale, Range{0.0, 1.0, false, true},
         {"calibrated views: match at this fraction of the processing resolution, then map the "
          "GCPs back (1 = full)"});
  s->Add("gcp.stereo.max_neighbors", &gcp.stereo.max_neighbors, Range::Between(1, 20),
         {"calibrated views: neighbours rectified with the reference and matched"});
  s->Add("gcp.stereo.min_confirmations", &gcp.stereo.min_confirmations, Range::Between(0, 19),
         {"calibrated views: other pairs that must confirm a GCP's depth"});
  s->Add("gcp.stereo.confirm_radius_px", &gcp.stereo.confirm_radius_px, Range::Between(0, 10),
         {"calibrated views: search radius of a confirmation", "px"});
  s->Add("gcp.stereo.refine_px", &gcp.stereo.refine_px, Range::Between(0.0, 10.0),
         {"calibrated views: search each GCP's depth again on the plane-sweep cost, within this "
          "many pixels of its match's disparity at the matching scale (0 = off)",
          "px"});
  s->Add("gcp.stereo.refine_window_px", &gcp.stereo.refine_window_px, Range::Between(1, 15),
         {"calibrated views: side of the square over which that cost is averaged, odd", "px"});
  s->Add("gcp.stereo.confirm_sigma", &gcp.stereo.confirm_sigma, Range::GreaterThan(0.0),
         {"calibrated views: depths agree within this many combined sigmas"});

  s->Add("cost.method", &cost.method, {"auto", "plane_sweep", "birchfield_tomasi"},
         {"matching cost: auto = Birchfield–Tomasi for a rectified pair, plane sweep otherwise"});
  s->Add(
      "cost.truncation", &cost.plane_sweep.truncation, Range::GreaterThan(0.0),
      {"plane sweep: per-neighbour truncation of the RGB difference norm", "RGB grey levels", "τ"});
  s->Add("cost.sweep_measure", &cost.plane_sweep.measure, {"rgb", "zncc"},
         {"plane sweep: photo-consistency of a sample: rgb = the pixel's truncated RGB difference "
          "(paper), zncc = windowed zero-mean normalised cross-correlation of grey levels "
          "(exposure-invariant), cost τ·min(1, 1 − ρ)"});
  s->Add("cost.zncc_window_px", &cost.plane_sweep.zncc_window_px, Range::Between(3, 21),
         {"plane sweep: side of the zncc window, odd", "px"});
  s->Add("cost.zncc_flat_fallback", &cost.plane_sweep.zncc_flat_fallback,
         {"plane sweep, zncc: in a flat reference window, where a correlation sees nothing, the "
          "cost moves to the difference of the window means (truncated at τ/√3 grey levels): "
          "Φ = τ·[(1 − w)·min(1, 1 − ρ) + w·min(1, |Δμ|√3/τ)], w = ε/(σ² + ε), ε = 4 grey²"});
  s->Add("cost.aggregation", &cost.plane_sweep.aggregation, {"mean", "best_k"},
         {"plane sweep: mean over the neighbours (paper) or mean of the best k (occlusions)"});
  s->Add("cost.best_k", &cost.plane_sweep.best_k, Range::AtLeast(1),
         {"plane sweep: k of best_k aggregation"});
  s->Add("cost.min_voters", &cost.plane_sweep.min_voters, Range::AtLeast(1),
         {"plane sweep: neighbours that must see a sample for it to have data"});
  s->Add("cost.bt_truncation", &cost.birchfield_tomasi.truncation, Range::GreaterThan(0.0),
         {"Birchfield–Tomasi: truncation of the summed RGB dissimilarity", "grey levels"});
  s->Add("cost.bt_channels", &cost.birchfield_tomasi.channels, {"sum", "max"},
         {"Birchfield–Tomasi: combine the RGB channels by sum or max"});
  s->Add("cost.census_window_px", &cost.birchfield_tomasi.census_window_px, Range::Between(1, 7),
         {"rectified pair: census window side added to BT (odd; 1 = BT alone, the paper)", "px"});
  s->Add("cost.census_weight", &cost.birchfield_tomasi.census_weight, Range::AtLeast(0.0),
         {"rectified pair: cost of one differing census bit", "grey levels"});
  s->Add("cost.census_mask_threshold", &cost.birchfield_tomasi.census_mask_threshold,
         Range::Between(0, 255),
         {"rectified pair: census bits only from neighbours within this many grey levels of the "
          "centre in the reference image, scaled to the full count (0 = every bit): neighbours "
          "across a depth edge no longer pull the cost toward the other surface",
          "grey levels"});
  AddCostFilterKeys(s, "cost.", "rectified pair", &cost.birchfield_tomasi.window);
  AddCostFilterKeys(s, "cost.sweep_", "plane sweep", &cost.plane_sweep.window);

  s->Add("propagation.method", &propagation.method,
         {"linear_system", "weighted_median", "local_plane"},
         {"linear_system = the paper's eq. 5 (a smooth, edge-aware interpolation); weighted_median "
          "= each pixel takes the colour- and distance-weighted median of the GCPs in its window "
          "(keeps thin foreground and depth edges of dense GCPs such as a LiDAR scan; no prior "
          "farther than the radius from every GCP); local_plane = each pixel takes its value on a "
          "robust colour- and distance-weighted plane through the GCPs in its window, fitted in "
          "disparity or inverse depth (slanted surfaces between sparse GCPs such as a laser at "
          "s = 16; no prior farther than the radius from every GCP)"});
  s->Add("propagation.plane_radius_px", &propagation.plane_radius_px, Range::Between(1, 100),
         {"local_plane: radius of the round window of GCPs", "px"});
  s->Add("propagation.plane_sigma_px", &propagation.plane_sigma_px, Range::GreaterThan(0.0),
         {"local_plane: spatial bandwidth of the weights exp(-d^2/(2 sigma^2))", "px"});
  s->Add("propagation.plane_sigma_colour", &propagation.plane_sigma_colour, Range::GreaterThan(0.0),
         {"local_plane: colour bandwidth of the weights exp(-|ΔRGB|^2/(2 sigma^2))", "RGB"});
  s->Add("propagation.median_radius_px", &propagation.median_radius_px, Range::Between(1, 100),
         {"weighted_median: half-size of the window of GCPs", "px"});
  s->Add("propagation.median_sigma_px", &propagation.median_sigma_px, Range::GreaterThan(0.0),
         {"weighted_median: spatial bandwidth of the weights exp(-d^2/(2 sigma^2))", "px"});
  s->Add("propagation.median_sigma_colour", &propagation.median_sigma_colour,
         Range::GreaterThan(0.0),
         {"weighted_median: colour bandwidth of the weights exp(-|ΔRGB|^2/(2 sigma^2))", "RGB"});
  s->Add("propagation.median_colour_floor", &propagation.median_colour_floor, Range::Between(0, 1),
         {"weighted_median: share of its spatial weight a GCP keeps however different its colour, "
          "w = w_s (floor + (1 - floor) w_c); 0 = the colour weight alone, 1 = spatial weights "
          "only"});
  s->Add("propagation.median_edge_stretch", &propagation.median_edge_stretch,
         Range::Between(1, 100),
         {"weighted_median: the distance across the local depth edge (the gradient of the "
          "least-squares plane through the window's GCPs) counts this many times in the squared "
          "distance of the spatial weight; 1 = isotropic"});
  s->Add("propagation.gamma", &propagation.gamma, Range::GreaterThan(0.0),
         {"colour bandwidth of the affinities w = exp(−|ΔRGB|/γ) (paper: 1.25; measured best: 4)",
          "RGB", "γ"});
  s->Add("propagation.epsilon", &propagation.epsilon, Range::HalfOpen(0.0, 1.0),
         {"lower bound of the affinities (paper: 0 for edge-preserving interpolation)", "", "ε"});
  s->Add("propagation.min_weight", &propagation.min_weight, Range::Between(0.0, 1.0),
         {"links weaker than this are cut (regions without a GCP are then reported unreached); 0 = "
          "none"});
  s->Add("propagation.solver", &propagation.solver, {"umfpack", "cholmod"},
         {"sparse solver: CHOLMOD on the symmetric form of eq. 5 (same solution to 1e-6, about "
          "twice as fast), or UMFPACK on eq. 5 as in the paper"});
  s->Add("propagation.ordering", &propagation.ordering, {"nested_dissection", "amd"},
         {"fill-reducing ordering: geometric nested dissection of the grid, or amd = the "
          "solver's own approximate minimum degree"});

  s->Add("optimizer.method", &optimizer.method, {"graph_cuts", "wta"},
         {"graph_cuts = minimise E_data + E_smooth + E_gcp (the paper); wta = winner-take-all of "
          "the matching costs alone (no smoothness, no GCP energy, no refinement)"});
  s->Add("optimizer.lambda_s", &optimizer.energy.lambda_s, Range::AtLeast(0.0),
         {"smoothness weight of eq. 3, each 4-neighbour pair counted once (the paper's 20 with its "
          "double sum = 40)",
          "energy per label step", "λs"});
  s->Add("optimizer.truncation", &optimizer.energy.truncation, Range::GreaterThan(0.0),
         {"truncation of the linear smoothness penalty (paper: 2)", "label steps", "T"});
  s->Add("optimizer.gamma_c", &optimizer.energy.gamma_c, Range::GreaterThan(0.0),
         {"colour bandwidth of the smoothness weights, eq. 4 (paper: 3.6)", "RGB", "γc"});
  s->Add("optimizer.epsilon", &optimizer.energy.epsilon, Range::Between(0.0, 1.0),
         {"lower bound of the smoothness weights, eq. 4 (paper: 0.3)", "", "ε"});
  s->Add("optimizer.lambda_r", &optimizer.energy.lambda_r, Range::AtLeast(0.0),
         {"weight of the GCP energy, eq. 8 (paper: 8)", "", "λr"});
  s->Add("optimizer.gamma_d", &optimizer.energy.gamma_d, Range::GreaterThan(0.0),
         {"sharpness of the robust GCP penalty, eq. 7 (paper: 2)", "label steps", "γd"});
  s->Add("optimizer.eta", &optimizer.energy.eta, Range{0.0, 1.0, false, false},
         {"upper-bound control of the robust GCP penalty, eq. 7 (lost from the paper's text; "
          "measured: 0.5)",
          "", "η"});
  s->Add("optimizer.gcp_confidence", &optimizer.energy.gcp_confidence, Range::Between(0.0, 1.0),
         {"how far each pixel's data confidence (the peak ratio of its cost curve, 0 flat … 1 one "
          "sharp minimum) lowers its GCP weight: λr·(1 − β·c_p); 0 = the paper's one λr for every "
          "pixel",
          "", "β"});
  s->Add("optimizer.gcp_confidence_radius", &optimizer.energy.gcp_confidence_radius,
         Range::Between(0, 10),
         {"radius of the window whose averaged costs give the data confidence of "
          "optimizer.gcp_confidence (0 = the pixel's own cost curve)",
          "px"});
  s->Add("optimizer.gcp_spread", &optimizer.energy.gcp_spread, Range::AtLeast(0.0),
         {"τ of eq. 10: how the GCPs' spread about a local plane (σ_p, the weighted RMS residual "
          "of the plane through the GCPs around the pixel) lowers its GCP weight: λr·ρ_p, ρ_p = "
          "1/(1 + σ_p²/τ²), so the prior yields where the GCPs disagree (gated by the data "
          "confidence: optimizer.gcp_spread_gated); 0 = the paper's one λr for every pixel",
          "label steps", "τ"});
  s->Add("optimizer.gcp_spread_sigma_px", &optimizer.energy.gcp_spread_sigma_px,
         Range::Between(1.0, 50.0),
         {"σw of eq. 10: the Gaussian window over which optimizer.gcp_spread fits the plane "
          "(it reaches 3σw)",
          "px"});
  s->Add("optimizer.gcp_spread_gated", &optimizer.energy.gcp_spread_gated,
         {"let optimizer.gcp_spread lower the GCP weight only as far as the pixel's data are "
          "decisive: 1 − c_p·(1 − ρ_p), c_p the data confidence of optimizer.gcp_confidence "
          "(over optimizer.gcp_confidence_radius); false = ρ_p everywhere"});
  s->Add("optimizer.gcp_spread_sigma_colour", &optimizer.energy.gcp_spread_sigma_colour,
         Range::AtLeast(0.0),
         {"σc of eq. 10: the colour bandwidth of the weights of optimizer.gcp_spread's plane, so "
          "that it keeps to the pixel's surface as D̂ does (0, the default = spatial weights only)",
          "RGB", "σc"});
  s->Add("optimizer.data_weight", &optimizer.energy.data_weight, Range::GreaterThan(0.0),
         {"scale of the matching costs in the energy"});
  s->Add("optimizer.use_gcp_energy", &optimizer.energy.use_gcp_energy,
         {"include E_gcp (false = the paper's baseline D, even with GCPs configured)"});
  s->Add("optimizer.prior_radius_px", &optimizer.prior_radius_px, Range::AtLeast(0.0),
         {"E_gcp only within this distance of a GCP (0 = everywhere, the paper)", "px"});
  s->Add("optimizer.prior_segment_k", &optimizer.prior_segment_k, Range::AtLeast(0.0),
         {"E_gcp only in the colour segments that hold a GCP (graph-based segmentation of the "
          "reference with this scale k; larger k, larger segments); 0 = everywhere (the paper)"});
  s->Add("optimizer.left_right_check", &optimizer.left_right_check,
         {"rectified pairs: solve again with the neighbour as reference and fill the pixels whose "
          "disparities disagree from the background side of their row (doubles the optimisation "
          "time)"});
  s->Add(
      "optimizer.left_right_max_difference_px", &optimizer.left_right_max_difference_px,
      Range::AtLeast(0.0),
      {"largest disparity difference between the two views that still counts as consistent", "px"});
  s->Add(
      "optimizer.left_right_gcp_radius_px", &optimizer.left_right_gcp_radius_px,
      Range::Between(0, 100),
      {"after the left-right fill, a filled pixel keeps its optimised value when the nearest GCP "
       "within this radius is closer to that value than to the fill's (0 = off): thin "
       "foreground the other view lost stays where the GCPs measure it",
       "px"});
  s->Add("optimizer.left_right_median_radius_px", &optimizer.left_right_median_radius_px,
         Range::Between(0, 50),
         {"after the left-right fill, a colour-weighted median over the filled pixels in a "
          "(2r+1)² window (0 = off): removes the fill's streaks and puts its edges on image edges",
          "px"});
  s->Add("optimizer.left_right_median_sigma", &optimizer.left_right_median_sigma,
         Range::GreaterThan(0.0),
         {"colour sigma of that median's weights exp(-|I_p - I_q|^2 / sigma^2), intensities in "
          "[0, 1]"});
  s->Add(
      "optimizer.plane_fit", &optimizer.plane_fit,
      {"rectified pairs: after the optimisation, over-segment the reference image by colour, fit "
       "a disparity plane to each segment robustly, and give the plane's value to the pixels of "
       "the segment that lie off it (foreground fattening, mismatches in weak texture); with "
       "the left-right check, consistent pixels support the fit and occluded ones are kept"});
  s->Add("optimizer.plane_fit_segment_k", &optimizer.plane_fit_options.segmentation.k,
         Range::GreaterThan(0.0),
         {"scale k of the graph-based colour segmentation (Felzenszwalb-Huttenlocher): larger k, "
          "larger segments"});
  s->Add("optimizer.plane_fit_min_segment_px",
         &optimizer.plane_fit_options.segmentation.min_segment_px, Range::Between(1, 100000),
         {"smallest colour segment; smaller ones are merged into a neighbour", "px"});
  s->Add("optimizer.plane_fit_inlier_px", &optimizer.plane_fit_options.inlier_px,
         Range::GreaterThan(0.0),
         {"a pixel within this disparity distance of its segment's plane lies on it", "px"});
  s->Add("optimizer.plane_fit_min_inlier_fraction",
         &optimizer.plane_fit_options.min_inlier_fraction, Range::Between(0.5, 1.0),
         {"share of a segment's support pixels that must lie on its plane for the plane to be used "
          "(support: the left-right consistent pixels when the check runs, else all)"});
  s->Add("optimizer.plane_fit_replace_all", &optimizer.plane_fit_options.replace_all,
         {"every pixel of a fitted segment takes the plane's value, not only those off it (still "
          "only nearer ones with plane_fit_only_farther)"});
  s->Add("optimizer.plane_fit_only_farther", &optimizer.plane_fit_options.only_farther,
         {"only pixels nearer than their segment's plane (larger disparity) take its value: "
          "foreground fattened over the segment"});
  s->Add("optimizer.max_cycles", &optimizer.expansion.max_cycles, Range::AtLeast(1),
         {"maximum α-expansion cycles over all labels"});
  s->Add("optimizer.convergence_tolerance", &optimizer.expansion.convergence_tolerance,
         Range::HalfOpen(0.0, 1.0),
         {"stop when a cycle lowers the energy by less than this fraction (0 = until no move "
          "improves)"});
  s->Add("optimizer.candidate_labels", &optimizer.candidate_labels, {"all", "local", "prior"},
         {"α-moves over all labels (all), per block over labels near the block's WTA votes and D̂ "
          "(local), or near D̂ and the start labels only (prior: for a dense, trusted D̂ such as "
          "a LiDAR scan's, with optimizer.initialization prior; without a prior — no GCPs, or "
          "optimizer.use_gcp_energy false — the same as local)"});
  s->Add("optimizer.candidate_block", &optimizer.expansion.candidate_block_px, Range::AtLeast(4),
         {"block side of the local candidate sets", "px"});
  s->Add("optimizer.candidate_radius", &optimizer.expansion.candidate_radius, Range::AtLeast(0),
         {"labels within this many steps of a voted label are candidates", "label steps"});
  s->Add("optimizer.candidate_min_votes", &optimizer.expansion.candidate_min_votes,
         Range::AtLeast(1), {"WTA votes that make a label a candidate"});
  s->Add("optimizer.candidate_min_confidence", &optimizer.expansion.candidate_min_confidence,
         Range::HalfOpen(0.0, 1.0),
         {"pixels whose cost-curve peak ratio is below this neither vote for candidate labels nor "
          "start from their own WTA label (they start from D̂, else the nearest confident "
          "pixel's label): flat costs such as sky stop making every label a candidate; 0 = off"});
  s->Add("optimizer.candidate_confidence_radius", &optimizer.expansion.candidate_confidence_radius,
         Range::Between(0, 10), {"window radius of that confidence", "px"});
  s->Add("optimizer.skip_unchanged_labels", &optimizer.expansion.skip_unchanged_labels,
         {"skip α-moves that cannot find a different cut (exact)"});
  s->Add("optimizer.prune_pixels", &optimizer.expansion.prune_pixels,
         {"leave out of a move pixels that provably keep their label (exact)"});
  s->Add("optimizer.retry_changed_blocks_only", &optimizer.expansion.retry_changed_blocks_only,
         {"when a label comes round again, try it only near blocks that changed since its last "
          "try (approximation; energy gap measured by the optimize benchmark)"});
  s->Add("optimizer.initialization", &optimizer.initialization, {"wta", "prior"},
         {"initial labelling: winner-take-all, or the propagated D̂ where it exists"});
  s->Add("optimizer.blend", &optimizer.blend, {"mean", "feather"},
         {"merging of the tile overlaps: mean (paper) or linear feathering"});
  s->Add("optimizer.refinement", &optimizer.refinement_method,
         {"none", "parabola", "ceres", "irls"},
         {"sub-label refinement after graph cuts: none, parabola (data only), or the joint "
          "continuous problem solved by irls (iteratively reweighted least squares) or ceres "
          "(Levenberg-Marquardt; same objective, slower)"});
  s->Add("optimizer.refinement_iterations", &optimizer.refinement.max_iterations, Range::AtLeast(1),
         {"irls/ceres refinement: maximum iterations"});
  s->Add("optimizer.refinement_huber", &optimizer.refinement.smoothness_huber,
         Range::GreaterThan(0.0),
         {"irls/ceres refinement: Huber width of the smoothness term", "label steps"});
  s->Add("optimizer.refinement_min_curvature", &optimizer.refinement.min_data_curvature,
         Range::GreaterThan(0.0),
         {"irls/ceres refinement: smallest curvature of the local data model"});

  s->Add("optimizer.tiles", &tiling.tiles, 2, Range::Between(1, 64),
         {"[rows, cols] of tiles for graph cuts (paper: [2, 2])"});
  s->Add("optimizer.tile_overlap", &tiling.tile_overlap, Range::Between(0, 1024),
         {"overlap between neighbouring tiles (paper: 16)", "px"});

  s->Add("mesh.max_depth_ratio", &mesh.meshing.max_depth_ratio, Range::Between(0.0, 10.0),
         {"drop a triangle whose largest/smallest vertex depth exceeds 1 + this (a depth "
          "discontinuity); 0 = off"});
  s->Add(
      "mesh.max_view_angle_deg", &mesh.meshing.max_view_angle_deg, Range{0.0, 90.0, false, true},
      {"drop a triangle seen more obliquely than this (normal vs viewing ray); 90 = off", "deg"});
  s->Add("mesh.stride", &mesh.meshing.stride_px, Range::Between(1, 1024),
         {"one vertex every n pixels", "px"});
  s->Add("mesh.preview.mode", &mesh.preview.mode, {"color", "shaded", "color_shaded"},
         {"mesh.png: vertex colours, headlight shading, or both"});
  s->Add("mesh.preview.yaw_deg", &mesh.preview_yaw_deg, Range::Between(-180.0, 180.0),
         {"mesh.png viewpoint: rotation about the vertical through the median vertex", "deg"});
  s->Add("mesh.preview.pitch_deg", &mesh.preview_pitch_deg, Range::Between(-89.0, 89.0),
         {"mesh.png viewpoint: elevation", "deg"});
  s->Add("mesh.preview.supersampling", &mesh.preview.supersampling, Range::Between(1, 4),
         {"mesh.png anti-aliasing samples per pixel side"});

  s->Add("eval.scene.gt_mesh", &eval.scene.gt_mesh, {},
         {"whole scenes: the true surface as a PLY mesh (world coordinates) for accuracy, "
          "completeness and F-score; empty = <dataset.path>/gt/mesh.ply when it exists"});
  s->Add("eval.scene.gt_points", &eval.scene.gt_points, {},
         {"whole scenes: a laser scan of the surface (PLY/PCD, world coordinates) scored against "
          "too; empty = <dataset.path>/gt/laser.ply when it exists"});
  s->Add("eval.scene.max_samples", &eval.scene.max_samples, Range::Between(1000, 100000000),
         {"whole scenes: at most this many samples of each surface compared (the mesh sampled "
          "every 2.5 mm, the fused points themselves, up to this count)"});
  s->Add("eval.scene.view_histograms", &eval.scene.view_histograms,
         {"whole scenes: the σ-histogram of the scene mesh rendered into every view with "
          "ground-truth depth and sigma"});

  // fusion.*: the scene's depth-map fusion (fusion/fusion.h).
  s->Add("fusion.min_views", &fusion.min_views, Range::Between(1, 64),
         {"keep a pixel's point where at least this many views (its own included) agree on it"});
  s->Add("fusion.depth_tolerance", &fusion.depth_tolerance, Range{0.0, 1.0, false, true},
         {"agreement: relative depth difference |z − z'| / z' at most this"});
  s->Add("fusion.normal_tolerance_deg", &fusion.normal_tolerance_deg,
         Range{0.0, 180.0, false, true},
         {"agreement: angle between the two depth maps' normals at most this", "deg"});
  s->Add("fusion.normal_radius_px", &fusion.normal_radius_px, Range::Between(1, 16),
         {"the depth maps' normals from neighbours this far on each side (larger = less noise)",
          "px"});
  s->Add("fusion.stride_px", &fusion.stride_px, Range::Between(1, 64),
         {"source pixels sampled every n pixels (1 = all)", "px"});
  s->Add("fusion.input", &fusion_input, {"depth", "propagated"},
         {"what is fused of each view: its depth.pfm, or its propagated_depth.pfm (D̂ alone, "
          "from views run with runtime.stop_after: propagation)"});
  s->Add("fusion.include_gcps", &fusion_include_gcps,
         {"the views' GCPs (gcps.ply) join the fused cloud with their sigma"});

  // scene_mesh.*: the scene's surface reconstruction (mesh/surface_reconstruction.h).
  s->Add("scene_mesh.depth", &scene_mesh.depth, Range::Between(5, 14),
         {"octree depth of the screened Poisson reconstruction: finest cell 1.1 × the cloud's "
          "largest side / 2^depth (finer = more detail, slower)"});
  s->Add("scene_mesh.point_weight", &scene_mesh.point_weight, Range::Between(0.0, 1000.0),
         {"screening weight of screened Poisson (pulls the surface onto the points); 0 = "
          "unscreened",
          "", "α"});
  s->Add("scene_mesh.trim_distance", &scene_mesh.trim_distance, Range::AtLeast(0.0),
         {"remove faces with a vertex farther than this from every fused point (the closed "
          "Poisson surface over holes and far from the data); 0 = automatic, max(4 × median "
          "point spacing, 2 × finest cell)",
          "m"});

  s->Add("eval.lidar_holdout", &eval.lidar_holdout,
         {"score against held-out LiDAR points: a checkerboard of blocks splits the projected "
          "scan into GCPs and scoring points"});
  s->Add("eval.sfm_holdout", &eval.sfm_holdout,
         {"score against held-out structure-from-motion points (colmap data sets): the same "
          "checkerboard splits the points the reference observes into sfm GCP candidates and "
          "scoring points (relative depth error above 1, 2 and 5 %, median)"});
  s->Add("eval.holdout_block_px", &eval.holdout_block_px, Range::Between(1, 256),
         {"block side of the held-out checkerboard", "px"});

  s->Add("runtime.threads", &runtime.threads, Range::Between(0, 1024),
         {"worker threads; 0 = all cores. Results do not depend on it"});
  s->Add("runtime.max_memory_gb", &runtime.max_memory_gb, Range::AtLeast(0.0),
         {"refuse a view whose estimated peak memory (report.json memory_estimate, made before "
          "the propagation, cost volumes and graphs are allocated) exceeds this; 0 = the memory "
          "available on the machine (/proc/meminfo MemAvailable). More optimizer.tiles, a smaller "
          "dataset.scale or fewer labels.count lower the estimate",
          "GB"});
  s->Add("runtime.log_level", &runtime.log_level,
         {"trace", "debug", "info", "warn", "error", "off"}, {"terminal log level"});

  s->Add("runtime.stop_after", &runtime.stop_after, {"load", "gcps", "propagation", "all"},
         {"stop after this stage (report.json and effective_config.yaml are still written): "
          "load checks the data set and range data, gcps also builds the GCPs, propagation "
          "also writes D̂ (propagated_depth.pfm, propagated_disparity.pfm) with its metrics and "
          "previews: a dense map from the range data alone, without stereo"});

  s->Add("output.previews", &output.previews, {"write the PNG previews and index.html"});
  s->Add("output.mesh", &output.mesh, {"write mesh.ply and mesh.obj (world coordinates)"});
  s->Add("output.points", &output.points,
         {"also write points.ply: one coloured 3D point per valid pixel (world coordinates)"});
  s->Add("output.colmap", &output.colmap,
         {"also write colmap/: a COLMAP dense workspace (images/, sparse/ as text, "
          "stereo/depth_maps and normal_maps/*.geometric.bin, fusion.cfg, patch-match.cfg) "
          "holding the depth maps, for colmap stereo_fusion and poisson_mesher; a scene's "
          "OUT/colmap holds every view. strecha, colmap and kitti_raw (calibrated cameras)"});
}

void PipelineConfig::Check() const {
  // The stage options' own checks (cross-field constraints; ranges are checked while loading).
  gcp.lidar.Check();
  gcp.lidar_motion.Check();
  gcp.stereo.Check();
  gcp.sfm.Check();
  cost.plane_sweep.Check();
  cost.birchfield_tomasi.Check();
  label_range.Check();
  propagation.Check();
  optimizer.energy.Check();
  optimizer.expansion.Check();
  optimizer.refinement.Check();
  mesh.meshing.Check();
  mesh.preview.Check();
  if (dataset.path.empty()) {
    throw ConfigError("dataset.path is required (the data set's folder)");
  }
  if (dataset.references.empty() && dataset.reference.empty()) {
    throw ConfigError("dataset.reference is required (the reference view's name, a list or all)");
  }
  for (size_t i = 0; i < dataset.references.size(); ++i) {
    const std::string& name = dataset.references[i];
    if (name.empty()) {
      throw ConfigError(ViolatedConstraint("dataset.reference", "''", "a view name"));
    }
    if (name == "all" && dataset.references.size() > 1) {
      throw ConfigError(ViolatedConstraint("dataset.reference", "[..., all, ...]",
                                           "all alone, or a list of view names"));
    }
    if (std::find(dataset.references.begin(), dataset.references.begin() + i, name) !=
        dataset.references.begin() + i) {
      throw ConfigError(ViolatedConstraint("dataset.reference", name, "each view listed once"));
    }
  }
  if (dataset.IsScene() && dataset.format == "kitti_raw") {
    throw ConfigError(ViolatedConstraint(
        "dataset.reference", dataset.references.size() > 1 ? "a list" : "all",
        "one frame for kitti_raw (the drive's poses are not read, so its frames share no world "
        "frame to fuse in): run the frames one by one"));
  }
  if (dataset.neighbors.size() > 1 && std::find(dataset.neighbors.begin(), dataset.neighbors.end(),
                                                "auto") != dataset.neighbors.end()) {
    throw ConfigError(ViolatedConstraint("dataset.neighbors", "[..., auto, ...]",
                                         "auto alone, or a list of view names"));
  }
  dataset.neighbor_selection.Check();
  dataset.align_options.Check();
  if (dataset.align != "none" && dataset.format != "colmap") {
    throw ConfigError(ViolatedConstraint(
        "dataset.align", dataset.align,
        "none unless dataset.format is colmap (only a COLMAP model lives in a frame of its own; "
        "here: " +
            dataset.format + ")"));
  }
  if (dataset.align == "scan" && gcp.lidar_path.empty()) {
    throw ConfigError(
        "dataset.align = scan needs the scan: set gcp.lidar.path (the point cloud in the target "
        "frame)");
  }
  if (dataset.align == "centres" && dataset.align_centres.empty()) {
    throw ConfigError(
        "dataset.align = centres needs dataset.align_centres (a file of '<image name> X Y Z' "
        "lines)");
  }
  if (dataset.align != "centres" && !dataset.align_centres.empty()) {
    throw ConfigError(
        ViolatedConstraint("dataset.align_centres", dataset.align_centres,
                           "set only with dataset.align: centres (here: " + dataset.align + ")"));
  }
  fusion.Check();
  scene_mesh.Check();
  if (labels.min && labels.max && !(*labels.min < *labels.max)) {
    std::ostringstream s;
    s << *labels.min << ", " << *labels.max;
    throw ConfigError(ViolatedConstraint("labels.min, labels.max", s.str(), "min < max"));
  }
  if (labels.space == "depth" && labels.min && !(*labels.min > 0.0)) {
    throw ConfigError(ViolatedConstraint("labels.min", std::to_string(*labels.min),
                                         "labels.min > 0 for depth labels"));
  }
  if (labels.space == "disparity" && (dataset.format == "strecha" || dataset.format == "colmap")) {
    throw ConfigError(ViolatedConstraint("labels.space", "disparity",
                                         "depth or inverse_depth for calibrated (strecha, colmap) "
                                         "data; "
                                         "disparity needs rectified data"));
  }
  if (output.colmap && dataset.format == "middlebury") {
    throw ConfigError(ViolatedConstraint(
        "output.colmap", "true",
        "false for middlebury (it publishes no camera calibration: its cameras and depths are in "
        "arbitrary units, so a COLMAP workspace of them would not be the scene)"));
  }
  if (gcp.lidar_motion.mode != "off" && dataset.format != "kitti_raw") {
    throw ConfigError(ViolatedConstraint(
        "gcp.lidar.motion.mode", gcp.lidar_motion.mode,
        "off unless dataset.format is kitti_raw (motion compensation needs the scan in the "
        "scanner's own frame)"));
  }
  if (eval.lidar_holdout &&
      std::find(gcp.sources.begin(), gcp.sources.end(), "lidar") == gcp.sources.end()) {
    throw ConfigError("eval.lidar_holdout needs lidar in gcp.sources");
  }
  if (eval.sfm_holdout && dataset.format != "colmap") {
    throw ConfigError(ViolatedConstraint(
        "eval.sfm_holdout", "true",
        "false unless dataset.format is colmap (the scored points are the COLMAP model's)"));
  }
  std::vector<std::string> seen;
  for (const auto& source : gcp.sources) {
    if (std::find(seen.begin(), seen.end(), source) != seen.end()) {
      throw ConfigError(ViolatedConstraint("gcp.sources", source, "each source listed once"));
    }
    seen.push_back(source);
    if (source == "lidar" && gcp.lidar_path.empty()) {
      throw ConfigError("gcp.sources lists lidar but gcp.lidar.path is not set");
    }
    if (source == "depth_map" && gcp.depth_map.path.empty()) {
      throw ConfigError("gcp.sources lists depth_map but gcp.depth_map.path is not set");
    }
    if (source == "sfm" && dataset.format != "colmap") {
      throw ConfigError(ViolatedConstraint("gcp.sources", "sfm",
                                           "sfm needs dataset.format colmap (the SfM points are "
                                           "the COLMAP model's), not " +
                                               dataset.format));
    }
  }
}

LoadedConfig::LoadedConfig() : schema_(std::make_unique<config::Schema>()) {
  options_.Register(schema_.get());
}

void LoadedConfig::Load(const std::string& path, const std::vector<std::string>& overrides) {
  if (!path.empty()) schema_->LoadFile(path);
  for (const auto& o : overrides) schema_->ApplyOverride(o);
  path_ = path;
  overrides_ = overrides;
  DatasetOptions& dataset = options_.dataset;
  dataset.reference = dataset.references.size() == 1 && dataset.references.front() != "all"
                          ? dataset.references.front()
                          : std::string();
  options_.Check();
}

std::unique_ptr<LoadedConfig> LoadedConfig::WithOverrides(
    const std::vector<std::string>& more) const {
  std::vector<std::string> all = overrides_;
  all.insert(all.end(), more.begin(), more.end());
  auto config = std::make_unique<LoadedConfig>();
  config->Load(path_, all);
  return config;
}

}  // namespace gcpstereo::pipeline
