// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// The LiDAR scan of a run as every consumer must see it — the GCP stage, the held-out scoring of
// `gcpstereo run` and `gcpstereo eval`, and the SGBM baseline — so that all of them use the same
// points: read from gcp.lidar.path, then motion-compensated as gcp.lidar.motion.* says
// (gcp/sweep_motion.h).

#include <string>
#include <vector>

#include "gcpstereo/core/types.h"
#include "gcpstereo/gcp/sweep_motion.h"

namespace gcpstereo::pipeline {

struct LidarScanSummary {
  std::string mode = "off";  // gcp.lidar.motion.mode
  bool compensated = false;  // the sweep's motion was removed
  gcp::SweepMotion motion;   // the motion removed (zero when not compensated)
  std::vector<gcp::ScanRegistrationSummary> registrations;  // mode registration
  std::string message;  // why a requested compensation was not applied (also logged as a warning)
  double seconds = 0.0;
};

// Reads `scan_path` (io::ReadPointCloud) and compensates the sweep's motion:
//   off           the scan as read;
//   given         speed_mps along +x and yaw_rate_deg_s;
//   registration  gcp::EstimateSweepMotion with the scans io::KittiNeighbourScans finds for
//                 `frame` in the KITTI raw drive folder `drive_path`; when none is found or none
//                 registers, the scan is used as read, with a warning and the reason in the
//                 summary (the run goes on: the scan is still the best range data there is).
// Throws IoError for unreadable files, ConfigError for invalid options.
PointCloud LoadLidarScan(const std::string& scan_path, const std::string& drive_path,
                         const std::string& frame, const gcp::LidarMotionOptions& options,
                         LidarScanSummary* summary = nullptr);

}  // namespace gcpstereo::pipeline
