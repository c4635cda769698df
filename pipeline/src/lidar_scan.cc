// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/lidar_scan.h"

#include <chrono>
#include <cmath>
#include <memory>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/point_cloud_io.h"

namespace gcpstereo::pipeline {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

PointCloud LoadLidarScan(const std::string& scan_path, const std::string& drive_path,
                         const std::string& frame, const gcp::LidarMotionOptions& options,
                         LidarScanSummary* summary) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  LidarScanSummary local;
  local.mode = options.mode;
  PointCloud scan = io::ReadPointCloud(scan_path);

  if (options.mode == "given") {
    local.motion.velocity = Eigen::Vector3d(options.speed_mps, 0.0, 0.0);
    local.motion.yaw_rate_rad_s = options.yaw_rate_deg_s * kPi / 180.0;
    local.compensated = true;
  } else if (options.mode == "registration") {
    const std::vector<io::KittiScanTime> neighbours =
        io::KittiNeighbourScans(drive_path, frame, options.max_gap_s);
    std::vector<std::unique_ptr<PointCloud>> clouds;
    std::vector<gcp::TimedScan> others;
    for (const io::KittiScanTime& n : neighbours) {
      clouds.push_back(std::make_unique<PointCloud>(io::ReadPointCloud(n.path)));
      others.push_back({clouds.back().get(), n.seconds_after_reference, n.frame});
    }
    const gcp::SweepMotionEstimate estimate =
        gcp::EstimateSweepMotion(scan, others, options.registration);
    local.registrations = estimate.registrations;
    for (const gcp::ScanRegistrationSummary& r : estimate.registrations) {
      const Eigen::Vector3d t = r.reference_from_other.topRightCorner<3, 1>();
      spdlog::info(
          "LiDAR motion: scan {} ({:+.2f} s) registered, {:.1f} % inliers, RMSE {:.3f}: moved "
          "{:.2f} {:.2f} {:.2f}{}",
          r.name, r.seconds_after_reference, 100.0 * r.inlier_fraction, r.rmse, t.x(), t.y(), t.z(),
          r.used ? "" : " (not used: too few inliers)");
    }
    if (estimate.valid) {
      local.motion = estimate.motion;
      local.compensated = true;
    } else {
      local.message = "the sweep's motion is not compensated: " +
                      (neighbours.empty() ? "no other scan of the drive within " +
                                                FormatNumber(options.max_gap_s) +
                                                " s (gcp.lidar.motion.max_gap_s) of frame " + frame
                                          : estimate.message);
      spdlog::warn("LiDAR motion: {}", local.message);
    }
  }
  if (local.compensated) {
    scan = gcp::CompensateSweepMotion(scan, local.motion, options.sweep);
    spdlog::info(
        "LiDAR motion: sweep compensated for {:.2f} m/s ({:.2f} {:.2f} {:.2f}), yaw rate "
        "{:.2f} deg/s",
        local.motion.velocity.norm(), local.motion.velocity.x(), local.motion.velocity.y(),
        local.motion.velocity.z(), local.motion.yaw_rate_rad_s * 180.0 / kPi);
  }
  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary) *summary = std::move(local);
  return scan;
}

}  // namespace gcpstereo::pipeline
