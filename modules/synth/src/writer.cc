// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/synth/writer.h"

#include <filesystem>
#include <fstream>
#include <system_error>

#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/camera_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/mesh_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"

namespace gcpstereo::synth {
namespace {

namespace fs = std::filesystem;

void MakeFolder(const fs::path& path) {
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec || !fs::is_directory(path)) {
    throw IoError(path.string(), "cannot create folder: " + (ec ? ec.message() : "not a folder"));
  }
}

}  // namespace

void WriteScene(const SyntheticScene& scene, const SynthOptions& options, const std::string& dir) {
  // "" is no folder: the files would land in the working folder.
  if (dir.empty()) throw Error("the synthetic data set's folder path is empty");
  const fs::path root(dir);
  // A folder that already holds a data set: one this command wrote before (gt/scene.json) is
  // replaced, so no view of another preset stays behind; any other is left untouched.
  std::error_code ec;
  const bool has_views =
      (fs::is_directory(root / "images", ec) && !fs::is_empty(root / "images", ec)) ||
      (fs::is_directory(root / "cameras", ec) && !fs::is_empty(root / "cameras", ec));
  if (has_views) {
    if (!fs::is_regular_file(root / "gt" / "scene.json", ec)) {
      throw IoError(dir,
                    "holds a data set that gcpstereo synth did not write (images/ or cameras/ "
                    "without gt/scene.json); choose an empty or new folder");
    }
    for (const char* sub : {"images", "cameras", "gt"}) fs::remove_all(root / sub, ec);
  }
  MakeFolder(root / "images");
  MakeFolder(root / "cameras");
  MakeFolder(root / "gt");
  for (size_t v = 0; v < scene.views.size(); ++v) {
    const std::string& name = scene.views[v].name;
    io::WritePng((root / "images" / (name + ".png")).string(), scene.views[v].image);
    io::WriteStrechaCamera((root / "cameras" / (name + ".png.camera")).string(),
                           scene.views[v].camera);
    io::WritePfm((root / "gt" / (name + ".depth.pfm")).string(), scene.depth[v]);
    io::WritePfm((root / "gt" / (name + ".sigma.pfm")).string(), scene.sigma[v]);
  }
  io::WritePointCloudPly((root / "gt" / "laser.ply").string(), scene.laser);
  io::WriteMeshPly((root / "gt" / "mesh.ply").string(), scene.mesh);

  // A small description a script or the demo can read (not part of the Strecha layout).
  const SynthSummary& s = scene.summary;
  nlohmann::json j;
  j["preset"] = s.preset;
  j["seed"] = s.seed;
  j["reference"] = scene.views[scene.reference_index].name;
  std::vector<std::string> neighbors;
  for (size_t v = 0; v < scene.views.size(); ++v) {
    if (static_cast<int>(v) != scene.reference_index) neighbors.push_back(scene.views[v].name);
  }
  j["neighbors"] = neighbors;
  j["width"] = s.width;
  j["height"] = s.height;
  j["reference_depth_min_m"] = s.reference_depth_min_m;
  j["reference_depth_max_m"] = s.reference_depth_max_m;
  j["reference_valid_fraction"] = s.reference_valid_fraction;
  j["laser"] = {{"scanner_center_world",
                 {scene.laser_scanner_world.x(), scene.laser_scanner_world.y(),
                  scene.laser_scanner_world.z()}},
                {"sigma_model", "sigma = a + b * range"},
                {"sigma_constant_m", options.laser_sigma_constant_m},
                {"sigma_per_m", options.laser_sigma_per_m},
                {"max_incidence_deg", options.laser_max_incidence_deg},
                {"rays", s.laser_rays},
                {"points", s.laser_points},
                {"misses", s.laser_misses},
                {"grazing_dropouts", s.laser_grazing_dropouts}};
  j["image_noise_sigma"] = options.image_noise_sigma;
  j["supersampling"] = s.supersampling;
  j["mesh"] = {{"vertices", s.mesh_vertices}, {"faces", s.mesh_faces}};
  const std::string text = j.dump(2) + "\n";
  io::WriteBytesAtomically((root / "gt" / "scene.json").string(), text.data(), text.size());
}

}  // namespace gcpstereo::synth
