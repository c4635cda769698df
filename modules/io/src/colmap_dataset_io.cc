// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// A COLMAP workspace as `colmap image_undistorter` writes it (dataset.format: colmap):
//   <path>/images/<name>     the images, <name> as the model names them (may hold sub-folders)
//   <path>/sparse/           cameras, images, points3D (.bin or .txt; colmap_io.h)
// View names are the model's image names ("0005.jpg"). Cameras of distorting models are
// undistorted into pinhole cameras on load (MakeColmapPinhole); the view records it.
#include <filesystem>
#include <map>
#include <sstream>

#include "dataset_internal.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/io/colmap_io.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"

namespace fs = std::filesystem;

namespace gcpstereo::io {
namespace {

// `pinholes`: the cameras converted so far, shared by the views (the undistortion maps are made
// once per camera), extended with this view's camera.
View LoadColmapView(const std::string& path, const ColmapModel& model, const std::string& name,
                    std::map<std::uint32_t, ColmapPinhole>* pinholes, double scale) {
  const ColmapImage& image = *model.FindImage(name);
  const ColmapCamera& camera = model.cameras.at(image.camera_id);
  const std::string image_path = (fs::path(path) / "images" / name).string();
  if (!internal::IsFile(image_path)) {
    throw IoError(image_path, "image " + name + " of the COLMAP model " + model.sparse_dir +
                                  " not found (expected <path>/images/<image name>)");
  }
  View view;
  view.name = name;
  view.image = ReadColorImage(image_path);
  // The size is checked before the camera is converted: the undistortion maps have the camera's
  // size, and a corrupt cameras file declaring 100000x100000 px would allocate 80 GB for them
  // (found with the COLMAP fuzz harnesses, tests/fuzz/colmap_*_fuzzer.cc).
  if (static_cast<std::uint64_t>(view.image.cols) != camera.width ||
      static_cast<std::uint64_t>(view.image.rows) != camera.height) {
    // COLMAP 3.8's image_undistorter --max_image_size shrinks the images but not the cameras.
    std::ostringstream s;
    s << "image is " << view.image.cols << "x" << view.image.rows << " but its COLMAP camera "
      << image.camera_id << " is " << camera.width << "x" << camera.height
      << " (resized images need a model of their size)";
    throw IoError(image_path, s.str());
  }
  auto it = pinholes->find(image.camera_id);
  if (it == pinholes->end()) {
    it = pinholes->emplace(image.camera_id, MakeColmapPinhole(camera, model.sparse_dir)).first;
  }
  const ColmapPinhole& pinhole = it->second;
  view.image = UndistortColmapImage(view.image, pinhole);
  view.camera = ColmapImageCamera(image, pinhole);
  view.camera.Validate(image_path);
  view.source_camera_model = pinhole.model_name;
  view.undistorted = pinhole.undistorted;
  if (scale != 1.0) {
    view.camera = view.camera.Rescaled(scale);
    view.image = internal::ResizeImage(view.image, cv::Size(view.camera.width, view.camera.height));
  }
  return view;
}

}  // namespace

namespace internal {

std::vector<std::string> ColmapViewNames(const std::string& path) {
  return ReadColmapModel(ColmapSparseDir(path)).ImageNames();
}

}  // namespace internal

Dataset LoadColmapDataset(const DatasetRequest& request) {
  internal::CheckRequest(request);
  ColmapModel model = ReadColmapModel(ColmapSparseDir(request.path));
  if (!request.world_from_model.isIdentity(0.0)) {
    TransformColmapModel(request.world_from_model, &model);
  }
  const std::vector<std::string> names = model.ImageNames();
  if (names.empty()) throw IoError(model.sparse_dir, "the COLMAP model has no registered images");
  std::vector<std::string> neighbor_names;
  internal::ResolveViewNames(request, names, &neighbor_names);
  if (!request.load_neighbors) neighbor_names.clear();

  // Every camera the loaded views use is converted once (the undistortion maps are shared), after
  // its first image's size is checked against it (LoadColmapView). Its model is checked first,
  // so that an unsupported model is the error whatever the images.
  std::map<std::uint32_t, ColmapPinhole> pinholes;
  std::vector<std::string> loaded = {request.reference};
  loaded.insert(loaded.end(), neighbor_names.begin(), neighbor_names.end());
  for (const std::string& name : loaded) {
    const ColmapCamera& camera = model.cameras.at(model.FindImage(name)->camera_id);
    if (!IsSupportedColmapCameraModel(camera.model_name)) {
      MakeColmapPinhole(camera, model.sparse_dir);  // throws, naming the model and the camera
    }
  }

  Dataset dataset;
  dataset.format = "colmap";
  dataset.path = request.path;
  dataset.rectified = false;
  dataset.world_from_lidar.setIdentity();
  dataset.reference =
      LoadColmapView(request.path, model, request.reference, &pinholes, request.scale);
  for (const auto& name : neighbor_names) {
    dataset.neighbors.push_back(
        LoadColmapView(request.path, model, name, &pinholes, request.scale));
  }
  const View& ref = dataset.reference;
  spdlog::info("colmap {}: reference {} + {} neighbours, {}x{}, camera model {}{}", request.path,
               request.reference, dataset.neighbors.size(), ref.image.cols, ref.image.rows,
               ref.source_camera_model, ref.undistorted ? " (undistorted on load)" : "");
  return dataset;
}

}  // namespace gcpstereo::io
