// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::synth {

// The range of SynthOptions::views other than 0.
constexpr int kMinSynthViews = 3;
constexpr int kMaxSynthViews = 99;
// 0 (the preset's cameras) or a count in [kMinSynthViews, kMaxSynthViews].
constexpr bool IsValidSynthViews(int views) {
  return views == 0 || (views >= kMinSynthViews && views <= kMaxSynthViews);
}

// Options of the synthetic data set generator (`gcpstereo synth`). The geometry (scene, cameras,
// scanner position) is fixed by the preset and `views`; `seed` drives the sensor noise, the
// per-view exposure and the laser noise. YAML keys are "synth.<field>".
struct SynthOptions {
  // Preset: "tiny" (5 views, 160×107), "small" (7 views, 640×427), "fountain" (11 views,
  // 1536×1024 placed like Strecha's fountain-P11). Views keep their fountain numbers, so the
  // reference is view "0005" in every preset.
  std::string preset = "small";
  // Number of views. 0 = the preset's own cameras (above). N in [kMinSynthViews, kMaxSynthViews]:
  // N cameras at evenly spaced angles over the preset's arc (from its first to its last
  // station's angle about the look-at point; not widened, so more views stand closer together),
  // at the distance and height of the preset's stations interpolated linearly in that angle, with
  // the preset's image size. Names are consecutive 4-digit numbers in arc order, left to right,
  // and "0005" is the reference (the laser's too): the station nearest head-on (0°) if at most
  // five stations lie left of it, else the sixth from the left (names 0000 … N−1). On the
  // fountain's arc (−52° … +53.5°) "0005" is the head-on station up to 11 views; with 31 it
  // stands at −34°.
  int views = 0;
  // Seed of every random draw (per-pixel and per-point generators are derived from it). Any value.
  std::uint64_t seed = 1;
  // Standard deviation of the additive Gaussian sensor noise, grey levels (0…255 scale), per
  // channel and pixel. Range [0, 20].
  double image_noise_sigma = 1.5;
  // Per-view exposure gain is 1 + u · exposure_gain_variation with u uniform in [−1, 1] (applied
  // to linear radiance). Fraction, range [0, 0.5].
  double exposure_gain_variation = 0.04;
  // Per-view brightness offset u · exposure_offset_variation, grey levels, range [0, 20].
  double exposure_offset_variation = 2.0;
  // Anti-aliasing: s×s samples per pixel (box filter). 0 = the preset's default (2 for every
  // preset; the procedural noise is already band-limited to ≈ 2.5 pixels). Range [0, 8].
  int supersampling = 0;
  // Laser range noise model σ(r) = a + b · r (r = range from the scanner in metres), used for
  // the scan's noise, its per-point sigma and the per-pixel sigma maps.
  // a: metres, range [0, 1]. The default puts σ(9 m) = 12 mm, so 3σ ≈ 3.6 cm ≈ 2 depth labels of
  // the paper's 360-level fountain setting: a good stereo result is far from 100 % within 3σ.
  double laser_sigma_constant_m = 0.003;
  // b: metres of sigma per metre of range, range [0, 0.1].
  double laser_sigma_per_m = 0.001;
  // Dropout: no return where the angle between the laser ray and the surface normal exceeds
  // this, degrees, range (0, 90].
  double laser_max_incidence_deg = 78.0;
  // Angular step of the scan grid (azimuth and elevation), radians. 0 = the preset's default
  // (tiny 6 mrad, small 3 mrad, fountain 1.5 mrad: 1–2 reference pixels). Range [0, 0.1].
  double laser_angular_step_rad = 0.0;
  // Maximum range of the scanner, metres; farther surfaces give no return. Range (0, 1000].
  double laser_max_range_m = 60.0;

  // Throws ConfigError naming the YAML key ("synth.<field>"), the value and the constraint.
  void Check() const;
};

// The fixed geometry of a preset (with SynthOptions::views its cameras only change).
struct PresetGeometry {
  std::string preset;
  std::vector<std::string> view_names;                      // "0003" … : fountain-P11 numbering
  std::vector<Camera> cameras;                              // one per view
  int reference_index = 0;                                  // index of view "0005" in `cameras`
  Eigen::Vector3d look_at_world = Eigen::Vector3d::Zero();  // the point the cameras converge on
  Eigen::Vector3d scanner_center_world = Eigen::Vector3d::Zero();
  double texture_min_wavelength_m = 0.0;  // finest texture detail (≈ 2.5 pixels at 9 m)
  int default_supersampling = 2;
  double default_laser_angular_step_rad = 0.0;
  double mesh_max_chord_error_m = 0.0;  // tessellation tolerance of gt/mesh.ply
};

// The cameras and constants of "tiny", "small" or "fountain"; throws ConfigError otherwise.
// `num_views`: 0 = the preset's own cameras, else that many over the preset's arc (see
// SynthOptions::views; ConfigError naming synth.views outside [kMinSynthViews, kMaxSynthViews]).
PresetGeometry MakePresetGeometry(const std::string& preset, int num_views = 0);

// The laser's standard deviation at range `range_m`: a + b · range (see SynthOptions).
double LaserSigma(const SynthOptions& options, double range_m);

// Counts and timings of one generation, for the log and report.json.
struct SynthSummary {
  std::string preset;
  std::uint64_t seed = 0;
  int num_views = 0;
  int width = 0;
  int height = 0;
  int supersampling = 0;
  std::string reference_name;
  double reference_depth_min_m = 0.0;  // over the reference view's valid depth pixels
  double reference_depth_max_m = 0.0;
  double reference_valid_fraction = 0.0;    // pixels with a surface (the rest is sky: +inf)
  std::int64_t laser_rays = 0;              // grid directions fired
  std::int64_t laser_points = 0;            // returns kept
  std::int64_t laser_misses = 0;            // no surface within range (sky)
  std::int64_t laser_grazing_dropouts = 0;  // incidence above laser_max_incidence_deg
  std::int64_t mesh_vertices = 0;
  std::int64_t mesh_faces = 0;
  double render_seconds = 0.0;
  double laser_seconds = 0.0;
  double mesh_seconds = 0.0;
  double total_seconds = 0.0;

  std::string FullReport() const;
};

// A generated data set, in memory.
struct SyntheticScene {
  std::vector<View> views;     // BGR 8-bit images with their exact cameras
  int reference_index = 0;     // views[reference_index].name == "0005"
  std::vector<cv::Mat> depth;  // CV_32F per view: exact depth along the camera's z of the
                               // pixel-centre ray; kInvalidDepth (+inf) where no surface
  std::vector<cv::Mat> sigma;  // CV_32F per view: the laser model's σ at that pixel's surface
                               // point, with the range from the scanner (also where the scanner
                               // does not see the point); +inf where no surface
  PointCloud laser;            // the simulated scan in WORLD coordinates, with per-point sigma
  Eigen::Vector3d laser_scanner_world = Eigen::Vector3d::Zero();
  TriangleMesh mesh;  // the exact surface (world coordinates), vertex colour = albedo
  SynthSummary summary;
};

// Renders the preset's views, ground truth, laser scan and mesh.
//
// Images: per pixel s×s rays (stratified grid, box filter) are traced to the nearest surface;
// radiance = albedo · (ambient + sun · max(0, n·l) · visible(sun)) with a hard shadow ray; per
// view the linear radiance is multiplied by the exposure gain, gamma-encoded (1/2.2), offset,
// and Gaussian noise is added before rounding to 8 bits. All random draws come from counter-based
// generators keyed by (seed, view, pixel) or (seed, scan point), so the bytes do not depend on
// the thread count. Rows are rendered in parallel (TBB).
//
// Laser: a scanner near the reference camera (offset 0.4 m right, 0.3 m back, 0.25 m lower, like
// a tripod beside the photographer) fires a regular azimuth × elevation grid covering the
// reference view; the first hit only (occlusion); no return beyond laser_max_range_m or when the
// incidence angle exceeds laser_max_incidence_deg; the range gets Gaussian noise of σ(r) = a + b·r.
//
// Progress is reported once per view and at the laser and mesh stages; if the callback returns
// false the generation stops and throws gcpstereo::Error.
SyntheticScene GenerateScene(const SynthOptions& options, const ProgressCallback& progress = {});

}  // namespace gcpstereo::synth
