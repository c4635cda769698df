// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Depth-map fusion (see fusion.h for the algorithm and its sources).
#include "gcpstereo/fusion/fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/flann.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"

namespace gcpstereo::fusion {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string MatSize(const cv::Mat& mat) {
  return std::to_string(mat.cols) + "x" + std::to_string(mat.rows);
}

void CheckDepthMap(const cv::Mat& depth, const Camera& camera, const std::string& context) {
  if (depth.empty()) throw Error(context + ": the depth map is empty");
  if (depth.type() != CV_32FC1) {
    throw Error(context + ": the depth map must be CV_32FC1, got type " +
                std::to_string(depth.type()));
  }
  if (depth.cols != camera.width || depth.rows != camera.height) {
    throw Error(context + ": the depth map is " + MatSize(depth) + " but the camera is " +
                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
}

// The per-pixel quantities of one view that the fusion reads, precomputed once.
struct ViewData {
  int width = 0;
  int height = 0;
  const Camera* camera = nullptr;
  Eigen::Matrix3d K;
  Eigen::Matrix3d K_inverse;
  Eigen::Matrix3d camera_from_world;
  Eigen::Vector3d center_world;
  cv::Mat depth;    // CV_32FC1
  cv::Mat normals;  // CV_32FC3, world frame, NaN = undefined
  cv::Mat image;    // CV_8UC3 (BGR) or CV_8UC1

  float Depth(int col, int row) const { return depth.ptr<float>(row)[col]; }
  Eigen::Vector3f Normal(int col, int row) const {
    const float* n = normals.ptr<float>(row) + 3 * col;
    return Eigen::Vector3f(n[0], n[1], n[2]);
  }
  // RGB
  Eigen::Vector3i Color(int col, int row) const {
    if (image.channels() == 1) {
      const int g = image.ptr<std::uint8_t>(row)[col];
      return Eigen::Vector3i(g, g, g);
    }
    const std::uint8_t* bgr = image.ptr<std::uint8_t>(row) + 3 * col;
    return Eigen::Vector3i(bgr[2], bgr[1], bgr[0]);
  }
  Eigen::Vector3d BackProject(int col, int row, double depth_m) const {
    Eigen::Vector3d ray = K_inverse * Eigen::Vector3d(col, row, 1.0);
    ray *= depth_m / ray.z();
    return camera_from_world.transpose() * ray + center_world;
  }
};

// The fused points with one source row, and the pixels of other views they consume.
struct RowResult {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Matrix<std::uint8_t, 3, 1>> colors;
  std::vector<std::uint16_t> num_views;
  std::vector<std::pair<int, int>> consumed;  // (view, row * width + col)
  std::int64_t samples = 0;
  std::int64_t skipped_consumed = 0;
  std::int64_t no_normal = 0;
  std::int64_t rejected = 0;
};

void FuseRow(const std::vector<ViewData>& data,
             const std::vector<std::vector<std::uint8_t>>& consumed, int source, int row,
             const FusionOptions& options, double cos_normal_tolerance, RowResult* out) {
  const ViewData& s = data[source];
  const int num_views = static_cast<int>(data.size());
  const bool normal_test = options.normal_tolerance_deg < 180.0;
  std::vector<std::pair<int, int>> agreeing;  // (view, pixel index)
  for (int col = 0; col < s.width; col += options.stride_px) {
    const float d = s.Depth(col, row);
    if (!IsValidDepth(d)) continue;
    ++out->samples;
    if (consumed[source][static_cast<size_t>(row) * s.width + col]) {
      ++out->skipped_consumed;
      continue;
    }
    const Eigen::Vector3f n_source = s.Normal(col, row);
    if (!std::isfinite(n_source.x())) {
      ++out->no_normal;
      continue;
    }
    const Eigen::Vector3d X = s.BackProject(col, row, d);
    agreeing.clear();
    for (int j = 0; j < num_views; ++j) {
      if (j == source) continue;
      const ViewData& v = data[j];
      const Eigen::Vector3d Xc = v.camera_from_world * (X - v.center_world);
      if (!(Xc.z() > 0.0)) continue;
      const Eigen::Vector3d h = v.K * Xc;
      const double u = h.x() / h.z();
      const double w = h.y() / h.z();
      // Nearest pixel; the image covers [-0.5, width - 0.5) × [-0.5, height - 0.5).
      if (!(u >= -0.5 && w >= -0.5 && u < v.width - 0.5 && w < v.height - 0.5)) continue;
      const int qc = std::min(static_cast<int>(std::floor(u + 0.5)), v.width - 1);
      const int qr = std::min(static_cast<int>(std::floor(w + 0.5)), v.height - 1);
      const float dq = v.Depth(qc, qr);
      if (!IsValidDepth(dq)) continue;
      if (std::abs(Xc.z() - dq) > options.depth_tolerance * dq) continue;
      const Eigen::Vector3f nq = v.Normal(qc, qr);
      if (!std::isfinite(nq.x())) continue;
      if (normal_test && nq.dot(n_source) < cos_normal_tolerance) continue;
      agreeing.emplace_back(j, qr * v.width + qc);
    }
    const int count = 1 + static_cast<int>(agreeing.size());
    if (count < options.min_views) {
      ++out->rejected;
      continue;
    }
    Eigen::Vector3d sum_point = X;
    Eigen::Vector3d sum_normal = n_source.cast<double>();
    Eigen::Vector3i sum_color = s.Color(col, row);
    for (const auto& [j, index] : agreeing) {
      const ViewData& v = data[j];
      const int qc = index % v.width;
      const int qr = index / v.width;
      sum_point += v.BackProject(qc, qr, v.Depth(qc, qr));
      sum_normal += v.Normal(qc, qr).cast<double>();
      sum_color += v.Color(qc, qr);
      out->consumed.emplace_back(j, index);
    }
    const double norm = sum_normal.norm();
    // Normals within normal_tolerance_deg of the source's never cancel unless the tolerance is
    // above 90°; fall back to the source's normal then.
    const Eigen::Vector3f normal = norm > 1e-9 ? (sum_normal / norm).cast<float>() : n_source;
    Eigen::Matrix<std::uint8_t, 3, 1> color;
    for (int k = 0; k < 3; ++k) {
      color[k] = static_cast<std::uint8_t>((sum_color[k] + count / 2) / count);
    }
    out->points.push_back((sum_point / count).cast<float>());
    out->normals.push_back(normal);
    out->colors.push_back(color);
    out->num_views.push_back(static_cast<std::uint16_t>(count));
  }
}

}  // namespace

void FusionOptions::Check() const {
  if (min_views < 1 || min_views > 64) {
    throw ConfigError(
        ViolatedConstraint("fusion.min_views", std::to_string(min_views), "1 <= min_views <= 64"));
  }
  if (!(depth_tolerance > 0.0 && depth_tolerance <= 1.0)) {
    throw ConfigError(ViolatedConstraint("fusion.depth_tolerance", FormatNumber(depth_tolerance),
                                         "0 < depth_tolerance <= 1"));
  }
  if (!(normal_tolerance_deg > 0.0 && normal_tolerance_deg <= 180.0)) {
    throw ConfigError(ViolatedConstraint("fusion.normal_tolerance_deg",
                                         FormatNumber(normal_tolerance_deg),
                                         "0 < normal_tolerance_deg <= 180"));
  }
  if (normal_radius_px < 1 || normal_radius_px > 16) {
    throw ConfigError(ViolatedConstraint("fusion.normal_radius_px",
                                         std::to_string(normal_radius_px),
                                         "1 <= normal_radius_px <= 16"));
  }
  if (stride_px < 1 || stride_px > 64) {
    throw ConfigError(
        ViolatedConstraint("fusion.stride_px", std::to_string(stride_px), "1 <= stride_px <= 64"));
  }
}

nlohmann::json FusionSummary::ToJson() const {
  nlohmann::json j;
  j["total_points"] = total_points;
  j["seconds"] = seconds;
  nlohmann::json per_view = nlohmann::json::array();
  for (const FusionViewSummary& v : views) {
    nlohmann::json e;
    e["name"] = v.name;
    e["valid_pixels"] = v.valid_pixels;
    e["samples"] = v.samples;
    e["consumed"] = v.consumed;
    e["no_normal"] = v.no_normal;
    e["rejected"] = v.rejected;
    e["kept"] = v.kept;
    e["mean_views_kept"] = v.mean_views_kept;
    per_view.push_back(e);
  }
  j["views"] = per_view;
  return j;
}

std::string FusionSummary::FullReport() const {
  std::ostringstream s;
  s << "Fusion: " << total_points << " points from " << views.size() << " views in " << seconds
    << " s";
  for (const FusionViewSummary& v : views) {
    s << "\n  view " << v.name << ": " << v.samples << " samples, " << v.consumed
      << " already fused, " << v.no_normal << " without normal, " << v.rejected << " rejected, "
      << v.kept << " kept (mean " << v.mean_views_kept << " views)";
  }
  return s.str();
}

cv::Mat DepthMapNormals(const cv::Mat& depth, const Camera& camera, int radius_px) {
  CheckDepthMap(depth, camera, "DepthMapNormals");
  if (radius_px < 1 || radius_px > 16) {
    throw Error("DepthMapNormals: radius_px = " + std::to_string(radius_px) +
                ", must be in [1, 16]");
  }
  const int width = depth.cols;
  const int height = depth.rows;
  const Eigen::Matrix3d K_inverse = camera.K.inverse();
  const Eigen::Matrix3d& R = camera.world_from_camera_rotation;
  // Back-projections of every valid pixel (world frame).
  std::vector<Eigen::Vector3d> points(static_cast<size_t>(width) * height);
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& r) {
    for (int row = r.begin(); row != r.end(); ++row) {
      const float* d = depth.ptr<float>(row);
      for (int col = 0; col < width; ++col) {
        if (!IsValidDepth(d[col])) continue;
        Eigen::Vector3d ray = K_inverse * Eigen::Vector3d(col, row, 1.0);
        ray *= d[col] / ray.z();
        points[static_cast<size_t>(row) * width + col] = R * ray + camera.center_world;
      }
    }
  });
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat normals(height, width, CV_32FC3, cv::Scalar(nan, nan, nan));
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& r) {
    for (int row = r.begin(); row != r.end(); ++row) {
      const float* d = depth.ptr<float>(row);
      float* out = normals.ptr<float>(row);
      for (int col = 0; col < width; ++col) {
        const float dc = d[col];
        if (!IsValidDepth(dc)) continue;
        const Eigen::Vector3d& X = points[static_cast<size_t>(row) * width + col];
        // Of the two pixels at `radius_px` on either side (along the step direction), the valid
        // one closer in depth (the +side on ties); the immediate neighbours when neither is
        // valid. The tangent always points towards +col / +row. False when none is valid.
        auto tangent = [&](int step_col, int step_row, Eigen::Vector3d* t) {
          for (const int r : {radius_px, 1}) {
            float best = std::numeric_limits<float>::infinity();
            int chosen_col = -1, chosen_row = -1, sign = 0;
            for (const int k : {1, -1}) {
              const int c = col + k * r * step_col;
              const int rr = row + k * r * step_row;
              if (c < 0 || c >= width || rr < 0 || rr >= height) continue;
              const float dn = depth.ptr<float>(rr)[c];
              if (!IsValidDepth(dn)) continue;
              const float diff = std::abs(dn - dc);
              if (diff < best) {
                best = diff;
                chosen_col = c;
                chosen_row = rr;
                sign = k;
              }
            }
            if (sign != 0) {
              const Eigen::Vector3d& Y =
                  points[static_cast<size_t>(chosen_row) * width + chosen_col];
              *t = sign > 0 ? Eigen::Vector3d(Y - X) : Eigen::Vector3d(X - Y);
              return true;
            }
            if (r == 1) break;
          }
          return false;
        };
        Eigen::Vector3d t_col, t_row;
        if (!tangent(1, 0, &t_col)) continue;
        if (!tangent(0, 1, &t_row)) continue;
        Eigen::Vector3d n = t_col.cross(t_row);
        const double norm = n.norm();
        if (!(norm > 0.0) || !std::isfinite(norm)) continue;
        n /= norm;
        if (n.dot(camera.center_world - X) < 0.0) n = -n;
        out[3 * col + 0] = static_cast<float>(n.x());
        out[3 * col + 1] = static_cast<float>(n.y());
        out[3 * col + 2] = static_cast<float>(n.z());
      }
    }
  });
  return normals;
}

OrientedPointCloud FuseDepthMaps(const std::vector<FusionView>& views, const FusionOptions& options,
                                 FusionSummary* summary, const ProgressCallback& progress) {
  const Timer timer;
  options.Check();
  if (views.empty()) throw Error("FuseDepthMaps: no views");
  if (views.size() > 65535) {
    throw Error("FuseDepthMaps: " + std::to_string(views.size()) +
                " views, at most 65535 are supported");
  }
  std::vector<ViewData> data(views.size());
  for (size_t i = 0; i < views.size(); ++i) {
    const FusionView& view = views[i];
    const std::string context = "FuseDepthMaps: view " + std::to_string(i) + " '" + view.name + "'";
    view.camera.Validate(context);
    CheckDepthMap(view.depth, view.camera, context);
    if (view.image_bgr.empty() ||
        (view.image_bgr.type() != CV_8UC3 && view.image_bgr.type() != CV_8UC1)) {
      throw Error(context + ": the image must be CV_8UC3 (BGR) or CV_8UC1, got " +
                  (view.image_bgr.empty() ? std::string("an empty image")
                                          : "type " + std::to_string(view.image_bgr.type())));
    }
    if (view.image_bgr.size() != view.depth.size()) {
      throw Error(context + ": the image is " + MatSize(view.image_bgr) + " but the depth map is " +
                  MatSize(view.depth));
    }
    ViewData& v = data[i];
    v.width = view.camera.width;
    v.height = view.camera.height;
    v.camera = &view.camera;
    v.K = view.camera.K;
    v.K_inverse = view.camera.K.inverse();
    v.camera_from_world = view.camera.world_from_camera_rotation.transpose();
    v.center_world = view.camera.center_world;
    v.depth = view.depth;
    v.image = view.image_bgr;
  }
  for (size_t i = 0; i < views.size(); ++i) {
    data[i].normals = DepthMapNormals(views[i].depth, views[i].camera, options.normal_radius_px);
  }

  std::vector<std::vector<std::uint8_t>> consumed(views.size());
  for (size_t i = 0; i < views.size(); ++i) {
    consumed[i].assign(static_cast<size_t>(data[i].width) * data[i].height, 0);
  }
  const double cos_normal_tolerance = std::cos(options.normal_tolerance_deg * kPi / 180.0);

  OrientedPointCloud cloud;
  FusionSummary s;
  for (size_t source = 0; source < views.size(); ++source) {
    const ViewData& v = data[source];
    const int grid_rows = (v.height + options.stride_px - 1) / options.stride_px;
    std::vector<RowResult> rows(grid_rows);
    // The check reads the marks of earlier views only (this view's pass sets marks on other
    // views after the loop), so the per-row results do not depend on the thread count.
    tbb::parallel_for(tbb::blocked_range<int>(0, grid_rows), [&](const tbb::blocked_range<int>& r) {
      for (int g = r.begin(); g != r.end(); ++g) {
        FuseRow(data, consumed, static_cast<int>(source), g * options.stride_px, options,
                cos_normal_tolerance, &rows[g]);
      }
    });
    FusionViewSummary vs;
    vs.name = views[source].name;
    for (int row = 0; row < v.height; ++row) {
      const float* d = v.depth.ptr<float>(row);
      for (int col = 0; col < v.width; ++col) vs.valid_pixels += IsValidDepth(d[col]) ? 1 : 0;
    }
    std::int64_t sum_views = 0;
    for (RowResult& row : rows) {
      vs.samples += row.samples;
      vs.consumed += row.skipped_consumed;
      vs.no_normal += row.no_normal;
      vs.rejected += row.rejected;
      vs.kept += static_cast<std::int64_t>(row.points.size());
      for (std::uint16_t n : row.num_views) sum_views += n;
      cloud.points.insert(cloud.points.end(), row.points.begin(), row.points.end());
      cloud.normals.insert(cloud.normals.end(), row.normals.begin(), row.normals.end());
      cloud.colors.insert(cloud.colors.end(), row.colors.begin(), row.colors.end());
      cloud.num_views.insert(cloud.num_views.end(), row.num_views.begin(), row.num_views.end());
      for (const auto& [j, index] : row.consumed) consumed[j][index] = 1;
      row = RowResult();
    }
    vs.mean_views_kept = vs.kept > 0 ? static_cast<double>(sum_views) / vs.kept : 0.0;
    s.views.push_back(vs);
    if (progress && !progress(static_cast<double>(source + 1) / views.size())) {
      throw Error("FuseDepthMaps: cancelled after view " + std::to_string(source) + " '" +
                  views[source].name + "'");
    }
  }
  cloud.sigma.assign(cloud.points.size(), 0.0f);
  s.total_points = static_cast<std::int64_t>(cloud.points.size());
  s.seconds = timer.ElapsedSeconds();
  if (summary) *summary = s;
  return cloud;
}

void AppendGcpPoints(const PointCloud& gcps_world, OrientedPointCloud* cloud) {
  if (!cloud) throw Error("AppendGcpPoints: cloud is null");
  const size_t n = cloud->points.size();
  if (cloud->normals.size() != n || cloud->colors.size() != n || cloud->num_views.size() != n ||
      cloud->sigma.size() != n) {
    throw Error("AppendGcpPoints: the cloud's channels differ in length (" + std::to_string(n) +
                " points, " + std::to_string(cloud->normals.size()) + " normals, " +
                std::to_string(cloud->colors.size()) + " colours, " +
                std::to_string(cloud->num_views.size()) + " view counts, " +
                std::to_string(cloud->sigma.size()) + " sigmas)");
  }
  if (gcps_world.empty()) return;
  if (!gcps_world.sigma.empty() && gcps_world.sigma.size() != gcps_world.size()) {
    throw Error("AppendGcpPoints: " + std::to_string(gcps_world.size()) + " GCPs but " +
                std::to_string(gcps_world.sigma.size()) + " sigma values");
  }
  std::vector<int> fused;
  for (size_t i = 0; i < n; ++i) {
    if (cloud->num_views[i] > 0) fused.push_back(static_cast<int>(i));
  }
  if (fused.empty()) {
    throw Error("AppendGcpPoints: the cloud has no fused points to take the GCPs' normals from");
  }
  cv::Mat features(static_cast<int>(fused.size()), 3, CV_32F);
  for (size_t i = 0; i < fused.size(); ++i) {
    for (int k = 0; k < 3; ++k)
      features.at<float>(static_cast<int>(i), k) = cloud->points[fused[i]][k];
  }
  cv::flann::GenericIndex<cvflann::L2_Simple<float>> index(features,
                                                           cvflann::KDTreeSingleIndexParams(10));
  constexpr int kNeighbors = 8;
  const int knn = std::min<int>(kNeighbors, features.rows);
  const int total = static_cast<int>(gcps_world.size());
  cv::Mat query(total, 3, CV_32F);
  for (int i = 0; i < total; ++i) {
    for (int k = 0; k < 3; ++k) query.at<float>(i, k) = gcps_world.points[i][k];
  }
  cv::Mat indices(total, knn, CV_32S), squared(total, knn, CV_32F);
  // eps = 0: the single KD-tree search is exact; results sorted by distance.
  index.knnSearch(query, indices, squared, knn, cvflann::SearchParams(-1, 0.0f, true));
  for (int i = 0; i < total; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int nearest = -1;
    for (int k = 0; k < knn; ++k) {
      const int f = indices.at<int>(i, k);
      if (f < 0 || f >= static_cast<int>(fused.size())) continue;
      if (nearest < 0) nearest = fused[f];
      sum += cloud->normals[fused[f]].cast<double>();
    }
    if (nearest < 0) throw Error("AppendGcpPoints: nearest-neighbour search failed");
    const double norm = sum.norm();
    const Eigen::Vector3f normal =
        norm > 1e-9 ? (sum / norm).cast<float>() : cloud->normals[nearest];
    cloud->points.push_back(gcps_world.points[i]);
    cloud->normals.push_back(normal);
    cloud->colors.push_back(cloud->colors[nearest]);
    cloud->num_views.push_back(0);
    cloud->sigma.push_back(gcps_world.sigma.empty() ? 0.0f : gcps_world.sigma[i]);
  }
}

}  // namespace gcpstereo::fusion
