// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"
#include "gcpstereo/gcp/sweep_motion.h"

namespace gcpstereo::gcp {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(SweepMotionTest, TimeOffsetFollowsTheRotation) {
  SweepOptions options;  // clockwise, 0.1 s, trigger facing +x
  const Eigen::Vector3f ahead(10, 0, 0), left(0, 10, 0), right(0, -10, 0);
  EXPECT_NEAR(SweepTimeOffset(ahead, options), 0.0, 1e-12);
  // Clockwise seen from above: the beam passes the left side before facing forward.
  EXPECT_NEAR(SweepTimeOffset(left, options), -0.025, 1e-9);
  EXPECT_NEAR(SweepTimeOffset(right, options), 0.025, 1e-9);
  EXPECT_NEAR(std::abs(SweepTimeOffset(Eigen::Vector3f(-10, 0, 0), options)), 0.05, 1e-9);
  options.clockwise = false;
  EXPECT_NEAR(SweepTimeOffset(left, options), 0.025, 1e-9);
  options.clockwise = true;
  options.trigger_azimuth_deg = 90.0;
  EXPECT_NEAR(SweepTimeOffset(left, options), 0.0, 1e-9);
  EXPECT_NEAR(SweepTimeOffset(ahead, options), 0.025, 1e-9);
}

// Static world points (trigger frame) as a moving, turning scanner measures them: the point is seen
// at the time t its azimuth in the sensor frame of time t is swept, a fixed point of
// t = offset(R(ωt)ᵀ (w − v t)) found by iteration (the scanner moves a few centimetres per sweep).
PointCloud SimulateSweep(const std::vector<Eigen::Vector3d>& world, const SweepMotion& motion,
                         const SweepOptions& options) {
  PointCloud scan;
  for (const Eigen::Vector3d& w : world) {
    double t = 0.0;
    Eigen::Vector3d measured = w;
    for (int it = 0; it < 50; ++it) {
      const Eigen::AngleAxisd yaw(motion.yaw_rate_rad_s * t, Eigen::Vector3d::UnitZ());
      measured = yaw.inverse() * (w - motion.velocity * t);
      t = SweepTimeOffset(measured.cast<float>(), options);
    }
    scan.points.push_back(measured.cast<float>());
    scan.intensity.push_back(0.5f);
  }
  return scan;
}

TEST(SweepMotionTest, CompensationUndoesASimulatedSweep) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> range(5.0, 40.0), angle(-kPi, kPi), height(-1.5, 3.0);
  std::vector<Eigen::Vector3d> world;
  for (int i = 0; i < 2000; ++i) {
    const double r = range(rng), a = angle(rng);
    // Stay clear of the seam behind the scanner, where a point's time jumps by a whole sweep.
    if (std::abs(std::abs(a) - kPi) < 0.3) continue;
    world.emplace_back(r * std::cos(a), r * std::sin(a), height(rng));
  }
  SweepOptions options;
  SweepMotion motion;
  motion.velocity = Eigen::Vector3d(12.0, 0.4, 0.1);
  motion.yaw_rate_rad_s = 0.3;
  const PointCloud scan = SimulateSweep(world, motion, options);

  double before = 0.0, after = 0.0;
  const PointCloud compensated = CompensateSweepMotion(scan, motion, options);
  ASSERT_EQ(compensated.size(), world.size());
  ASSERT_EQ(compensated.intensity, scan.intensity);
  for (size_t i = 0; i < world.size(); ++i) {
    before = std::max(before, (scan.points[i].cast<double>() - world[i]).norm());
    after = std::max(after, (compensated.points[i].cast<double>() - world[i]).norm());
  }
  EXPECT_GT(before, 0.3);  // up to v·T/2 = 0.6 m off before
  EXPECT_LT(after, 1e-4);  // float rounding after
}

TEST(SweepMotionTest, NoMotionAndNonFinitePointsAreLeftAlone) {
  PointCloud scan;
  scan.points = {Eigen::Vector3f(3, 4, 1), Eigen::Vector3f(NAN, 0, 0), Eigen::Vector3f(-2, 7, 0)};
  scan.sigma = {0.01f, 0.02f, 0.03f};
  const PointCloud same = CompensateSweepMotion(scan, SweepMotion{}, SweepOptions{});
  EXPECT_EQ(same.points[0], scan.points[0]);
  EXPECT_EQ(same.points[2], scan.points[2]);
  EXPECT_TRUE(std::isnan(same.points[1].x()));
  EXPECT_EQ(same.sigma, scan.sigma);

  SweepMotion moving;
  moving.velocity = Eigen::Vector3d(10, 0, 0);
  const PointCloud moved = CompensateSweepMotion(scan, moving, SweepOptions{});
  EXPECT_TRUE(std::isnan(moved.points[1].x()));
  EXPECT_NE(moved.points[0], scan.points[0]);
}

TEST(SweepMotionTest, OptionsNameTheKey) {
  SweepOptions sweep;
  sweep.period_s = 0.0;
  try {
    CompensateSweepMotion(PointCloud{}, SweepMotion{}, sweep);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gcp.lidar.motion.sweep_period_s"), std::string::npos)
        << e.what();
  }
  LidarMotionOptions motion;
  motion.mode = "imu";
  try {
    motion.Check();
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gcp.lidar.motion.mode"), std::string::npos) << e.what();
  }
  motion.mode = "registration";
  motion.max_gap_s = -1.0;
  EXPECT_THROW(motion.Check(), ConfigError);
}

// A street: ground, two building fronts with recesses, and boxes (parked cars, poles) along both
// sides at seeded random places, so that the scene pins down the position along the street.
std::vector<Eigen::Vector3d> Street(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> surface;
  for (int i = 0; i < 15000; ++i) surface.emplace_back(-80 + 160 * u(rng), -9 + 18 * u(rng), -1.7);
  for (int side = -1; side <= 1; side += 2) {
    for (int i = 0; i < 15000; ++i) {
      const double x = -80 + 160 * u(rng);
      const double recess = std::fmod(std::abs(x), 11.0) < 3.0 ? 1.5 : 0.0;  // doorways
      surface.emplace_back(x, side * (9.0 + recess), -1.7 + 8 * u(rng));
    }
  }
  std::mt19937 place(seed + 1);
  std::uniform_real_distribution<double> along(-70.0, 70.0), size(0.3, 4.0);
  for (int b = 0; b < 40; ++b) {
    const int side = b % 2 == 0 ? -1 : 1;
    const Eigen::Vector3d lo(along(place), side * 6.5, -1.7);
    const Eigen::Vector3d extent(size(place), 1.2 + 0.3 * size(place), 0.5 + size(place));
    for (int i = 0; i < 400; ++i) {  // points on the box's faces
      Eigen::Vector3d p =
          lo + Eigen::Vector3d(u(rng) * extent.x(), u(rng) * extent.y(), u(rng) * extent.z());
      const int axis = i % 3;
      p[axis] = lo[axis] + (u(rng) < 0.5 ? 0.0 : extent[axis]);
      surface.push_back(p);
    }
  }
  return surface;
}

// The points of `world` a scanner at `world_from_sensor` sees within 60 m, in its frame, thinned
// at random so that two scans never share points.
PointCloud ScanFrom(const std::vector<Eigen::Vector3d>& world, const Eigen::Isometry3d& pose,
                    unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution keep(0.5);
  PointCloud scan;
  const Eigen::Isometry3d sensor_from_world = pose.inverse();
  for (const Eigen::Vector3d& w : world) {
    const Eigen::Vector3d p = sensor_from_world * w;
    if (p.head<2>().norm() < 60.0 && keep(rng)) scan.points.push_back(p.cast<float>());
  }
  return scan;
}

TEST(SweepMotionTest, RegistrationRecoversTheDistanceDriven) {
  const std::vector<Eigen::Vector3d> street = Street(3);
  const PointCloud reference = ScanFrom(street, Eigen::Isometry3d::Identity(), 11);
  // One second later the vehicle is 10.6 m further, 0.3 m to the left, turned 1.5° left.
  Eigen::Isometry3d later = Eigen::Isometry3d::Identity();
  later.translate(Eigen::Vector3d(10.6, 0.3, 0.0));
  later.rotate(Eigen::AngleAxisd(1.5 * kPi / 180.0, Eigen::Vector3d::UnitZ()));
  const PointCloud other = ScanFrom(street, later, 12);
  // And one second earlier, 9.8 m behind.
  Eigen::Isometry3d earlier = Eigen::Isometry3d::Identity();
  earlier.translate(Eigen::Vector3d(-9.8, 0.0, 0.0));
  const PointCloud before = ScanFrom(street, earlier, 13);

  const SweepMotionEstimate estimate =
      EstimateSweepMotion(reference, {{&before, -1.0, "before"}, {&other, 1.0, "after"}});
  ASSERT_TRUE(estimate.valid) << estimate.message;
  ASSERT_EQ(estimate.registrations.size(), 2u);
  // Within 0.1 m over 1 s: a velocity 0.1 m/s off moves a point by at most 0.1 · T/2 = 5 mm, far
  // below the scanner's noise (the ICP runs on 0.5 m voxel centroids, which differ between scans).
  EXPECT_EQ(estimate.registrations[0].name, "before");
  const Eigen::Matrix4d& after = estimate.registrations[1].reference_from_other;
  EXPECT_NEAR(after(0, 3), 10.6, 0.1);
  EXPECT_NEAR(after(1, 3), 0.3, 0.1);
  EXPECT_NEAR(std::atan2(after(1, 0), after(0, 0)) * 180.0 / kPi, 1.5, 0.1);
  EXPECT_NEAR(estimate.registrations[0].reference_from_other(0, 3), -9.8, 0.1);
  for (const ScanRegistrationSummary& r : estimate.registrations) {
    EXPECT_TRUE(r.used);
    EXPECT_GT(r.inlier_fraction, 0.5);
  }
  // The mean of (−9.8 m over −1 s) and (10.6 m over +1 s).
  EXPECT_NEAR(estimate.motion.velocity.x(), 10.2, 0.1);
  EXPECT_NEAR(estimate.motion.yaw_rate_rad_s * 180.0 / kPi, 0.75, 0.1);
}

TEST(SweepMotionTest, AnUnrelatedScanIsNotUsed) {
  const PointCloud reference = ScanFrom(Street(3), Eigen::Isometry3d::Identity(), 11);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-40.0, 40.0);
  PointCloud clutter;  // points scattered through the air: nothing to register with
  for (int i = 0; i < 5000; ++i) clutter.points.emplace_back(u(rng), u(rng), u(rng) / 8.0);
  const SweepMotionEstimate estimate = EstimateSweepMotion(reference, {{&clutter, 1.0, "clutter"}});
  EXPECT_FALSE(estimate.valid);
  ASSERT_EQ(estimate.registrations.size(), 1u);
  EXPECT_FALSE(estimate.registrations[0].used);
  EXPECT_LT(estimate.registrations[0].inlier_fraction, 0.25);
  EXPECT_NE(estimate.message.find("inlier fraction"), std::string::npos) << estimate.message;

  const SweepMotionEstimate none = EstimateSweepMotion(reference, {});
  EXPECT_FALSE(none.valid);
  EXPECT_EQ(none.message, "no other scan to register with");
}

TEST(SweepMotionTest, BadScansAreErrors) {
  const PointCloud scan;
  try {
    EstimateSweepMotion(scan, {{&scan, 0.0, "same"}});
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'same' was taken at the reference's time"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(EstimateSweepMotion(scan, {{nullptr, 1.0, "null"}}), Error);
}

}  // namespace
}  // namespace gcpstereo::gcp
