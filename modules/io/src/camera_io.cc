// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/camera_io.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <locale>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/SVD>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/io/atomic_file.h"

namespace gcpstereo::io {
namespace {

constexpr int kStrechaLines = 9;

// Splits the text into its non-empty lines (trailing blank lines are ignored, a CR before LF too).
std::vector<std::string> NonEmptyLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    lines.push_back(line);
  }
  return lines;
}

// Parses exactly `count` numbers from line `line_number` (1-based).
std::vector<double> ParseNumbers(const std::string& path, const std::string& line, int line_number,
                                 int count) {
  std::istringstream in(line);
  in.imbue(std::locale::classic());
  std::vector<double> values;
  std::string token;
  while (in >> token) {
    // std::stod accepts "nan" and "inf", which we want to reject with a clear message.
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size()) {
      throw IoError(path, "line " + std::to_string(line_number) + ": cannot parse '" + token +
                              "' as a number");
    }
    if (!std::isfinite(value)) {
      throw IoError(path,
                    "line " + std::to_string(line_number) + ": non-finite value '" + token + "'");
    }
    values.push_back(value);
  }
  if (static_cast<int>(values.size()) != count) {
    throw IoError(path, "line " + std::to_string(line_number) + ": expected " +
                            std::to_string(count) + " numbers, found " +
                            std::to_string(values.size()));
  }
  return values;
}

}  // namespace

Camera ReadStrechaCamera(const std::string& path) {
  const std::vector<std::string> lines = NonEmptyLines(ReadFileBytes(path));
  if (static_cast<int>(lines.size()) != kStrechaLines) {
    throw IoError(path, "expected " + std::to_string(kStrechaLines) +
                            " lines (K, distortion, R, C, size), found " +
                            std::to_string(lines.size()));
  }
  Camera camera;
  for (int r = 0; r < 3; ++r) {
    const auto v = ParseNumbers(path, lines[r], r + 1, 3);
    for (int c = 0; c < 3; ++c) camera.K(r, c) = v[c];
  }
  const auto distortion = ParseNumbers(path, lines[3], 4, 3);
  for (int r = 0; r < 3; ++r) {
    const auto v = ParseNumbers(path, lines[4 + r], 5 + r, 3);
    for (int c = 0; c < 3; ++c) camera.world_from_camera_rotation(r, c) = v[c];
  }
  const auto center = ParseNumbers(path, lines[7], 8, 3);
  camera.center_world = Eigen::Vector3d(center[0], center[1], center[2]);
  const auto size = ParseNumbers(path, lines[8], 9, 2);
  for (double s : size) {
    if (s != std::floor(s) || s <= 0 || s > 1e6) {
      throw IoError(path,
                    "line 9: image size must be two positive integers, found '" + lines[8] + "'");
    }
  }
  camera.width = static_cast<int>(size[0]);
  camera.height = static_cast<int>(size[1]);
  if (distortion[0] != 0.0 || distortion[1] != 0.0 || distortion[2] != 0.0) {
    spdlog::warn(
        "{}: non-zero radial distortion ({} {} {}) is ignored; images are assumed "
        "undistorted",
        path, distortion[0], distortion[1], distortion[2]);
  }
  camera.Validate(path);
  // The files print R with about 6 significant digits, so RᵀR = I only to ~1e-6; Camera uses Rᵀ
  // as R⁻¹ (Project after BackProject would be off by ~1e-6 relative). Replace R by the nearest
  // rotation (polar decomposition, R = U Vᵀ from the SVD), which moves it by the same ~1e-6.
  // Already-orthonormal matrices (our own 17-digit files) are left bit-identical.
  Eigen::Matrix3d& R = camera.world_from_camera_rotation;
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-12) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    R = svd.matrixU() * svd.matrixV().transpose();  // det +1: Validate checked det ≈ +1
  }
  return camera;
}

void WriteStrechaCamera(const std::string& path, const Camera& camera) {
  camera.Validate(path);
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(std::numeric_limits<double>::max_digits10);
  auto row = [&out](double a, double b, double c) { out << a << ' ' << b << ' ' << c << '\n'; };
  for (int r = 0; r < 3; ++r) row(camera.K(r, 0), camera.K(r, 1), camera.K(r, 2));
  row(0.0, 0.0, 0.0);
  const Eigen::Matrix3d& R = camera.world_from_camera_rotation;
  for (int r = 0; r < 3; ++r) row(R(r, 0), R(r, 1), R(r, 2));
  row(camera.center_world.x(), camera.center_world.y(), camera.center_world.z());
  out << camera.width << ' ' << camera.height << '\n';
  const std::string text = out.str();
  WriteBytesAtomically(path, text.data(), text.size());
}

}  // namespace gcpstereo::io
