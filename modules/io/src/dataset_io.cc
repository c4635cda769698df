// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/dataset_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "dataset_internal.h"
#include "gcpstereo/core/error.h"

namespace fs = std::filesystem;

namespace gcpstereo::io {
namespace internal {

void CheckRequest(const DatasetRequest& request) {
  if (!std::isfinite(request.scale) || !(request.scale > 0.0) || request.scale > 4.0) {
    std::ostringstream value;
    value << request.scale;
    throw ConfigError(ViolatedConstraint("dataset.scale", value.str(), "0 < dataset.scale <= 4"));
  }
  if (request.path.empty()) {
    throw ConfigError(ViolatedConstraint("dataset.path", "''", "a data set folder"));
  }
  if (!IsFolder(request.path)) throw IoError(request.path, "data set folder not found");
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) out += (i ? ", " : "") + names[i];
  return out;
}

void ResolveViewNames(const DatasetRequest& request, const std::vector<std::string>& available,
                      std::vector<std::string>* neighbors) {
  auto known = [&available](const std::string& name) {
    return std::find(available.begin(), available.end(), name) != available.end();
  };
  if (!known(request.reference)) {
    throw ConfigError(ViolatedConstraint(
        "dataset.reference", "'" + request.reference + "'",
        "a view of " + request.path + " (valid names: " + JoinNames(available) + ")"));
  }
  neighbors->clear();
  if (request.neighbors.empty()) {
    for (const auto& name : available) {
      if (name != request.reference) neighbors->push_back(name);
    }
  } else {
    std::set<std::string> seen;
    for (const auto& name : request.neighbors) {
      if (!known(name)) {
        throw ConfigError(ViolatedConstraint(
            "dataset.neighbors", "'" + name + "'",
            "a view of " + request.path + " (valid names: " + JoinNames(available) + ")"));
      }
      if (name == request.reference) {
        throw ConfigError(ViolatedConstraint("dataset.neighbors", "'" + name + "'",
                                             "must differ from dataset.reference"));
      }
      if (!seen.insert(name).second) {
        throw ConfigError(ViolatedConstraint("dataset.neighbors", "'" + name + "'",
                                             "each neighbour listed once"));
      }
      neighbors->push_back(name);
    }
  }
  if (neighbors->empty()) {
    // Only reached with no list given (all others, or `auto`): a listed neighbour is checked
    // above. The message used to say "dataset.neighbors = []", a value the user never wrote.
    throw ConfigError("dataset.neighbors: " + request.path +
                      " has no view besides the reference '" + request.reference +
                      "' (a depth map needs at least one neighbour view)");
  }
}

cv::Mat ResizeImage(const cv::Mat& image, cv::Size size) {
  if (image.size() == size) return image;
  cv::Mat out;
  cv::resize(image, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat ResizeNearest(const cv::Mat& map, cv::Size size) {
  if (map.empty() || map.size() == size) return map;
  cv::Mat out;
  cv::resize(map, out, size, 0, 0, cv::INTER_NEAREST);
  return out;
}

std::string LowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

bool IsFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

bool IsFolder(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

}  // namespace internal

Dataset LoadDataset(const DatasetRequest& request) {
  if (request.format == "strecha") return LoadStrechaDataset(request);
  if (request.format == "middlebury") return LoadMiddleburyDataset(request);
  if (request.format == "kitti_raw") return LoadKittiRawDataset(request);
  if (request.format == "colmap") return LoadColmapDataset(request);
  throw ConfigError(ViolatedConstraint("dataset.format", "'" + request.format + "'",
                                       "one of strecha, middlebury, kitti_raw, colmap"));
}

std::vector<std::string> ListDatasetViews(const std::string& format, const std::string& path) {
  if (!internal::IsFolder(path)) throw IoError(path, "data set folder not found");
  if (format == "strecha") return internal::StrechaViewNames(path);
  if (format == "middlebury") return internal::MiddleburyViewNames(path);
  if (format == "kitti_raw") return internal::KittiFrameNames(path);
  if (format == "colmap") return internal::ColmapViewNames(path);
  throw ConfigError(ViolatedConstraint("dataset.format", "'" + format + "'",
                                       "one of strecha, middlebury, kitti_raw, colmap"));
}

std::string KittiVelodynePath(const std::string& drive_path, const std::string& frame) {
  return (fs::path(drive_path) / "velodyne_points" / "data" / (frame + ".bin")).string();
}

}  // namespace gcpstereo::io
