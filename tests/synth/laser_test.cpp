// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The simulated laser scan: points on the surface with residuals distributed as their sigma,
// first returns only, and dropouts at grazing angles.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/scene.h"
#include "laser_coverage.h"

namespace gcpstereo::synth {
namespace {

using Eigen::Vector3d;

struct ResidualStats {
  double mean = 0.0, stddev = 0.0, max_incidence_deg = 0.0;
  int count = 0;
};

ResidualStats ScanResiduals(const SyntheticScene& s, const SynthOptions& options) {
  const PresetGeometry g = MakePresetGeometry(options.preset);
  const AnalyticScene scene = AnalyticScene::MakeCourtyard(g.texture_min_wavelength_m, 1);
  const Vector3d scanner = s.laser_scanner_world;
  double sum = 0.0, sum_sq = 0.0;
  ResidualStats stats;
  for (size_t i = 0; i < s.laser.size(); ++i) {
    const Vector3d p = s.laser.points[i].cast<double>();
    const Vector3d d = (p - scanner).normalized();
    SurfaceHit hit;
    // The first surface along the measured point's ray: a point behind an occluder would show up
    // as a residual of metres.
    if (!scene.Intersect(scanner, d, 1e4, &hit)) {
      ADD_FAILURE() << "laser point " << i << " has no surface behind it";
      continue;
    }
    const double sigma = s.laser.sigma[i];
    EXPECT_NEAR(sigma, LaserSigma(options, hit.t), 1e-6);
    const double z = ((p - scanner).norm() - hit.t) / sigma;
    sum += z;
    sum_sq += z * z;
    ++stats.count;
    stats.max_incidence_deg =
        std::max(stats.max_incidence_deg, std::acos(-hit.normal_world.dot(d)) * 180.0 / M_PI);
  }
  stats.mean = sum / stats.count;
  stats.stddev = std::sqrt(sum_sq / stats.count - stats.mean * stats.mean);
  return stats;
}

TEST(SynthLaserTest, ResidualsMatchTheirSigma) {
  SynthOptions options;
  options.preset = "tiny";
  options.seed = 12345;
  const SyntheticScene s = GenerateScene(options);
  ASSERT_GT(s.laser.size(), 5000u);
  const ResidualStats stats = ScanResiduals(s, options);
  // Normalised residuals are standard normal: with n > 5000 the sample std is within ±2 % and the
  // mean within ±0.03 (2σ of their sampling distributions).
  EXPECT_GT(stats.stddev, 0.9);
  EXPECT_LT(stats.stddev, 1.1);
  EXPECT_LT(std::abs(stats.mean), 0.05);
  EXPECT_LE(stats.max_incidence_deg, options.laser_max_incidence_deg + 0.01);
}

TEST(SynthLaserTest, NoiseModelKnobsAreHonoured) {
  SynthOptions options;
  options.preset = "tiny";
  options.laser_sigma_constant_m = 0.02;
  options.laser_sigma_per_m = 0.0;
  options.laser_max_incidence_deg = 60.0;
  options.laser_angular_step_rad = 0.01;
  const SyntheticScene s = GenerateScene(options);
  const ResidualStats stats = ScanResiduals(s, options);
  EXPECT_GT(stats.stddev, 0.9);
  EXPECT_LT(stats.stddev, 1.1);
  for (float sigma : s.laser.sigma) ASSERT_FLOAT_EQ(sigma, 0.02f);
  EXPECT_LE(stats.max_incidence_deg, 60.01);
  // A stricter incidence limit drops more points.
  SynthOptions loose = options;
  loose.laser_max_incidence_deg = 85.0;
  const SyntheticScene t = GenerateScene(loose);
  EXPECT_EQ(s.summary.laser_rays, t.summary.laser_rays);
  EXPECT_GT(s.summary.laser_grazing_dropouts, t.summary.laser_grazing_dropouts);
  EXPECT_LT(s.summary.laser_points, t.summary.laser_points);
}

TEST(SynthLaserTest, ScanCoversTheReferenceView) {
  SynthOptions options;
  options.preset = "tiny";
  const SyntheticScene s = GenerateScene(options);
  const BlockCoverage coverage = LaserCoverageOfReference(s);
  EXPECT_GT(coverage.covered, 0.9 * coverage.total)
      << coverage.covered << " of " << coverage.total << " blocks";
}

}  // namespace
}  // namespace gcpstereo::synth
