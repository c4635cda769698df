// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Synthetic multi-view data sets with exact ground truth, standing in for the laser-scanned
// Fountain-P11 of Strecha et al. (CVPR 2008) that Wang & Yang (CVPR 2011, §4.2, Fig. 3–4) use:
// the views, the cameras in the Strecha format, a simulated time-of-flight laser scan whose points
// carry their standard deviation σ, and per-view depth and σ maps ("within 3σ" histograms).
#include "gcpstereo/synth/generator.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/synth/scene.h"
#include "random.h"

namespace gcpstereo::synth {
namespace {

using Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;
constexpr double kFarM = 1e4;  // rays are traced up to 10 km; beyond is sky

// Fixed texture lattice: the scene looks the same for every seed; the seed drives the noise.
constexpr std::uint64_t kTextureSeed = 0x5eed0fc0ffeeULL;

// Lighting (linear radiance units): sun direction (towards the sun), sun and ambient strength.
const Vector3d kSunDirection = Vector3d(0.45, -0.55, 0.70).normalized();
constexpr double kSunStrength = 0.85;
constexpr double kAmbient = 0.30;
// Linear radiance that maps to white at gain 1.
constexpr double kWhiteRadiance = 1.05;

// Strecha-style camera (camera-to-world rotation R) at `center` looking at `target`, image x to
// the right, y down, world z up.
Camera LookAtCamera(const Vector3d& center, const Vector3d& target, double fx, double fy, double cx,
                    double cy, int width, int height) {
  const Vector3d z = (target - center).normalized();
  const Vector3d x = z.cross(Vector3d::UnitZ()).normalized();
  const Vector3d y = z.cross(x);
  Camera camera;
  camera.K << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  camera.world_from_camera_rotation.col(0) = x;
  camera.world_from_camera_rotation.col(1) = y;
  camera.world_from_camera_rotation.col(2) = z;
  camera.center_world = center;
  camera.width = width;
  camera.height = height;
  return camera;
}

Vector3d SkyRadiance(const Vector3d& direction) {
  const double up = std::clamp(direction.z(), 0.0, 1.0);
  return Vector3d(0.78, 0.84, 0.95) * (1.0 - up) + Vector3d(0.42, 0.56, 0.88) * up;
}

// Linear radiance seen along a ray.
Vector3d Radiance(const AnalyticScene& scene, const Vector3d& origin, const Vector3d& direction) {
  SurfaceHit hit;
  if (!scene.Intersect(origin, direction, kFarM, &hit)) return SkyRadiance(direction);
  const Vector3d point = origin + hit.t * direction;
  const Vector3d albedo = scene.Albedo(hit.primitive, point);
  double light = kAmbient;
  const double cos_sun = hit.normal_world.dot(kSunDirection);
  if (cos_sun > 0.0) {
    const Vector3d shadow_origin = point + 1e-5 * hit.normal_world;
    if (!scene.Occluded(shadow_origin, kSunDirection, kFarM)) light += kSunStrength * cos_sun;
  }
  return albedo * light;
}

struct ViewRender {
  cv::Mat image, depth, sigma;
};

ViewRender RenderView(const AnalyticScene& scene, const Camera& camera, const SynthOptions& options,
                      int supersampling, int view_key, const Vector3d& scanner) {
  const int w = camera.width, h = camera.height;
  ViewRender out;
  out.image.create(h, w, CV_8UC3);
  out.depth.create(h, w, CV_32F);
  out.sigma.create(h, w, CV_32F);
  const Eigen::Matrix3d K_inv = camera.K.inverse();
  const Eigen::Matrix3d& R = camera.world_from_camera_rotation;
  const Vector3d C = camera.center_world;
  // Per-view exposure from the view's own generator.
  internal::KeyedRng view_rng(internal::HashKeys(options.seed, 0xe0e0, view_key));
  const double gain = 1.0 + options.exposure_gain_variation * (2.0 * view_rng.Uniform() - 1.0);
  const double offset = options.exposure_offset_variation * (2.0 * view_rng.Uniform() - 1.0);
  const int s = supersampling;
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int row = rows.begin(); row < rows.end(); ++row) {
      auto* pixel_out = out.image.ptr<cv::Vec3b>(row);
      float* depth_out = out.depth.ptr<float>(row);
      float* sigma_out = out.sigma.ptr<float>(row);
      for (int col = 0; col < w; ++col) {
        // Ground truth: the pixel-centre ray.
        const Vector3d ray_camera = K_inv * Vector3d(col, row, 1.0);
        const Vector3d dir_centre = (R * ray_camera).normalized();
        SurfaceHit hit;
        if (scene.Intersect(C, dir_centre, kFarM, &hit)) {
          const Vector3d point = C + hit.t * dir_centre;
          depth_out[col] = static_cast<float>(camera.CameraFromWorld(point).z());
          sigma_out[col] = static_cast<float>(LaserSigma(options, (point - scanner).norm()));
        } else {
          depth_out[col] = kInvalidDepth;
          sigma_out[col] = kInvalidDepth;
        }
        // Image: s×s stratified samples over the pixel square [col−½, col+½]×[row−½, row+½].
        Vector3d sum = Vector3d::Zero();
        for (int j = 0; j < s; ++j) {
          for (int i = 0; i < s; ++i) {
            const double x = col - 0.5 + (i + 0.5) / s, y = row - 0.5 + (j + 0.5) / s;
            const Vector3d dir = (R * (K_inv * Vector3d(x, y, 1.0))).normalized();
            sum += Radiance(scene, C, dir);
          }
        }
        const Vector3d radiance = sum / (s * s) * (gain / kWhiteRadiance);
        internal::KeyedRng rng(internal::HashKeys(options.seed, 0x9a9a, view_key,
                                                  static_cast<std::uint64_t>(row) * w + col));
        cv::Vec3b& px = pixel_out[col];
        for (int c = 0; c < 3; ++c) {
          // Output is BGR: channel c of the image holds radiance component 2 − c.
          const double linear = std::max(0.0, radiance[2 - c]);
          const double encoded = 255.0 * std::pow(std::min(linear, 1.0), 1.0 / 2.2);
          const double value = encoded + offset + options.image_noise_sigma * rng.Gaussian();
          px[c] = static_cast<uchar>(std::clamp(std::lround(value), 0L, 255L));
        }
      }
    }
  });
  return out;
}

struct LaserResult {
  PointCloud cloud;
  std::int64_t rays = 0, misses = 0, grazing = 0;
};

// The scan: azimuth about world z and elevation from the horizontal, on a regular grid covering
// the reference view (plus a 2° margin).
LaserResult SimulateLaser(const AnalyticScene& scene, const Camera& reference,
                          const Vector3d& scanner, const SynthOptions& options, double step_rad) {
  double az_min = 1e9, az_max = -1e9, el_min = 1e9, el_max = -1e9;
  const double forward_az = [&] {
    const Vector3d z = reference.world_from_camera_rotation.col(2);
    return std::atan2(z.y(), z.x());
  }();
  const Eigen::Matrix3d K_inv = reference.K.inverse();
  for (int k = 0; k < 64; ++k) {  // sample the image border, at 3 m and at 30 m
    const double u = (k % 16) / 15.0, side = k / 16;
    Eigen::Vector2d px;
    if (side == 0) px = {u * reference.width, 0};
    if (side == 1) px = {u * reference.width, reference.height};
    if (side == 2) px = {0, u * reference.height};
    if (side == 3) px = {reference.width, u * reference.height};
    for (double range : {3.0, 30.0}) {
      const Vector3d dir_cam = K_inv * Vector3d(px.x() - 0.5, px.y() - 0.5, 1.0);
      const Vector3d p = reference.WorldFromCamera(dir_cam * range);
      const Vector3d d = p - scanner;
      double az = std::atan2(d.y(), d.x()) - forward_az;
      az = std::remainder(az, 2.0 * kPi);
      const double el = std::atan2(d.z(), std::hypot(d.x(), d.y()));
      az_min = std::min(az_min, az);
      az_max = std::max(az_max, az);
      el_min = std::min(el_min, el);
      el_max = std::max(el_max, el);
    }
  }
  const double margin = 2.0 * kPi / 180.0;
  az_min -= margin;
  az_max += margin;
  el_min = std::max(el_min - margin, -0.5 * kPi + 0.01);
  el_max = std::min(el_max + margin, 0.5 * kPi - 0.01);
  const int n_az = static_cast<int>(std::floor((az_max - az_min) / step_rad)) + 1;
  const int n_el = static_cast<int>(std::floor((el_max - el_min) / step_rad)) + 1;
  const double cos_max = std::cos(options.laser_max_incidence_deg * kPi / 180.0);

  struct Row {
    std::vector<Eigen::Vector3f> points;
    std::vector<float> sigma;
    std::int64_t misses = 0, grazing = 0;
  };
  std::vector<Row> rows(n_el);
  tbb::parallel_for(tbb::blocked_range<int>(0, n_el), [&](const tbb::blocked_range<int>& range) {
    for (int r = range.begin(); r < range.end(); ++r) {
      Row& row = rows[r];
      // Top row first, like a scanner sweeping down.
      const double el = el_max - r * step_rad;
      for (int c = 0; c < n_az; ++c) {
        const double az = forward_az + az_min + c * step_rad;
        const Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
        SurfaceHit hit;
        if (!scene.Intersect(scanner, dir, options.laser_max_range_m, &hit)) {
          ++row.misses;
          continue;
        }
        if (-hit.normal_world.dot(dir) < cos_max) {
          ++row.grazing;
          continue;
        }
        const double sigma = LaserSigma(options, hit.t);
        internal::KeyedRng rng(internal::HashKeys(options.seed, 0x1a5e, r, c));
        const double range_measured = hit.t + sigma * rng.Gaussian();
        row.points.push_back((scanner + range_measured * dir).cast<float>());
        row.sigma.push_back(static_cast<float>(sigma));
      }
    }
  });
  LaserResult result;
  result.rays = static_cast<std::int64_t>(n_az) * n_el;
  for (Row& row : rows) {
    result.cloud.points.insert(result.cloud.points.end(), row.points.begin(), row.points.end());
    result.cloud.sigma.insert(result.cloud.sigma.end(), row.sigma.begin(), row.sigma.end());
    result.misses += row.misses;
    result.grazing += row.grazing;
  }
  return result;
}

// Throws ConfigError naming synth.views unless IsValidSynthViews(views).
void CheckViews(int views) {
  if (IsValidSynthViews(views)) return;
  throw ConfigError(ViolatedConstraint("synth.views", std::to_string(views),
                                       "views == 0 (the preset's cameras) or " +
                                           std::to_string(kMinSynthViews) +
                                           " <= views <= " + std::to_string(kMaxSynthViews)));
}

}  // namespace

void SynthOptions::Check() const {
  auto fail = [](const std::string& key, const std::string& value, const std::string& c) {
    throw ConfigError(ViolatedConstraint(key, value, c));
  };
  if (preset != "tiny" && preset != "small" && preset != "fountain") {
    fail("synth.preset", "'" + preset + "'", "one of tiny, small, fountain");
  }
  if (!(image_noise_sigma >= 0.0 && image_noise_sigma <= 20.0)) {
    fail("synth.image_noise_sigma", FormatNumber(image_noise_sigma),
         "0 <= image_noise_sigma <= 20");
  }
  if (!(exposure_gain_variation >= 0.0 && exposure_gain_variation <= 0.5)) {
    fail("synth.exposure_gain_variation", FormatNumber(exposure_gain_variation),
         "0 <= exposure_gain_variation <= 0.5");
  }
  if (!(exposure_offset_variation >= 0.0 && exposure_offset_variation <= 20.0)) {
    fail("synth.exposure_offset_variation", FormatNumber(exposure_offset_variation),
         "0 <= exposure_offset_variation <= 20");
  }
  CheckViews(views);
  if (supersampling < 0 || supersampling > 8) {
    fail("synth.supersampling", std::to_string(supersampling), "0 <= supersampling <= 8");
  }
  if (!(laser_sigma_constant_m >= 0.0 && laser_sigma_constant_m <= 1.0)) {
    fail("synth.laser_sigma_constant_m", FormatNumber(laser_sigma_constant_m),
         "0 <= laser_sigma_constant_m <= 1");
  }
  if (!(laser_sigma_per_m >= 0.0 && laser_sigma_per_m <= 0.1)) {
    fail("synth.laser_sigma_per_m", FormatNumber(laser_sigma_per_m),
         "0 <= laser_sigma_per_m <= 0.1");
  }
  if (!(laser_max_incidence_deg > 0.0 && laser_max_incidence_deg <= 90.0)) {
    fail("synth.laser_max_incidence_deg", FormatNumber(laser_max_incidence_deg),
         "0 < laser_max_incidence_deg <= 90");
  }
  if (!(laser_angular_step_rad >= 0.0 && laser_angular_step_rad <= 0.1)) {
    fail("synth.laser_angular_step_rad", FormatNumber(laser_angular_step_rad),
         "0 <= laser_angular_step_rad <= 0.1");
  }
  if (!(laser_max_range_m > 0.0 && laser_max_range_m <= 1000.0)) {
    fail("synth.laser_max_range_m", FormatNumber(laser_max_range_m),
         "0 < laser_max_range_m <= 1000");
  }
}

double LaserSigma(const SynthOptions& options, double range_m) {
  return options.laser_sigma_constant_m + options.laser_sigma_per_m * range_m;
}

PresetGeometry MakePresetGeometry(const std::string& preset, int num_views) {
  // Full-size geometry, then scaled: f ≈ 1380 px at 1536×1024 (58° horizontal field of view, like
  // fountain-P11 at half resolution); 11 cameras on an arc converging on the fountain, 8.6–9.8 m
  // from the look-at point, 1.5–1.9 m apart, at eye height with varied tilt, like the real survey.
  int first = 0, count = 11, width = 1536, height = 1024;
  PresetGeometry g;
  g.preset = preset;
  if (preset == "tiny") {
    first = 3, count = 5, width = 160, height = 107;
    g.default_supersampling = 2;
    g.default_laser_angular_step_rad = 0.006;
    g.mesh_max_chord_error_m = 0.004;
  } else if (preset == "small") {
    first = 2, count = 7, width = 640, height = 427;
    g.default_supersampling = 2;
    g.default_laser_angular_step_rad = 0.003;
    g.mesh_max_chord_error_m = 0.002;
  } else if (preset == "fountain") {
    g.default_supersampling = 2;
    g.default_laser_angular_step_rad = 0.0015;
    g.mesh_max_chord_error_m = 0.001;
  } else {
    throw ConfigError(
        ViolatedConstraint("synth.preset", "'" + preset + "'", "one of tiny, small, fountain"));
  }
  CheckViews(num_views);
  const double scale = width / 1536.0;
  const double f_full = 1381.0, fy_full = 1383.5, cx_full = 759.6, cy_full = 503.2;
  // Angles (degrees, about the look-at point, 0 = straight in front of the wall, positive to the
  // right) and distances of the 11 stations; heights vary a little as a hand-held survey would.
  constexpr int kStations = 11;
  const double angle_deg[kStations] = {-52.0, -41.5, -30.5, -20.5, -10.4, 0.0,
                                       10.9,  21.4,  32.6,  43.0,  53.5};
  const double distance_m[kStations] = {9.7, 9.5, 9.2, 9.0, 8.8, 8.9, 8.7, 8.8, 9.1, 9.4, 9.6};
  const double height_m[kStations] = {1.62, 1.66, 1.60, 1.70, 1.64, 1.68,
                                      1.72, 1.63, 1.67, 1.61, 1.65};
  g.look_at_world = Vector3d(0.0, -2.2, 1.9);

  // One station: its angle, distance and height, and its number (the view's name and the key of
  // its aiming jitter and of its image noise).
  struct Station {
    double angle_deg, distance_m, height_m;
    int number;
  };
  std::vector<Station> stations;
  if (num_views == 0) {
    for (int i = first; i < first + count; ++i) {
      stations.push_back({angle_deg[i], distance_m[i], height_m[i], i});
    }
  } else {
    // Evenly spaced over the preset's arc; distance and height interpolated between the two
    // stations around each angle.
    const double arc_begin = angle_deg[first], arc_end = angle_deg[first + count - 1];
    const double step = (arc_end - arc_begin) / (num_views - 1);
    int nearest_head_on = 0;
    for (int k = 0; k < num_views; ++k) {
      const double a = k + 1 == num_views ? arc_end : arc_begin + k * step;
      int i = 0;
      while (i + 2 < kStations && angle_deg[i + 1] <= a) ++i;
      const double t = std::clamp((a - angle_deg[i]) / (angle_deg[i + 1] - angle_deg[i]), 0.0, 1.0);
      stations.push_back({a, distance_m[i] + t * (distance_m[i + 1] - distance_m[i]),
                          height_m[i] + t * (height_m[i + 1] - height_m[i]), 0});
      if (std::abs(a) < std::abs(stations[nearest_head_on].angle_deg)) nearest_head_on = k;
    }
    // The reference "0005": the head-on station, unless more than five lie left of it (names
    // are non-negative and in arc order); then the sixth.
    const int reference = std::min(nearest_head_on, 5);
    for (int k = 0; k < num_views; ++k) stations[k].number = 5 - reference + k;
  }
  for (const Station& station : stations) {
    const int i = station.number;
    const double a = station.angle_deg * kPi / 180.0;
    const Vector3d center(g.look_at_world.x() + station.distance_m * std::sin(a),
                          g.look_at_world.y() - station.distance_m * std::cos(a), station.height_m);
    // Aim at points spread a little around the look-at point (hand-held aiming).
    const Vector3d target =
        g.look_at_world + Vector3d(0.15 * std::sin(3.0 * i), 0.0, 0.25 * std::cos(2.0 * i));
    Camera full = LookAtCamera(center, target, f_full, fy_full, cx_full, cy_full, 1536, 1024);
    Camera camera = scale == 1.0 ? full : full.Rescaled(scale);
    camera.width = width;
    camera.height = height;
    std::ostringstream name;
    name << std::setw(4) << std::setfill('0') << i;
    if (i == 5) g.reference_index = static_cast<int>(g.cameras.size());
    g.view_names.push_back(name.str());
    g.cameras.push_back(camera);
  }
  // The scanner: a tripod 0.4 m right of, 0.3 m behind and 0.25 m below the reference camera.
  const Camera& ref = g.cameras[g.reference_index];
  const Eigen::Matrix3d& R = ref.world_from_camera_rotation;
  const Vector3d right = R.col(0), forward(R(0, 2), R(1, 2), 0.0);
  g.scanner_center_world =
      ref.center_world + 0.4 * right - 0.3 * forward.normalized() - Vector3d(0, 0, 0.25);
  // Finest texture detail ≈ 2.5 pixel footprints at 9 m.
  g.texture_min_wavelength_m = 2.5 * 9.0 / (f_full * scale);
  return g;
}

std::string SynthSummary::FullReport() const {
  std::ostringstream s;
  s << "synthetic scene '" << preset << "' (seed " << seed << "): " << num_views << " views of "
    << width << "x" << height << ", " << supersampling << "x" << supersampling
    << " samples per pixel, reference " << reference_name << "\n"
    << "  reference depth " << reference_depth_min_m << " .. " << reference_depth_max_m << " m, "
    << 100.0 * reference_valid_fraction << " % of pixels with a surface\n"
    << "  laser: " << laser_rays << " rays, " << laser_points << " points, " << laser_misses
    << " misses, " << laser_grazing_dropouts << " grazing-angle dropouts\n"
    << "  mesh: " << mesh_vertices << " vertices, " << mesh_faces << " faces\n"
    << "  time: render " << render_seconds << " s, laser " << laser_seconds << " s, mesh "
    << mesh_seconds << " s, total " << total_seconds << " s";
  return s.str();
}

SyntheticScene GenerateScene(const SynthOptions& options, const ProgressCallback& progress) {
  options.Check();
  Timer total_timer;
  const PresetGeometry geometry = MakePresetGeometry(options.preset, options.views);
  const AnalyticScene scene =
      AnalyticScene::MakeCourtyard(geometry.texture_min_wavelength_m, kTextureSeed);
  const int supersampling =
      options.supersampling > 0 ? options.supersampling : geometry.default_supersampling;
  const double step = options.laser_angular_step_rad > 0 ? options.laser_angular_step_rad
                                                         : geometry.default_laser_angular_step_rad;
  const int num_views = static_cast<int>(geometry.cameras.size());
  const double num_steps = num_views + 2.0;
  auto report = [&](double done) {
    if (progress && !progress(done / num_steps)) {
      throw Error("synthetic scene generation was cancelled (preset '" + options.preset + "')");
    }
  };

  SyntheticScene out;
  out.reference_index = geometry.reference_index;
  out.laser_scanner_world = geometry.scanner_center_world;
  SynthSummary& summary = out.summary;
  summary.preset = options.preset;
  summary.seed = options.seed;
  summary.num_views = num_views;
  summary.width = geometry.cameras[0].width;
  summary.height = geometry.cameras[0].height;
  summary.supersampling = supersampling;
  summary.reference_name = geometry.view_names[geometry.reference_index];

  Timer timer;
  for (int v = 0; v < num_views; ++v) {
    // The key of a view is its fountain number, so a view renders identically in every preset
    // that contains it at the same size (with synth.views a number may name another station).
    const int view_key = std::stoi(geometry.view_names[v]);
    ViewRender r = RenderView(scene, geometry.cameras[v], options, supersampling, view_key,
                              geometry.scanner_center_world);
    out.views.push_back(View{geometry.view_names[v], r.image, geometry.cameras[v]});
    out.depth.push_back(r.depth);
    out.sigma.push_back(r.sigma);
    report(v + 1);
  }
  summary.render_seconds = timer.ElapsedSeconds();

  timer.Restart();
  LaserResult laser = SimulateLaser(scene, geometry.cameras[geometry.reference_index],
                                    geometry.scanner_center_world, options, step);
  out.laser = std::move(laser.cloud);
  summary.laser_rays = laser.rays;
  summary.laser_points = static_cast<std::int64_t>(out.laser.size());
  summary.laser_misses = laser.misses;
  summary.laser_grazing_dropouts = laser.grazing;
  summary.laser_seconds = timer.ElapsedSeconds();
  report(num_views + 1);

  timer.Restart();
  out.mesh = scene.Tessellate(geometry.mesh_max_chord_error_m);
  summary.mesh_vertices = static_cast<std::int64_t>(out.mesh.vertices.size());
  summary.mesh_faces = static_cast<std::int64_t>(out.mesh.faces.size());
  summary.mesh_seconds = timer.ElapsedSeconds();
  report(num_steps);

  const cv::Mat& ref_depth = out.depth[geometry.reference_index];
  double dmin = std::numeric_limits<double>::infinity(), dmax = 0.0;
  std::int64_t valid = 0;
  for (int r = 0; r < ref_depth.rows; ++r) {
    for (int c = 0; c < ref_depth.cols; ++c) {
      const float d = ref_depth.at<float>(r, c);
      if (!IsValidDepth(d)) continue;
      ++valid;
      dmin = std::min<double>(dmin, d);
      dmax = std::max<double>(dmax, d);
    }
  }
  summary.reference_depth_min_m = valid > 0 ? dmin : 0.0;
  summary.reference_depth_max_m = dmax;
  summary.reference_valid_fraction = static_cast<double>(valid) / ref_depth.total();
  summary.total_seconds = total_timer.ElapsedSeconds();
  spdlog::info("{}", summary.FullReport());
  return out;
}

}  // namespace gcpstereo::synth
