// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The fused cloud's PLY (fused.ply): written by hand like point_cloud_write.cc, and read back by a
// parser of exactly that header (no PCL: the properties and their order are fixed).
#include <algorithm>
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
namespace {

using internal::AppendLittleEndian;
using internal::HostIsLittleEndian;

// The property lines, in file order, and the bytes of one vertex.
const char* const kProperties[] = {
    "property float x",    "property float y",      "property float z",    "property float nx",
    "property float ny",   "property float nz",     "property uchar red",  "property uchar green",
    "property uchar blue", "property ushort views", "property float sigma"};
constexpr std::size_t kVertexBytes = 6 * 4 + 3 * 1 + 2 + 4;

template <typename T>
T ReadLittleEndian(const char* bytes) {
  char raw[sizeof(T)];
  std::memcpy(raw, bytes, sizeof(T));
  if (!HostIsLittleEndian()) std::reverse(raw, raw + sizeof(T));
  T value;
  std::memcpy(&value, raw, sizeof(T));
  return value;
}

}  // namespace

void WriteOrientedPointCloudPly(const std::string& path, const OrientedPointCloud& cloud) {
  const std::size_t n = cloud.points.size();
  auto check = [&](std::size_t size, const char* channel) {
    if (size != n) {
      throw IoError(path, "oriented point cloud has " + std::to_string(n) + " points but " +
                              std::to_string(size) + " " + channel);
    }
  };
  check(cloud.normals.size(), "normals");
  check(cloud.colors.size(), "colours");
  check(cloud.num_views.size(), "view counts");
  check(cloud.sigma.size(), "sigma values");
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\n"
         << "comment written by gcpstereo: fused points in world coordinates\n"
         << "comment views = number of agreeing views (0 = ground control point), sigma = the "
            "GCP's standard deviation (0 for fused points)\n"
         << "element vertex " << n << "\n";
  for (const char* property : kProperties) header << property << "\n";
  header << "end_header\n";
  std::string bytes = header.str();
  bytes.reserve(bytes.size() + kVertexBytes * n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) AppendLittleEndian(&bytes, cloud.points[i][k]);
    for (int k = 0; k < 3; ++k) AppendLittleEndian(&bytes, cloud.normals[i][k]);
    for (int k = 0; k < 3; ++k) AppendLittleEndian(&bytes, cloud.colors[i][k]);
    AppendLittleEndian(&bytes, cloud.num_views[i]);
    AppendLittleEndian(&bytes, cloud.sigma[i]);
  }
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

OrientedPointCloud ReadOrientedPointCloudPly(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  // Header lines up to and including "end_header\n".
  std::vector<std::string> lines;
  std::size_t pos = 0;
  bool ended = false;
  while (pos < bytes.size() && lines.size() < 1000) {
    const std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) break;
    std::string line = bytes.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    if (line.rfind("comment", 0) == 0 || line.rfind("obj_info", 0) == 0) continue;
    lines.push_back(line);
    if (line == "end_header") {
      ended = true;
      break;
    }
  }
  if (lines.empty() || lines[0] != "ply") throw IoError(path, "not a PLY file (no 'ply' line)");
  if (!ended) throw IoError(path, "PLY header without end_header (truncated or not a PLY file)");
  auto expect = [&](std::size_t index, const std::string& wanted) {
    const std::string got = index < lines.size() ? lines[index] : std::string("(none)");
    if (got != wanted) {
      throw IoError(path, "not a fused-cloud PLY: header line '" + got + "' where '" + wanted +
                              "' was expected");
    }
  };
  expect(1, "format binary_little_endian 1.0");
  const std::string element = lines.size() > 2 ? lines[2] : std::string();
  std::size_t count = 0;
  {
    std::istringstream s(element);
    std::string word, name;
    long long value = -1;
    std::string rest;
    if (!(s >> word >> name >> value) || word != "element" || name != "vertex" || value < 0 ||
        (s >> rest)) {
      throw IoError(path, "not a fused-cloud PLY: header line '" + element +
                              "' where 'element vertex <count>' was expected");
    }
    count = static_cast<std::size_t>(value);
  }
  const std::size_t num_properties = sizeof(kProperties) / sizeof(kProperties[0]);
  for (std::size_t k = 0; k < num_properties; ++k) expect(3 + k, kProperties[k]);
  expect(3 + num_properties, "end_header");

  const std::size_t available = bytes.size() - pos;
  if (count > available / kVertexBytes) {
    throw IoError(path, "truncated: " + std::to_string(count) + " vertices need " +
                            std::to_string(count * kVertexBytes) + " bytes of data, the file has " +
                            std::to_string(available));
  }
  if (available != count * kVertexBytes) {
    throw IoError(path, std::to_string(available - count * kVertexBytes) + " bytes after the " +
                            std::to_string(count) + " vertices the header announces");
  }
  OrientedPointCloud cloud;
  cloud.points.resize(count);
  cloud.normals.resize(count);
  cloud.colors.resize(count);
  cloud.num_views.resize(count);
  cloud.sigma.resize(count);
  const char* p = bytes.data() + pos;
  for (std::size_t i = 0; i < count; ++i, p += kVertexBytes) {
    for (int k = 0; k < 3; ++k) cloud.points[i][k] = ReadLittleEndian<float>(p + 4 * k);
    for (int k = 0; k < 3; ++k) cloud.normals[i][k] = ReadLittleEndian<float>(p + 12 + 4 * k);
    for (int k = 0; k < 3; ++k) cloud.colors[i][k] = static_cast<std::uint8_t>(p[24 + k]);
    cloud.num_views[i] = ReadLittleEndian<std::uint16_t>(p + 27);
    cloud.sigma[i] = ReadLittleEndian<float>(p + 29);
  }
  return cloud;
}

}  // namespace gcpstereo::io
