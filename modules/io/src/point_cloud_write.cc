// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// PLY writers for point clouds and GCPs. Written by hand (the format is a few header lines and a
// packed little-endian array) so that this file does not pull in PCL/VTK; reading goes through PCL
// in point_cloud_read.cc.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "little_endian.h"

namespace gcpstereo::io {
using internal::AppendLittleEndian;

void WritePointCloudPly(const std::string& path, const PointCloud& cloud) {
  const bool has_sigma = !cloud.sigma.empty();
  const bool has_intensity = !cloud.intensity.empty();
  if (has_sigma && cloud.sigma.size() != cloud.points.size()) {
    throw IoError(path, "point cloud has " + std::to_string(cloud.points.size()) + " points but " +
                            std::to_string(cloud.sigma.size()) + " sigma values");
  }
  if (has_intensity && cloud.intensity.size() != cloud.points.size()) {
    throw IoError(path, "point cloud has " + std::to_string(cloud.points.size()) + " points but " +
                            std::to_string(cloud.intensity.size()) + " intensity values");
  }
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by gcpstereo\n"
         << "element vertex " << cloud.points.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n";
  if (has_sigma) header << "property float sigma\n";
  if (has_intensity) header << "property float intensity\n";
  header << "end_header\n";
  std::string bytes = header.str();
  const std::size_t stride = 12 + (has_sigma ? 4 : 0) + (has_intensity ? 4 : 0);
  bytes.reserve(bytes.size() + stride * cloud.points.size());
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    AppendLittleEndian(&bytes, p.x());
    AppendLittleEndian(&bytes, p.y());
    AppendLittleEndian(&bytes, p.z());
    if (has_sigma) AppendLittleEndian(&bytes, cloud.sigma[i]);
    if (has_intensity) AppendLittleEndian(&bytes, cloud.intensity[i]);
  }
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

void WriteGcpsPly(const std::string& path, const GcpSet& gcps, const Camera& reference) {
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by gcpstereo: ground control "
            "points in world coordinates\n"
         << "comment source: 0 = lidar (red), 1 = depth_map (green), 2 = stereo (blue)\n"
         << "element vertex " << gcps.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
         << "property float sigma\nproperty uchar source\n"
         << "property int col\nproperty int row\nproperty float depth\n"
         << "end_header\n";
  std::string bytes = header.str();
  for (std::size_t i = 0; i < gcps.points.size(); ++i) {
    const Gcp& g = gcps.points[i];
    if (!(g.depth > 0.0) || !std::isfinite(g.depth)) {
      throw IoError(path,
                    "GCP " + std::to_string(i) + " has invalid depth " + std::to_string(g.depth));
    }
    const Eigen::Vector3d X = reference.BackProject(Eigen::Vector2d(g.col, g.row), g.depth);
    AppendLittleEndian(&bytes, static_cast<float>(X.x()));
    AppendLittleEndian(&bytes, static_cast<float>(X.y()));
    AppendLittleEndian(&bytes, static_cast<float>(X.z()));
    std::uint8_t rgb[3] = {0, 0, 0};
    switch (g.source) {
      case GcpSource::kLidar:
        rgb[0] = 255;
        break;
      case GcpSource::kDepthMap:
        rgb[1] = 255;
        break;
      case GcpSource::kStereo:
        rgb[2] = 255;
        break;
      case GcpSource::kSfm:  // yellow
        rgb[0] = 255;
        rgb[1] = 255;
        break;
    }
    AppendLittleEndian(&bytes, rgb[0]);
    AppendLittleEndian(&bytes, rgb[1]);
    AppendLittleEndian(&bytes, rgb[2]);
    AppendLittleEndian(&bytes, static_cast<float>(g.sigma));
    AppendLittleEndian(&bytes, static_cast<std::uint8_t>(g.source));
    AppendLittleEndian(&bytes, static_cast<std::int32_t>(g.col));
    AppendLittleEndian(&bytes, static_cast<std::int32_t>(g.row));
    AppendLittleEndian(&bytes, static_cast<float>(g.depth));
  }
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

}  // namespace gcpstereo::io
