// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The analytic scene against its own tessellation, and the generator's depth maps against direct
// ray casting.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/scene.h"

namespace gcpstereo::synth {
namespace {

using Eigen::Vector3d;

// Möller–Trumbore; returns the nearest t > 1e-6 over all faces, +inf when none.
double NearestMeshHit(const TriangleMesh& mesh, const Vector3d& o, const Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : mesh.faces) {
    const Vector3d a = mesh.vertices[f[0]].cast<double>();
    const Vector3d e1 = mesh.vertices[f[1]].cast<double>() - a;
    const Vector3d e2 = mesh.vertices[f[2]].cast<double>() - a;
    const Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) continue;
    const double inv = 1.0 / det;
    const Vector3d s = o - a;
    const double u = s.dot(p) * inv;
    if (u < 0.0 || u > 1.0) continue;
    const Vector3d q = s.cross(e1);
    const double v = d.dot(q) * inv;
    if (v < 0.0 || u + v > 1.0) continue;
    const double t = e2.dot(q) * inv;
    if (t > 1e-6 && t < best) best = t;
  }
  return best;
}

TEST(AnalyticSceneTest, TessellatedMeshAgreesWithExactIntersection) {
  const double tol = 0.004;  // chord error of the tessellation, metres
  const AnalyticScene scene = AnalyticScene::MakeCourtyard(0.05, 1);
  const TriangleMesh mesh = scene.Tessellate(tol);
  ASSERT_GT(mesh.faces.size(), 1000u);
  ASSERT_EQ(mesh.colors.size(), mesh.vertices.size());
  const PresetGeometry g = MakePresetGeometry("tiny");
  const Camera& cam = g.cameras[g.reference_index];
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0.0, cam.width - 1.0), uy(0.0, cam.height - 1.0);
  int compared = 0, agree = 0, skipped_grazing = 0;
  double worst_agreeing_error = 0.0;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector2d px(ux(rng), uy(rng));
    const Vector3d d = (cam.BackProject(px, 1.0) - cam.center_world).normalized();
    SurfaceHit hit;
    const bool exact = scene.Intersect(cam.center_world, d, 1e4, &hit);
    const double t_mesh = NearestMeshHit(mesh, cam.center_world, d);
    if (!exact) {
      EXPECT_FALSE(std::isfinite(t_mesh)) << "mesh hit where the analytic scene has sky";
      continue;
    }
    const double cos_incidence = -hit.normal_world.dot(d);
    ASSERT_GT(cos_incidence, 0.0);
    if (cos_incidence < 0.2) {  // grazing: a chord error is magnified without bound
      ++skipped_grazing;
      continue;
    }
    ++compared;
    // The mesh lies within `tol` of the surface along its normal, i.e. within tol / cos along the
    // ray; inscribed polygons can also let a ray near a silhouette pass to the background.
    const double err = std::abs(t_mesh - hit.t);
    if (err <= tol / cos_incidence + 1e-5) {
      ++agree;
      worst_agreeing_error = std::max(worst_agreeing_error, err);
    }
  }
  EXPECT_GT(compared, 250);
  EXPECT_LT(skipped_grazing, 30);
  // Allow a few silhouette rays (of 300) to pass beside the inscribed polygon.
  EXPECT_GE(agree, compared - 3) << "compared " << compared;
}

TEST(AnalyticSceneTest, KnownSurfacesAtKnownDistances) {
  const AnalyticScene scene = AnalyticScene::MakeCourtyard(0.05, 1);
  SurfaceHit hit;
  // Straight down from 10 m onto open ground.
  ASSERT_TRUE(scene.Intersect(Vector3d(10.0, -12.0, 10.0), Vector3d(0, 0, -1), 1e4, &hit));
  EXPECT_NEAR(hit.t, 10.0, 1e-9);
  EXPECT_EQ(scene.PrimitiveName(hit.primitive), "ground");
  EXPECT_NEAR(hit.normal_world.z(), 1.0, 1e-12);
  // Horizontally onto the plaster wall (front face y = 0) at x = 6.5, z = 3.
  ASSERT_TRUE(scene.Intersect(Vector3d(6.5, -20.0, 3.0), Vector3d(0, 1, 0), 1e4, &hit));
  EXPECT_NEAR(hit.t, 20.0, 1e-9);
  EXPECT_EQ(scene.PrimitiveName(hit.primitive), "wall");
  EXPECT_EQ(scene.PrimitiveTexture(hit.primitive), TextureKind::kWeak);
  // Onto the fountain's ball (centre (0, −2.9, 1.7), radius 0.21) from above.
  ASSERT_TRUE(scene.Intersect(Vector3d(0.0, -2.9, 5.0), Vector3d(0, 0, -1), 1e4, &hit));
  EXPECT_NEAR(hit.t, 5.0 - 1.70 - 0.21, 1e-9);
  EXPECT_EQ(scene.PrimitiveName(hit.primitive), "fountain_ball");
  // Onto the basin's outer rim (radius 1.25 at z = 0.95 … 1.02) horizontally.
  ASSERT_TRUE(scene.Intersect(Vector3d(-5.0, -2.9, 0.99), Vector3d(1, 0, 0), 1e4, &hit));
  EXPECT_NEAR(hit.t, 5.0 - 1.25, 1e-9);
  EXPECT_EQ(scene.PrimitiveName(hit.primitive), "fountain_basin");
  EXPECT_NEAR(hit.normal_world.x(), -1.0, 1e-9);
  // Sky.
  EXPECT_FALSE(scene.Intersect(Vector3d(0, -10, 2), Vector3d(0, 0, 1), 1e4, &hit));
  // The relief stands out of the central section (front face y = −0.15) by up to 0.10 m.
  ASSERT_TRUE(scene.Intersect(Vector3d(0.0, -20.0, 3.9), Vector3d(0, 1, 0), 1e4, &hit));
  EXPECT_EQ(scene.PrimitiveName(hit.primitive), "relief");
  EXPECT_GT(hit.t, 20.0 - 0.15 - 0.10 - 1e-9);
  EXPECT_LT(hit.t, 20.0 - 0.15 - 0.03);
}

TEST(AnalyticSceneTest, RejectsBadArguments) {
  try {
    AnalyticScene::MakeCourtyard(0.0, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("texture_min_wavelength_m must be > 0"),
              std::string::npos);
  }
  const AnalyticScene scene = AnalyticScene::MakeCourtyard(0.05, 1);
  EXPECT_THROW(scene.Tessellate(-1.0), Error);
}

TEST(GeneratorDepthTest, DepthMapsMatchDirectRayCasting) {
  SynthOptions options;
  options.preset = "tiny";
  const SyntheticScene s = GenerateScene(options);
  const PresetGeometry g = MakePresetGeometry("tiny");
  const AnalyticScene scene = AnalyticScene::MakeCourtyard(g.texture_min_wavelength_m, 1);
  std::mt19937 rng(11);
  int valid = 0;
  for (size_t v = 0; v < s.views.size(); ++v) {
    const Camera& cam = s.views[v].camera;
    std::uniform_int_distribution<int> uc(0, cam.width - 1), ur(0, cam.height - 1);
    for (int i = 0; i < 200; ++i) {
      const int col = uc(rng), row = ur(rng);
      // Independent construction of the pixel-centre ray: through the point at depth 1.
      const Vector3d x1 = cam.BackProject(Eigen::Vector2d(col, row), 1.0);
      const Vector3d d = (x1 - cam.center_world).normalized();
      SurfaceHit hit;
      const float depth = s.depth[v].at<float>(row, col);
      if (!scene.Intersect(cam.center_world, d, 1e4, &hit)) {
        EXPECT_EQ(depth, kInvalidDepth);
        EXPECT_EQ(s.sigma[v].at<float>(row, col), kInvalidDepth);
        continue;
      }
      ++valid;
      const Vector3d p = cam.center_world + hit.t * d;
      Eigen::Vector2d px;
      double z;
      ASSERT_TRUE(cam.Project(p, &px, &z));
      EXPECT_NEAR(px.x(), col, 1e-6);
      EXPECT_NEAR(px.y(), row, 1e-6);
      EXPECT_NEAR(depth, z, 1e-5 * z) << "view " << v << " pixel " << col << "," << row;
      const double range = (p - s.laser_scanner_world).norm();
      EXPECT_NEAR(s.sigma[v].at<float>(row, col), LaserSigma(options, range), 1e-6);
    }
  }
  EXPECT_GT(valid, 800);
}

}  // namespace
}  // namespace gcpstereo::synth
