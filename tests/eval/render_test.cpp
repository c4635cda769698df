// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/render.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/eval/depth_sigma.h"

namespace gcpstereo::eval {
namespace {

// f = 10 px, principal point (32, 24), 64×48, at the origin looking down +z.
Camera TestCamera() { return RectifiedSequenceCamera(10.0, 32.0, 24.0, 0.1, 0, 64, 48); }

// The square [x0, x1] × [y0, y1] at depth z (two triangles).
void AddQuad(TriangleMesh* mesh, float x0, float x1, float y0, float y1, float z0, float z1) {
  const int base = static_cast<int>(mesh->vertices.size());
  mesh->vertices.push_back({x0, y0, z0});
  mesh->vertices.push_back({x1, y0, z1});
  mesh->vertices.push_back({x1, y1, z1});
  mesh->vertices.push_back({x0, y1, z0});
  mesh->faces.push_back({base, base + 1, base + 2});
  mesh->faces.push_back({base, base + 2, base + 3});
}

TEST(RenderMesh, QuadAtKnownDepth) {
  TriangleMesh mesh;
  AddQuad(&mesh, -1.0f, 1.0f, -1.0f, 1.0f, 5.0f, 5.0f);  // pixels [30, 34] × [22, 26]
  RenderMeshOptions options;
  options.sigma = 0.01;
  const RenderedDepth r = RenderMeshDepth(mesh, TestCamera(), options);
  ASSERT_EQ(r.depth.type(), CV_32F);
  ASSERT_EQ(r.depth.size(), cv::Size(64, 48));
  // Closed edges: the pixel centres on the quad's border (and on the shared diagonal) are covered.
  EXPECT_EQ(r.summary.pixels_covered, 25);
  EXPECT_EQ(r.summary.primitives, 2);
  for (int row = 0; row < 48; ++row) {
    for (int col = 0; col < 64; ++col) {
      const bool inside = col >= 30 && col <= 34 && row >= 22 && row <= 26;
      const float d = r.depth.at<float>(row, col);
      if (inside) {
        EXPECT_FLOAT_EQ(d, 5.0f) << col << "," << row;
        EXPECT_FLOAT_EQ(r.sigma.at<float>(row, col), 0.01f);
      } else {
        EXPECT_FALSE(std::isfinite(d)) << col << "," << row;
        EXPECT_FALSE(std::isfinite(r.sigma.at<float>(row, col)));
      }
    }
  }
  // The rendered GT evaluated against itself: 100 % within 1σ.
  const SigmaHistogram h = EvaluateDepthSigma(r.depth, r.depth, r.sigma);
  EXPECT_EQ(h.counted, 25);
  EXPECT_DOUBLE_EQ(h.WithinPercent(1), 100.0);
}

TEST(RenderMesh, SlantedPlaneIsPerspectiveCorrect) {
  // Plane through (−2, ·, 4) and (2, ·, 8): z = 6 + x. Along the ray of pixel column c,
  // x = z (c − 32) / 10, so z = 6 / (1 − (c − 32) / 10).
  TriangleMesh mesh;
  AddQuad(&mesh, -2.0f, 2.0f, -2.0f, 2.0f, 4.0f, 8.0f);
  const RenderedDepth r = RenderMeshDepth(mesh, TestCamera());
  EXPECT_TRUE(r.sigma.empty());
  int checked = 0;
  for (int col = 0; col < 64; ++col) {
    const float d = r.depth.at<float>(24, col);
    if (!std::isfinite(d)) continue;
    const double expected = 6.0 / (1.0 - (col - 32) / 10.0);
    EXPECT_NEAR(d, expected, 1e-5 * expected) << col;
    ++checked;
  }
  // x from −2 at z = 4 (pixel 27) to 2 at z = 8 (pixel 34.5): columns 27 … 34.
  EXPECT_EQ(checked, 8);
}

TEST(RenderMesh, NearestSurfaceWinsAndBadFacesAreCounted) {
  TriangleMesh mesh;
  AddQuad(&mesh, -1.0f, 1.0f, -1.0f, 1.0f, 5.0f, 5.0f);
  AddQuad(&mesh, -0.3f, 0.3f, -0.3f, 0.3f, 3.0f, 3.0f);    // nearer, pixels [31, 33] × [23, 25]
  AddQuad(&mesh, -1.0f, 1.0f, -1.0f, 1.0f, -2.0f, -2.0f);  // behind the camera
  mesh.faces.push_back({0, 0, 1});                         // repeated index
  mesh.faces.push_back({0, 1, 99});                        // index out of range
  const RenderedDepth r = RenderMeshDepth(mesh, TestCamera());
  EXPECT_EQ(r.summary.skipped_behind, 2);
  EXPECT_EQ(r.summary.skipped_degenerate, 2);
  EXPECT_EQ(r.summary.pixels_covered, 25);
  EXPECT_FLOAT_EQ(r.depth.at<float>(24, 32), 3.0f);
  EXPECT_FLOAT_EQ(r.depth.at<float>(23, 31), 3.0f);
  EXPECT_FLOAT_EQ(r.depth.at<float>(22, 30), 5.0f);
  // Face order does not matter.
  TriangleMesh reversed = mesh;
  std::reverse(reversed.faces.begin(), reversed.faces.end());
  const RenderedDepth r2 = RenderMeshDepth(reversed, TestCamera());
  const cv::Mat differs = r.depth != r2.depth;
  EXPECT_EQ(cv::countNonZero(differs), 0);
}

TEST(RenderMesh, RotatedCameraMatchesBackProjection) {
  // A large plane seen by a rotated, translated camera: every covered pixel back-projects onto it.
  Camera camera = RectifiedSequenceCamera(40.0, 32.0, 24.0, 0.1, 0, 64, 48);
  camera.world_from_camera_rotation =
      Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.3, 1.0, 0.1).normalized()).toRotationMatrix();
  camera.center_world = Eigen::Vector3d(0.5, -0.2, -1.0);
  TriangleMesh mesh;
  AddQuad(&mesh, -20.0f, 20.0f, -20.0f, 20.0f, 6.0f, 9.0f);  // z = 7.5 + 0.075 x
  const RenderedDepth r = RenderMeshDepth(mesh, camera);
  EXPECT_EQ(r.summary.pixels_covered, 64 * 48);
  for (int row = 0; row < 48; row += 7) {
    for (int col = 0; col < 64; col += 5) {
      const Eigen::Vector3d p =
          camera.BackProject(Eigen::Vector2d(col, row), r.depth.at<float>(row, col));
      EXPECT_NEAR(p.z(), 7.5 + 0.075 * p.x(), 1e-4) << col << "," << row;
    }
  }
}

TEST(RenderPoints, NearestPointSigmaAndSplat) {
  PointCloud cloud;
  cloud.points = {{0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, 4.0f}, {0.5f, 0.0f, 5.0f}, {0.0f, 0.0f, -3.0f}};
  cloud.sigma = {0.1f, 0.2f, 0.3f, 0.4f};
  const RenderedDepth r = RenderPointDepth(cloud, TestCamera());
  EXPECT_EQ(r.summary.skipped_behind, 1);
  EXPECT_EQ(r.summary.pixels_covered, 2);
  EXPECT_FLOAT_EQ(r.depth.at<float>(24, 32), 4.0f);
  EXPECT_FLOAT_EQ(r.sigma.at<float>(24, 32), 0.2f);
  EXPECT_FLOAT_EQ(r.depth.at<float>(24, 33), 5.0f);
  EXPECT_FLOAT_EQ(r.sigma.at<float>(24, 33), 0.3f);

  RenderPointsOptions options;
  options.splat_radius_px = 1;
  const RenderedDepth s =
      RenderPointDepth(cloud, TestCamera(), Eigen::Matrix4d::Identity(), options);
  EXPECT_EQ(s.summary.pixels_covered, 12);           // two 3×3 squares overlapping in 3 pixels
  EXPECT_FLOAT_EQ(s.depth.at<float>(24, 33), 4.0f);  // the nearer point's splat wins
  EXPECT_FLOAT_EQ(s.depth.at<float>(24, 34), 5.0f);

  cloud.sigma.pop_back();
  try {
    RenderPointDepth(cloud, TestCamera());
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "RenderPointDepth: the cloud has 4 points but 3 sigma values");
  }
  cloud.sigma.clear();
  const RenderedDepth no_sigma = RenderPointDepth(cloud, TestCamera());
  EXPECT_TRUE(no_sigma.sigma.empty());
  options = {};
  options.splat_radius_px = 17;
  EXPECT_THROW(RenderPointDepth(cloud, TestCamera(), Eigen::Matrix4d::Identity(), options),
               ConfigError);
}

}  // namespace
}  // namespace gcpstereo::eval
