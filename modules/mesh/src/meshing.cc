// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Depth map → triangle mesh over the pixel grid (see meshing.h for the rules). Not part of Wang &
// Yang (CVPR 2011): the paper evaluates depth maps; the mesh is the output a person opens in
// MeshLab or CloudCompare over the laser scan, hence world coordinates.
//
// Discontinuity criteria (both documented on MeshingOptions):
//   ratio:  max(z0, z1, z2) / min(z0, z1, z2) > 1 + max_depth_ratio          → drop
//   angle:  acos(|n · c| / (|n| |c|)) > max_view_angle_deg                    → drop
//           n = (P1 − P0) × (P2 − P0), c = (P0 + P1 + P2) / 3, P in the camera frame (the camera
//           centre is the origin, so c is the viewing ray to the centroid).
#include "gcpstereo/mesh/meshing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"

namespace gcpstereo::mesh {
namespace {

using Color = Eigen::Matrix<std::uint8_t, 3, 1>;

constexpr double kPi = 3.14159265358979323846;

template <typename T>
std::string Str(T value) {
  std::ostringstream stream;
  stream << value;
  return stream.str();
}

void CheckStride(int stride_px) {
  if (stride_px < 1 || stride_px > 1024) {
    throw ConfigError(ViolatedConstraint("mesh.stride", Str(stride_px), "1 <= stride <= 1024"));
  }
}

// The node coordinates along one axis: 0, s, 2s, … and the last index.
std::vector<int> GridCoordinates(int size, int stride) {
  std::vector<int> coordinates;
  for (int i = 0; i < size; i += stride) coordinates.push_back(i);
  if (coordinates.back() != size - 1) coordinates.push_back(size - 1);
  return coordinates;
}

void CheckInputs(const cv::Mat& depth, const cv::Mat& image_bgr, const Camera& camera,
                 const char* function) {
  const std::string context = std::string(function) + ": ";
  if (depth.empty()) throw Error(context + "the depth map is empty");
  if (depth.type() != CV_32FC1) {
    throw Error(context + "the depth map must be CV_32FC1, got type " + Str(depth.type()) +
                " with " + Str(depth.channels()) + " channel(s)");
  }
  camera.Validate(context + "camera");
  if (depth.cols != camera.width || depth.rows != camera.height) {
    throw Error(context + "the depth map is " + Str(depth.cols) + "x" + Str(depth.rows) +
                " but the camera is " + Str(camera.width) + "x" + Str(camera.height));
  }
  if (!image_bgr.empty()) {
    if (image_bgr.type() != CV_8UC3 && image_bgr.type() != CV_8UC1) {
      throw Error(context + "the image must be CV_8UC3 (BGR) or CV_8UC1, got type " +
                  Str(image_bgr.type()) + " with " + Str(image_bgr.channels()) + " channel(s)");
    }
    if (image_bgr.size() != depth.size()) {
      throw Error(context + "the image is " + Str(image_bgr.cols) + "x" + Str(image_bgr.rows) +
                  " but the depth map is " + Str(depth.cols) + "x" + Str(depth.rows));
    }
  }
}

Color PixelColor(const cv::Mat& image, int col, int row) {
  if (image.type() == CV_8UC1) {
    const std::uint8_t g = image.at<std::uint8_t>(row, col);
    return Color(g, g, g);
  }
  const cv::Vec3b& bgr = image.at<cv::Vec3b>(row, col);
  return Color(bgr[2], bgr[1], bgr[0]);
}

// The valid grid nodes: camera-frame points (for the criteria) and world points.
struct Grid {
  std::vector<int> cols;  // pixel column of each node column
  std::vector<int> rows;  // pixel row of each node row
  std::vector<std::uint8_t> valid;
  std::vector<Eigen::Vector3d> point_camera;
  std::vector<Eigen::Vector3d> point_world;

  int width() const { return static_cast<int>(cols.size()); }
  int height() const { return static_cast<int>(rows.size()); }
  size_t Index(int grid_col, int grid_row) const {
    return static_cast<size_t>(grid_row) * cols.size() + grid_col;
  }
};

// Back-projects each valid node with the formula of Camera::BackProject (K⁻¹ computed once).
Grid BackProjectGrid(const cv::Mat& depth, const Camera& camera, int stride) {
  Grid grid;
  grid.cols = GridCoordinates(depth.cols, stride);
  grid.rows = GridCoordinates(depth.rows, stride);
  const size_t n = grid.cols.size() * grid.rows.size();
  grid.valid.assign(n, 0);
  grid.point_camera.assign(n, Eigen::Vector3d::Zero());
  grid.point_world.assign(n, Eigen::Vector3d::Zero());
  const Eigen::Matrix3d k_inverse = camera.K.inverse();
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.height()),
                    [&](const tbb::blocked_range<int>& r) {
                      for (int gr = r.begin(); gr != r.end(); ++gr) {
                        const float* depth_row = depth.ptr<float>(grid.rows[gr]);
                        for (int gc = 0; gc < grid.width(); ++gc) {
                          const float z = depth_row[grid.cols[gc]];
                          if (!IsValidDepth(z)) continue;
                          const size_t i = grid.Index(gc, gr);
                          const Eigen::Vector3d ray =
                              k_inverse * Eigen::Vector3d(grid.cols[gc], grid.rows[gr], 1.0);
                          grid.point_camera[i] = ray * (static_cast<double>(z) / ray.z());
                          grid.point_world[i] = camera.WorldFromCamera(grid.point_camera[i]);
                          grid.valid[i] = 1;
                        }
                      }
                    });
  return grid;
}

// Faces of one row of grid cells, as node indices, with the drop counts.
struct CellRowFaces {
  std::vector<Eigen::Vector3i> faces;
  std::int64_t dropped_invalid = 0;
  std::int64_t dropped_depth_ratio = 0;
  std::int64_t dropped_view_angle = 0;
};

class FaceFilter {
 public:
  FaceFilter(const Grid& grid, const MeshingOptions& options)
      : grid_(grid),
        max_ratio_(options.max_depth_ratio > 0.0 ? 1.0 + options.max_depth_ratio : 0.0),
        min_cos_(options.max_view_angle_deg < 90.0
                     ? std::cos(options.max_view_angle_deg * kPi / 180.0)
                     : -1.0) {}

  // Appends the triangle (a, b, c) to `out` or counts why it was dropped.
  void Consider(size_t a, size_t b, size_t c, CellRowFaces* out) const {
    const Eigen::Vector3d& p0 = grid_.point_camera[a];
    const Eigen::Vector3d& p1 = grid_.point_camera[b];
    const Eigen::Vector3d& p2 = grid_.point_camera[c];
    if (max_ratio_ > 0.0) {
      const double z_min = std::min({p0.z(), p1.z(), p2.z()});
      const double z_max = std::max({p0.z(), p1.z(), p2.z()});
      if (z_max > max_ratio_ * z_min) {
        ++out->dropped_depth_ratio;
        return;
      }
    }
    if (min_cos_ > -1.0) {
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
      const Eigen::Vector3d centroid = (p0 + p1 + p2) / 3.0;
      const double cos_angle = std::abs(normal.dot(centroid)) / (normal.norm() * centroid.norm());
      // A NaN (degenerate triangle) compares false and is dropped too.
      if (!(cos_angle >= min_cos_)) {
        ++out->dropped_view_angle;
        return;
      }
    }
    out->faces.emplace_back(static_cast<int>(a), static_cast<int>(b), static_cast<int>(c));
  }

 private:
  const Grid& grid_;
  double max_ratio_;  // 0 = off
  double min_cos_;    // −1 = off
};

void TriangulateCellRow(const Grid& grid, const FaceFilter& filter, int gr, CellRowFaces* out) {
  for (int gc = 0; gc + 1 < grid.width(); ++gc) {
    const size_t tl = grid.Index(gc, gr);
    const size_t tr = grid.Index(gc + 1, gr);
    const size_t bl = grid.Index(gc, gr + 1);
    const size_t br = grid.Index(gc + 1, gr + 1);
    const int num_valid = grid.valid[tl] + grid.valid[tr] + grid.valid[bl] + grid.valid[br];
    if (num_valid < 3) {
      out->dropped_invalid += 2;
      continue;
    }
    // Counter-clockwise as seen from the camera = TL → BL → TR in the image (y down).
    if (num_valid == 3) {
      out->dropped_invalid += 1;
      if (!grid.valid[tl]) {
        filter.Consider(tr, bl, br, out);
      } else if (!grid.valid[tr]) {
        filter.Consider(tl, bl, br, out);
      } else if (!grid.valid[bl]) {
        filter.Consider(tl, br, tr, out);
      } else {
        filter.Consider(tl, bl, tr, out);
      }
      continue;
    }
    const double diagonal_tl_br = std::abs(grid.point_camera[tl].z() - grid.point_camera[br].z());
    const double diagonal_tr_bl = std::abs(grid.point_camera[tr].z() - grid.point_camera[bl].z());
    if (diagonal_tl_br <= diagonal_tr_bl) {
      filter.Consider(tl, bl, br, out);
      filter.Consider(tl, br, tr, out);
    } else {
      filter.Consider(tl, bl, tr, out);
      filter.Consider(tr, bl, br, out);
    }
  }
}

// The angle atan2(y, x) in [0, π] for y >= 0, to about 1e-5 rad (a minimax polynomial for atan
// on [−1, 1]; std::atan2 made the vertex normals the slowest part of a rendering).
double AngleOf(double y, double x) {
  const auto atan_unit = [](double t) {  // |t| <= 1
    const double t2 = t * t;
    return t *
           (0.99997726 +
            t2 * (-0.33262347 +
                  t2 * (0.19354346 + t2 * (-0.11643287 + t2 * (0.05265332 - t2 * 0.01172120)))));
  };
  if (y == 0.0 && x == 0.0) return 0.0;
  if (std::abs(x) >= y) {
    const double a = atan_unit(y / std::abs(x));
    return x > 0.0 ? a : kPi - a;
  }
  return 0.5 * kPi - atan_unit(x / y);
}

}  // namespace

void MeshingOptions::Check() const {
  if (!(max_depth_ratio >= 0.0 && max_depth_ratio <= 10.0)) {
    throw ConfigError(ViolatedConstraint("mesh.max_depth_ratio", Str(max_depth_ratio),
                                         "0 <= max_depth_ratio <= 10 (0 = off)"));
  }
  if (!(max_view_angle_deg > 0.0 && max_view_angle_deg <= 90.0)) {
    throw ConfigError(ViolatedConstraint("mesh.max_view_angle_deg", Str(max_view_angle_deg),
                                         "0 < max_view_angle_deg <= 90 (90 = off)"));
  }
  CheckStride(stride_px);
}

std::string MeshingSummary::FullReport() const {
  std::ostringstream s;
  s << "Meshing: grid " << grid_cols << "x" << grid_rows << " nodes, " << valid_nodes << " valid; "
    << vertices << " vertices (" << isolated_nodes << " isolated nodes left out), " << faces
    << " faces of " << candidate_faces << " candidates; dropped: " << dropped_invalid
    << " invalid corner, " << dropped_depth_ratio << " depth ratio, " << dropped_view_angle
    << " view angle; " << seconds << " s";
  return s.str();
}

TriangleMesh MeshFromDepthMap(const cv::Mat& depth, const cv::Mat& image_bgr, const Camera& camera,
                              const MeshingOptions& options, MeshingSummary* summary) {
  const Timer timer;
  options.Check();
  CheckInputs(depth, image_bgr, camera, "MeshFromDepthMap");
  const Grid grid = BackProjectGrid(depth, camera, options.stride_px);
  const FaceFilter filter(grid, options);

  // Faces per row of cells (in parallel), concatenated in row order: deterministic.
  const int cell_rows = grid.height() - 1;
  std::vector<CellRowFaces> rows(std::max(cell_rows, 0));
  tbb::parallel_for(tbb::blocked_range<int>(0, cell_rows), [&](const tbb::blocked_range<int>& r) {
    for (int gr = r.begin(); gr != r.end(); ++gr) TriangulateCellRow(grid, filter, gr, &rows[gr]);
  });

  MeshingSummary s;
  s.grid_cols = grid.width();
  s.grid_rows = grid.height();
  s.candidate_faces =
      2 * static_cast<std::int64_t>(grid.width() - 1) * static_cast<std::int64_t>(cell_rows);
  size_t num_faces = 0;
  for (const CellRowFaces& row : rows) {
    num_faces += row.faces.size();
    s.dropped_invalid += row.dropped_invalid;
    s.dropped_depth_ratio += row.dropped_depth_ratio;
    s.dropped_view_angle += row.dropped_view_angle;
  }

  // Vertices: the nodes used by a face, numbered in raster order.
  std::vector<int> vertex_of_node(grid.valid.size(), -1);
  for (const CellRowFaces& row : rows) {
    for (const Eigen::Vector3i& face : row.faces) {
      for (int k = 0; k < 3; ++k) vertex_of_node[face[k]] = 0;
    }
  }
  TriangleMesh mesh;
  const bool with_colors = !image_bgr.empty();
  for (int gr = 0; gr < grid.height(); ++gr) {
    for (int gc = 0; gc < grid.width(); ++gc) {
      const size_t i = grid.Index(gc, gr);
      if (!grid.valid[i]) continue;
      ++s.valid_nodes;
      if (vertex_of_node[i] < 0) {
        ++s.isolated_nodes;
        continue;
      }
      vertex_of_node[i] = static_cast<int>(mesh.vertices.size());
      mesh.vertices.push_back(grid.point_world[i].cast<float>());
      if (with_colors) mesh.colors.push_back(PixelColor(image_bgr, grid.cols[gc], grid.rows[gr]));
    }
  }
  mesh.faces.reserve(num_faces);
  for (const CellRowFaces& row : rows) {
    for (const Eigen::Vector3i& face : row.faces) {
      mesh.faces.emplace_back(vertex_of_node[face[0]], vertex_of_node[face[1]],
                              vertex_of_node[face[2]]);
    }
  }
  s.vertices = static_cast<std::int64_t>(mesh.vertices.size());
  s.faces = static_cast<std::int64_t>(mesh.faces.size());
  s.seconds = timer.ElapsedSeconds();
  if (summary != nullptr) *summary = s;
  return mesh;
}

PointCloud PointCloudFromDepthMap(const cv::Mat& depth, const Camera& camera, int stride_px) {
  CheckStride(stride_px);
  CheckInputs(depth, cv::Mat(), camera, "PointCloudFromDepthMap");
  const Grid grid = BackProjectGrid(depth, camera, stride_px);
  PointCloud cloud;
  for (size_t i = 0; i < grid.valid.size(); ++i) {
    if (grid.valid[i]) cloud.points.push_back(grid.point_world[i].cast<float>());
  }
  return cloud;
}

TriangleMesh ColoredPointsFromDepthMap(const cv::Mat& depth, const cv::Mat& image_bgr,
                                       const Camera& camera, int stride_px) {
  CheckStride(stride_px);
  CheckInputs(depth, image_bgr, camera, "ColoredPointsFromDepthMap");
  const Grid grid = BackProjectGrid(depth, camera, stride_px);
  TriangleMesh points;
  for (int gr = 0; gr < grid.height(); ++gr) {
    for (int gc = 0; gc < grid.width(); ++gc) {
      const size_t i = grid.Index(gc, gr);
      if (!grid.valid[i]) continue;
      points.vertices.push_back(grid.point_world[i].cast<float>());
      if (!image_bgr.empty()) {
        points.colors.push_back(PixelColor(image_bgr, grid.cols[gc], grid.rows[gr]));
      }
    }
  }
  return points;
}

std::vector<Eigen::Vector3f> VertexNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (const Eigen::Vector3i& face : mesh.faces) {
    const Eigen::Vector3d p[3] = {mesh.vertices[face[0]].cast<double>(),
                                  mesh.vertices[face[1]].cast<double>(),
                                  mesh.vertices[face[2]].cast<double>()};
    const Eigen::Vector3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
    const double norm = normal.norm();
    if (!(norm > 0.0)) continue;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e1 = p[(k + 1) % 3] - p[k];
      const Eigen::Vector3d e2 = p[(k + 2) % 3] - p[k];
      const double angle = AngleOf(norm, e1.dot(e2));  // |e1 × e2| = |normal| for every corner
      sum[face[k]] += (angle / norm) * normal;
    }
  }
  std::vector<Eigen::Vector3f> normals(sum.size());
  for (size_t i = 0; i < sum.size(); ++i) {
    const double norm = sum[i].norm();
    normals[i] =
        norm > 0.0 ? Eigen::Vector3f((sum[i] / norm).cast<float>()) : Eigen::Vector3f::Zero();
  }
  return normals;
}

}  // namespace gcpstereo::mesh
