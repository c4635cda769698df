// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Point cloud reading. The only translation unit of the project that includes PCL (slow to compile:
// PCL pulls in VTK and Boost); PCL is linked privately to gcpstereo_io.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

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

// The header of a PLY or PCD file, checked before PCL reads it: PCL crashes on an empty or
// headerless PCD file and allocates whatever a header declares (a PLY claiming 10⁹ vertices took
// 16 GB before failing). Throws IoError unless the header is there and the data it declares can
// fit in the bytes that follow it (each binary record at its size, each ASCII value in ≥ 2 bytes).
void CheckPointCloudHeader(const std::string& path, bool ply) {
  std::error_code ec;
  const std::uintmax_t file_bytes = std::filesystem::file_size(path, ec);
  if (ec) throw IoError(path, "cannot read point cloud: " + ec.message());
  if (file_bytes == 0) throw IoError(path, "point cloud file is empty");
  std::ifstream in(path, std::ios::binary);
  const char* kind = ply ? "PLY" : "PCD";
  auto fail = [&](const std::string& problem) {
    throw IoError(path, std::string("not a valid ") + kind + " file: " + problem);
  };
  auto type_bytes = [&](const std::string& type) -> std::uintmax_t {
    static const std::pair<const char*, int> kTypes[] = {
        {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
        {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
        {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
    for (const auto& [name, bytes] : kTypes) {
      if (type == name) return static_cast<std::uintmax_t>(bytes);
    }
    fail("unknown property type '" + type + "'");
    return 0;
  };
  std::string line;
  std::uintmax_t header_bytes = 0, needed = 0;
  bool first = true, done = false;
  if (ply) {
    std::string format, element;
    // Per element: its count and the least bytes of one record.
    std::vector<std::pair<std::uintmax_t, std::uintmax_t>> elements;
    while (!done && header_bytes < (1u << 20) && std::getline(in, line)) {
      header_bytes += line.size() + 1;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      std::istringstream words(line);
      std::string key;
      words >> key;
      if (first) {
        if (key != "ply") fail("it does not begin with 'ply'");
        first = false;
      } else if (key == "format") {
        words >> format;
      } else if (key == "element") {
        long double count = -1;
        words >> element >> count;
        if (!(count >= 0)) fail("element '" + element + "' has no valid count");
        // 1e20 does not fit the integer (UBSan: found by fuzzing).
        if (count >= 1.8e19L) {
          fail("element '" + element + "' declares " + FormatNumber(static_cast<double>(count)) +
               " records");
        }
        elements.emplace_back(static_cast<std::uintmax_t>(count), 0);
      } else if (key == "property") {
        if (elements.empty()) fail("a property before any element");
        std::string type;
        words >> type;
        const bool ascii = format == "ascii";
        if (type == "list" && element == "vertex") {
          // PCL 1.13 aborts (assert) on a list property of the vertex element (found by
          // fuzzing, tests/fuzz/point_cloud_fuzzer.cc, the ply harness).
          fail("a list property in element 'vertex' (only scalar vertex properties are read)");
        }
        if (type == "list") {
          std::string count_type;
          words >> count_type;
          elements.back().second += ascii ? 2 : type_bytes(count_type);
        } else {
          elements.back().second += ascii ? 2 : type_bytes(type);
        }
      } else if (key == "end_header") {
        done = true;
      }
    }
    if (!done) fail("no 'end_header' line");
    if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
      fail("unknown format '" + format + "'");
    }
    for (const auto& [count, bytes] : elements) {
      // Records of no property take no bytes, but PCL still loops over each.
      if (bytes == 0 && count > file_bytes) {
        fail("an element of no property declares " + std::to_string(count) + " records");
      }
      if (bytes > 0 && count > file_bytes / bytes) {
        fail("its header declares " + std::to_string(count) + " records of at least " +
             std::to_string(bytes) + " bytes, more than the file's " + std::to_string(file_bytes) +
             " bytes (truncated or corrupt)");
      }
      needed += count * bytes;
    }
  } else {
    std::vector<std::uintmax_t> sizes, counts;
    std::uintmax_t width = 0, height = 0, points = 0;
    bool have_points = false;
    std::string data;
    while (!done && header_bytes < (1u << 20) && std::getline(in, line)) {
      header_bytes += line.size() + 1;
      // A header line of only a carriage return made PCL 1.13 read through a null pointer (found
      // by fuzzing); an empty line is harmless.
      if (line == "\r") fail("a header line holding only a carriage return");
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty() || line[0] == '#') continue;
      std::istringstream words(line);
      std::string key;
      words >> key;
      std::vector<long double> values;
      if (key == "SIZE" || key == "COUNT" || key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
        long double v = 0;
        while (words >> v) values.push_back(v);
        for (const long double v2 : values) {
          if (!(v2 >= 0)) fail("negative " + key);
          // 1e20 does not fit the integer (UBSan: found by fuzzing).
          if (v2 >= 1.8e19L) fail(key + " " + FormatNumber(static_cast<double>(v2)));
        }
        if (values.empty()) fail("'" + key + "' without a value");
      }
      if (key == "VERSION" || key == "FIELDS" || key == "TYPE" || key == "VIEWPOINT") {
        // nothing to check
      } else if (key == "SIZE") {
        // PCL sizes each record from SIZE × COUNT, also for ASCII data, and allocates that for
        // every point before reading any: a SIZE of 444444444444444 took 6 GB (found by fuzzing,
        // tests/fuzz/point_cloud_fuzzer.cc, the pcd harness). PCD types are 1, 2, 4 or 8 bytes.
        for (const long double v : values) {
          if (v != 1 && v != 2 && v != 4 && v != 8) {
            fail("SIZE " + FormatNumber(static_cast<double>(v)) + " (expected 1, 2, 4 or 8)");
          }
          sizes.push_back(static_cast<std::uintmax_t>(v));
        }
      } else if (key == "COUNT") {
        for (const long double v : values) {
          if (!(v >= 1 && v <= static_cast<long double>(file_bytes))) {
            fail("COUNT " + FormatNumber(static_cast<double>(v)) + " (expected 1 to the file's " +
                 std::to_string(file_bytes) + " bytes)");
          }
          counts.push_back(static_cast<std::uintmax_t>(v));
        }
      } else if (key == "WIDTH") {
        width = static_cast<std::uintmax_t>(values[0]);
      } else if (key == "HEIGHT") {
        height = static_cast<std::uintmax_t>(values[0]);
      } else if (key == "POINTS") {
        points = static_cast<std::uintmax_t>(values[0]);
        have_points = true;
      } else if (key == "DATA") {
        words >> data;
        done = true;
      } else {
        std::string shown = line.substr(0, 40);
        for (char& c : shown) {
          if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
        }
        fail("unexpected header line '" + shown + "'");
      }
    }
    if (!done) fail("no 'DATA' line");
    if (sizes.empty()) fail("no 'SIZE' line");
    if (!have_points) {
      if (height != 0 && width > UINTMAX_MAX / height) fail("WIDTH × HEIGHT overflows");
      points = width * height;
    }
    std::uintmax_t record = 0;
    for (size_t i = 0; i < sizes.size(); ++i) {
      record += sizes[i] * (i < counts.size() ? counts[i] : 1);
    }
    if (data == "ascii") {
      record = 0;  // each value at least a digit and a separator
      for (size_t i = 0; i < sizes.size(); ++i) record += 2 * (i < counts.size() ? counts[i] : 1);
    } else if (data == "binary_compressed") {
      record = 0;  // compressed: the size is not known from the header
    } else if (data != "binary") {
      fail("unknown DATA '" + data + "'");
    }
    if (record > 0 && points > file_bytes / record) {
      fail("its header declares " + std::to_string(points) + " points of at least " +
           std::to_string(record) + " bytes, more than the file's " + std::to_string(file_bytes) +
           " bytes (truncated or corrupt)");
    }
    needed = points * record;
  }
  if (header_bytes + needed > file_bytes) {
    fail("the data its header declares (" + std::to_string(needed) + " bytes) is longer than the " +
         std::to_string(file_bytes - std::min(file_bytes, header_bytes)) +
         " bytes after the header (truncated?)");
  }
}

// PCL can return a cloud whose sizes disagree with its data (found by fuzzing: a PCD header with
// two FIELDS lines made pcl::fromPCLPointCloud2 index an empty cloud). Throws IoError unless every
// field lies inside the point record and the data holds exactly width × height records.
void CheckBlob(const std::string& path, const pcl::PCLPointCloud2& blob) {
  auto fail = [&](const std::string& problem) {
    throw IoError(path, "cannot read point cloud: inconsistent fields or sizes (" + problem + ")");
  };
  if (blob.point_step == 0) fail("empty point record");
  const std::uint64_t points = static_cast<std::uint64_t>(blob.width) * blob.height;
  if (blob.row_step != static_cast<std::uint64_t>(blob.width) * blob.point_step ||
      blob.data.size() != points * blob.point_step) {
    fail(std::to_string(blob.data.size()) + " bytes for " + std::to_string(points) + " points of " +
         std::to_string(blob.point_step) + " bytes");
  }
  for (const pcl::PCLPointField& f : blob.fields) {
    std::uint64_t bytes = 0;
    switch (f.datatype) {
      case pcl::PCLPointField::INT8:
      case pcl::PCLPointField::UINT8:
        bytes = 1;
        break;
      case pcl::PCLPointField::INT16:
      case pcl::PCLPointField::UINT16:
        bytes = 2;
        break;
      case pcl::PCLPointField::INT32:
      case pcl::PCLPointField::UINT32:
      case pcl::PCLPointField::FLOAT32:
        bytes = 4;
        break;
      case pcl::PCLPointField::FLOAT64:
        bytes = 8;
        break;
      default:
        fail("field '" + f.name + "' of unknown type " + std::to_string(f.datatype));
    }
    if (f.count == 0 || f.offset + bytes * f.count > blob.point_step) {
      fail("field '" + f.name + "' outside the " + std::to_string(blob.point_step) +
           "-byte point record");
    }
  }
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
  CheckBlob(path, blob);
  // pcl::fromPCLPointCloud2 takes &cloud[0] of an empty cloud (UBSan; found by fuzzing).
  if (static_cast<std::uint64_t>(blob.width) * blob.height == 0) {
    throw IoError(path, "point cloud is empty");
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
    CheckPointCloudHeader(path, /*ply=*/true);
    cloud = ReadWithPcl(path, /*ply=*/true);
  } else if (ext == ".pcd") {
    CheckPointCloudHeader(path, /*ply=*/false);
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
