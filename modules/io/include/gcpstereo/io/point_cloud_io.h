// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::io {

// Writes a binary little-endian PLY with one `vertex` element: float x, y, z, then float `sigma`
// when cloud.sigma is non-empty, then float `intensity` when cloud.intensity is non-empty.
// Atomic. Throws IoError when a channel's length differs from the point count.
void WritePointCloudPly(const std::string& path, const PointCloud& cloud);

// Reads a point cloud, dispatching on the extension (case-insensitive):
//   .ply, .pcd  through PCL (x, y, z; optional scalar fields `sigma` and `intensity` are read when
//               present);
//   .bin        KITTI Velodyne scan: float32 x, y, z, reflectance per point (reflectance goes to
//               `intensity`); a length not divisible by 16 bytes is an error.
// Throws IoError naming the file for an unknown extension, an unreadable or corrupt file, an empty
// cloud, and a non-finite coordinate (naming the point index).
PointCloud ReadPointCloud(const std::string& path);

// Writes the GCPs of the reference view as 3D points in world coordinates
// (reference.BackProject(pixel, depth)), binary little-endian PLY with float x y z, uchar red green
// blue (a colour per source: lidar red, depth_map green, stereo blue), float sigma, uchar source
// (0 lidar, 1 depth_map, 2 stereo), int col, int row and float depth. Atomic.
void WriteGcpsPly(const std::string& path, const GcpSet& gcps, const Camera& reference);

}  // namespace gcpstereo::io
