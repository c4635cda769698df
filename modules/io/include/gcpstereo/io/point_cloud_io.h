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
// blue (a colour per source: lidar red, depth_map green, stereo blue, sfm yellow), float sigma,
// uchar source (0 lidar, 1 depth_map, 2 stereo, 3 sfm), int col, int row and float depth. Atomic.
void WriteGcpsPly(const std::string& path, const GcpSet& gcps, const Camera& reference);

// Writes a fused cloud (fused.ply): binary little-endian PLY with one `vertex` element of the
// properties, in this order, float x, y, z (world frame), float nx, ny, nz (unit normal), uchar
// red, green, blue, ushort views (OrientedPointCloud::num_views; 0 = a GCP) and float sigma
// (33 bytes per vertex). MeshLab, CloudCompare and Open3D read it as a coloured cloud with
// normals. Atomic. Throws IoError when a channel's length differs from the point count.
void WriteOrientedPointCloudPly(const std::string& path, const OrientedPointCloud& cloud);

// Reads what WriteOrientedPointCloudPly writes: the same format line and properties in the same
// order ("comment" and "obj_info" lines are skipped; any other header is rejected: this is not a
// general PLY reader, see ReadPointCloud). Throws IoError naming the file for an unreadable file,
// a header that differs (naming the line), a missing end_header, and vertex data shorter
// ("truncated") or longer than the vertex count says.
OrientedPointCloud ReadOrientedPointCloudPly(const std::string& path);

}  // namespace gcpstereo::io
