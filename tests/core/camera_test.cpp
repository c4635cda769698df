// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/camera.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"

namespace gcpstereo {
namespace {

Camera MakeCamera() {
  Camera c;
  c.K << 1000.0, 0.0, 320.0, 0.0, 1010.0, 240.0, 0.0, 0.0, 1.0;
  c.world_from_camera_rotation =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1.0, -0.4).normalized()).toRotationMatrix();
  c.center_world = Eigen::Vector3d(1.0, -2.0, 0.5);
  c.width = 640;
  c.height = 480;
  return c;
}

TEST(Camera, ProjectBackProjectRoundTrip) {
  const Camera c = MakeCamera();
  const Eigen::Vector2d pixel(123.25, 345.5);
  const Eigen::Vector3d X = c.BackProject(pixel, 7.5);
  Eigen::Vector2d projected;
  double depth = 0.0;
  ASSERT_TRUE(c.Project(X, &projected, &depth));
  EXPECT_NEAR(depth, 7.5, 1e-12);
  EXPECT_NEAR((projected - pixel).norm(), 0.0, 1e-9);
  // The projection matrix agrees with Project().
  const Eigen::Vector3d h = c.ProjectionMatrix() * X.homogeneous();
  EXPECT_NEAR((h.head<2>() / h.z() - pixel).norm(), 0.0, 1e-9);
}

TEST(Camera, PointBehindIsNotProjected) {
  const Camera c = MakeCamera();
  const Eigen::Vector3d behind = c.WorldFromCamera(Eigen::Vector3d(0.1, 0.2, -3.0));
  Eigen::Vector2d pixel(-1, -1);
  double depth = -1;
  EXPECT_FALSE(c.Project(behind, &pixel, &depth));
  EXPECT_EQ(depth, -1);
}

TEST(Camera, RescaleKeepsPixelCentreConvention) {
  const Camera c = MakeCamera();
  const Camera half = c.Rescaled(0.5);
  EXPECT_EQ(half.width, 320);
  EXPECT_EQ(half.height, 240);
  const Eigen::Vector3d X = c.BackProject(Eigen::Vector2d(99.5, 199.5), 4.0);
  Eigen::Vector2d full_px, half_px;
  double d1, d2;
  ASSERT_TRUE(c.Project(X, &full_px, &d1));
  ASSERT_TRUE(half.Project(X, &half_px, &d2));
  // Full-resolution pixels 99 and 100 (centres 99, 100) make half-resolution pixel 49.5 … centre
  // of the 2×2 block: x' = 0.5 (x + 0.5) − 0.5.
  EXPECT_NEAR(half_px.x(), 0.5 * (full_px.x() + 0.5) - 0.5, 1e-9);
  EXPECT_NEAR(half_px.y(), 0.5 * (full_px.y() + 0.5) - 0.5, 1e-9);
}

TEST(Camera, ValidateRejectsBadCameras) {
  Camera c = MakeCamera();
  EXPECT_NO_THROW(c.Validate("cam"));

  Camera bad_focal = c;
  bad_focal.K(0, 0) = -5.0;
  EXPECT_THROW(
      {
        try {
          bad_focal.Validate("cam.camera");
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(),
                       "cam.camera: focal lengths must be positive, got fx = -5, fy = 1010");
          throw;
        }
      },
      Error);

  Camera not_orthonormal = c;
  not_orthonormal.world_from_camera_rotation(0, 0) += 0.01;
  try {
    not_orthonormal.Validate("x");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("rotation is not orthonormal"), std::string::npos);
  }

  Camera reflection = c;
  reflection.world_from_camera_rotation.col(0) *= -1.0;
  try {
    reflection.Validate("x");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("determinant is -1"), std::string::npos) << e.what();
  }

  Camera nan_center = c;
  nan_center.center_world.x() = std::nan("");
  EXPECT_THROW(nan_center.Validate("x"), Error);
}

TEST(Camera, RectifiedSequenceDisparity) {
  // A point at depth z has disparity f·B/z per view step between neighbouring views.
  const double f = 500.0, B = 0.1, z = 2.5;
  const Camera left = RectifiedSequenceCamera(f, 200, 150, B, 0, 400, 300);
  const Camera right = RectifiedSequenceCamera(f, 200, 150, B, 1, 400, 300);
  const Eigen::Vector3d X = left.BackProject(Eigen::Vector2d(210.0, 100.0), z);
  Eigen::Vector2d pr;
  double d;
  ASSERT_TRUE(right.Project(X, &pr, &d));
  EXPECT_NEAR(210.0 - pr.x(), f * B / z, 1e-9);
  EXPECT_NEAR(pr.y(), 100.0, 1e-9);
}

}  // namespace
}  // namespace gcpstereo
