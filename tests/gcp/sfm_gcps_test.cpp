// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// GCPs from SfM points: each filter drops exactly its points, the z-buffer keeps the nearest, and
// sigma is the depth change that the image error causes when the point is triangulated again.
#include "gcpstereo/gcp/sfm_gcps.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo::gcp {
namespace {

// Looks down +z from the origin, f = 100 px, 200×100 pixels.
Camera Reference() {
  Camera c;
  c.K << 100, 0, 99.5, 0, 100, 49.5, 0, 0, 1;
  c.width = 200;
  c.height = 100;
  return c;
}

SfmPoint Point(const Eigen::Vector3d& X, int track, double error,
               std::vector<Eigen::Vector3d> others) {
  SfmPoint p;
  p.point_world = X;
  p.track_length = track;
  p.error_px = error;
  p.other_centers_world = std::move(others);
  return p;
}

std::vector<SfmPoint> FilterCases() {
  const Eigen::Vector3d left(-1, 0, 0), right(1, 0, 0);
  return {
      Point({0.0, 0.0, 5.0}, 3, 0.5, {left, right}),   // 0 kept
      Point({0.5, 0.0, 5.0}, 2, 0.5, {right}),         // 1 short track
      Point({-0.5, 0.0, 5.0}, 3, 3.0, {left, right}),  // 2 large error
      Point({0.0, 0.5, 5.0}, 3, 0.5, {{0.05, 0, 0}}),  // 3 small angle (0.57°)
      Point({0.0, 0.0, -5.0}, 3, 0.5, {left, right}),  // 4 behind
      Point({20.0, 0.0, 5.0}, 3, 0.5, {left, right}),  // 5 outside
      Point({0.0, 0.0, 7.0}, 3, 0.5, {left, right}),   // 6 same pixel as 0, farther
  };
}

TEST(SfmGcps, EachFilterDropsItsPoints) {
  GcpSourceSummary summary;
  const GcpSet gcps = GcpsFromSfmPoints(FilterCases(), Reference(), 1.0, {}, &summary);
  ASSERT_EQ(gcps.size(), 1u);
  EXPECT_EQ(gcps.points[0].col, 100);  // x = 99.5 rounds to 100
  EXPECT_EQ(gcps.points[0].row, 50);
  EXPECT_DOUBLE_EQ(gcps.points[0].depth, 5.0);
  EXPECT_EQ(gcps.points[0].source, GcpSource::kSfm);
  EXPECT_EQ(summary.source, "sfm");
  EXPECT_EQ(summary.num_input, 7);
  EXPECT_EQ(summary.num_short_track, 1);
  EXPECT_EQ(summary.num_large_error, 1);
  EXPECT_EQ(summary.num_small_angle, 1);
  EXPECT_EQ(summary.num_behind_camera, 1);
  EXPECT_EQ(summary.num_outside_image, 1);
  EXPECT_EQ(summary.num_same_pixel, 1);
  EXPECT_EQ(summary.num_gcps, 1);

  // Each key, relaxed, lets its point through.
  SfmGcpOptions o;
  o.min_track_length = 2;
  EXPECT_EQ(GcpsFromSfmPoints(FilterCases(), Reference(), 1.0, o).size(), 2u);
  o = {};
  o.max_error_px = 3.5;
  EXPECT_EQ(GcpsFromSfmPoints(FilterCases(), Reference(), 1.0, o).size(), 2u);
  o = {};
  o.min_angle_deg = 0.5;
  EXPECT_EQ(GcpsFromSfmPoints(FilterCases(), Reference(), 1.0, o).size(), 2u);
}

// The reference sees X on its axis; another camera (identity rotation, centre C) observes it with
// an error of e pixels along x. Triangulating again moves X along the reference's ray by Δz.
double DepthChangeOfImageError(const Eigen::Vector3d& X, const Eigen::Vector3d& C, double f,
                               double e) {
  const Eigen::Vector3d v = X - C;
  // The other camera's perturbed ray: direction (v.x/v.z + e/f, v.y/v.z, 1).
  const Eigen::Vector3d d(v.x() / v.z() + e / f, v.y() / v.z(), 1.0);
  // Intersect C + s d with the reference's axis x = 0 (y = 0 holds here): s = −C.x / d.x.
  const double s = -C.x() / d.x();
  return std::abs((C + s * d).z() - X.z());
}

TEST(SfmGcps, SigmaIsTheTriangulationDepthError) {
  const Eigen::Vector3d X(0, 0, 5), C(1.0, 0, 0);
  for (const double scale : {1.0, 0.5}) {
    Camera reference = Reference();
    if (scale != 1.0) reference = reference.Rescaled(scale);
    const GcpSet gcps = GcpsFromSfmPoints({Point(X, 3, 0.8, {C})}, reference, scale, {});
    ASSERT_EQ(gcps.size(), 1u);
    // The model's images have f = 100 whatever the reference's scale.
    const double expected = DepthChangeOfImageError(X, C, 100.0, 0.8);
    EXPECT_NEAR(gcps.points[0].sigma, expected, 0.02 * expected) << "scale " << scale;
  }
  // The best observer counts; an error below min_error_px counts as min_error_px.
  const GcpSet best =
      GcpsFromSfmPoints({Point(X, 3, 0.01, {C, Eigen::Vector3d(0.2, 0, 0)})}, Reference(), 1.0, {});
  ASSERT_EQ(best.size(), 1u);
  const double expected = DepthChangeOfImageError(X, C, 100.0, 0.5);
  EXPECT_NEAR(best.points[0].sigma, expected, 0.02 * expected);
}

// gcp.sfm.projected: an unobserved point behind an observed wall fails the LiDAR source's
// consistency test; one beside the wall is added; off, neither is.
TEST(SfmGcps, ProjectedPointsPassTheVisibilityTests) {
  const Eigen::Vector3d left(-1, 0, 0), right(1, 0, 0);
  auto at = [](double col, double row, double z) {
    return Eigen::Vector3d((col - 99.5) / 100 * z, (row - 49.5) / 100 * z, z);
  };
  std::vector<SfmPoint> points;
  for (int row = 30; row <= 70; row += 2) {
    for (int col = 80; col <= 120; col += 2) {
      points.push_back(Point(at(col, row, 5.0), 3, 0.5, {left, right}));
    }
  }
  const size_t wall = points.size();
  SfmPoint behind = Point(at(101, 51, 8.0), 3, 0.5, {left, right});
  behind.observed = false;
  SfmPoint beside = Point(at(20, 20, 8.0), 3, 0.5, {left, right});
  beside.observed = false;
  points.push_back(behind);
  points.push_back(beside);

  GcpSourceSummary summary;
  const GcpSet observed_only = GcpsFromSfmPoints(points, Reference(), 1.0, {}, &summary);
  EXPECT_EQ(observed_only.size(), wall);
  EXPECT_EQ(summary.num_input, static_cast<int>(wall));

  SfmGcpOptions o;
  o.projected = true;
  const GcpSet gcps = GcpsFromSfmPoints(points, Reference(), 1.0, o, &summary);
  ASSERT_EQ(gcps.size(), wall + 1);
  EXPECT_EQ(summary.num_input, static_cast<int>(wall + 2));
  EXPECT_EQ(summary.num_inconsistent, 1);
  EXPECT_EQ(summary.num_same_pixel, 0);
  bool found_beside = false;
  for (const Gcp& g : gcps.points) {
    EXPECT_FALSE(g.col == 101 && g.row == 51) << "the point behind the wall";
    if (g.col == 20 && g.row == 20) {
      found_beside = true;
      EXPECT_NEAR(g.depth, 8.0, 1e-9);
      EXPECT_GT(g.sigma, 0.0);
    }
  }
  EXPECT_TRUE(found_beside);

  // It is the consistency test that hides the point behind the wall (z-buffer only: it passes).
  LidarGcpOptions zbuffer_only;
  zbuffer_only.consistency_radius_px = 0;
  EXPECT_EQ(GcpsFromSfmPoints(points, Reference(), 1.0, o, nullptr, zbuffer_only).size(), wall + 2);
}

TEST(SfmGcps, BadOptionsNameTheKey) {
  auto error = [](SfmGcpOptions o) -> std::string {
    try {
      o.Check();
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(no error)";
  };
  SfmGcpOptions o;
  o.min_track_length = 1;
  EXPECT_EQ(error(o),
            "gcp.sfm.min_track_length = 1. Violated constraint: gcp.sfm.min_track_length >= 2");
  o = {};
  o.min_angle_deg = 90;
  EXPECT_EQ(error(o),
            "gcp.sfm.min_angle_deg = 90. Violated constraint: 0 < gcp.sfm.min_angle_deg < 90");
  o = {};
  o.max_error_px = 0;
  EXPECT_EQ(error(o), "gcp.sfm.max_error_px = 0. Violated constraint: gcp.sfm.max_error_px > 0");
}

}  // namespace
}  // namespace gcpstereo::gcp
