// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Strecha et al.'s multi-view layout (fountain-P11, Herz-Jesu-P8, …) and the project's synthetic
// sets, which use the same layout plus exact ground truth:
//   <path>/images/<name>.<ext>            the undistorted images (any format OpenCV reads)
//   <path>/cameras/<name>.<ext>.camera    Strecha's 9-line camera (camera_io.h)
//   <path>/gt/<name>.depth.pfm            optional: depth along the camera's z (synthetic sets)
//   <path>/gt/<name>.sigma.pfm            optional: per-pixel laser standard deviation
#include <algorithm>
#include <filesystem>
#include <map>
#include <sstream>

#include "dataset_internal.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/io/camera_io.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/pfm.h"

namespace fs = std::filesystem;

namespace gcpstereo::io {
namespace {

bool IsImageExtension(const std::string& ext) {
  static const char* const kExtensions[] = {".jpg", ".jpeg", ".png",  ".ppm", ".pgm",
                                            ".pnm", ".tif",  ".tiff", ".bmp", ".webp"};
  return std::find(std::begin(kExtensions), std::end(kExtensions), ext) != std::end(kExtensions);
}

// View name → image file name (e.g. "0005" → "0005.jpg"), sorted by name.
std::map<std::string, std::string> ImageFiles(const std::string& path) {
  const fs::path images = fs::path(path) / "images";
  if (!internal::IsFolder(images.string())) {
    throw IoError(images.string(), "Strecha image folder not found (expected <path>/images/)");
  }
  std::map<std::string, std::string> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(images, ec)) {
    if (!entry.is_regular_file()) continue;
    const std::string file = entry.path().filename().string();
    if (!IsImageExtension(internal::LowerExtension(file))) continue;
    const std::string name = entry.path().stem().string();
    const auto [it, inserted] = files.emplace(name, file);
    if (!inserted) {
      throw IoError(images.string(),
                    "two images for view '" + name + "': " + it->second + " and " + file);
    }
  }
  if (ec) throw IoError(images.string(), "cannot list folder: " + ec.message());
  if (files.empty()) throw IoError(images.string(), "no image files");
  return files;
}

View LoadStrechaView(const std::string& path, const std::string& name, const std::string& file,
                     double scale) {
  const std::string image_path = (fs::path(path) / "images" / file).string();
  const std::string camera_path = (fs::path(path) / "cameras" / (file + ".camera")).string();
  View view;
  view.name = name;
  view.camera = ReadStrechaCamera(camera_path);
  view.image = ReadColorImage(image_path);
  if (view.image.cols != view.camera.width || view.image.rows != view.camera.height) {
    std::ostringstream s;
    s << "image is " << view.image.cols << "x" << view.image.rows << " but " << camera_path
      << " declares " << view.camera.width << "x" << view.camera.height;
    throw IoError(image_path, s.str());
  }
  if (scale != 1.0) {
    view.camera = view.camera.Rescaled(scale);
    view.image = internal::ResizeImage(view.image, cv::Size(view.camera.width, view.camera.height));
  }
  return view;
}

// Reads an optional ground-truth map of the reference view; checks its size against the image.
cv::Mat LoadGroundTruthMap(const std::string& map_path, const cv::Size& full_size,
                           const cv::Size& scaled_size) {
  if (!internal::IsFile(map_path)) return cv::Mat();
  cv::Mat map = ReadPfm(map_path);
  if (map.type() != CV_32FC1) throw IoError(map_path, "expected a one-channel PFM (Pf)");
  if (map.size() != full_size) {
    std::ostringstream s;
    s << "ground-truth map is " << map.cols << "x" << map.rows << ", the image is "
      << full_size.width << "x" << full_size.height;
    throw IoError(map_path, s.str());
  }
  return internal::ResizeNearest(map, scaled_size);
}

}  // namespace

namespace internal {

std::vector<std::string> StrechaViewNames(const std::string& path) {
  std::vector<std::string> names;
  for (const auto& [name, file] : ImageFiles(path)) names.push_back(name);
  return names;
}

}  // namespace internal

Dataset LoadStrechaDataset(const DatasetRequest& request) {
  internal::CheckRequest(request);
  const std::map<std::string, std::string> files = ImageFiles(request.path);
  std::vector<std::string> names;
  for (const auto& [name, file] : files) names.push_back(name);
  std::vector<std::string> neighbor_names;
  internal::ResolveViewNames(request, names, &neighbor_names);
  if (!request.load_neighbors) neighbor_names.clear();

  Dataset dataset;
  dataset.format = "strecha";
  dataset.path = request.path;
  dataset.rectified = false;
  dataset.world_from_lidar.setIdentity();
  dataset.reference =
      LoadStrechaView(request.path, request.reference, files.at(request.reference), request.scale);
  for (const auto& name : neighbor_names) {
    dataset.neighbors.push_back(LoadStrechaView(request.path, name, files.at(name), request.scale));
  }

  // Ground truth of the reference view (synthetic sets). The maps are defined on the full-size
  // image; with dataset.scale they are resampled nearest-neighbour, values unchanged.
  const Camera full_camera = ReadStrechaCamera(
      (fs::path(request.path) / "cameras" / (files.at(request.reference) + ".camera")).string());
  const cv::Size full_size(full_camera.width, full_camera.height);
  const cv::Size scaled_size = dataset.reference.image.size();
  const fs::path gt = fs::path(request.path) / "gt";
  dataset.ground_truth.depth = LoadGroundTruthMap(
      (gt / (request.reference + ".depth.pfm")).string(), full_size, scaled_size);
  dataset.ground_truth.sigma = LoadGroundTruthMap(
      (gt / (request.reference + ".sigma.pfm")).string(), full_size, scaled_size);
  spdlog::info("strecha {}: reference {} + {} neighbours, {}x{}{}", request.path, request.reference,
               dataset.neighbors.size(), scaled_size.width, scaled_size.height,
               dataset.ground_truth.HasDepth() ? ", with ground-truth depth" : "");
  return dataset;
}

}  // namespace gcpstereo::io
