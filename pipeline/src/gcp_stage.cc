// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Stage 2: ground control points from the configured sources (LiDAR, a depth image, image matches).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/gcp/calibrated_stereo_gcps.h"
#include "gcpstereo/gcp/gcp_sources.h"
#include "gcpstereo/gcp/lidar_holdout.h"
#include "gcpstereo/gcp/sfm_gcps.h"
#include "gcpstereo/gcp/stereo_gcps.h"
#include "gcpstereo/io/colmap_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/pipeline/lidar_scan.h"
#include "model_alignment.h"
#include "stages.h"

namespace gcpstereo::pipeline::internal {
namespace {

using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;

json SummaryJson(const gcp::GcpSourceSummary& s) {
  return {{"source", s.source},
          {"input", s.num_input},
          {"invalid", s.num_invalid},
          {"behind_camera", s.num_behind_camera},
          {"outside_image", s.num_outside_image},
          {"same_pixel", s.num_same_pixel},
          {"inconsistent", s.num_inconsistent},
          {"short_track", s.num_short_track},
          {"large_error", s.num_large_error},
          {"small_angle", s.num_small_angle},
          {"gcps", s.num_gcps},
          {"density_percent", s.density_percent}};
}

json LidarMotionJson(const LidarScanSummary& s) {
  json out = {{"mode", s.mode}, {"compensated", s.compensated}, {"seconds", s.seconds}};
  if (s.compensated) {
    out["velocity_mps"] = {s.motion.velocity.x(), s.motion.velocity.y(), s.motion.velocity.z()};
    out["speed_mps"] = s.motion.velocity.norm();
    out["yaw_rate_deg_s"] = s.motion.yaw_rate_rad_s * 180.0 / kPi;
  }
  if (!s.message.empty()) out["message"] = s.message;
  for (const gcp::ScanRegistrationSummary& r : s.registrations) {
    const Eigen::Vector3d t = r.reference_from_other.topRightCorner<3, 1>();
    out["registrations"].push_back({{"scan", r.name},
                                    {"seconds_after_reference", r.seconds_after_reference},
                                    {"translation", {t.x(), t.y(), t.z()}},
                                    {"inlier_fraction", r.inlier_fraction},
                                    {"rmse", r.rmse},
                                    {"used", r.used}});
  }
  return out;
}

// Reads gcp.depth_map.path as a depth map of the reference view (CV_32F, +inf = none).
cv::Mat ReadDepthMapSource(const DepthMapGcpOptions& options, const Dataset& dataset,
                           double dataset_scale) {
  const std::string ext = std::filesystem::path(options.path).extension().string();
  cv::Mat values;
  if (ext == ".pfm" || ext == ".PFM") {
    values = io::ReadPfm(options.path);
    if (values.channels() != 1) throw IoError(options.path, "expected a 1-channel PFM");
  } else {
    const cv::Mat raw = io::ReadImage(options.path, cv::IMREAD_UNCHANGED);
    if (raw.channels() != 1 || (raw.depth() != CV_8U && raw.depth() != CV_16U)) {
      throw IoError(options.path, "expected an 8- or 16-bit single-channel image");
    }
    raw.convertTo(values, CV_32F, 1.0 / options.scale);
    values.setTo(std::numeric_limits<float>::quiet_NaN(), raw == 0);
  }
  // The image is of the reference view at its original size: resize to the processed size.
  const cv::Size size = dataset.reference.image.size();
  if (values.size() != size) {
    const double sx = static_cast<double>(size.width) / values.cols;
    const double sy = static_cast<double>(size.height) / values.rows;
    if (std::abs(sx - dataset_scale) > 0.01 || std::abs(sy - dataset_scale) > 0.01) {
      throw IoError(options.path, "size " + std::to_string(values.cols) + "x" +
                                      std::to_string(values.rows) +
                                      " does not match the reference view");
    }
    cv::resize(values, values, size, 0, 0, cv::INTER_NEAREST);
    if (options.kind == "disparity") values *= dataset_scale;  // disparities scale with the image
  }
  if (options.kind == "depth") {
    values.setTo(kInvalidDepth, ~(values > 0));  // also catches NaN
    return values;
  }
  if (!dataset.rectified) {
    throw ConfigError(
        "gcp.depth_map.kind = disparity needs rectified data (middlebury, kitti_raw)");
  }
  return gcp::DisparityToDepth(values, dataset.disparity_numerator);
}

// The COLMAP model's 3D points (in the aligned frame, dataset.align) that the reference image
// observes (its keypoints' point3D ids),
// each once, with its error, track length and the centres of the track's other images; with
// `all`, every other point of the model too (observed = false).
std::vector<gcp::SfmPoint> SfmPointsOfReference(const PipelineConfig& config,
                                                const std::string& reference_name, bool all) {
  const io::ColmapModel model = ReadAlignedColmapModel(config);
  const io::ColmapImage* image = model.FindImage(reference_name);
  if (!image) {
    throw ConfigError("gcp.sources: sfm: the COLMAP model " + model.sparse_dir +
                      " has no image named " + reference_name);
  }
  std::vector<gcp::SfmPoint> points;
  std::vector<std::uint64_t> seen;
  for (const io::ColmapPoint2D& keypoint : image->points2d) {
    if (!keypoint.HasPoint3D()) continue;
    seen.push_back(keypoint.point3d_id);
  }
  std::sort(seen.begin(), seen.end());
  seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
  std::vector<std::uint64_t> ids = seen;
  if (all) {
    for (const auto& [id, p] : model.points3d) {
      if (!std::binary_search(seen.begin(), seen.end(), id)) ids.push_back(id);
    }
  }
  for (const std::uint64_t id : ids) {
    const io::ColmapPoint3D& p = model.points3d.at(id);
    gcp::SfmPoint point;
    point.observed = std::binary_search(seen.begin(), seen.end(), id);
    point.point_world = p.xyz_world;
    point.error_px = p.error_px;
    std::vector<std::uint32_t> images;
    for (const io::ColmapTrackElement& e : p.track) images.push_back(e.image_id);
    std::sort(images.begin(), images.end());
    images.erase(std::unique(images.begin(), images.end()), images.end());
    point.track_length = static_cast<int>(images.size());
    for (const std::uint32_t other : images) {
      if (other != image->image_id) {
        point.other_centers_world.push_back(model.images.at(other).CenterWorld());
      }
    }
    points.push_back(std::move(point));
  }
  return points;
}

}  // namespace

SfmHoldout SplitSfmPointsForHoldout(const PipelineConfig& config, const std::string& reference_name,
                                    const Camera& reference) {
  std::vector<gcp::SfmPoint> points =
      SfmPointsOfReference(config, reference_name, config.gcp.sfm.projected);
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> depths;
  std::vector<int> kept;  // indices into `points` of the points in front and inside the image
  for (size_t i = 0; i < points.size(); ++i) {
    Eigen::Vector2d pixel;
    double depth = 0.0;
    if (!reference.Project(points[i].point_world, &pixel, &depth) || !reference.InImage(pixel)) {
      continue;
    }
    kept.push_back(static_cast<int>(i));
    pixels.push_back(pixel);
    depths.push_back(depth);
  }
  const eval::LidarSplit split = eval::CheckerboardSplit(pixels, config.eval.holdout_block_px);
  SfmHoldout holdout;
  for (const int k : split.gcp_indices) holdout.gcp_part.push_back(std::move(points[kept[k]]));
  for (const int k : split.score_indices) {
    // Only what the reference itself observed is scored: a projected point may be hidden.
    if (points[kept[k]].observed) holdout.scored.push_back({pixels[k], depths[k]});
  }
  return holdout;
}

RectifiedPair FindRectifiedPair(const Dataset& dataset, const std::string& purpose) {
  if (!dataset.rectified || dataset.neighbors.empty()) {
    throw ConfigError(purpose +
                      " needs a rectified pair (middlebury or kitti_raw with a neighbour)");
  }
  RectifiedPair pair;
  pair.neighbor = &dataset.neighbors.front();
  const double baseline =
      pair.neighbor->camera.center_world.x() - dataset.reference.camera.center_world.x();
  pair.numerator = dataset.reference.camera.K(0, 0) * baseline;
  if (!(pair.numerator > 0.0)) {
    throw ConfigError(purpose +
                      " needs the first of dataset.neighbors to be right of the "
                      "reference view ('" +
                      pair.neighbor->name + "' is not)");
  }
  return pair;
}

GcpStageResult RunGcpStage(const PipelineConfig& config, const Dataset& dataset,
                           const ProvisionalLabels& provisional_labels_of) {
  GcpStageResult result;
  const Camera& reference = dataset.reference.camera;
  const int width = dataset.reference.image.cols, height = dataset.reference.image.rows;
  const std::vector<std::string>& names = config.gcp.sources;
  std::vector<GcpSet> sets(names.size());
  std::vector<json> source_reports(names.size());
  // Stereo last: its search range may come from the other sources' GCPs.
  std::vector<size_t> order;
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] != "stereo") order.push_back(i);
  }
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "stereo") order.push_back(i);
  }
  LabelSpace provisional_labels;
  json lidar_motion;  // gcp.lidar.motion: what was compensated, for report.json
  std::vector<gcp::SfmPoint> sfm_gcp_part;  // eval.sfm_holdout: the GCP squares' SfM points
  if (config.eval.sfm_holdout) {
    SfmHoldout holdout = SplitSfmPointsForHoldout(config, dataset.reference.name, reference);
    result.sfm_holdout = std::move(holdout.scored);
    sfm_gcp_part = std::move(holdout.gcp_part);
    spdlog::info("SfM hold-out: {} points as sfm GCP candidates, {} points for scoring",
                 sfm_gcp_part.size(), result.sfm_holdout.size());
  }

  for (const size_t index : order) {
    const std::string& source = names[index];
    gcp::GcpSourceSummary summary;
    if (source == "stereo") {
      std::vector<GcpSet> others;
      for (size_t i = 0; i < names.size(); ++i) {
        if (names[i] != "stereo") others.push_back(sets[i]);
      }
      provisional_labels = provisional_labels_of(gcp::MergeGcpSets(others));
    }
    if (source == "lidar") {
      LidarScanSummary scan_summary;
      PointCloud cloud =
          LoadLidarScan(config.gcp.lidar_path, config.dataset.path, config.dataset.reference,
                        config.gcp.lidar_motion, &scan_summary);
      lidar_motion = LidarMotionJson(scan_summary);
      if (config.eval.lidar_holdout) {
        // Checkerboard split: GCP blocks feed the GCPs; the visible points of the other blocks
        // score the result (gcp::SplitScanForHoldout).
        result.holdout_in_disparity = dataset.rectified;
        gcp::LidarHoldout holdout = gcp::SplitScanForHoldout(
            cloud, dataset.world_from_lidar, reference, config.gcp.lidar,
            config.eval.holdout_block_px, dataset.rectified ? dataset.disparity_numerator : 0.0);
        result.lidar_holdout = std::move(holdout.scored);
        result.lidar_holdout_not_visible = holdout.not_visible;
        spdlog::info(
            "LiDAR hold-out: {} points as GCP candidates, {} points for scoring ({} held-out "
            "points not visible from the camera are not scored)",
            holdout.gcp_part.size(), result.lidar_holdout.size(), holdout.not_visible);
        cloud = std::move(holdout.gcp_part);
      }
      sets[index] = gcp::GcpsFromPointCloud(cloud, dataset.world_from_lidar, reference,
                                            config.gcp.lidar, &summary);
    } else if (source == "sfm") {
      const std::vector<gcp::SfmPoint> points =
          config.eval.sfm_holdout
              ? sfm_gcp_part
              : SfmPointsOfReference(config, dataset.reference.name, config.gcp.sfm.projected);
      sets[index] = gcp::GcpsFromSfmPoints(points, reference, config.dataset.scale, config.gcp.sfm,
                                           &summary, config.gcp.lidar);
      spdlog::info(
          "sfm GCPs: {} of {} model points ({}; {} short tracks, {} with large errors, {} at "
          "small angles, {} sharing a pixel, {} outside the image, {} failing the visibility "
          "tests)",
          summary.num_gcps, summary.num_input,
          config.gcp.sfm.projected ? "observed or projected" : "observed by the reference",
          summary.num_short_track, summary.num_large_error, summary.num_small_angle,
          summary.num_same_pixel, summary.num_outside_image, summary.num_inconsistent);
    } else if (source == "depth_map") {
      const cv::Mat depth = ReadDepthMapSource(config.gcp.depth_map, dataset, config.dataset.scale);
      sets[index] =
          gcp::GcpsFromDepthMap(depth, config.gcp.depth_map.sigma, GcpSource::kDepthMap, &summary);
    } else if (source == "stereo" && !dataset.rectified) {
      // Calibrated views: rectify the reference with each neighbour, confirm across pairs.
      double z0 = provisional_labels.DepthOfLabel(0);
      double z1 = provisional_labels.DepthOfLabel(provisional_labels.count() - 1);
      if (z0 > z1) std::swap(z0, z1);
      if (!std::isfinite(z1)) {
        // Infinite depth is the last depth label, or value 0 of inverse depth.
        const bool depth_labels = provisional_labels.kind() == LabelSpaceKind::kDepth;
        throw ConfigError(ViolatedConstraint(
            depth_labels ? "labels.max" : "labels.min",
            FormatNumber(depth_labels ? provisional_labels.max() : provisional_labels.min()),
            "stereo GCPs of calibrated views search a bounded depth range, and this one reaches "
            "infinite depth: set labels.min and labels.max (or labels.auto.max_depth)"));
      }
      ProgressBar bar("stereo GCPs", 1000);
      const gcp::CalibratedStereoGcpResult stereo = gcp::ExtractCalibratedStereoGcps(
          dataset.reference, dataset.neighbors, z0, z1, config.gcp.stereo, bar.AsCallback());
      bar.Finish();
      for (const gcp::CalibratedPairSummary& p : stereo.pairs) {
        spdlog::info(
            "stereo GCPs: pair with '{}' (B = {:.4g}, f = {:.1f} px{}, d {}..{}): {} matches, {} "
            "on the reference grid, {} confirmed, {:.1f} s",
            p.neighbor, p.baseline, p.focal_px, p.mirrored ? ", mirrored" : "", p.min_disparity_px,
            p.max_disparity_px, p.num_matches, p.num_projected, p.num_confirmed, p.seconds);
      }
      summary = stereo.summary;
      sets[index] = stereo.gcps;
    } else if (source == "stereo") {
      const RectifiedPair pair = FindRectifiedPair(dataset, "gcp.sources: stereo");
      // Pair disparities of the label range: numerator / depth at both ends.
      double d0 = pair.numerator / provisional_labels.DepthOfLabel(0);
      double d1 = pair.numerator / provisional_labels.DepthOfLabel(provisional_labels.count() - 1);
      if (!std::isfinite(d0)) d0 = 0.0;
      if (!std::isfinite(d1)) d1 = 0.0;
      // A disparity of the image width or more matches nothing: an automatic range from the
      // views' overlap reaches it.
      const int max_disparity = std::min(static_cast<int>(std::ceil(std::max(d0, d1))), width - 1);
      const int min_disparity =
          std::min(static_cast<int>(std::floor(std::min(d0, d1))), max_disparity - 1);
      ProgressBar bar("stereo GCPs", 1000);
      const gcp::StereoGcpResult stereo =
          gcp::ExtractStereoGcps(dataset.reference.image, pair.neighbor->image, min_disparity,
                                 max_disparity, config.gcp.stereo, bar.AsCallback());
      bar.Finish();
      sets[index] = gcp::StereoGcpsToGcpSet(stereo.disparity, pair.numerator,
                                            config.gcp.stereo.sigma_px, &summary);
      summary.source = "stereo";
    }
    summary.source = source;
    spdlog::info("GCP source {}: {} GCPs ({:.2f} % of the pixels)", source, summary.num_gcps,
                 summary.density_percent);
    if (summary.num_gcps == 0) {
      spdlog::warn(
          "GCP source {} gave no GCP ({} inputs: {} behind the camera, {} outside the image, "
          "{} invalid, {} inconsistent); the run goes on without its GCPs",
          source, summary.num_input, summary.num_behind_camera, summary.num_outside_image,
          summary.num_invalid, summary.num_inconsistent);
    }
    source_reports[index] = SummaryJson(summary);
  }
  json sources = json::array();
  for (json& j : source_reports) sources.push_back(std::move(j));

  const GcpSet merged = gcp::MergeGcpSets(sets);
  result.gcps = gcp::Downsample(merged, config.gcp.downsample, width, height);
  json refinement;
  if (config.gcp.stereo.refine_px > 0.0 && !dataset.rectified &&
      std::find(config.gcp.sources.begin(), config.gcp.sources.end(), "stereo") !=
          config.gcp.sources.end()) {
    // Calibrated stereo GCPs, matched at gcp.stereo.image_scale, searched again on the labels.
    gcp::GcpRefinementSummary refined;
    result.gcps = gcp::RefineGcpsOnLabels(
        result.gcps, dataset.reference, dataset.neighbors, provisional_labels,
        config.gcp.stereo.refine_px, config.gcp.stereo.sigma_px, config.gcp.stereo.refine_window_px,
        config.cost.plane_sweep, &refined);
    spdlog::info(
        "stereo GCPs refined on the plane-sweep cost: {} of {} kept ({} with the minimum on the "
        "search's edge, {} without data dropped), mean shift {:.2f} labels, {:.1f} s",
        refined.refined, refined.input, refined.dropped_at_edge, refined.dropped_no_data,
        refined.mean_shift_labels, refined.seconds);
    refinement = {{"input", refined.input},
                  {"refined", refined.refined},
                  {"dropped_at_edge", refined.dropped_at_edge},
                  {"dropped_no_data", refined.dropped_no_data},
                  {"mean_shift_labels", refined.mean_shift_labels},
                  {"seconds", refined.seconds}};
  }
  result.report = {{"sources", sources},
                   {"downsample", config.gcp.downsample},
                   {"before_downsample", merged.size()},
                   {"count", result.gcps.size()},
                   {"density_percent", gcp::DensityPercent(result.gcps, width, height)}};
  if (!refinement.is_null()) result.report["stereo_refinement"] = refinement;
  if (!lidar_motion.is_null()) result.report["lidar_motion"] = lidar_motion;
  return result;
}

cv::Mat SparseGcpLabels(const GcpSet& gcps, const LabelSpace& labels, cv::Size size) {
  cv::Mat sparse(size, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (const Gcp& g : gcps.points) {
    if (g.row < 0 || g.col < 0 || g.row >= size.height || g.col >= size.width) continue;
    const double label = labels.LabelOfDepth(g.depth);
    if (std::isfinite(label)) sparse.at<float>(g.row, g.col) = static_cast<float>(label);
  }
  return sparse;
}

cv::Mat SparseGcpDisparity(const GcpSet& gcps, double numerator, cv::Size size) {
  cv::Mat sparse(size, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (const Gcp& g : gcps.points) {
    if (g.row < 0 || g.col < 0 || g.row >= size.height || g.col >= size.width) continue;
    sparse.at<float>(g.row, g.col) = static_cast<float>(numerator / g.depth);
  }
  return sparse;
}

cv::Mat LabelMapToDepth(const cv::Mat& labels, const LabelSpace& space) {
  cv::Mat float_labels;
  labels.convertTo(float_labels, CV_32F);
  cv::Mat depth(labels.size(), CV_32F);
  for (int r = 0; r < labels.rows; ++r) {
    const float* in = float_labels.ptr<float>(r);
    float* out = depth.ptr<float>(r);
    for (int c = 0; c < labels.cols; ++c) {
      const float label = in[c] < kLabelZeroSnap ? std::min(in[c], 0.0f) : in[c];
      const double d =
          std::isfinite(label) && label >= 0 ? space.DepthOfLabel(label) : kInvalidDepth;
      out[c] = std::isfinite(d) && d > 0 ? static_cast<float>(d) : kInvalidDepth;
    }
  }
  return depth;
}

cv::Mat LabelMapToDisparity(const cv::Mat& labels, const LabelSpace& space, double numerator) {
  cv::Mat float_labels;
  labels.convertTo(float_labels, CV_32F);
  cv::Mat disparity(labels.size(), CV_32F);
  for (int r = 0; r < labels.rows; ++r) {
    const float* in = float_labels.ptr<float>(r);
    float* out = disparity.ptr<float>(r);
    for (int c = 0; c < labels.cols; ++c) {
      const float label = in[c] < kLabelZeroSnap ? std::min(in[c], 0.0f) : in[c];
      if (!std::isfinite(label) || label < 0) {
        out[c] = kInvalidDepth;
      } else if (space.kind() == LabelSpaceKind::kDisparity) {
        out[c] = static_cast<float>(space.ValueOfLabel(label));
      } else {
        out[c] = static_cast<float>(numerator / space.DepthOfLabel(label));
      }
    }
  }
  return disparity;
}

cv::Mat DisparityMapToLabels(const cv::Mat& disparity, const LabelSpace& space, double numerator) {
  cv::Mat labels(disparity.size(), CV_32F);
  const double last = space.count() - 1;
  for (int r = 0; r < disparity.rows; ++r) {
    const float* in = disparity.ptr<float>(r);
    float* out = labels.ptr<float>(r);
    for (int c = 0; c < disparity.cols; ++c) {
      double label = std::numeric_limits<double>::quiet_NaN();
      if (std::isfinite(in[c]) && space.kind() == LabelSpaceKind::kDisparity) {
        label = space.LabelOfValue(in[c]);
      } else if (std::isfinite(in[c]) && in[c] > 0) {
        label = space.LabelOfDepth(numerator / in[c]);
      }
      out[c] = std::isnan(label) ? static_cast<float>(label)
                                 : static_cast<float>(std::clamp(label, 0.0, last));
    }
  }
  return labels;
}

}  // namespace gcpstereo::pipeline::internal
