// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"
#include "gcpstereo/gcp/gcp_sources.h"

namespace gcpstereo::gcp {
namespace {

// Scene (world frame): a wall z = 10 and a box [−0.5, 0.5]×[−0.4, 0.4]×[6, 7] in front of it.
// The camera sits at the origin looking down +z; the scanner at (2, 0.3, 0) sees the wall behind
// the box and the box's right side face, both hidden from the camera.
const Eigen::Vector3d kBoxMin(-0.5, -0.4, 6.0);
const Eigen::Vector3d kBoxMax(0.5, 0.4, 7.0);
constexpr double kWallZ = 10.0;

// Entry parameter t ∈ [0, 1] of the segment origin + t·(end − origin) into the box, or +inf.
double BoxEntry(const Eigen::Vector3d& origin, const Eigen::Vector3d& end) {
  const Eigen::Vector3d dir = end - origin;
  double t0 = 0.0, t1 = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-15) {
      if (origin[a] < kBoxMin[a] || origin[a] > kBoxMax[a]) return kInvalidDepth;
      continue;
    }
    double ta = (kBoxMin[a] - origin[a]) / dir[a];
    double tb = (kBoxMax[a] - origin[a]) / dir[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return kInvalidDepth;
  }
  return t0;
}

Camera ReferenceCamera() {
  Camera camera;
  camera.K << 200, 0, 79.5, 0, 200, 59.5, 0, 0, 1;
  camera.width = 160;
  camera.height = 120;
  return camera;
}

struct Scan {
  std::vector<Eigen::Vector3d> points_world;
  PointCloud cloud;  // in the lidar frame
  Eigen::Matrix4d world_from_lidar;
};

Scan MakeScan() {
  Scan scan;
  const Eigen::Vector3d scanner(2.0, 0.3, 0.0);
  // The lidar frame: rotated 30° about y and 10° about x, origin at the scanner.
  Eigen::Affine3d world_from_lidar = Eigen::Translation3d(scanner) *
                                     Eigen::AngleAxisd(0.5236, Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd(0.1745, Eigen::Vector3d::UnitX());
  scan.world_from_lidar = world_from_lidar.matrix();
  const Eigen::Affine3d lidar_from_world = world_from_lidar.inverse();
  // Rays through a 0.07 m grid on the wall (pixels are 0.05 m there): first hit of box or wall.
  for (double y = -3.2; y <= 3.2; y += 0.07) {
    for (double x = -4.2; x <= 4.2; x += 0.07) {
      const Eigen::Vector3d on_wall(x, y, kWallZ);
      const double t = BoxEntry(scanner, on_wall);
      const Eigen::Vector3d hit = std::isfinite(t) ? scanner + t * (on_wall - scanner) : on_wall;
      const Eigen::Vector3f stored = (lidar_from_world * hit).cast<float>();
      scan.cloud.points.push_back(stored);
      // The point as the library sees it (float storage), back in the world frame.
      scan.points_world.push_back(world_from_lidar * stored.cast<double>());
    }
  }
  return scan;
}

TEST(LidarGcpsTest, VisiblePointsLandOnTheirPixelAndOccludedOnesAreRejected) {
  const Scan scan = MakeScan();
  const Camera camera = ReferenceCamera();
  LidarGcpOptions options;
  options.default_sigma = 0.0;  // tolerance = slant term only
  GcpSourceSummary summary;
  const GcpSet gcps =
      GcpsFromPointCloud(scan.cloud, scan.world_from_lidar, camera, options, &summary);

  std::map<std::pair<int, int>, Gcp> by_pixel;
  for (const Gcp& g : gcps.points) {
    EXPECT_TRUE(by_pixel.emplace(std::make_pair(g.row, g.col), g).second) << "duplicate pixel";
    EXPECT_EQ(g.source, GcpSource::kLidar);
  }
  const double slope = std::tan(options.max_surface_slant_deg * M_PI / 180.0) / 200.0;
  const double max_window_px = options.consistency_radius_px * std::sqrt(2.0) + 1.0;
  int hidden_wall = 0, hidden_side = 0, visible_checked = 0, kept_occluded = 0;
  for (const Eigen::Vector3d& p : scan.points_world) {
    Eigen::Vector2d pixel;
    double depth = 0.0;
    ASSERT_TRUE(camera.Project(p, &pixel, &depth));
    if (!camera.InImage(pixel)) continue;
    const std::pair<int, int> key(static_cast<int>(std::lround(pixel.y())),
                                  static_cast<int>(std::lround(pixel.x())));
    const double entry = BoxEntry(Eigen::Vector3d::Zero(), p);
    const double gap = std::isfinite(entry) ? depth * (1.0 - entry) : 0.0;  // behind the occluder
    const auto it = by_pixel.find(key);
    const bool is_gcp = it != by_pixel.end() && std::abs(it->second.depth - depth) < 1e-6;
    if (gap > 1e-6) {
      if (p.z() > kWallZ - 1e-4)
        ++hidden_wall;
      else
        ++hidden_side;
      // An occluded point may only survive within the slant tolerance of the test (side-face
      // points right behind the front edge); never one seen through the box.
      if (is_gcp) {
        ++kept_occluded;
        EXPECT_LE(gap, depth * max_window_px * slope) << p.transpose();
      }
      if (gap > 1.0) {
        EXPECT_FALSE(is_gcp) << "wall point behind the box kept: " << p.transpose();
      }
      continue;
    }
    // Visible. Wall points within r + 1.5 px of the box silhouette may be dropped by design.
    const double u = pixel.x() - 79.5, v = pixel.y() - 59.5;
    const double box_u = 200.0 * 0.5 / 6.0, box_v = 200.0 * 0.4 / 6.0;
    const double outside = std::max(std::abs(u) - box_u, std::abs(v) - box_v);
    if (p.z() > kWallZ - 1e-4 && outside < options.consistency_radius_px + 1.5) continue;
    ++visible_checked;
    ASSERT_NE(it, by_pixel.end()) << "visible point lost: " << p.transpose() << " at pixel "
                                  << pixel.transpose();
    // Either this point is the pixel's GCP, or a nearer point of the same pixel won the z-buffer.
    EXPECT_LE(it->second.depth, depth + 1e-6);
    EXPECT_LT(depth - it->second.depth, 0.1);
  }
  EXPECT_GT(hidden_wall, 100);  // the scene really tests occlusion
  EXPECT_GT(hidden_side, 20);
  EXPECT_GT(visible_checked, 3000);
  EXPECT_EQ(summary.num_gcps, static_cast<int>(gcps.size()));
  EXPECT_EQ(summary.num_input, static_cast<int>(scan.cloud.size()));
  EXPECT_GT(summary.num_inconsistent, hidden_wall / 2);
  std::cout << "[ lidar    ] " << scan.cloud.size() << " points: " << summary.num_outside_image
            << " outside, " << summary.num_same_pixel << " same pixel, " << summary.num_inconsistent
            << " inconsistent, " << summary.num_gcps << " GCPs (" << summary.density_percent
            << " %); occluded in view: " << hidden_wall << " wall + " << hidden_side
            << " side, kept " << kept_occluded << "\n";
}

TEST(LidarGcpsTest, ZBufferOnlyKeepsNearestPerPixel) {
  // Two points on the same pixel ray: the nearer one wins even without the window test.
  PointCloud cloud;
  cloud.points = {Eigen::Vector3f(0, 0, 5), Eigen::Vector3f(0, 0, 3), Eigen::Vector3f(0.5, 0, 5)};
  cloud.sigma = {0.1f, 0.2f, 0.3f};
  LidarGcpOptions options;
  options.consistency_radius_px = 0;
  GcpSourceSummary summary;
  const GcpSet gcps =
      GcpsFromPointCloud(cloud, Eigen::Matrix4d::Identity(), ReferenceCamera(), options, &summary);
  ASSERT_EQ(gcps.size(), 2u);
  EXPECT_EQ(gcps.points[0].col, 80);  // 79.5 rounds half away from zero
  EXPECT_DOUBLE_EQ(gcps.points[0].depth, 3.0);
  EXPECT_FLOAT_EQ(static_cast<float>(gcps.points[0].sigma), 0.2f);
  EXPECT_EQ(gcps.points[1].col, static_cast<int>(std::lround(79.5 + 200 * 0.5 / 5)));
  EXPECT_EQ(summary.num_same_pixel, 1);
}

TEST(LidarGcpsTest, CountsPointsBehindAndOutside) {
  PointCloud cloud;
  cloud.points = {Eigen::Vector3f(0, 0, -2), Eigen::Vector3f(50, 0, 2),
                  Eigen::Vector3f(0, 0, std::numeric_limits<float>::quiet_NaN())};
  GcpSourceSummary summary;
  const GcpSet gcps = GcpsFromPointCloud(cloud, Eigen::Matrix4d::Identity(), ReferenceCamera(),
                                         LidarGcpOptions(), &summary);
  EXPECT_TRUE(gcps.empty());
  EXPECT_EQ(summary.num_behind_camera, 1);
  EXPECT_EQ(summary.num_outside_image, 1);
  EXPECT_EQ(summary.num_invalid, 1);
}

TEST(LidarGcpsTest, BadInputsThrow) {
  PointCloud cloud;
  cloud.points = {Eigen::Vector3f(0, 0, 2)};
  cloud.sigma = {0.1f, 0.2f};
  try {
    GcpsFromPointCloud(cloud, Eigen::Matrix4d::Identity(), ReferenceCamera(), LidarGcpOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "GcpsFromPointCloud: the cloud has 1 points but 2 sigma values");
  }
  LidarGcpOptions options;
  options.max_surface_slant_deg = 90.0;
  try {
    options.Check();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "gcp.lidar.max_surface_slant_deg = 90. Violated constraint: 0 < "
                 "max_surface_slant_deg < 90");
  }
  options = LidarGcpOptions();
  options.consistency_radius_px = -1;
  EXPECT_THROW(options.Check(), ConfigError);
}

}  // namespace
}  // namespace gcpstereo::gcp
