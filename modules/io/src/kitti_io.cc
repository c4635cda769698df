// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// KITTI raw drives (Geiger et al., IJRR 2013), synced + rectified:
//   <date>/calib_cam_to_cam.txt                        P_rect_02, P_rect_03, R_rect_00, S_rect_02
//   <date>/calib_velo_to_cam.txt                       R, T (Velodyne → unrectified camera 0)
//   <date>/<date>_drive_NNNN_sync/image_02/data/F.png  left colour image = the reference view
//   <date>/<date>_drive_NNNN_sync/image_03/data/F.png  right colour image = the single neighbour
//   <date>/<date>_drive_NNNN_sync/velodyne_points/data/F.bin  (KittiVelodynePath)
// World frame = the rectified camera-0 frame. Each rectified camera has identity rotation and
// P_rect_0i = K [I | t_i], so x ~ K (X + t_i): its centre is C_i = −t_i = −K⁻¹ P_rect_0i(:, 3).
// (To first order C_x = −P(0,3)/P(0,0); the exact inverse also accounts for the small y/z terms of
// the colour cameras' P.) disparity_numerator = f · (C_3x − C_2x), the left↔right baseline, and
// world_from_lidar = [R_rect_00 0; 0 1] · [R T; 0 1], so a Velodyne point reaches the left image
// through P_rect_02 · R_rect_00 · [R|T] · X as in KITTI's devkit.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include <Eigen/LU>

#include "dataset_internal.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"

namespace fs = std::filesystem;

namespace gcpstereo::io {
namespace {

// "key: v1 v2 ..." lines of a KITTI calibration file.
class KittiCalibration {
 public:
  explicit KittiCalibration(std::string path) : path_(std::move(path)) {
    if (!internal::IsFile(path_)) throw IoError(path_, "KITTI calibration file not found");
    std::istringstream in(ReadFileBytes(path_));
    std::string line;
    while (std::getline(in, line)) {
      const auto colon = line.find(':');
      if (colon == std::string::npos) continue;
      lines_[line.substr(0, colon)] = line.substr(colon + 1);
    }
  }

  // The `count` numbers of `key`; throws IoError naming the file and the key.
  std::vector<double> Numbers(const std::string& key, int count) const {
    const auto it = lines_.find(key);
    if (it == lines_.end()) throw IoError(path_, "missing calibration key '" + key + "'");
    std::istringstream in(it->second);
    in.imbue(std::locale::classic());
    std::vector<double> values;
    std::string token;
    while (in >> token) {
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(token, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != token.size() || !std::isfinite(v)) {
        throw IoError(path_, "key '" + key + "': invalid number '" + token + "'");
      }
      values.push_back(v);
    }
    if (static_cast<int>(values.size()) != count) {
      throw IoError(path_, "key '" + key + "': expected " + std::to_string(count) +
                               " numbers, found " + std::to_string(values.size()));
    }
    return values;
  }

  template <int Rows, int Cols>
  Eigen::Matrix<double, Rows, Cols> Matrix(const std::string& key) const {
    const std::vector<double> v = Numbers(key, Rows * Cols);
    Eigen::Matrix<double, Rows, Cols> m;
    for (int r = 0; r < Rows; ++r) {
      for (int c = 0; c < Cols; ++c) m(r, c) = v[r * Cols + c];  // row-major in the file
    }
    return m;
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::map<std::string, std::string> lines_;
};

// The rectified camera of P_rect (identity rotation in the rectified camera-0 frame).
Camera CameraFromProjection(const KittiCalibration& calib, const std::string& key, int width,
                            int height) {
  const Eigen::Matrix<double, 3, 4> P = calib.Matrix<3, 4>(key);
  Camera camera;
  camera.K = P.leftCols<3>();
  if (camera.K(1, 0) != 0.0 || camera.K(2, 0) != 0.0 || camera.K(2, 1) != 0.0 ||
      camera.K(2, 2) != 1.0 || !(camera.K(0, 0) > 0.0)) {
    throw IoError(calib.path(), "key '" + key +
                                    "': left 3x3 block is not a rectified intrinsic "
                                    "matrix [f 0 cx; 0 f cy; 0 0 1]");
  }
  camera.center_world = -camera.K.inverse() * P.col(3);
  camera.width = width;
  camera.height = height;
  camera.Validate(calib.path() + " (" + key + ")");
  return camera;
}

bool IsFrameName(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(),
                                      [](unsigned char c) { return std::isdigit(c) != 0; });
}

// Seconds since midnight of a KITTI timestamp "YYYY-MM-DD hh:mm:ss.fffffffff"; NaN if malformed.
double TimeOfDaySeconds(const std::string& line) {
  const auto space = line.find(' ');
  if (space == std::string::npos) return std::nan("");
  std::istringstream in(line.substr(space + 1));
  in.imbue(std::locale::classic());
  int hours = 0, minutes = 0;
  double seconds = 0.0;
  char c1 = 0, c2 = 0;
  if (!(in >> hours >> c1 >> minutes >> c2 >> seconds) || c1 != ':' || c2 != ':') {
    return std::nan("");
  }
  return hours * 3600.0 + minutes * 60.0 + seconds;
}

// The frame names (NNNNNNNNNN) of the files with `extension` in `dir`, sorted; none if no folder.
std::vector<std::string> FramesIn(const fs::path& dir, const std::string& extension) {
  std::vector<std::string> frames;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_regular_file() && internal::LowerExtension(entry.path().string()) == extension &&
        IsFrameName(entry.path().stem().string())) {
      frames.push_back(entry.path().stem().string());
    }
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

}  // namespace

namespace internal {

std::vector<std::string> KittiFrameNames(const std::string& drive_path) {
  const fs::path dir = fs::path(drive_path) / "image_02" / "data";
  if (!IsFolder(dir.string())) {
    throw IoError(dir.string(),
                  "KITTI left image folder not found (expected a raw drive folder "
                  "<date>/<date>_drive_NNNN_sync)");
  }
  const std::vector<std::string> frames = FramesIn(dir, ".png");
  if (frames.empty()) throw IoError(dir.string(), "no frames (NNNNNNNNNN.png)");
  return frames;
}

}  // namespace internal

std::vector<KittiScanTime> KittiNeighbourScans(const std::string& drive_path,
                                               const std::string& frame, double max_gap_s) {
  if (!IsFrameName(frame)) throw IoError(drive_path, "'" + frame + "' is not a KITTI frame number");
  const fs::path dir = fs::path(drive_path) / "velodyne_points";
  std::vector<std::string> timestamps;
  const fs::path stamp_file = dir / "timestamps.txt";
  if (internal::IsFile(stamp_file.string())) {
    std::istringstream in(ReadFileBytes(stamp_file.string()));
    std::string line;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      timestamps.push_back(line);
    }
  }
  auto time_of = [&](const std::string& name) {
    const long index = std::stol(name);
    if (timestamps.empty()) return 0.1 * static_cast<double>(index);  // KITTI raw sync: 10 Hz
    if (index < 0 || static_cast<size_t>(index) >= timestamps.size()) {
      throw IoError(stamp_file.string(), "has no line for frame " + name);
    }
    const double t = TimeOfDaySeconds(timestamps[index]);
    if (!std::isfinite(t)) {
      throw IoError(stamp_file.string(), "line " + std::to_string(index + 1) +
                                             " is not a timestamp: '" + timestamps[index] + "'");
    }
    return t;
  };

  const double reference_time = time_of(frame);
  KittiScanTime before, after;  // empty frame: none found
  for (const std::string& name : FramesIn(dir / "data", ".bin")) {
    if (name == frame) continue;
    double dt = time_of(name) - reference_time;
    if (dt > 43200.0) dt -= 86400.0;  // the drive crossed midnight
    if (dt < -43200.0) dt += 86400.0;
    if (dt == 0.0 || std::abs(dt) > max_gap_s) continue;
    KittiScanTime& slot = dt < 0.0 ? before : after;
    if (slot.frame.empty() || std::abs(dt) < std::abs(slot.seconds_after_reference)) {
      slot = {name, KittiVelodynePath(drive_path, name), dt};
    }
  }
  std::vector<KittiScanTime> out;
  if (!before.frame.empty()) out.push_back(before);
  if (!after.frame.empty()) out.push_back(after);
  return out;
}

Dataset LoadKittiRawDataset(const DatasetRequest& request) {
  internal::CheckRequest(request);
  // A trailing slash would make parent_path() the drive folder itself.
  fs::path drive = fs::path(request.path);
  if (drive.filename().empty()) drive = drive.parent_path();
  const fs::path date_dir = drive.parent_path();
  const std::vector<std::string> frames = internal::KittiFrameNames(drive.string());
  if (std::find(frames.begin(), frames.end(), request.reference) == frames.end()) {
    throw ConfigError(ViolatedConstraint(
        "dataset.reference", "'" + request.reference + "'",
        "a frame of " + drive.string() + " (valid names: " + internal::JoinNames(frames) + ")"));
  }
  if (!request.neighbors.empty()) {
    spdlog::warn("kitti_raw: dataset.neighbors is ignored (the right image is the neighbour)");
  }

  const KittiCalibration cam_to_cam((date_dir / "calib_cam_to_cam.txt").string());
  const KittiCalibration velo_to_cam((date_dir / "calib_velo_to_cam.txt").string());
  const std::vector<double> size = cam_to_cam.Numbers("S_rect_02", 2);
  const int width = static_cast<int>(std::lround(size[0]));
  const int height = static_cast<int>(std::lround(size[1]));
  const Camera left = CameraFromProjection(cam_to_cam, "P_rect_02", width, height);
  const Camera right = CameraFromProjection(cam_to_cam, "P_rect_03", width, height);
  const Eigen::Matrix3d rect = cam_to_cam.Matrix<3, 3>("R_rect_00");
  const Eigen::Matrix3d velo_R = velo_to_cam.Matrix<3, 3>("R");
  const Eigen::Vector3d velo_T = velo_to_cam.Matrix<3, 1>("T");

  auto load = [&](const std::string& name, const std::string& folder, const Camera& camera) {
    const std::string file = (drive / folder / "data" / (request.reference + ".png")).string();
    View view;
    view.name = name;
    view.image = ReadColorImage(file);
    if (view.image.cols != width || view.image.rows != height) {
      std::ostringstream s;
      s << "image is " << view.image.cols << "x" << view.image.rows << " but " << cam_to_cam.path()
        << " declares S_rect_02 = " << width << "x" << height;
      throw IoError(file, s.str());
    }
    view.camera = camera;
    if (request.scale != 1.0) {
      view.camera = camera.Rescaled(request.scale);
      view.image =
          internal::ResizeImage(view.image, cv::Size(view.camera.width, view.camera.height));
    }
    return view;
  };

  Dataset dataset;
  dataset.format = "kitti_raw";
  dataset.path = request.path;
  dataset.reference = load(request.reference, "image_02", left);
  dataset.neighbors.push_back(load(request.reference + "_right", "image_03", right));
  dataset.rectified = true;
  const double baseline = right.center_world.x() - left.center_world.x();
  if (!(baseline > 0.0)) {
    throw IoError(cam_to_cam.path(), "P_rect_03 is not to the right of P_rect_02 (baseline " +
                                         std::to_string(baseline) + ")");
  }
  dataset.disparity_numerator = dataset.reference.camera.K(0, 0) * baseline;
  Eigen::Matrix4d rect4 = Eigen::Matrix4d::Identity();
  rect4.topLeftCorner<3, 3>() = rect;
  Eigen::Matrix4d velo4 = Eigen::Matrix4d::Identity();
  velo4.topLeftCorner<3, 3>() = velo_R;
  velo4.topRightCorner<3, 1>() = velo_T;
  dataset.world_from_lidar = rect4 * velo4;
  spdlog::info("kitti_raw {}: frame {}, {}x{}, baseline {:.4f} m, f·B = {:.2f}", drive.string(),
               request.reference, dataset.reference.image.cols, dataset.reference.image.rows,
               baseline, dataset.disparity_numerator);
  return dataset;
}

}  // namespace gcpstereo::io
