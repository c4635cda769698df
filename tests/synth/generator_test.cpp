// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/synth/generator.h"
#include "laser_coverage.h"

namespace gcpstereo::synth {
namespace {

using Eigen::Vector3d;

bool SameBytes(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int r = 0; r < a.rows; ++r) {
    if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

const SyntheticScene& TinyScene() {
  static const SyntheticScene scene = [] {
    SynthOptions options;
    options.preset = "tiny";
    return GenerateScene(options);
  }();
  return scene;
}

TEST(SynthGeneratorTest, TinyPresetLayout) {
  const SyntheticScene& s = TinyScene();
  ASSERT_EQ(s.views.size(), 5u);
  EXPECT_EQ(s.views[s.reference_index].name, "0005");
  EXPECT_EQ(s.views.front().name, "0003");
  EXPECT_EQ(s.views.back().name, "0007");
  for (size_t v = 0; v < s.views.size(); ++v) {
    EXPECT_EQ(s.views[v].image.cols, 160);
    EXPECT_EQ(s.views[v].image.rows, 107);
    EXPECT_EQ(s.views[v].image.type(), CV_8UC3);
    EXPECT_EQ(s.depth[v].type(), CV_32F);
    EXPECT_EQ(s.sigma[v].size(), s.depth[v].size());
    EXPECT_NO_THROW(s.views[v].camera.Validate("view " + s.views[v].name));
  }
  EXPECT_EQ(s.summary.laser_points, static_cast<std::int64_t>(s.laser.size()));
  EXPECT_EQ(s.laser.sigma.size(), s.laser.size());
  EXPECT_EQ(s.summary.laser_rays,
            s.summary.laser_points + s.summary.laser_misses + s.summary.laser_grazing_dropouts);
  EXPECT_GT(s.summary.laser_points, 1000);
  EXPECT_GT(s.summary.laser_grazing_dropouts, 0);
  EXPECT_GT(s.summary.mesh_faces, 1000);
  // The reference view sees the scene 4–13 m away, with a little sky in the top corners at most.
  EXPECT_GT(s.summary.reference_depth_min_m, 3.5);
  EXPECT_LT(s.summary.reference_depth_max_m, 13.0);
  EXPECT_GT(s.summary.reference_valid_fraction, 0.9);
}

TEST(SynthGeneratorTest, ImagesHaveTextureAndVaryInBrightness) {
  const SyntheticScene& s = TinyScene();
  cv::Scalar mean, stddev;
  cv::meanStdDev(s.views[s.reference_index].image, mean, stddev);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(mean[c], 50.0);
    EXPECT_LT(mean[c], 220.0);
    EXPECT_GT(stddev[c], 15.0);
  }
  // Views are not saturated.
  cv::Mat grey;
  cv::extractChannel(s.views[s.reference_index].image, grey, 1);
  EXPECT_LT(cv::countNonZero(grey >= 255), grey.total() / 100);
}

TEST(SynthGeneratorTest, SameSeedSameBytesDifferentSeedDifferentNoise) {
  SynthOptions options;
  options.preset = "tiny";
  const SyntheticScene& a = TinyScene();
  const SyntheticScene b = GenerateScene(options);
  options.seed = 2;
  const SyntheticScene c = GenerateScene(options);
  for (size_t v = 0; v < a.views.size(); ++v) {
    EXPECT_TRUE(SameBytes(a.views[v].image, b.views[v].image)) << "view " << v;
    EXPECT_TRUE(SameBytes(a.depth[v], b.depth[v]));
    EXPECT_TRUE(SameBytes(a.sigma[v], b.sigma[v]));
    EXPECT_FALSE(SameBytes(a.views[v].image, c.views[v].image)) << "view " << v;
    // The geometry does not depend on the seed: same depth, different noise.
    EXPECT_TRUE(SameBytes(a.depth[v], c.depth[v]));
    cv::Mat diff;
    cv::absdiff(a.views[v].image, c.views[v].image, diff);
    EXPECT_LT(cv::mean(diff)[1], 8.0);  // noise and exposure only
  }
  ASSERT_EQ(a.laser.size(), b.laser.size());
  EXPECT_TRUE(std::equal(a.laser.points.begin(), a.laser.points.end(), b.laser.points.begin()));
  ASSERT_EQ(a.laser.size(), c.laser.size());
  EXPECT_FALSE(std::equal(a.laser.points.begin(), a.laser.points.end(), c.laser.points.begin()));
}

TEST(SynthGeneratorTest, ResultDoesNotDependOnTheThreadCount) {
  SynthOptions options;
  options.preset = "tiny";
  SyntheticScene one_thread;
  tbb::task_arena arena(1);
  arena.execute([&] { one_thread = GenerateScene(options); });
  const SyntheticScene& many = TinyScene();
  for (size_t v = 0; v < many.views.size(); ++v) {
    EXPECT_TRUE(SameBytes(one_thread.views[v].image, many.views[v].image)) << "view " << v;
    EXPECT_TRUE(SameBytes(one_thread.depth[v], many.depth[v]));
  }
  ASSERT_EQ(one_thread.laser.size(), many.laser.size());
  EXPECT_TRUE(std::equal(many.laser.points.begin(), many.laser.points.end(),
                         one_thread.laser.points.begin()));
  EXPECT_TRUE(
      std::equal(many.laser.sigma.begin(), many.laser.sigma.end(), one_thread.laser.sigma.begin()));
}

TEST(SynthGeneratorTest, ZeroNoiseSeedsGiveIdenticalImages) {
  SynthOptions options;
  options.preset = "tiny";
  options.image_noise_sigma = 0.0;
  options.exposure_gain_variation = 0.0;
  options.exposure_offset_variation = 0.0;
  options.supersampling = 1;
  const SyntheticScene a = GenerateScene(options);
  options.seed = 99;
  const SyntheticScene b = GenerateScene(options);
  for (size_t v = 0; v < a.views.size(); ++v) {
    EXPECT_TRUE(SameBytes(a.views[v].image, b.views[v].image));
  }
}

TEST(SynthGeneratorTest, FountainCamerasArePlacedLikeFountainP11) {
  const PresetGeometry g = MakePresetGeometry("fountain");
  ASSERT_EQ(g.cameras.size(), 11u);
  ASSERT_EQ(g.view_names.size(), 11u);
  EXPECT_EQ(g.view_names[g.reference_index], "0005");
  EXPECT_EQ(g.reference_index, 5);
  Vector3d mean_center = Vector3d::Zero();
  for (const Camera& c : g.cameras) {
    EXPECT_EQ(c.width, 1536);
    EXPECT_EQ(c.height, 1024);
    EXPECT_NO_THROW(c.Validate("fountain camera"));
    mean_center += c.center_world / 11.0;
    // 8–10 m from the scene (the point the views converge on), which projects into the image.
    const double distance = (c.center_world - g.look_at_world).norm();
    EXPECT_GE(distance, 8.0);
    EXPECT_LE(distance, 10.0);
    Eigen::Vector2d px;
    double depth;
    ASSERT_TRUE(c.Project(g.look_at_world, &px, &depth));
    EXPECT_TRUE(c.InImage(px));
    EXPECT_NEAR(px.x(), 768.0, 200.0);
    EXPECT_NEAR(px.y(), 512.0, 200.0);
  }
  for (size_t i = 0; i + 1 < g.cameras.size(); ++i) {
    const double baseline = (g.cameras[i + 1].center_world - g.cameras[i].center_world).norm();
    EXPECT_GE(baseline, 1.4) << "between views " << i << " and " << i + 1;
    EXPECT_LE(baseline, 2.1) << "between views " << i << " and " << i + 1;
  }
  // The reference is the middle station: it looks at the scene head-on, the others converge.
  const Camera& ref = g.cameras[g.reference_index];
  const Vector3d ref_axis = ref.world_from_camera_rotation.col(2);
  EXPECT_GT(ref_axis.y(), 0.99);  // towards the wall (+y is into the wall)
  EXPECT_LT(std::abs(ref.center_world.x() - g.look_at_world.x()), 0.5);
  const Vector3d first_axis = g.cameras.front().world_from_camera_rotation.col(2);
  const Vector3d last_axis = g.cameras.back().world_from_camera_rotation.col(2);
  const double span_deg = std::acos(first_axis.dot(last_axis)) * 180.0 / M_PI;
  EXPECT_GT(span_deg, 90.0);  // fountain-P11 spans about 108°
  EXPECT_LT(span_deg, 120.0);
  // The scanner stands near, but not at, the reference camera.
  const double offset = (g.scanner_center_world - ref.center_world).norm();
  EXPECT_GT(offset, 0.2);
  EXPECT_LT(offset, 1.0);
}

TEST(SynthGeneratorTest, SmallerPresetsAreSubsetsOfTheFountainArc) {
  const PresetGeometry fountain = MakePresetGeometry("fountain");
  for (const char* name : {"tiny", "small"}) {
    const PresetGeometry g = MakePresetGeometry(name);
    EXPECT_EQ(g.view_names[g.reference_index], "0005");
    for (size_t i = 0; i < g.cameras.size(); ++i) {
      const int index = std::stoi(g.view_names[i]);
      EXPECT_LT((g.cameras[i].center_world - fountain.cameras[index].center_world).norm(), 1e-12);
      // Same field of view: focal length scales with the width.
      EXPECT_NEAR(g.cameras[i].K(0, 0) / g.cameras[i].width,
                  fountain.cameras[index].K(0, 0) / 1536.0, 1e-9);
    }
  }
  EXPECT_EQ(MakePresetGeometry("small").cameras[0].width, 640);
  EXPECT_EQ(MakePresetGeometry("small").cameras[0].height, 427);
  EXPECT_EQ(MakePresetGeometry("small").cameras.size(), 7u);
}

// The angle of a camera centre about the look-at point, degrees (0 = in front of the wall,
// positive to the right), and its horizontal distance from it: the stations' coordinates.
double StationAngleDeg(const PresetGeometry& g, const Camera& c) {
  const Vector3d d = c.center_world - g.look_at_world;
  return std::atan2(d.x(), -d.y()) * 180.0 / M_PI;
}
double StationDistance(const PresetGeometry& g, const Camera& c) {
  const Vector3d d = c.center_world - g.look_at_world;
  return std::hypot(d.x(), d.y());
}

// views = 0 keeps each preset's own stations: fountain-P11's uneven angles, distances and
// heights, written out here so that a change to the default geometry fails.
TEST(SynthGeneratorTest, DefaultViewsAreThePresetsOwnStations) {
  EXPECT_EQ(SynthOptions().views, 0);
  const double angle_deg[11] = {-52.0, -41.5, -30.5, -20.5, -10.4, 0.0,
                                10.9,  21.4,  32.6,  43.0,  53.5};
  const double distance_m[11] = {9.7, 9.5, 9.2, 9.0, 8.8, 8.9, 8.7, 8.8, 9.1, 9.4, 9.6};
  const double height_m[11] = {1.62, 1.66, 1.60, 1.70, 1.64, 1.68, 1.72, 1.63, 1.67, 1.61, 1.65};
  const struct {
    const char* preset;
    int first, count;
  } presets[] = {{"tiny", 3, 5}, {"small", 2, 7}, {"fountain", 0, 11}};
  for (const auto& p : presets) {
    const PresetGeometry g = MakePresetGeometry(p.preset, 0);
    ASSERT_EQ(g.cameras.size(), static_cast<size_t>(p.count)) << p.preset;
    EXPECT_EQ(g.reference_index, 5 - p.first) << p.preset;
    for (int k = 0; k < p.count; ++k) {
      const int i = p.first + k;
      char name[8];
      std::snprintf(name, sizeof(name), "%04d", i);
      EXPECT_EQ(g.view_names[k], name) << p.preset;
      EXPECT_NEAR(StationAngleDeg(g, g.cameras[k]), angle_deg[i], 1e-9) << p.preset << " " << i;
      EXPECT_NEAR(StationDistance(g, g.cameras[k]), distance_m[i], 1e-9) << p.preset << " " << i;
      EXPECT_NEAR(g.cameras[k].center_world.z(), height_m[i], 1e-12) << p.preset << " " << i;
    }
  }
}

// views = N: N cameras evenly spaced over the preset's arc at the preset's distances, named in
// arc order with consecutive 4-digit numbers, "0005" the reference and the laser's.
TEST(SynthGeneratorTest, ViewsOptionSpreadsNCamerasOverThePresetsArc) {
  for (const char* preset : {"tiny", "small", "fountain"}) {
    const PresetGeometry own = MakePresetGeometry(preset);
    const double arc_begin = StationAngleDeg(own, own.cameras.front());
    const double arc_end = StationAngleDeg(own, own.cameras.back());
    double min_distance = 1e9, max_distance = 0.0;
    for (const Camera& c : own.cameras) {
      min_distance = std::min(min_distance, StationDistance(own, c));
      max_distance = std::max(max_distance, StationDistance(own, c));
    }
    for (int n : {3, 4, 6, 7, 11, 12, 21, 31, 99}) {
      SCOPED_TRACE(std::string(preset) + " with " + std::to_string(n) + " views");
      const PresetGeometry g = MakePresetGeometry(preset, n);
      ASSERT_EQ(g.cameras.size(), static_cast<size_t>(n));
      ASSERT_EQ(g.view_names.size(), static_cast<size_t>(n));
      ASSERT_GE(g.reference_index, 0);
      ASSERT_LT(g.reference_index, n);
      EXPECT_EQ(g.view_names[g.reference_index], "0005");
      const int first_number = std::stoi(g.view_names.front());
      EXPECT_GE(first_number, 0);
      const double step = (arc_end - arc_begin) / (n - 1);
      int head_on = 0;
      for (int k = 0; k < n; ++k) {
        char name[8];
        std::snprintf(name, sizeof(name), "%04d", first_number + k);
        EXPECT_EQ(g.view_names[k], name);
        const Camera& c = g.cameras[k];
        EXPECT_EQ(c.width, own.cameras[0].width);
        EXPECT_EQ(c.height, own.cameras[0].height);
        EXPECT_EQ(c.K, own.cameras[0].K);
        EXPECT_NO_THROW(c.Validate("camera " + g.view_names[k]));
        const double angle = StationAngleDeg(g, c);
        EXPECT_NEAR(angle, arc_begin + k * step, 1e-9) << "view " << k;
        if (std::abs(angle) < std::abs(StationAngleDeg(g, g.cameras[head_on]))) head_on = k;
        const double distance = StationDistance(g, c);
        EXPECT_GE(distance, min_distance - 1e-9);
        EXPECT_LE(distance, max_distance + 1e-9);
        Eigen::Vector2d px;
        double depth;
        ASSERT_TRUE(c.Project(g.look_at_world, &px, &depth));
        EXPECT_TRUE(c.InImage(px));
      }
      // The arc's ends are the preset's first and last stations.
      EXPECT_LT((g.cameras.front().center_world - own.cameras.front().center_world).norm(), 1e-9);
      EXPECT_LT((g.cameras.back().center_world - own.cameras.back().center_world).norm(), 1e-9);
      // "0005" is the head-on camera, or the sixth when more than five lie left of it.
      EXPECT_EQ(g.reference_index, std::min(head_on, 5));
      EXPECT_EQ(first_number, 5 - g.reference_index);
      // The scanner stands beside the reference camera, as in the preset.
      const Camera& ref = g.cameras[g.reference_index];
      const double offset = (g.scanner_center_world - ref.center_world).norm();
      EXPECT_NEAR(offset,
                  (own.scanner_center_world - own.cameras[own.reference_index].center_world).norm(),
                  1e-9);
      // Scene constants do not change with the number of views.
      EXPECT_EQ(g.texture_min_wavelength_m, own.texture_min_wavelength_m);
      EXPECT_EQ(g.default_laser_angular_step_rad, own.default_laser_angular_step_rad);
      EXPECT_EQ(g.mesh_max_chord_error_m, own.mesh_max_chord_error_m);
    }
  }
  // On the fountain's arc "0005" is head-on up to 11 views and the sixth beyond.
  EXPECT_LT(std::abs(StationAngleDeg(MakePresetGeometry("fountain", 11),
                                     MakePresetGeometry("fountain", 11).cameras[5])),
            1.0);
  const PresetGeometry fountain31 = MakePresetGeometry("fountain", 31);
  EXPECT_EQ(fountain31.view_names.front(), "0000");
  EXPECT_EQ(fountain31.view_names.back(), "0030");
  EXPECT_EQ(fountain31.reference_index, 5);
  const PresetGeometry tiny3 = MakePresetGeometry("tiny", 3);
  EXPECT_EQ(tiny3.view_names, (std::vector<std::string>{"0004", "0005", "0006"}));
}

// A generated scene with N views: N images with their ground truth, the laser fired from beside
// "0005" and covering it.
TEST(SynthGeneratorTest, ViewsOptionGeneratesNViews) {
  SynthOptions options;
  options.preset = "tiny";
  options.supersampling = 1;
  options.views = 8;
  const SyntheticScene s = GenerateScene(options);
  const PresetGeometry g = MakePresetGeometry("tiny", 8);
  ASSERT_EQ(s.views.size(), 8u);
  ASSERT_EQ(s.depth.size(), 8u);
  ASSERT_EQ(s.sigma.size(), 8u);
  EXPECT_EQ(s.summary.num_views, 8);
  EXPECT_EQ(s.reference_index, g.reference_index);
  EXPECT_EQ(s.views[s.reference_index].name, "0005");
  EXPECT_EQ(s.summary.reference_name, "0005");
  EXPECT_LT((s.laser_scanner_world - g.scanner_center_world).norm(), 1e-12);
  for (size_t v = 0; v < s.views.size(); ++v) {
    EXPECT_EQ(s.views[v].name, g.view_names[v]);
    EXPECT_EQ(s.views[v].image.cols, 160);
    EXPECT_EQ(s.views[v].image.rows, 107);
    EXPECT_EQ(s.depth[v].size(), s.views[v].image.size());
    EXPECT_LT((s.views[v].camera.center_world - g.cameras[v].center_world).norm(), 1e-12);
  }
  // The scan covers the reference view as it does the preset's (laser_test.cpp): a laser point
  // in more than 90 % of its 8×8 pixel blocks.
  const BlockCoverage coverage = LaserCoverageOfReference(s);
  EXPECT_GT(coverage.covered, 0.9 * coverage.total)
      << coverage.covered << " of " << coverage.total << " blocks";
  options.views = 0;
  EXPECT_EQ(GenerateScene(options).views.size(), 5u);
}

TEST(SynthGeneratorTest, OptionsCheckNamesTheKey) {
  auto message = [](const SynthOptions& o) -> std::string {
    try {
      o.Check();
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  SynthOptions o;
  EXPECT_EQ(message(o), "");
  o.preset = "huge";
  EXPECT_EQ(message(o), "synth.preset = 'huge'. Violated constraint: one of tiny, small, fountain");
  o = SynthOptions();
  o.image_noise_sigma = -1.0;
  EXPECT_EQ(message(o),
            "synth.image_noise_sigma = -1. Violated constraint: 0 <= image_noise_sigma <= 20");
  o = SynthOptions();
  o.laser_max_incidence_deg = 95.0;
  EXPECT_EQ(
      message(o),
      "synth.laser_max_incidence_deg = 95. Violated constraint: 0 < laser_max_incidence_deg <= 90");
  o = SynthOptions();
  o.supersampling = 9;
  EXPECT_EQ(message(o), "synth.supersampling = 9. Violated constraint: 0 <= supersampling <= 8");
  o = SynthOptions();
  o.laser_sigma_per_m = std::nan("");
  EXPECT_NE(message(o).find("synth.laser_sigma_per_m = nan"), std::string::npos);
  EXPECT_THROW(MakePresetGeometry("medium"), ConfigError);
  for (int views : {-1, 1, 2, 100}) {
    o = SynthOptions();
    o.views = views;
    EXPECT_EQ(message(o), "synth.views = " + std::to_string(views) +
                              ". Violated constraint: views == 0 (the preset's cameras) or 3 <= "
                              "views <= 99");
    try {
      MakePresetGeometry("tiny", views);
      ADD_FAILURE() << "views " << views << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_EQ(std::string(e.what()), message(o));
    }
  }
  for (int views : {0, 3, 99}) {
    o.views = views;
    EXPECT_EQ(message(o), "") << views;
  }
}

TEST(SynthGeneratorTest, ProgressIsReportedAndCanCancel) {
  SynthOptions options;
  options.preset = "tiny";
  options.supersampling = 1;
  std::vector<double> fractions;
  GenerateScene(options, [&](double f) {
    fractions.push_back(f);
    return true;
  });
  ASSERT_EQ(fractions.size(), 7u);  // 5 views, laser, mesh
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  try {
    GenerateScene(options, [](double) { return false; });
    FAIL() << "expected cancellation";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cancelled"), std::string::npos);
  }
}

}  // namespace
}  // namespace gcpstereo::synth
