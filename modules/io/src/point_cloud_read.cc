// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Point cloud reading. The only translation unit of the project that includes PCL (slow to compile:
// PCL pulls in VTK and Boost); PCL is linked privately to gcpstereo_io.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/point_cloud_io.h"

namespace gcpstereo::io {
namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// Reads an optional scalar field (any numeric PCL type) of every point into `values` as float.
bool ReadScalarField(const pcl::PCLPointCloud2& blob, const std::string& name,
                     std::vector<float>* values) {
  const auto it = std::find_if(blob.fields.begin(), blob.fields.end(),
                               [&name](const pcl::PCLPointField& f) { return f.name == name; });
  if (it == blob.fields.end()) return false;
  const std::size_t count = static_cast<std::size_t>(blob.width) * blob.height;
  values->resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint8_t* p = blob.data.data() + i * blob.point_step + it->offset;
    double v = 0.0;
    switch (it->datatype) {
      case pcl::PCLPointField::INT8: {
        std::int8_t x;
        std::memcpy(&x, p, 1);
        v = x;
        break;
      }
      case pcl::PCLPointField::UINT8: {
        std::uint8_t x;
        std::memcpy(&x, p, 1);
        v = x;
        break;
      }
      case pcl::PCLPointField::INT16: {
        std::int16_t x;
        std::memcpy(&x, p, 2);
        v = x;
        break;
      }
      case pcl::PCLPointField::UINT16: {
        std::uint16_t x;
        std::memcpy(&x, p, 2);
        v = x;
        break;
      }
      case pcl::PCLPointField::INT32: {
        std::int32_t x;
        std::memcpy(&x, p, 4);
        v = x;
        break;
      }
      case pcl::PCLPointField::UINT32: {
        std::uint32_t x;
        std::memcpy(&x, p, 4);
        v = x;
        break;
      }
      case pcl::PCLPointField::FLOAT32: {
        float x;
        std::memcpy(&x, p, 4);
        v = x;
        break;
      }
      case pcl::PCLPointField::FLOAT64: {
        double x;
        std::memcpy(&x, p, 8);
        v = x;
        break;
      }
      default:
        return false;
    }
    (*values)[i] = static_cast<float>(v);
  }
  return true;
}

PointCloud ReadWithPcl(const std::string& path, bool ply) {
  pcl::PCLPointCloud2 blob;
  int status = -1;
  // PCL prints its own parse errors to stderr; we throw one IoError naming the file instead (the
  // contract: one clear line on stderr). The verbosity is process-global, so restore it after.
  const pcl::console::VERBOSITY_LEVEL previous_level = pcl::console::getVerbosityLevel();
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  struct RestoreLevel {
    pcl::console::VERBOSITY_LEVEL level;
    ~RestoreLevel() { pcl::console::setVerbosityLevel(level); }
  } restore{previous_level};
  try {
    status = ply ? pcl::io::loadPLYFile(path, blob) : pcl::io::loadPCDFile(path, blob);
  } catch (const std::exception& e) {
    throw IoError(path, std::string("cannot read point cloud: ") + e.what());
  }
  if (status < 0) {
    throw IoError(path, std::string("cannot read point cloud: corrupt or unsupported ") +
                            (ply ? "PLY" : "PCD") + " file (PCL status " + std::to_string(status) +
                            ")");
  }
  for (const char* axis : {"x", "y", "z"}) {
    const bool present =
        std::any_of(blob.fields.begin(), blob.fields.end(),
                    [axis](const pcl::PCLPointField& f) { return f.name == axis; });
    if (!present) throw IoError(path, std::string("point cloud has no '") + axis + "' field");
  }
  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::fromPCLPointCloud2(blob, xyz);
  PointCloud cloud;
  cloud.points.reserve(xyz.size());
  for (const auto& p : xyz.points) cloud.points.emplace_back(p.x, p.y, p.z);
  ReadScalarField(blob, "sigma", &cloud.sigma);
  ReadScalarField(blob, "intensity", &cloud.intensity);
  return cloud;
}

PointCloud ReadKittiBin(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  constexpr std::size_t kPointBytes = 16;  // float32 x, y, z, reflectance
  if (bytes.size() % kPointBytes != 0) {
    throw IoError(path, "KITTI Velodyne file length " + std::to_string(bytes.size()) +
                            " bytes is not a multiple of 16 (float32 x, y, z, reflectance)");
  }
  const std::size_t count = bytes.size() / kPointBytes;
  PointCloud cloud;
  cloud.points.resize(count);
  cloud.intensity.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    float v[4];
    std::memcpy(v, bytes.data() + i * kPointBytes, kPointBytes);  // KITTI files are little-endian
    cloud.points[i] = Eigen::Vector3f(v[0], v[1], v[2]);
    cloud.intensity[i] = v[3];
  }
  return cloud;
}

}  // namespace

PointCloud ReadPointCloud(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw IoError(path, "point cloud file not found");
  const std::string ext = LowerExtension(path);
  PointCloud cloud;
  if (ext == ".ply") {
    cloud = ReadWithPcl(path, /*ply=*/true);
  } else if (ext == ".pcd") {
    cloud = ReadWithPcl(path, /*ply=*/false);
  } else if (ext == ".bin") {
    cloud = ReadKittiBin(path);
  } else {
    throw IoError(path,
                  "unknown point cloud extension '" + ext + "' (expected .ply, .pcd or .bin)");
  }
  if (cloud.empty()) throw IoError(path, "point cloud is empty");
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (!cloud.points[i].allFinite()) {
      throw IoError(path, "point " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
  return cloud;
}

}  // namespace gcpstereo::io
