// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Stereo GCPs for calibrated views (see calibrated_stereo_gcps.h): rectify each
// reference–neighbour pair, match it with ExtractStereoGcps (Wang & Yang, CVPR 2011, §4.1),
// triangulate, project into the reference, and keep the depths another pair confirms.
#include "gcpstereo/gcp/calibrated_stereo_gcps.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/cost/rectify.h"

namespace gcpstereo::gcp {
namespace {

// One pair's GCPs on the reference grid: depth (+inf = none) and sigma, CV_64F.
struct PairMaps {
  cv::Mat depth, sigma;
  cv::Mat wta_depth, wta_sigma;  // the pair's dense NCC WTA, same grid (the confirmation source)
};

PairMaps MatchPair(const View& reference, const View& neighbor, double min_depth, double max_depth,
                   const StereoGcpOptions& options, CalibratedPairSummary* summary) {
  const auto start = std::chrono::steady_clock::now();
  const cv::Size size = reference.image.size();
  const Camera& ref_camera = reference.camera;
  const Camera& nb_camera = neighbor.camera;
  summary->neighbor = neighbor.name;
  summary->baseline = (ref_camera.center_world - nb_camera.center_world).norm();
  PairMaps maps;
  maps.depth = cv::Mat(size, CV_64F, cv::Scalar(kInvalidDepth));
  maps.sigma = cv::Mat(size, CV_64F, cv::Scalar(0.0));
  maps.wta_depth = maps.depth.clone();
  maps.wta_sigma = maps.sigma.clone();

  const cost::RectifiedCalibratedPair pair = cost::RectifyCalibratedPair(reference, neighbor);
  if (pair.vertical) {
    spdlog::warn("stereo GCPs: pair ({}, {}) rectifies vertically; skipped", reference.name,
                 neighbor.name);
    return maps;
  }
  const double f = pair.focal_px;
  const double cx = pair.cx, cy = pair.cy;
  const double baseline = pair.baseline;
  summary->focal_px = f;
  summary->mirrored = pair.mirrored;

  const double fb = f * baseline;
  const int min_d = std::max(0, static_cast<int>(std::floor(0.9 * fb / max_depth)) - 2);
  const int max_d = std::min(size.width - 1, static_cast<int>(std::ceil(1.1 * fb / min_depth)) + 2);
  summary->min_disparity_px = min_d;
  summary->max_disparity_px = max_d;
  if (max_d <= min_d) return maps;

  const cv::Mat& left = pair.left;
  const cv::Mat& right = pair.right;
  const cv::Mat& left_valid = pair.left_valid;
  const cv::Mat& right_valid = pair.right_valid;
  const StereoPairEvidence evidence = ComputeStereoEvidence(left, right, min_d, max_d, options);
  const StereoGcpResult stereo = SelectStereoGcps(evidence, options);
  summary->num_matches = stereo.num_gcps;

  const Eigen::Matrix3d& ref_from_rect = pair.ref_from_rect;
  // Rectified (mirrored) left pixel (x, y) at disparity d → reference pixel and z-buffered depth.
  auto splat = [&](int x, int y, double d, cv::Mat* depth_map, cv::Mat* sigma_map) {
    const int xr = x - static_cast<int>(std::lround(d));
    if (!(d > 0.0) || !left_valid.at<uchar>(y, x) || xr < 0 || !right_valid.at<uchar>(y, xr)) {
      return false;
    }
    const double x_rect = summary->mirrored ? size.width - 1 - x : x;
    const double z_rect = fb / d;
    const Eigen::Vector3d point_rect((x_rect - cx) * z_rect / f, (y - cy) * z_rect / f, z_rect);
    const Eigen::Vector3d point_ref = ref_from_rect * point_rect;
    if (!(point_ref.z() > 0.0)) return false;
    const Eigen::Vector3d uvw = ref_camera.K * point_ref;
    const int col = static_cast<int>(std::lround(uvw.x() / uvw.z()));
    const int row = static_cast<int>(std::lround(uvw.y() / uvw.z()));
    if (col < 0 || row < 0 || col >= size.width || row >= size.height) return false;
    if (point_ref.z() < depth_map->at<double>(row, col)) {
      depth_map->at<double>(row, col) = point_ref.z();
      // σ_z = z² σ_d / (f B), with the rectified pair's z.
      sigma_map->at<double>(row, col) = z_rect * z_rect * options.sigma_px / fb;
    }
    return true;
  };
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const float d = stereo.disparity.at<float>(y, x);
      if (std::isfinite(d) && !splat(x, y, d, &maps.depth, &maps.sigma)) ++summary->num_invalid;
      const int d_wta = evidence.left.wta_ncc.at<int>(y, x);
      if (d_wta > 0) splat(x, y, d_wta, &maps.wta_depth, &maps.wta_sigma);
    }
  }
  summary->num_projected = cv::countNonZero(maps.depth < kInvalidDepth);
  summary->seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return maps;
}

// ExtractCalibratedStereoGcps at the views' own resolution.
CalibratedStereoGcpResult ExtractAtViewResolution(const View& reference,
                                                  const std::vector<View>& neighbors,
                                                  double min_depth, double max_depth,
                                                  const StereoGcpOptions& options,
                                                  const ProgressCallback& progress) {
  const auto start = std::chrono::steady_clock::now();
  if (neighbors.empty()) throw Error("ExtractCalibratedStereoGcps: no neighbour view");
  if (!(min_depth > 0.0) || !(max_depth > min_depth) || !std::isfinite(max_depth)) {
    throw Error("ExtractCalibratedStereoGcps: depth range [" + FormatNumber(min_depth) + ", " +
                FormatNumber(max_depth) + "] must satisfy 0 < min < max < inf");
  }
  const int num_pairs = std::min<int>(options.max_neighbors, static_cast<int>(neighbors.size()));
  // The nearest neighbours (camera centres; ties: list order).
  const std::vector<std::size_t> order = cost::NeighborsByDistance(reference, neighbors);
  auto check_view = [](const View& view) {
    view.camera.Validate("view '" + view.name + "'");
    if (view.image.type() != CV_8UC3 || view.image.cols != view.camera.width ||
        view.image.rows != view.camera.height) {
      throw Error("ExtractCalibratedStereoGcps: view '" + view.name +
                  "' must be a CV_8UC3 image of its camera's size");
    }
  };
  check_view(reference);
  for (int i = 0; i < num_pairs; ++i) {
    const View& neighbor = neighbors[order[i]];
    check_view(neighbor);
    if (neighbor.image.size() != reference.image.size()) {
      throw Error("ExtractCalibratedStereoGcps: view '" + neighbor.name +
                  "' differs in size from the reference");
    }
    if ((neighbor.camera.center_world - reference.camera.center_world).norm() <= 0.0) {
      throw Error("ExtractCalibratedStereoGcps: view '" + neighbor.name +
                  "' has the reference's camera centre (no baseline)");
    }
  }

  CalibratedStereoGcpResult result;
  std::vector<PairMaps> maps(num_pairs);
  result.pairs.resize(num_pairs);
  for (int i = 0; i < num_pairs; ++i) {
    maps[i] =
        MatchPair(reference, neighbors[order[i]], min_depth, max_depth, options, &result.pairs[i]);
    if (progress && !progress((i + 1.0) / num_pairs)) {
      throw Error("ExtractCalibratedStereoGcps: cancelled");
    }
  }

  // Consistency between pairs, then the smallest sigma per pixel.
  const int width = reference.image.cols, height = reference.image.rows;
  const int radius = options.confirm_radius_px;
  GcpSourceSummary& summary = result.summary;
  summary.source = GcpSourceName(GcpSource::kStereo);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      int best = -1;
      for (int i = 0; i < num_pairs; ++i) {
        const double z = maps[i].depth.at<double>(row, col);
        if (!std::isfinite(z)) continue;
        ++summary.num_input;
        const double sigma = maps[i].sigma.at<double>(row, col);
        int confirmations = 0;
        for (int j = 0; j < num_pairs && confirmations < options.min_confirmations; ++j) {
          if (j == i) continue;
          bool agrees = false;
          for (int r = std::max(0, row - radius);
               r <= std::min(height - 1, row + radius) && !agrees; ++r) {
            for (int c = std::max(0, col - radius); c <= std::min(width - 1, col + radius); ++c) {
              const double zj = maps[j].wta_depth.at<double>(r, c);
              if (!std::isfinite(zj)) continue;
              const double sj = maps[j].wta_sigma.at<double>(r, c);
              if (std::abs(z - zj) <= options.confirm_sigma * std::sqrt(sigma * sigma + sj * sj)) {
                agrees = true;
                break;
              }
            }
          }
          if (agrees) ++confirmations;
        }
        if (confirmations < options.min_confirmations) {
          ++summary.num_inconsistent;
          continue;
        }
        ++result.pairs[i].num_confirmed;
        if (best < 0 || sigma < maps[best].sigma.at<double>(row, col)) best = i;
      }
      if (best < 0) continue;
      Gcp gcp;
      gcp.col = col;
      gcp.row = row;
      gcp.depth = maps[best].depth.at<double>(row, col);
      gcp.sigma = maps[best].sigma.at<double>(row, col);
      gcp.source = GcpSource::kStereo;
      result.gcps.points.push_back(gcp);
    }
  }
  summary.num_gcps = static_cast<int>(result.gcps.size());
  summary.density_percent = DensityPercent(result.gcps, width, height);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

View Rescaled(const View& view, double scale) {
  View out;
  out.name = view.name;
  out.camera = view.camera.Rescaled(scale);
  cv::resize(view.image, out.image, cv::Size(out.camera.width, out.camera.height), 0, 0,
             cv::INTER_AREA);
  return out;
}

}  // namespace

CalibratedStereoGcpResult ExtractCalibratedStereoGcps(const View& reference,
                                                      const std::vector<View>& neighbors,
                                                      double min_depth, double max_depth,
                                                      const StereoGcpOptions& options,
                                                      const ProgressCallback& progress) {
  options.Check();
  const double scale = options.image_scale;
  if (scale == 1.0) {
    return ExtractAtViewResolution(reference, neighbors, min_depth, max_depth, options, progress);
  }
  std::vector<View> small_neighbors;
  for (const View& n : neighbors) small_neighbors.push_back(Rescaled(n, scale));
  CalibratedStereoGcpResult result = ExtractAtViewResolution(
      Rescaled(reference, scale), small_neighbors, min_depth, max_depth, options, progress);
  // Back to the reference grid (pixel-centre convention x = (x_s + 0.5) / scale − 0.5, nearest
  // pixel); depth and sigma are unchanged.
  const int width = reference.image.cols, height = reference.image.rows;
  GcpSet mapped;
  for (Gcp g : result.gcps.points) {
    g.col = static_cast<int>(std::lround((g.col + 0.5) / scale - 0.5));
    g.row = static_cast<int>(std::lround((g.row + 0.5) / scale - 0.5));
    if (g.col < 0 || g.row < 0 || g.col >= width || g.row >= height) continue;
    mapped.points.push_back(g);
  }
  result.gcps = std::move(mapped);
  result.summary.num_gcps = static_cast<int>(result.gcps.size());
  result.summary.density_percent = DensityPercent(result.gcps, width, height);
  return result;
}

GcpSet RefineGcpsOnLabels(const GcpSet& gcps, const View& reference,
                          const std::vector<View>& neighbors, const LabelSpace& labels,
                          double radius_px, double sigma_px, int window_px,
                          const cost::PlaneSweepOptions& sweep, GcpRefinementSummary* summary) {
  const Timer timer;
  if (!(radius_px > 0.0) || !(sigma_px > 0.0)) {
    throw Error("RefineGcpsOnLabels: radius_px and sigma_px must be positive, got " +
                FormatNumber(radius_px) + " and " + FormatNumber(sigma_px));
  }
  if (window_px < 1 || window_px % 2 == 0) {
    throw Error("RefineGcpsOnLabels: window_px must be odd and positive, got " +
                std::to_string(window_px));
  }
  const int half = window_px / 2;
  const cv::Rect image_rect(0, 0, reference.image.cols, reference.image.rows);
  const int num_labels = labels.count();
  GcpRefinementSummary s;
  // The stereo GCPs' windows, swept together (the neighbours' images are prepared once).
  std::vector<size_t> stereo;
  std::vector<cv::Rect> windows;
  for (size_t i = 0; i < gcps.size(); ++i) {
    const Gcp& g = gcps.points[i];
    if (g.source != GcpSource::kStereo) continue;
    stereo.push_back(i);
    windows.push_back(cv::Rect(g.col - half, g.row - half, window_px, window_px) & image_rect);
  }
  cost::PlaneSweepOptions pixelwise = sweep;
  pixelwise.window.window_px = 1;  // the window is this function's own mean
  const std::vector<CostVolume> volumes =
      windows.empty()
          ? std::vector<CostVolume>()
          : cost::ComputePlaneSweepCostForRegions(reference, neighbors, labels, windows, pixelwise);

  std::vector<std::uint8_t> keep(gcps.size(), 1);
  GcpSet refined_set = gcps;
  double shift_sum = 0.0;
  for (size_t k = 0; k < stereo.size(); ++k) {
    Gcp& g = refined_set.points[stereo[k]];
    const CostVolume& volume = volumes[k];
    ++s.input;
    keep[stereo[k]] = 0;
    const double label = labels.LabelOfDepth(g.depth);
    if (!std::isfinite(label) || !(g.sigma > 0.0)) {
      ++s.dropped_no_data;
      continue;
    }
    // The depths of the match's disparity ± radius_px.
    const double focal_baseline = g.depth * g.depth * sigma_px / g.sigma;
    const double disparity = focal_baseline / g.depth;
    const double near = focal_baseline / (disparity + radius_px);
    const double far = disparity > radius_px ? focal_baseline / (disparity - radius_px)
                                             : std::numeric_limits<double>::infinity();
    // Continuous labels of both ends (+∞ depth is label +∞ in depth, a finite one otherwise),
    // clamped to the range before rounding outward.
    const double top = num_labels - 1.0;
    double near_label = std::clamp(labels.LabelOfDepth(near), 0.0, top);
    double far_label = std::clamp(labels.LabelOfDepth(far), 0.0, top);
    if (near_label > far_label) std::swap(near_label, far_label);  // inverse-depth labels
    const int lo = static_cast<int>(std::floor(near_label));
    const int hi = static_cast<int>(std::ceil(far_label));
    // C(l) for the searched labels and one beyond each end (for the parabola).
    const int first = std::max(0, lo - 1), last = std::min(num_labels - 1, hi + 1);
    std::vector<double> sum(last - first + 1, 0.0);
    bool complete = true;
    for (int l = first; l <= last && complete; ++l) {
      for (int r = 0; r < volume.height(); ++r) {
        for (int c = 0; c < volume.width(); ++c) {
          if (!volume.HasData(r, c, l)) complete = false;
          sum[l - first] += volume.Cost(r, c, l);
        }
      }
    }
    if (!complete) {
      ++s.dropped_no_data;
      continue;
    }
    int best = lo;
    for (int l = lo; l <= hi; ++l) {
      if (sum[l - first] < sum[best - first]) best = l;
    }
    if ((best == lo && lo > 0) || (best == hi && hi < num_labels - 1)) {
      ++s.dropped_at_edge;
      continue;
    }
    double offset = 0.0;
    if (best > first && best < last) {
      const double a = sum[best - 1 - first], b = sum[best - first], c = sum[best + 1 - first];
      const double curvature = a - 2.0 * b + c;
      if (curvature > 0.0) offset = std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5);
    }
    const double new_label = best + offset;
    const double depth = labels.DepthOfLabel(new_label);
    if (!(std::isfinite(depth) && depth > 0.0)) {
      ++s.dropped_no_data;
      continue;
    }
    g.depth = depth;
    g.sigma =
        0.5 * std::abs(labels.DepthOfLabel(new_label + 0.5) - labels.DepthOfLabel(new_label - 0.5));
    shift_sum += std::abs(new_label - label);
    ++s.refined;
    keep[stereo[k]] = 1;
  }
  GcpSet out;
  for (size_t i = 0; i < refined_set.size(); ++i) {
    if (keep[i]) out.points.push_back(refined_set.points[i]);
  }
  s.mean_shift_labels = s.refined > 0 ? shift_sum / s.refined : 0.0;
  s.seconds = timer.ElapsedSeconds();
  if (summary != nullptr) *summary = s;
  return out;
}

}  // namespace gcpstereo::gcp
