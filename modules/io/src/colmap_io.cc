// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// COLMAP sparse models, binary and text (colmap_io.h). Written from the format description at
// https://colmap.github.io/format.html:
//   cameras   per camera: camera_id, model, width, height, params
//   images    per image: image_id, qw qx qy qz, tx ty tz, camera_id, name, then its keypoints
//             (x, y, point3D_id; −1 = none)
//   points3D  per point: point3D_id, x y z, r g b, error, track (image_id, point2D_idx)…
// Binary files are little-endian: every list starts with a uint64 count, ids are uint32 (camera,
// image, point2D_idx) or uint64 (point3D), model ids int32, sizes uint64, names NUL-terminated.
#include "gcpstereo/io/colmap_io.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <locale>
#include <set>
#include <sstream>
#include <utility>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "dataset_internal.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"
#include "little_endian.h"

namespace fs = std::filesystem;

namespace gcpstereo::io {
namespace {

// COLMAP's camera models, indexed by model id, with their parameter counts.
struct ModelInfo {
  int id;
  const char* name;
  std::size_t num_params;
};
constexpr ModelInfo kModels[] = {
    {0, "SIMPLE_PINHOLE", 3},
    {1, "PINHOLE", 4},
    {2, "SIMPLE_RADIAL", 4},
    {3, "RADIAL", 5},
    {4, "OPENCV", 8},
    {5, "OPENCV_FISHEYE", 8},
    {6, "FULL_OPENCV", 12},
    {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4},
    {9, "RADIAL_FISHEYE", 5},
    {10, "THIN_PRISM_FISHEYE", 12},
    {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16},
};

const ModelInfo* ModelById(int id) {
  for (const ModelInfo& m : kModels) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

const ModelInfo* ModelByName(const std::string& name) {
  for (const ModelInfo& m : kModels) {
    if (name == m.name) return &m;
  }
  return nullptr;
}

constexpr const char* kSupportedModels =
    "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV";

// ---- Binary ----------------------------------------------------------------------------------

// A bounds-checked little-endian reader over a whole file's bytes.
class BinaryReader {
 public:
  BinaryReader(std::string path, std::string bytes)
      : path_(std::move(path)), bytes_(std::move(bytes)) {}

  template <typename T>
  T Read(const char* what) {
    Need(sizeof(T), what);
    char raw[sizeof(T)];
    std::memcpy(raw, bytes_.data() + offset_, sizeof(T));
    if (!internal::HostIsLittleEndian()) std::reverse(raw, raw + sizeof(T));
    offset_ += sizeof(T);
    T value;
    std::memcpy(&value, raw, sizeof(T));
    return value;
  }

  double ReadFinite(const char* what) {
    const std::size_t at = offset_;
    const double value = Read<double>(what);
    if (!std::isfinite(value)) Fail(std::string("non-finite ") + what, at);
    return value;
  }

  std::string ReadName(const char* what) {
    const std::size_t end = bytes_.find('\0', offset_);
    if (end == std::string::npos)
      Fail(std::string("truncated: ") + what + " without its NUL", offset_);
    std::string name = bytes_.substr(offset_, end - offset_);
    offset_ = end + 1;
    return name;
  }

  // A count of records of at least `min_record_bytes` each: rejected before anything is allocated
  // when the bytes left cannot hold them.
  std::uint64_t ReadCount(const char* what, std::size_t min_record_bytes) {
    const std::size_t at = offset_;
    const std::uint64_t count = Read<std::uint64_t>(what);
    const std::uint64_t left = bytes_.size() - offset_;
    if (count > left / min_record_bytes) {
      std::ostringstream s;
      s << "corrupt or truncated: " << what << " = " << count << " needs at least "
        << min_record_bytes << " bytes each, but only " << left << " bytes follow";
      Fail(s.str(), at);
    }
    return count;
  }

  void ExpectEnd() const {
    if (offset_ != bytes_.size()) {
      Fail(std::to_string(bytes_.size() - offset_) + " unexpected trailing bytes", offset_);
    }
  }

  [[noreturn]] void Fail(const std::string& problem, std::size_t at) const {
    throw IoError(path_, problem + " (at byte " + std::to_string(at) + " of " +
                             std::to_string(bytes_.size()) + ")");
  }
  const std::string& path() const { return path_; }

 private:
  void Need(std::size_t n, const char* what) const {
    if (bytes_.size() - offset_ < n) {
      Fail(std::string("truncated: the file ends inside ") + what, offset_);
    }
  }

  std::string path_;
  std::string bytes_;
  std::size_t offset_ = 0;
};

void ReadCamerasBinary(const std::string& path, ColmapModel* model) {
  BinaryReader in(path, ReadFileBytes(path));
  // camera_id u32, model_id i32, width u64, height u64, then ≥ 3 doubles.
  const std::uint64_t count = in.ReadCount("the number of cameras", 4 + 4 + 8 + 8 + 3 * 8);
  for (std::uint64_t i = 0; i < count; ++i) {
    ColmapCamera camera;
    camera.camera_id = in.Read<std::uint32_t>("a camera id");
    camera.model_id = in.Read<std::int32_t>("a camera model id");
    const ModelInfo* info = ModelById(camera.model_id);
    if (!info) {
      throw IoError(path, "camera " + std::to_string(camera.camera_id) + ": unknown model id " +
                              std::to_string(camera.model_id) + " (corrupt file or a model newer " +
                              "than this reader)");
    }
    camera.model_name = info->name;
    camera.width = in.Read<std::uint64_t>("a camera width");
    camera.height = in.Read<std::uint64_t>("a camera height");
    for (std::size_t p = 0; p < info->num_params; ++p) {
      camera.params.push_back(in.ReadFinite("a camera parameter"));
    }
    const std::uint32_t id = camera.camera_id;
    if (!model->cameras.emplace(id, std::move(camera)).second) {
      throw IoError(path, "camera id " + std::to_string(id) + " appears twice");
    }
  }
  in.ExpectEnd();
}

void ReadImagesBinary(const std::string& path, ColmapModel* model) {
  BinaryReader in(path, ReadFileBytes(path));
  // image_id u32, 7 doubles, camera_id u32, a name of ≥ 1 byte + NUL, the keypoint count u64.
  const std::uint64_t count = in.ReadCount("the number of images", 4 + 7 * 8 + 4 + 2 + 8);
  for (std::uint64_t i = 0; i < count; ++i) {
    ColmapImage image;
    image.image_id = in.Read<std::uint32_t>("an image id");
    for (int k = 0; k < 4; ++k) image.qvec_wxyz[k] = in.ReadFinite("an image's qvec");
    for (int k = 0; k < 3; ++k) image.tvec[k] = in.ReadFinite("an image's tvec");
    image.camera_id = in.Read<std::uint32_t>("an image's camera id");
    image.name = in.ReadName("an image name");
    const std::uint64_t num_points = in.ReadCount("an image's number of keypoints", 3 * 8);
    image.points2d.resize(num_points);
    for (ColmapPoint2D& point : image.points2d) {
      point.xy_colmap_px.x() = in.ReadFinite("a keypoint's x");
      point.xy_colmap_px.y() = in.ReadFinite("a keypoint's y");
      point.point3d_id = in.Read<std::uint64_t>("a keypoint's point3D id");
    }
    const std::uint32_t id = image.image_id;
    if (!model->images.emplace(id, std::move(image)).second) {
      throw IoError(path, "image id " + std::to_string(id) + " appears twice");
    }
  }
  in.ExpectEnd();
}

void ReadPoints3DBinary(const std::string& path, ColmapModel* model) {
  BinaryReader in(path, ReadFileBytes(path));
  // point3D_id u64, 3 doubles, 3 bytes of colour, error double, track length u64.
  const std::uint64_t count = in.ReadCount("the number of 3D points", 8 + 3 * 8 + 3 + 8 + 8);
  for (std::uint64_t i = 0; i < count; ++i) {
    ColmapPoint3D point;
    point.point3d_id = in.Read<std::uint64_t>("a point3D id");
    for (int k = 0; k < 3; ++k) point.xyz_world[k] = in.ReadFinite("a point's xyz");
    for (int k = 0; k < 3; ++k) point.rgb[k] = in.Read<std::uint8_t>("a point's colour");
    point.error_px = in.Read<double>("a point's error");  // COLMAP writes −1 when unknown
    const std::uint64_t length = in.ReadCount("a point's track length", 4 + 4);
    point.track.resize(length);
    for (ColmapTrackElement& element : point.track) {
      element.image_id = in.Read<std::uint32_t>("a track's image id");
      element.point2d_idx = in.Read<std::uint32_t>("a track's point2D index");
    }
    const std::uint64_t id = point.point3d_id;
    if (!model->points3d.emplace(id, std::move(point)).second) {
      throw IoError(path, "point3D id " + std::to_string(id) + " appears twice");
    }
  }
  in.ExpectEnd();
}

// ---- Text ------------------------------------------------------------------------------------

// The lines of a text file with their 1-based numbers, CR before LF removed.
struct TextLine {
  int number;
  std::string text;
};

std::vector<TextLine> Lines(const std::string& path) {
  std::istringstream in(ReadFileBytes(path));
  std::vector<TextLine> lines;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back({number, line});
  }
  return lines;
}

bool IsBlankOrComment(const std::string& line) {
  const std::size_t first = line.find_first_not_of(" \t");
  return first == std::string::npos || line[first] == '#';
}

std::vector<std::string> Tokens(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> tokens;
  std::string token;
  while (in >> token) tokens.push_back(token);
  return tokens;
}

class TextParser {
 public:
  TextParser(const std::string& path, int line) : path_(path), line_(line) {}

  [[noreturn]] void Fail(const std::string& problem) const {
    throw IoError(path_, "line " + std::to_string(line_) + ": " + problem);
  }

  double Double(const std::string& token, const char* what) const {
    errno = 0;
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    if (end != token.c_str() + token.size() || token.empty() || errno == ERANGE) {
      Fail(std::string("cannot parse '") + token + "' as " + what);
    }
    if (!std::isfinite(value)) Fail(std::string("non-finite ") + what + " '" + token + "'");
    return value;
  }

  // An integer in [min, max].
  long long Integer(const std::string& token, const char* what, long long min,
                    unsigned long long max) const {
    errno = 0;
    char* end = nullptr;
    if (!token.empty() && token[0] == '-') {
      const long long value = std::strtoll(token.c_str(), &end, 10);
      if (end != token.c_str() + token.size() || errno == ERANGE || value < min) {
        Fail(std::string("'") + token + "' is not a valid " + what);
      }
      return value;
    }
    const unsigned long long value = std::strtoull(token.c_str(), &end, 10);
    if (token.empty() || end != token.c_str() + token.size() || errno == ERANGE || value > max) {
      Fail(std::string("'") + token + "' is not a valid " + what);
    }
    return static_cast<long long>(value);
  }

  std::uint64_t Uint64(const std::string& token, const char* what) const {
    errno = 0;
    char* end = nullptr;
    const unsigned long long value = std::strtoull(token.c_str(), &end, 10);
    if (token.empty() || token[0] == '-' || end != token.c_str() + token.size() ||
        errno == ERANGE) {
      Fail(std::string("'") + token + "' is not a valid " + what);
    }
    return value;
  }

 private:
  const std::string& path_;
  int line_;
};

constexpr unsigned long long kMaxU32 = std::numeric_limits<std::uint32_t>::max();

void ReadCamerasText(const std::string& path, ColmapModel* model) {
  for (const TextLine& line : Lines(path)) {
    if (IsBlankOrComment(line.text)) continue;
    const TextParser p(path, line.number);
    const std::vector<std::string> t = Tokens(line.text);
    if (t.size() < 4) p.Fail("expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    ColmapCamera camera;
    camera.camera_id = static_cast<std::uint32_t>(p.Integer(t[0], "camera id", 0, kMaxU32));
    camera.model_name = t[1];
    const ModelInfo* info = ModelByName(camera.model_name);
    if (!info) {
      p.Fail("camera " + t[0] + ": unknown camera model '" + t[1] + "'");
    }
    camera.model_id = info->id;
    camera.width = p.Uint64(t[2], "width");
    camera.height = p.Uint64(t[3], "height");
    if (t.size() - 4 != info->num_params) {
      p.Fail("camera " + t[0] + ": model " + t[1] + " has " + std::to_string(info->num_params) +
             " parameters, found " + std::to_string(t.size() - 4));
    }
    for (std::size_t k = 4; k < t.size(); ++k) camera.params.push_back(p.Double(t[k], "parameter"));
    if (!model->cameras.emplace(camera.camera_id, camera).second) {
      p.Fail("camera id " + t[0] + " appears twice");
    }
  }
}

void ReadImagesText(const std::string& path, ColmapModel* model) {
  const std::vector<TextLine> lines = Lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (IsBlankOrComment(lines[i].text)) continue;
    const TextParser p(path, lines[i].number);
    // IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME; the name is the rest of the line.
    std::istringstream in(lines[i].text);
    std::vector<std::string> t(9);
    for (std::string& token : t) {
      if (!(in >> token)) p.Fail("expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
    }
    std::string name;
    std::getline(in, name);
    const std::size_t first = name.find_first_not_of(" \t");
    const std::size_t last = name.find_last_not_of(" \t");
    if (first == std::string::npos) p.Fail("an image without a NAME");
    ColmapImage image;
    image.name = name.substr(first, last - first + 1);
    image.image_id = static_cast<std::uint32_t>(p.Integer(t[0], "image id", 0, kMaxU32));
    for (int k = 0; k < 4; ++k) image.qvec_wxyz[k] = p.Double(t[1 + k], "quaternion component");
    for (int k = 0; k < 3; ++k) image.tvec[k] = p.Double(t[5 + k], "translation component");
    image.camera_id = static_cast<std::uint32_t>(p.Integer(t[8], "camera id", 0, kMaxU32));
    // The keypoint line follows directly (it is empty for an image without keypoints).
    if (i + 1 >= lines.size()) p.Fail("image " + t[0] + " lacks its POINTS2D line");
    ++i;
    const TextParser q(path, lines[i].number);
    const std::vector<std::string> k = Tokens(lines[i].text);
    if (k.size() % 3 != 0) q.Fail("POINTS2D: expected triples X Y POINT3D_ID");
    image.points2d.resize(k.size() / 3);
    for (std::size_t j = 0; j < image.points2d.size(); ++j) {
      ColmapPoint2D& point = image.points2d[j];
      point.xy_colmap_px.x() = q.Double(k[3 * j], "keypoint x");
      point.xy_colmap_px.y() = q.Double(k[3 * j + 1], "keypoint y");
      const std::string& id = k[3 * j + 2];
      point.point3d_id = id == "-1" ? ColmapPoint2D::kNoPoint3D : q.Uint64(id, "point3D id");
    }
    if (!model->images.emplace(image.image_id, std::move(image)).second) {
      p.Fail("image id " + t[0] + " appears twice");
    }
  }
}

void ReadPoints3DText(const std::string& path, ColmapModel* model) {
  for (const TextLine& line : Lines(path)) {
    if (IsBlankOrComment(line.text)) continue;
    const TextParser p(path, line.number);
    const std::vector<std::string> t = Tokens(line.text);
    if (t.size() < 8 || (t.size() - 8) % 2 != 0) {
      p.Fail("expected POINT3D_ID X Y Z R G B ERROR (IMAGE_ID POINT2D_IDX)...");
    }
    ColmapPoint3D point;
    point.point3d_id = p.Uint64(t[0], "point3D id");
    for (int k = 0; k < 3; ++k) point.xyz_world[k] = p.Double(t[1 + k], "coordinate");
    for (int k = 0; k < 3; ++k) {
      point.rgb[k] = static_cast<std::uint8_t>(p.Integer(t[4 + k], "colour (0…255)", 0, 255));
    }
    point.error_px = p.Double(t[7], "error");
    for (std::size_t k = 8; k < t.size(); k += 2) {
      point.track.push_back(
          {static_cast<std::uint32_t>(p.Integer(t[k], "track image id", 0, kMaxU32)),
           static_cast<std::uint32_t>(p.Integer(t[k + 1], "track point2D index", 0, kMaxU32))});
    }
    if (!model->points3d.emplace(point.point3d_id, std::move(point)).second) {
      p.Fail("point3D id " + t[0] + " appears twice");
    }
  }
}

// ---- The model -------------------------------------------------------------------------------

// <dir>/<stem>.bin when it exists, else <dir>/<stem>.txt; "" when neither does.
std::string ModelFile(const std::string& dir, const std::string& stem, bool* binary) {
  const std::string bin = (fs::path(dir) / (stem + ".bin")).string();
  const std::string txt = (fs::path(dir) / (stem + ".txt")).string();
  *binary = internal::IsFile(bin);
  if (*binary) return bin;
  if (!internal::IsFile(txt)) {
    throw IoError(dir, "no " + stem + ".bin or " + stem + ".txt (a COLMAP sparse model folder " +
                           "holds cameras, images and points3D)");
  }
  return txt;
}

// Cross-references: cameras of images, images and keypoints of tracks, points of keypoints.
void CheckReferences(const ColmapModel& model, const std::string& images_file,
                     const std::string& points_file) {
  for (const auto& [id, image] : model.images) {
    if (!model.cameras.count(image.camera_id)) {
      throw IoError(images_file, "image " + std::to_string(id) + " (" + image.name +
                                     ") refers to camera " + std::to_string(image.camera_id) +
                                     ", which the cameras file does not define");
    }
    const double norm = image.qvec_wxyz.norm();
    if (!(norm > 1e-6)) {
      throw IoError(images_file,
                    "image " + std::to_string(id) + " (" + image.name + "): zero quaternion");
    }
    for (const ColmapPoint2D& point : image.points2d) {
      if (point.HasPoint3D() && !model.points3d.count(point.point3d_id)) {
        throw IoError(images_file, "image " + std::to_string(id) + " (" + image.name +
                                       ") observes point3D " + std::to_string(point.point3d_id) +
                                       ", which the points3D file does not define");
      }
    }
  }
  for (const auto& [id, point] : model.points3d) {
    for (const ColmapTrackElement& element : point.track) {
      const auto image = model.images.find(element.image_id);
      if (image == model.images.end()) {
        throw IoError(points_file, "point3D " + std::to_string(id) + ": track refers to image " +
                                       std::to_string(element.image_id) +
                                       ", which the images file does not define");
      }
      if (element.point2d_idx >= image->second.points2d.size()) {
        throw IoError(points_file, "point3D " + std::to_string(id) + ": track refers to keypoint " +
                                       std::to_string(element.point2d_idx) + " of image " +
                                       std::to_string(element.image_id) + ", which has " +
                                       std::to_string(image->second.points2d.size()));
      }
    }
  }
}

}  // namespace

Eigen::Matrix3d ColmapImage::CameraFromWorldRotation() const {
  const Eigen::Quaterniond q(qvec_wxyz[0], qvec_wxyz[1], qvec_wxyz[2], qvec_wxyz[3]);
  return q.normalized().toRotationMatrix();
}

Eigen::Vector3d ColmapImage::CenterWorld() const {
  return -CameraFromWorldRotation().transpose() * tvec;
}

const ColmapImage* ColmapModel::FindImage(const std::string& name) const {
  for (const auto& [id, image] : images) {
    if (image.name == name) return &image;
  }
  return nullptr;
}

std::vector<std::string> ColmapModel::ImageNames() const {
  std::vector<std::string> names;
  for (const auto& [id, image] : images) names.push_back(image.name);
  std::sort(names.begin(), names.end());
  return names;
}

ColmapModel ReadColmapModel(const std::string& sparse_dir) {
  if (!internal::IsFolder(sparse_dir)) {
    throw IoError(sparse_dir, "COLMAP sparse model folder not found");
  }
  ColmapModel model;
  model.sparse_dir = sparse_dir;
  bool binary = false;
  const std::string cameras_file = ModelFile(sparse_dir, "cameras", &binary);
  binary ? ReadCamerasBinary(cameras_file, &model) : ReadCamerasText(cameras_file, &model);
  const std::string images_file = ModelFile(sparse_dir, "images", &binary);
  binary ? ReadImagesBinary(images_file, &model) : ReadImagesText(images_file, &model);
  const std::string points_file = ModelFile(sparse_dir, "points3D", &binary);
  binary ? ReadPoints3DBinary(points_file, &model) : ReadPoints3DText(points_file, &model);
  CheckReferences(model, images_file, points_file);
  std::vector<std::string> names = model.ImageNames();
  const auto duplicate = std::adjacent_find(names.begin(), names.end());
  if (duplicate != names.end()) {
    throw IoError(images_file, "two images are named '" + *duplicate + "'");
  }
  return model;
}

bool IsSupportedColmapCameraModel(const std::string& model_name) {
  return model_name == "SIMPLE_PINHOLE" || model_name == "PINHOLE" ||
         model_name == "SIMPLE_RADIAL" || model_name == "RADIAL" || model_name == "OPENCV" ||
         model_name == "FULL_OPENCV";
}

ColmapPinhole MakeColmapPinhole(const ColmapCamera& camera, const std::string& context) {
  const std::string id = std::to_string(camera.camera_id);
  if (!IsSupportedColmapCameraModel(camera.model_name)) {
    throw IoError(context,
                  "camera " + id + " has model " + camera.model_name +
                      ", which gcpstereo does not support (supported: " + kSupportedModels + ")");
  }
  const ModelInfo* info = ModelByName(camera.model_name);
  if (camera.params.size() != info->num_params) {
    throw IoError(context, "camera " + id + " (" + camera.model_name + ") has " +
                               std::to_string(camera.params.size()) + " parameters, expected " +
                               std::to_string(info->num_params));
  }
  if (camera.width == 0 || camera.height == 0 || camera.width > 1000000 ||
      camera.height > 1000000) {
    throw IoError(context, "camera " + id + ": image size " + std::to_string(camera.width) + "x" +
                               std::to_string(camera.height) + " out of range");
  }
  const std::vector<double>& p = camera.params;
  // fx, fy, cx, cy and OpenCV's distortion coefficients (k1 k2 p1 p2 k3 k4 k5 k6); COLMAP's
  // SIMPLE_RADIAL, RADIAL, OPENCV and FULL_OPENCV distort normalised coordinates exactly as
  // OpenCV's model does with the coefficients they lack set to zero.
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<double> distortion(8, 0.0);
  const std::string& m = camera.model_name;
  if (m == "SIMPLE_PINHOLE" || m == "SIMPLE_RADIAL" || m == "RADIAL") {
    fx = fy = p[0];
    cx = p[1];
    cy = p[2];
    if (m != "SIMPLE_PINHOLE") distortion[0] = p[3];
    if (m == "RADIAL") distortion[1] = p[4];
  } else {  // PINHOLE, OPENCV, FULL_OPENCV
    fx = p[0];
    fy = p[1];
    cx = p[2];
    cy = p[3];
    for (std::size_t k = 4; k < p.size(); ++k) distortion[k - 4] = p[k];
  }
  if (!(fx > 0.0) || !(fy > 0.0)) {
    throw IoError(context, "camera " + id + ": non-positive focal length");
  }
  ColmapPinhole out;
  out.model_name = m;
  out.width = static_cast<int>(camera.width);
  out.height = static_cast<int>(camera.height);
  // COLMAP puts pixel centres at +0.5, this project (and OpenCV) at integers.
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = fx;
  K(1, 1) = fy;
  K(0, 2) = cx - 0.5;
  K(1, 2) = cy - 0.5;
  out.K = K;
  if (m == "SIMPLE_PINHOLE" || m == "PINHOLE") return out;

  out.undistorted = true;
  const cv::Matx33d K_cv(K(0, 0), 0, K(0, 2), 0, K(1, 1), K(1, 2), 0, 0, 1);
  const cv::Size size(out.width, out.height);
  const cv::Mat new_K =
      cv::getOptimalNewCameraMatrix(K_cv, distortion, size, /*alpha=*/0.0, size, nullptr);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.K(r, c) = new_K.at<double>(r, c);
  }
  if (!(out.K(0, 0) > 0.0) || !(out.K(1, 1) > 0.0) || !out.K.allFinite()) {
    throw IoError(context, "camera " + id + " (" + m +
                               "): OpenCV finds no valid undistorted camera for its distortion");
  }
  cv::initUndistortRectifyMap(K_cv, distortion, cv::noArray(), new_K, size, CV_32FC1, out.map_x,
                              out.map_y);
  return out;
}

cv::Mat UndistortColmapImage(const cv::Mat& image, const ColmapPinhole& pinhole) {
  if (!pinhole.undistorted) return image;
  if (image.cols != pinhole.width || image.rows != pinhole.height) {
    throw Error("UndistortColmapImage: the image is " + std::to_string(image.cols) + "x" +
                std::to_string(image.rows) + ", the camera " + std::to_string(pinhole.width) + "x" +
                std::to_string(pinhole.height));
  }
  cv::Mat out;
  // alpha = 0 keeps every target pixel inside the source; replicate covers rounding at the rim.
  cv::remap(image, out, pinhole.map_x, pinhole.map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

Camera ColmapImageCamera(const ColmapImage& image, const ColmapPinhole& pinhole) {
  Camera camera;
  camera.K = pinhole.K;
  camera.width = pinhole.width;
  camera.height = pinhole.height;
  camera.world_from_camera_rotation = image.CameraFromWorldRotation().transpose();
  camera.center_world = image.CenterWorld();
  return camera;
}

void WriteColmapModelText(const std::string& sparse_dir, const ColmapModel& model) {
  const fs::path dir(sparse_dir);
  const std::string cameras_file = (dir / "cameras.txt").string();
  const std::string images_file = (dir / "images.txt").string();
  const std::string points_file = (dir / "points3D.txt").string();
  // What the reader would refuse is refused before anything is written.
  for (const auto& [id, camera] : model.cameras) {
    const ModelInfo* info = ModelByName(camera.model_name);
    if (!info) {
      throw IoError(cameras_file, "camera " + std::to_string(id) + ": unknown camera model '" +
                                      camera.model_name + "'");
    }
    if (camera.params.size() != info->num_params) {
      throw IoError(cameras_file, "camera " + std::to_string(id) + ": model " + camera.model_name +
                                      " has " + std::to_string(info->num_params) +
                                      " parameters, given " + std::to_string(camera.params.size()));
    }
  }
  for (const auto& [id, image] : model.images) {
    // The text reader takes the rest of the line, trimmed, as the name.
    const std::string& name = image.name;
    if (name.empty() || name.find_first_of("\r\n") != std::string::npos || name.front() == ' ' ||
        name.front() == '\t' || name.back() == ' ' || name.back() == '\t') {
      throw IoError(images_file, "image " + std::to_string(id) + ": the name '" + name +
                                     "' cannot be written as text (empty, a line break, or "
                                     "blanks at either end)");
    }
  }
  CheckReferences(model, images_file, points_file);

  auto stream = [] {
    std::ostringstream s;
    s.imbue(std::locale::classic());
    s << std::setprecision(17);
    return s;
  };
  std::ostringstream cameras = stream();
  cameras << "# Camera list with one line of data per camera:\n"
          << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
          << "# Number of cameras: " << model.cameras.size() << "\n";
  for (const auto& [id, camera] : model.cameras) {
    cameras << id << " " << camera.model_name << " " << camera.width << " " << camera.height;
    for (double p : camera.params) cameras << " " << p;
    cameras << "\n";
  }
  std::size_t observations = 0;
  for (const auto& [id, image] : model.images) observations += image.points2d.size();
  std::ostringstream images = stream();
  images << "# Image list with two lines of data per image:\n"
         << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
         << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
         << "# Number of images: " << model.images.size() << ", mean observations per image: "
         << (model.images.empty() ? 0.0 : static_cast<double>(observations) / model.images.size())
         << "\n";
  for (const auto& [id, image] : model.images) {
    images << id;
    for (int k = 0; k < 4; ++k) images << " " << image.qvec_wxyz[k];
    for (int k = 0; k < 3; ++k) images << " " << image.tvec[k];
    images << " " << image.camera_id << " " << image.name << "\n";
    for (std::size_t j = 0; j < image.points2d.size(); ++j) {
      const ColmapPoint2D& point = image.points2d[j];
      images << (j ? " " : "") << point.xy_colmap_px.x() << " " << point.xy_colmap_px.y() << " ";
      if (point.HasPoint3D()) {
        images << point.point3d_id;
      } else {
        images << "-1";
      }
    }
    images << "\n";
  }
  std::size_t track_elements = 0;
  for (const auto& [id, point] : model.points3d) track_elements += point.track.size();
  std::ostringstream points = stream();
  points << "# 3D point list with one line of data per point:\n"
         << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
         << "# Number of points: " << model.points3d.size() << ", mean track length: "
         << (model.points3d.empty() ? 0.0
                                    : static_cast<double>(track_elements) / model.points3d.size())
         << "\n";
  for (const auto& [id, point] : model.points3d) {
    points << id;
    for (int k = 0; k < 3; ++k) points << " " << point.xyz_world[k];
    for (int k = 0; k < 3; ++k) points << " " << static_cast<int>(point.rgb[k]);
    points << " " << point.error_px;
    for (const ColmapTrackElement& element : point.track) {
      points << " " << element.image_id << " " << element.point2d_idx;
    }
    points << "\n";
  }
  const std::vector<std::pair<std::string, std::string>> files = {
      {cameras_file, cameras.str()}, {images_file, images.str()}, {points_file, points.str()}};
  for (const auto& [path, text] : files) WriteBytesAtomically(path, text.data(), text.size());
}

std::string ColmapSparseDir(const std::string& workspace) {
  return (fs::path(workspace) / "sparse").string();
}

void TransformColmapModel(const Eigen::Matrix4d& world_from_model, ColmapModel* model) {
  const Eigen::Matrix3d sr = world_from_model.topLeftCorner<3, 3>();
  const double scale = std::cbrt(sr.determinant());
  const Eigen::Matrix3d rotation = scale > 0.0 ? Eigen::Matrix3d(sr / scale) : sr;
  const Eigen::Vector3d translation = world_from_model.topRightCorner<3, 1>();
  if (!world_from_model.allFinite() || !(scale > 0.0) ||
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      !world_from_model.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1))) {
    throw Error("TransformColmapModel: not a similarity transform [sR t; 0 1]");
  }
  for (auto& [id, point] : model->points3d) {
    point.xyz_world = scale * (rotation * point.xyz_world) + translation;
  }
  for (auto& [id, image] : model->images) {
    const Eigen::Matrix3d camera_from_world =
        image.CameraFromWorldRotation() * rotation.transpose();
    image.tvec = scale * image.tvec - camera_from_world * translation;
    const Eigen::Quaterniond q(camera_from_world);
    image.qvec_wxyz = Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
  }
}

std::vector<KnownCentre> ReadKnownCentres(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot open the camera centres file");
  std::vector<KnownCentre> centres;
  std::set<std::string> names;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    // The last three fields are the coordinates, everything before them the name.
    std::vector<std::string> fields;
    std::istringstream split(line);
    for (std::string field; split >> field;) fields.push_back(field);
    const std::string where = "line " + std::to_string(number) + ": ";
    if (fields.size() < 4) {
      throw IoError(path, where + "expected '<image name> X Y Z', got '" + line + "'");
    }
    KnownCentre centre;
    for (int k = 0; k < 3; ++k) {
      const std::string& text = fields[fields.size() - 3 + k];
      char* end = nullptr;
      errno = 0;
      const double value = std::strtod(text.c_str(), &end);
      if (end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(value)) {
        throw IoError(path, where + "'" + text + "' is not a finite coordinate");
      }
      centre.center_world[k] = value;
    }
    // The name as written (inner spaces kept), without the coordinates' fields.
    size_t end_of_name = line.size();
    for (int k = 0; k < 3; ++k) {
      end_of_name = line.find_last_not_of(" \t", end_of_name - 1);
      end_of_name = line.find_last_of(" \t", end_of_name);
    }
    const size_t name_end = line.find_last_not_of(" \t", end_of_name);
    centre.name = line.substr(first, name_end - first + 1);
    if (!names.insert(centre.name).second) {
      throw IoError(path, where + "image '" + centre.name + "' is listed twice");
    }
    centres.push_back(std::move(centre));
  }
  if (centres.empty()) throw IoError(path, "no camera centre in the file");
  return centres;
}

}  // namespace gcpstereo::io
