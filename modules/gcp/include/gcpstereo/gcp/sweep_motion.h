// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// Motion compensation ("deskewing") of a spinning LiDAR's sweep, and the ego-motion it needs,
// estimated by registering the scan with another scan of the same drive.
//
// A spinning scanner (KITTI's Velodyne HDL-64E: 10 Hz) measures each azimuth at another time,
// while the vehicle moves; a camera takes its image at one instant (KITTI triggers it when the
// scanner faces forward). A point measured t seconds after that instant is in the sensor frame of
// time t; in the sensor frame of the trigger it is
//   p' = Rz(ω t) · p + v t,       t = −wrap(α − α₀) / (2π) · T   (clockwise rotation, from above)
// with α = atan2(y, x) the point's azimuth (x forward, y left, z up), α₀ the trigger azimuth, T the
// sweep period, v the sensor's velocity and ω its yaw rate (constant over the sweep). Without it,
// on KITTI drive 0009 at ≈ 10.5 m/s a pole 5.4 m away at 34° to the right lands 9 px right of
// where the image has it (the scanner saw it 9.4 ms after the trigger, 0.1 m further back);
// every image-guided use of the scan (colour-weighted interpolation, the data term) then fights
// the scan at depth edges. Not in Wang & Yang (their laser scans are static).

#include <string>
#include <vector>

#include <Eigen/Core>

#include "gcpstereo/core/types.h"

namespace gcpstereo::gcp {

// How the scanner sweeps. Keys gcp.lidar.motion.*.
struct SweepOptions {
  // Duration of one revolution, seconds (HDL-64E in KITTI: 0.1). Valid: > 0.
  // Key gcp.lidar.motion.sweep_period_s.
  double period_s = 0.1;
  // Direction of rotation seen from above (+z): Velodyne scanners turn clockwise.
  // Key gcp.lidar.motion.clockwise.
  bool clockwise = true;
  // Azimuth at the camera's exposure, degrees from +x towards +y (KITTI: 0, facing forward).
  // Valid: [−180, 180]. Key gcp.lidar.motion.trigger_azimuth_deg.
  double trigger_azimuth_deg = 0.0;

  void Check() const;  // throws ConfigError naming the key
};

// The sensor's motion during the sweep, in the sensor frame of the trigger instant.
struct SweepMotion {
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // data set unit (metres) per second
  double yaw_rate_rad_s = 0.0;                         // about +z, counter-clockwise positive
};

// Seconds between the trigger and the measurement of `point` (sensor frame); in (−T/2, T/2].
double SweepTimeOffset(const Eigen::Vector3f& point, const SweepOptions& options);

// Every point moved into the sensor frame of the trigger instant (formula above); sigma and
// intensity are kept. Non-finite points stay as they are.
PointCloud CompensateSweepMotion(const PointCloud& scan, const SweepMotion& motion,
                                 const SweepOptions& options);

// Scan-to-scan registration (point-to-point ICP, PCL) used to estimate the ego-motion.
struct ScanRegistrationOptions {
  double min_range = 3.0;   // points nearer than this (horizontal range) are the vehicle: ignored
  double max_range = 60.0;  // and farther ones too sparse to register (data set unit)
  double voxel = 0.5;       // voxel-grid leaf of the refinement (the coarse stage uses 2×)
  // Initial guesses: the other scan displaced by s · Δt along +x for each s (the vehicle drives
  // along x); the best registration after the coarse stage is refined. Metres per second.
  // The coarse stage pulls from up to 5 m away, so starts 10 m/s apart cover 1 s between scans.
  std::vector<double> initial_speeds_mps = {-10.0, 0.0, 10.0, 20.0, 30.0, 40.0};
  double inlier_distance = 0.3;  // a registered point within this of the target is an inlier
  // A registration with fewer inliers is not used (KITTI drive 0009, scans 1 s apart: 0.51–0.57;
  // a wrong basin: below 0.1).
  double min_inlier_fraction = 0.25;
};

// A scan of the same sensor at another time (seconds_after_reference < 0: earlier).
struct TimedScan {
  const PointCloud* scan = nullptr;
  double seconds_after_reference = 0.0;
  std::string name;  // for the summary
};

struct ScanRegistrationSummary {
  std::string name;
  double seconds_after_reference = 0.0;
  Eigen::Matrix4d reference_from_other = Eigen::Matrix4d::Identity();
  double inlier_fraction = 0.0;  // of the other scan's registered (filtered) points
  double rmse = 0.0;             // of the inliers, data set unit
  bool used = false;             // passed min_inlier_fraction
};

struct SweepMotionEstimate {
  bool valid = false;  // at least one registration was used
  SweepMotion motion;  // the mean of the used registrations' velocities and yaw rates
  std::vector<ScanRegistrationSummary> registrations;
  std::string message;  // why the estimate is not valid, when it is not
};

// Where the ego-motion comes from. Keys gcp.lidar.motion.*.
struct LidarMotionOptions {
  // "off": the scan is used as measured (a static scanner, or one already compensated);
  // "given": speed_mps along the sensor's +x and yaw_rate_deg_s (odometry, a vehicle's CAN bus);
  // "registration": registered with the drive's nearest earlier and later scans within max_gap_s
  // (EstimateSweepMotion; KITTI raw only). Key gcp.lidar.motion.mode.
  std::string mode = "off";
  double speed_mps = 0.0;       // "given"; key gcp.lidar.motion.speed_mps. Valid: finite
  double yaw_rate_deg_s = 0.0;  // "given", counter-clockwise positive; key ….yaw_rate_deg_s
  // "registration": the other scans are at most this far in time from the reference's, seconds.
  // Valid: > 0. Key gcp.lidar.motion.max_gap_s.
  double max_gap_s = 2.0;
  SweepOptions sweep;
  ScanRegistrationOptions registration;  // min_inlier_fraction: key ….min_inlier_fraction

  void Check() const;  // throws ConfigError naming the key
};

// The ego-motion of `reference`'s sweep from registrations with `others`: the other scan's sensor
// origin in the reference sensor frame is the translation of reference_from_other, so the velocity
// is that translation over seconds_after_reference and the yaw rate the rotation's yaw over it
// (constant velocity between the scans). Throws Error for a null scan or a zero time difference.
SweepMotionEstimate EstimateSweepMotion(const PointCloud& reference,
                                        const std::vector<TimedScan>& others,
                                        const ScanRegistrationOptions& options = {});

}  // namespace gcpstereo::gcp
