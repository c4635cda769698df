// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// `gcpstereo run`: load → GCPs → labels → propagation (D̂) → cost + graph cuts per tile →
// depth/disparity → mesh → evaluation → outputs (../shared/CONTRACT.md).
#include "gcpstereo/pipeline/run.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <future>
#include <limits>
#include <optional>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/cost/birchfield_tomasi.h"
#include "gcpstereo/cost/label_range.h"
#include "gcpstereo/cost/plane_sweep.h"
#include "gcpstereo/cost/winner_take_all.h"
#include "gcpstereo/gcp/gcp_sources.h"
#include "gcpstereo/gcp/stereo_gcps.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/mesh_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "gcpstereo/io/preview.h"
#include "gcpstereo/mesh/meshing.h"
#include "gcpstereo/mesh/render.h"
#include "gcpstereo/optimize/left_right.h"
#include "gcpstereo/optimize/plane_fit.h"
#include "gcpstereo/optimize/tiling.h"
#include "gcpstereo/pipeline/output_folder.h"
#include "gcpstereo/propagation/propagation.h"
#include "stages.h"

namespace gcpstereo::pipeline {
namespace {

using nlohmann::json;

json ViewJson(const View& v) {
  return {{"name", v.name}, {"width", v.image.cols}, {"height", v.image.rows}};
}

void WriteText(const std::string& path, const std::string& text) {
  io::WriteBytesAtomically(path, text.data(), text.size());
}

// Records one stage's wall time and the process's peak memory after it.
class StageClock {
 public:
  StageClock(json* stages, std::string name) : stages_(stages), name_(std::move(name)) {
    spdlog::info("{} …", name_);
  }
  void Done(json extra = json::object()) {
    extra["seconds"] = timer_.ElapsedSeconds();
    extra["peak_memory_bytes_after"] = PeakResidentMemoryBytes();
    (*stages_)[name_] = extra;
    spdlog::info("{}: {:.2f} s", name_, extra["seconds"].get<double>());
  }

 private:
  json* stages_;
  std::string name_;
  Timer timer_;
};

// Depth preview with a range shared by every depth picture of the run.
cv::Mat DepthPreview(const cv::Mat& depth, double lo, double hi) {
  return io::RenderDepthPreview(depth, lo, hi, "m");
}

optimize::ExpansionOptions ExpansionOptionsOf(const PipelineConfig& options) {
  optimize::ExpansionOptions expansion = options.optimizer.expansion;
  expansion.candidate_labels = optimize::ParseCandidateLabels(options.optimizer.candidate_labels);
  expansion.initialization = options.optimizer.initialization == "prior"
                                 ? optimize::Initialization::kPrior
                                 : optimize::Initialization::kWinnerTakeAll;
  expansion.num_threads = options.runtime.threads;
  return expansion;
}

// D̂ (eq. 5 or another propagation.method) from GCP labels, in labels. The local planes are fitted
// to a quantity affine over a scene plane: depth labels are propagated as inverse depth and
// converted back; inverse-depth and disparity labels already are affine.
propagation::PropagationResult PropagateLabels(const cv::Mat& image_bgr,
                                               const cv::Mat& sparse_labels,
                                               const LabelSpace& labels,
                                               const propagation::PropagationOptions& options) {
  if (options.method != "local_plane" || labels.kind() != LabelSpaceKind::kDepth) {
    return propagation::Propagate(image_bgr, sparse_labels, options);
  }
  cv::Mat inverse_depth = sparse_labels.clone();
  inverse_depth.forEach<float>([&](float& v, const int*) {
    if (std::isfinite(v)) v = static_cast<float>(1.0 / labels.DepthOfLabel(v));
  });
  propagation::PropagationResult result = propagation::Propagate(image_bgr, inverse_depth, options);
  result.values.forEach<float>([&](float& v, const int*) {
    v = std::isfinite(v) && v > 0.0f ? static_cast<float>(labels.LabelOfDepth(1.0 / v))
                                     : std::numeric_limits<float>::quiet_NaN();
  });
  // The GCPs keep their labels exactly, not after a round trip through inverse depth.
  sparse_labels.copyTo(result.values, sparse_labels == sparse_labels);
  return result;
}

// D̂ restricted, given a segmentation, to the colour segments that hold a GCP (NaN in the others):
// there D̂ interpolates GCPs of the same surface; elsewhere it is extrapolated across a colour edge
// (Midd1's textureless lamp-shade opening next to GCPs on its rim). No segmentation: unchanged.
cv::Mat PriorInGcpSegments(const cv::Mat& prior, const std::vector<cv::Point>& gcp_pixels,
                           const cv::Mat& image_bgr,
                           const optimize::SegmentationOptions* segmentation) {
  if (prior.empty() || segmentation == nullptr) return prior;
  const cv::Mat segments = optimize::SegmentImage(image_bgr, *segmentation);
  double max_label = 0.0;
  cv::minMaxLoc(segments, nullptr, &max_label);
  std::vector<std::uint8_t> has_gcp(static_cast<size_t>(max_label) + 1, 0);
  for (const cv::Point& p : gcp_pixels) has_gcp[segments.at<int>(p)] = 1;
  cv::Mat masked = prior.clone();
  for (int r = 0; r < masked.rows; ++r) {
    for (int c = 0; c < masked.cols; ++c) {
      if (!has_gcp[segments.at<int>(r, c)]) {
        masked.at<float>(r, c) = std::numeric_limits<float>::quiet_NaN();
      }
    }
  }
  return masked;
}

// D̂ restricted to within `radius_px` of a GCP pixel (NaN farther away); radius 0 = unchanged.
cv::Mat PriorNearGcps(const cv::Mat& prior, const std::vector<cv::Point>& gcp_pixels,
                      double radius_px) {
  if (prior.empty() || radius_px <= 0.0) return prior;
  cv::Mat not_gcp(prior.size(), CV_8U, cv::Scalar(255));
  for (const cv::Point& p : gcp_pixels) not_gcp.at<std::uint8_t>(p) = 0;
  cv::Mat distance_px;
  cv::distanceTransform(not_gcp, distance_px, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat near = prior.clone();
  near.setTo(std::numeric_limits<float>::quiet_NaN(), distance_px > radius_px);
  return near;
}

// The GCPs as the other image of a rectified pair sees them, mirrored left-right so that the
// pair's disparity convention holds with that image as reference (the left-right check in
// RunPipeline). Each GCP is back-projected from the reference and projected into `partner` with
// the visibility tests of the LiDAR source (z-buffer and depth-consistency window): a point the
// partner cannot see — background next to a pole, hidden behind it from the other camera — would
// otherwise tie the occluder's pixels to the background. Values are labels (NaN elsewhere);
// `pixels` receives the occupied pixels.
cv::Mat MirroredPartnerGcpLabels(const GcpSet& gcps, const LabelSpace& labels,
                                 const Camera& reference, const Camera& partner,
                                 const gcp::LidarGcpOptions& visibility,
                                 std::vector<cv::Point>* pixels) {
  PointCloud cloud;
  for (const Gcp& g : gcps.points) {
    cloud.points.push_back(
        reference.BackProject(Eigen::Vector2d(g.col, g.row), g.depth).cast<float>());
    cloud.sigma.push_back(static_cast<float>(g.sigma));
  }
  const GcpSet seen =
      gcp::GcpsFromPointCloud(cloud, Eigen::Matrix4d::Identity(), partner, visibility);
  cv::Mat sparse(partner.height, partner.width, CV_32F,
                 cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  pixels->clear();
  for (const Gcp& g : seen.points) {
    const double label = labels.LabelOfDepth(g.depth);
    if (!std::isfinite(label)) continue;
    const int col = partner.width - 1 - g.col;
    sparse.at<float>(g.row, col) = static_cast<float>(label);
    pixels->emplace_back(col, g.row);
  }
  return sparse;
}

// The reference image in grey with the pixels that failed the left-right check in red, and in
// yellow those of them that kept their value because a GCP confirmed it (`after` = the mask once
// optimize::RestoreGcpConfirmed has run).
cv::Mat RenderInconsistent(const cv::Mat& image_bgr, const cv::Mat& consistent,
                           const cv::Mat& after) {
  cv::Mat grey, picture;
  cv::cvtColor(image_bgr, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, picture, cv::COLOR_GRAY2BGR);
  picture.setTo(cv::Scalar(0, 0, 255), consistent == 0);
  picture.setTo(cv::Scalar(0, 255, 255), (consistent == 0) & (after != 0));
  return picture;
}

// The plane fit's picture: the grey reference with the colour segments' borders lightened and the
// pixels that took a plane's value in cyan.
cv::Mat RenderPlaneFit(const cv::Mat& image_bgr, const cv::Mat& segments, const cv::Mat& before,
                       const cv::Mat& after) {
  cv::Mat grey, picture;
  cv::cvtColor(image_bgr, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, picture, cv::COLOR_GRAY2BGR);
  const cv::Mat changed = cv::abs(before - after) > 1e-6f;
  for (int r = 0; r < picture.rows; ++r) {
    for (int c = 0; c < picture.cols; ++c) {
      const int s = segments.at<int>(r, c);
      const bool border = (c + 1 < picture.cols && segments.at<int>(r, c + 1) != s) ||
                          (r + 1 < picture.rows && segments.at<int>(r + 1, c) != s);
      cv::Vec3b& pixel = picture.at<cv::Vec3b>(r, c);
      if (changed.at<std::uint8_t>(r, c)) {
        pixel = cv::Vec3b(255, 255, 0);
      } else if (border) {
        for (int k = 0; k < 3; ++k) pixel[k] = static_cast<std::uint8_t>((pixel[k] + 255) / 2);
      }
    }
  }
  return picture;
}

// GCPs the labels cannot reach: the range misses the scene (a frequent configuration slip).
// Warns when they are 10 % of the GCPs or more; returns their number.
int WarnOfGcpsOutsideLabels(const GcpSet& gcps, const LabelSpace& labels) {
  int outside = 0;
  for (const Gcp& g : gcps.points) {
    const double l = labels.LabelOfDepth(g.depth);
    if (!(l >= -0.5 && l <= labels.count() - 0.5)) ++outside;
  }
  if (outside > 0 && outside * 10 >= static_cast<int>(gcps.size())) {
    spdlog::warn(
        "{} of the {} GCPs ({:.0f} %) lie outside the label range [{}, {}] ({}): check "
        "labels.min, labels.max and labels.space",
        outside, gcps.size(), 100.0 * outside / gcps.size(), FormatNumber(labels.min()),
        FormatNumber(labels.max()), LabelSpaceKindName(labels.kind()));
  }
  return outside;
}

// Warns when most estimated pixels of `label_map` took the first or last label: the range is
// likely to miss the scene.
void WarnOfLabelsAtTheRangeEnds(const cv::Mat& label_map, const LabelSpace& labels) {
  int at_ends = 0, estimated = 0;
  const float top = static_cast<float>(labels.count() - 1);
  for (int r = 0; r < label_map.rows; ++r) {
    const float* row = label_map.ptr<float>(r);
    for (int c = 0; c < label_map.cols; ++c) {
      if (!std::isfinite(row[c])) continue;
      ++estimated;
      at_ends += (row[c] <= 0.5f || row[c] >= top - 0.5f) ? 1 : 0;
    }
  }
  if (estimated > 0 && at_ends * 2 > estimated) {
    spdlog::warn(
        "{:.0f} % of the pixels took the first or last label of [{}, {}] ({}): the label range "
        "probably misses the scene; check labels.min, labels.max and labels.space",
        100.0 * at_ends / estimated, FormatNumber(labels.min()), FormatNumber(labels.max()),
        LabelSpaceKindName(labels.kind()));
  }
}

// The GCP sources' input files exist before the data set is loaded: a wrong path stops the run at
// once and names its key (a `--set dataset.path=…` override does not move the other paths).
void CheckGcpInputFilesExist(const PipelineConfig& options) {
  const auto& sources = options.gcp.sources;
  auto check = [&](const char* source, const char* key, const std::string& path) {
    std::error_code ec;
    if (std::find(sources.begin(), sources.end(), source) == sources.end() ||
        std::filesystem::is_regular_file(path, ec)) {
      return;
    }
    throw IoError(path, std::string("file not found (") + key +
                            "; a relative path is relative to the working directory)");
  };
  check("lidar", "gcp.lidar.path", options.gcp.lidar_path);
  check("depth_map", "gcp.depth_map.path", options.gcp.depth_map.path);
}

// KITTI raw: gcp.lidar.path is velodyne_points/data/NNNNNNNNNN.bin of one frame, and nothing ties
// it to dataset.reference, so a config edited for another frame (or a --set of one key but not
// the other) would take its GCPs from a scan of another moment of the drive. Warns when the scan's
// file name is a frame number other than the reference's (a warning: the file may have been
// renamed; a name that is not a number is not checked). Returns what report.json records
// (dataset.lidar_scan), null when there is nothing to check.
json WarnOfScanOfAnotherFrame(const PipelineConfig& options) {
  const std::vector<std::string>& sources = options.gcp.sources;
  if (options.dataset.format != "kitti_raw" ||
      std::find(sources.begin(), sources.end(), "lidar") == sources.end()) {
    return nullptr;
  }
  const std::string scan = std::filesystem::path(options.gcp.lidar_path).stem().string();
  const std::string& frame = options.dataset.reference;
  auto is_number = [](const std::string& name) {
    return !name.empty() && std::all_of(name.begin(), name.end(),
                                        [](unsigned char c) { return std::isdigit(c) != 0; });
  };
  if (!is_number(scan) || !is_number(frame)) return nullptr;
  // The same number however many leading zeros (0000000010 = 10).
  auto without_zeros = [](const std::string& digits) {
    const size_t first = digits.find_first_not_of('0');
    return first == std::string::npos ? std::string("0") : digits.substr(first);
  };
  const bool same = without_zeros(scan) == without_zeros(frame);
  if (!same) {
    spdlog::warn(
        "gcp.lidar.path {} is by its name the Velodyne scan of frame {}, but dataset.reference is "
        "frame {}: the LiDAR GCPs come from another moment of the drive (set gcp.lidar.path to "
        "the scan of frame {}, unless the file was renamed)",
        options.gcp.lidar_path, scan, frame, frame);
  }
  return {{"path", options.gcp.lidar_path}, {"frame", scan}, {"same_frame_as_reference", same}};
}

RunSummary RunInFolder(const LoadedConfig& config, OutputFolder& out,
                       const std::string& config_path) {
  const PipelineConfig& options = config.options();
  Timer total;

  json report;
  report["gcpstereo_version"] = GCPSTEREO_VERSION;
  report["config"] = config_path;
  json& stages = report["stages"];
  stages = json::object();

  // 1. Load the data set.
  CheckGcpInputFilesExist(options);
  StageClock load_clock(&stages, "load");
  io::DatasetRequest request;
  request.format = options.dataset.format;
  request.path = options.dataset.path;
  request.reference = options.dataset.reference;
  request.neighbors = options.dataset.neighbors;
  request.scale = options.dataset.scale;
  const Dataset dataset = io::LoadDataset(request);
  const View& reference = dataset.reference;
  const cv::Size size = reference.image.size();
  json views = json::array();
  for (const auto& n : dataset.neighbors) views.push_back(ViewJson(n));
  report["dataset"] = {{"format", dataset.format},
                       {"path", dataset.path},
                       {"rectified", dataset.rectified},
                       {"reference", ViewJson(reference)},
                       {"neighbors", views},
                       {"num_views", 1 + dataset.neighbors.size()},
                       {"ground_truth",
                        {{"depth", dataset.ground_truth.HasDepth()},
                         {"sigma", !dataset.ground_truth.sigma.empty()},
                         {"disparity", dataset.ground_truth.HasDisparity()}}}};
  spdlog::info("loaded {} views: reference {} ({}x{}) and {} neighbours",
               1 + dataset.neighbors.size(), reference.name, size.width, size.height,
               dataset.neighbors.size());
  if (json scan = WarnOfScanOfAnotherFrame(options); !scan.is_null()) {
    report["dataset"]["lidar_scan"] = std::move(scan);
  }
  if (dataset.neighbors.empty()) {
    throw ConfigError("dataset.neighbors: no neighbour view to match the reference against");
  }
  const std::string cost_method =
      options.cost.method != "auto"
          ? options.cost.method
          : (dataset.rectified && dataset.neighbors.size() == 1 ? "birchfield_tomasi"
                                                                : "plane_sweep");
  if (options.optimizer.left_right_check && cost_method != "birchfield_tomasi") {
    throw ConfigError(
        "optimizer.left_right_check = true needs a rectified pair matched with cost.method = "
        "birchfield_tomasi (here: " +
        cost_method + ")");
  }
  if (options.optimizer.plane_fit && !dataset.rectified) {
    throw ConfigError(
        "optimizer.plane_fit = true needs a rectified data set (its planes are fitted in "
        "disparity)");
  }
  if (!options.optimizer.left_right_check && (options.optimizer.left_right_gcp_radius_px > 0 ||
                                              options.optimizer.left_right_median_radius_px > 0)) {
    spdlog::warn(
        "optimizer.left_right_gcp_radius_px and left_right_median_radius_px act on the left-right "
        "check's fill: without optimizer.left_right_check they have no effect");
  }
  load_clock.Done();

  // Writes the report and the effective configuration and moves every output into place.
  auto finish = [&](const std::vector<std::string>& images) {
    report["peak_memory_bytes"] = PeakResidentMemoryBytes();
    report["total_seconds"] = total.ElapsedSeconds();
    if (options.output.previews && !images.empty()) {
      WriteText(out.Path("index.html"), internal::MakeIndexHtml(report, images));
    }
    WriteText(out.Path("effective_config.yaml"), config.schema().ToYaml());
    const std::string report_text = report.dump(2) + "\n";
    WriteText(out.Path("report.json"), report_text);
    out.Commit();
    RunSummary summary;
    summary.output_dir = out.final_dir();
    summary.total_seconds = total.ElapsedSeconds();
    summary.peak_memory_bytes = PeakResidentMemoryBytes();
    summary.report_json = report_text;
    summary.terminal_summary = internal::TerminalSummary(report);
    return summary;
  };
  const std::string& stop_after = options.runtime.stop_after;
  if (stop_after == "load") {
    // The range data named by the configuration is read too, so that it is validated.
    if (!options.gcp.lidar_path.empty()) {
      report["lidar"] = {{"path", options.gcp.lidar_path},
                         {"num_points", io::ReadPointCloud(options.gcp.lidar_path).size()}};
    }
    return finish({});
  }

  // 2. Labels (from the configuration or the views) and ground control points.
  StageClock gcp_clock(&stages, "gcps");
  const LabelSpaceKind kind = ParseLabelSpaceKind(options.labels.space);
  if (kind == LabelSpaceKind::kDisparity && !dataset.rectified) {
    throw ConfigError("labels.space = disparity needs rectified data (middlebury, kitti_raw)");
  }
  // Stereo GCPs search the label range before their own GCPs exist: it comes from the
  // configuration, the other sources' GCPs, the pair's matched disparities or the views' overlap
  // then. The views' matched range is computed once for both label spaces.
  cost::MatchedDepthRange matched_range;
  const internal::ProvisionalLabels provisional = [&](const GcpSet& other_gcps) {
    return cost::MakeLabelSpace(kind, options.labels.count, options.labels.min, options.labels.max,
                                other_gcps, reference, dataset.neighbors,
                                dataset.disparity_numerator, dataset.rectified, options.label_range,
                                nullptr, &matched_range);
  };
  internal::GcpStageResult gcp_stage = internal::RunGcpStage(options, dataset, provisional);
  const GcpSet& gcps = gcp_stage.gcps;
  report["gcps"] = gcp_stage.report;
  gcp_clock.Done({{"count", gcps.size()}});

  cost::LabelRangeSummary range_summary;
  const LabelSpace labels =
      cost::MakeLabelSpace(kind, options.labels.count, options.labels.min, options.labels.max, gcps,
                           reference, dataset.neighbors, dataset.disparity_numerator,
                           dataset.rectified, options.label_range, &range_summary, &matched_range);
  report["labels"] = {{"space", LabelSpaceKindName(labels.kind())},
                      {"count", labels.count()},
                      {"min", labels.min()},
                      {"max", labels.max()},
                      {"step", labels.step()},
                      {"range_source", range_summary.source},
                      {"depth_of_first_label", labels.DepthOfLabel(0)},
                      {"depth_of_last_label", labels.DepthOfLabel(labels.count() - 1)}};
  report["labels"]["gcps_outside_range"] = WarnOfGcpsOutsideLabels(gcps, labels);
  // GCP quality against the ground truth (the paper's Table 1: outliers = |error| > 1 px).
  if (!gcps.empty() && dataset.ground_truth.HasDisparity()) {
    const cv::Mat sparse = internal::SparseGcpDisparity(gcps, dataset.disparity_numerator, size);
    const gcp::GcpOutlierStats stats =
        gcp::ComputeOutlierStats(sparse, dataset.ground_truth.disparity, 1.0);
    report["gcps"]["outliers"] = {{"definition", "|disparity - gt| > 1 px"},
                                  {"evaluated", stats.num_evaluated},
                                  {"outliers", stats.num_outliers},
                                  {"percent", stats.outlier_percent}};
  } else if (!gcps.empty() && dataset.ground_truth.HasDepth()) {
    cv::Mat sparse(size, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
    cv::Mat gt_labels(size, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
    int within_3_sigma = 0, with_sigma = 0;
    for (const Gcp& g : gcps.points) {
      sparse.at<float>(g.row, g.col) = static_cast<float>(labels.LabelOfDepth(g.depth));
      const float gt = dataset.ground_truth.depth.at<float>(g.row, g.col);
      if (!IsValidDepth(gt)) continue;
      gt_labels.at<float>(g.row, g.col) = static_cast<float>(labels.LabelOfDepth(gt));
      if (!dataset.ground_truth.sigma.empty()) {
        const float sigma = dataset.ground_truth.sigma.at<float>(g.row, g.col);
        if (std::isfinite(sigma) && sigma > 0) {
          ++with_sigma;
          within_3_sigma += std::abs(g.depth - gt) <= 3.0 * sigma;
        }
      }
    }
    const gcp::GcpOutlierStats stats = gcp::ComputeOutlierStats(sparse, gt_labels, 1.0);
    report["gcps"]["outliers"] = {
        {"definition", "|label - gt label| > 1 label step"},
        {"evaluated", stats.num_evaluated},
        {"outliers", stats.num_outliers},
        {"percent", stats.outlier_percent},
        {"within_3_sigma_percent", with_sigma ? 100.0 * within_3_sigma / with_sigma : 0.0}};
  }
  spdlog::info("labels: {} {} from {} to {} (range from {})", labels.count(),
               LabelSpaceKindName(labels.kind()), labels.min(), labels.max(), range_summary.source);

  if (stop_after == "gcps") {
    io::WriteGcpsPly(out.Path("gcps.ply"), gcps, reference.camera);
    return finish({});
  }

  // 3. Adaptive propagation of the GCPs (eq. 5): the prior D̂ of the GCP energy, in labels.
  const bool use_gcp_energy = options.optimizer.energy.use_gcp_energy && !gcps.empty();
  cv::Mat prior;
  if (!gcps.empty()) {
    StageClock clock(&stages, "propagation");
    const cv::Mat sparse = internal::SparseGcpLabels(gcps, labels, size);
    const propagation::PropagationResult propagated =
        PropagateLabels(reference.image, sparse, labels, options.propagation);
    prior = propagated.values;
    const double unreached_percent = 100.0 * propagated.num_unreached_pixels / size.area();
    if (propagated.num_unreached_pixels > 0) {
      spdlog::warn("propagation: {} pixels ({:.1f} %) in {} regions no GCP reaches have no prior",
                   propagated.num_unreached_pixels, unreached_percent,
                   propagated.num_unreached_regions);
    }
    clock.Done({{"solver", propagated.solver},
                {"gcps", propagated.num_gcps},
                {"unknowns", propagated.num_unknowns},
                {"unreached_pixels", propagated.num_unreached_pixels},
                {"unreached_percent", unreached_percent},
                {"unreached_regions", propagated.num_unreached_regions},
                {"setup_seconds", propagated.setup_seconds},
                {"solve_seconds", propagated.solve_seconds},
                {"residual", propagated.residual}});
  }

  // D̂ in the data set's units: an output of every run with GCPs, and the product of one stopped
  // after the propagation (LiDAR depth completion without stereo).
  cv::Mat prior_depth, prior_disparity;
  if (!prior.empty()) {
    prior_depth = internal::LabelMapToDepth(prior, labels);
    if (dataset.rectified) {
      prior_disparity = internal::LabelMapToDisparity(prior, labels, dataset.disparity_numerator);
    }
  }
  // Scores the result (`depth`, `disparity`; empty when the run stopped before it) and D̂ against
  // the data set's ground truth into report["metrics"]; returns the error previews.
  auto evaluate = [&](const cv::Mat& depth, const cv::Mat& disparity) {
    StageClock clock(&stages, "evaluation");
    std::vector<std::pair<std::string, cv::Mat>> previews;
    internal::EvaluationInputs inputs;
    if (!depth.empty()) inputs.depth_maps.emplace_back("result", depth);
    if (!prior_depth.empty()) inputs.depth_maps.emplace_back("propagated", prior_depth);
    if (!disparity.empty()) inputs.disparity_maps.emplace_back("result", disparity);
    if (!prior_disparity.empty()) inputs.disparity_maps.emplace_back("propagated", prior_disparity);
    inputs.lidar_holdout = &gcp_stage.lidar_holdout;
    inputs.holdout_in_disparity = gcp_stage.holdout_in_disparity;
    inputs.holdout_not_visible = gcp_stage.lidar_holdout_not_visible;
    report["metrics"] = internal::Evaluate(dataset, inputs, &previews);
    clock.Done();
    return previews;
  };
  // Writes D̂'s maps and the GCPs.
  auto write_prior_and_gcps = [&] {
    if (!prior_depth.empty()) io::WritePfm(out.Path("propagated_depth.pfm"), prior_depth);
    if (!prior_disparity.empty()) {
      io::WritePfm(out.Path("propagated_disparity.pfm"), prior_disparity);
    }
    io::WriteGcpsPly(out.Path("gcps.ply"), gcps, reference.camera);
  };
  // Writes the previews (when output.previews is on): the result's depth (if any), D̂, the GCPs,
  // the ground truth, then `more` in order (empty images skipped); returns the names written.
  auto write_previews = [&](const cv::Mat& depth,
                            const std::vector<std::pair<std::string, cv::Mat>>& more) {
    std::vector<std::string> images;
    if (!options.output.previews) return images;
    double lo = labels.DepthOfLabel(0), hi = labels.DepthOfLabel(labels.count() - 1);
    if (lo > hi) std::swap(lo, hi);
    if (!std::isfinite(hi)) io::RobustValueRange(depth.empty() ? prior_depth : depth, &lo, &hi);
    auto add = [&](const std::string& name, const cv::Mat& image) {
      if (image.empty()) return;
      io::WritePng(out.Path(name), image);
      images.push_back(name);
    };
    if (!depth.empty()) add("depth.png", DepthPreview(depth, lo, hi));
    if (!prior_depth.empty()) add("propagated.png", DepthPreview(prior_depth, lo, hi));
    add("gcps.png", internal::RenderGcpOverlay(reference.image, gcps));
    if (dataset.ground_truth.HasDepth()) {
      add("ground_truth.png", DepthPreview(dataset.ground_truth.depth, lo, hi));
    }
    for (const auto& [name, image] : more) add(name, image);
    return images;
  };

  if (stop_after == "propagation") {
    const std::vector<std::pair<std::string, cv::Mat>> previews = evaluate(cv::Mat(), cv::Mat());
    write_prior_and_gcps();
    StageClock write_clock(&stages, "write");
    const std::vector<std::string> images = write_previews(cv::Mat(), previews);
    write_clock.Done();
    return finish(images);
  }

  // The prior of the GCP energy: D̂, optionally only within optimizer.prior_radius_px of a GCP.
  std::vector<cv::Point> gcp_pixels;
  for (const Gcp& g : gcps.points) gcp_pixels.emplace_back(g.col, g.row);
  // … and optionally only in the colour segments that hold a GCP (optimizer.prior_segment_k).
  optimize::SegmentationOptions prior_segmentation =
      options.optimizer.plane_fit_options.segmentation;
  prior_segmentation.k = options.optimizer.prior_segment_k;
  const optimize::SegmentationOptions* segmentation =
      options.optimizer.prior_segment_k > 0.0 ? &prior_segmentation : nullptr;
  const cv::Mat energy_prior =
      PriorNearGcps(PriorInGcpSegments(prior, gcp_pixels, reference.image, segmentation),
                    gcp_pixels, options.optimizer.prior_radius_px);
  const double prior_percent =
      prior.empty() ? 0.0 : 100.0 * cv::countNonZero(energy_prior == energy_prior) / size.area();
  if (!prior.empty() && (options.optimizer.prior_radius_px > 0.0 || segmentation != nullptr)) {
    spdlog::info("GCP energy on {:.1f} % of the pixels (within {} px of a GCP{})", prior_percent,
                 options.optimizer.prior_radius_px,
                 segmentation != nullptr ? ", in colour segments holding one" : "");
  }

  // 4–5. Matching costs and global optimisation, tile by tile (memory follows the tile).
  std::vector<double> pair_disparities;
  const View* pair_neighbor = nullptr;
  if (cost_method == "birchfield_tomasi") {
    const internal::RectifiedPair pair = internal::FindRectifiedPair(dataset, "cost.method");
    pair_neighbor = pair.neighbor;
    for (int l = 0; l < labels.count(); ++l) {
      const double depth = labels.DepthOfLabel(l);
      pair_disparities.push_back(std::isfinite(depth) ? pair.numerator / depth : 0.0);
    }
  }
  optimize::EnergyOptions energy = options.optimizer.energy;
  energy.use_gcp_energy = use_gcp_energy;
  optimize::TilingOptions tiling;
  tiling.rows = options.tiling.tiles[0];
  tiling.cols = options.tiling.tiles[1];
  tiling.overlap_px = options.tiling.tile_overlap;
  tiling.blend = options.optimizer.blend;
  const optimize::ExpansionOptions expansion = ExpansionOptionsOf(options);

  StageClock optimize_clock(&stages, "cost_and_optimization");
  // The tile problem of a rectified pair seen from `left` (Birchfield–Tomasi against `right`);
  // `view_prior` is read when a tile is built, so it may be filled in after this call.
  auto pair_problem = [&](const cv::Mat& left, const cv::Mat& right, const cv::Mat* view_prior) {
    return [&, left, right, view_prior](const cv::Rect& region) {
      optimize::OwnedMrfProblem problem;
      problem.data = cost::ComputeBirchfieldTomasiCost(left, right, pair_disparities, region,
                                                       options.cost.birchfield_tomasi);
      problem.image = left(region).clone();
      if (use_gcp_energy) problem.prior = (*view_prior)(region).clone();
      return problem;
    };
  };
  optimize::MakeTileProblem make_problem;
  if (cost_method == "birchfield_tomasi") {
    make_problem = pair_problem(reference.image, pair_neighbor->image, &energy_prior);
  } else {
    make_problem = [&](const cv::Rect& region) {
      optimize::OwnedMrfProblem problem;
      problem.data = cost::ComputePlaneSweepCost(reference, dataset.neighbors, labels, region,
                                                 options.cost.plane_sweep);
      problem.image = reference.image(region).clone();
      if (use_gcp_energy) problem.prior = energy_prior(region).clone();
      return problem;
    };
  }
  // Winner-take-all or graph cuts over the tiles of one view's problem; an empty title shows no
  // progress bar.
  auto optimize_view = [&](const optimize::MakeTileProblem& make_view_problem,
                           const std::string& progress_title) {
    optimize::TiledResult optimized;
    if (options.optimizer.method == "wta") {
      // Winner-take-all per tile: the same tiling and cost code, no energy minimisation.
      optimized.labels = cv::Mat(size, CV_32F, cv::Scalar(0));
      cv::Mat weight(size, CV_32F, cv::Scalar(0));
      for (const cv::Rect& region : optimize::TileLayout(size, tiling)) {
        optimize::OwnedMrfProblem problem = make_view_problem(region);
        cv::Mat labels = cost::WinnerTakeAll(problem.data);
        cv::Mat float_labels;
        labels.convertTo(float_labels, CV_32F);
        float_labels.setTo(std::numeric_limits<float>::quiet_NaN(), labels < 0);
        // Overlaps: the mean, as the graph-cut merge does.
        cv::Mat target = optimized.labels(region), w = weight(region);
        for (int r = 0; r < region.height; ++r) {
          for (int c = 0; c < region.width; ++c) {
            const float v = float_labels.at<float>(r, c);
            if (std::isnan(v)) continue;
            target.at<float>(r, c) += v;
            w.at<float>(r, c) += 1.0f;
          }
        }
      }
      optimized.labels /= weight;  // 0/0 = NaN where no tile had data: no estimate
    } else {
      std::optional<ProgressBar> bar;
      if (!progress_title.empty()) bar.emplace(progress_title, 1000);
      optimize::RefinementOptions refinement = options.optimizer.refinement;
      refinement.method = optimize::ParseRefinementMethod(options.optimizer.refinement_method);
      optimized = optimize::OptimizeTiled(size, make_view_problem, energy, expansion, tiling, {},
                                          bar ? bar->AsCallback() : ProgressCallback(), refinement);
    }
    return optimized;
  };
  // The left-right check's second problem (5b below): the neighbour as reference, solved on
  // mirrored images so that every cost and GCP routine keeps its disparity convention. It needs
  // nothing from the first solve, so it runs alongside it (α-expansion on one tile is mostly
  // single-threaded: the two solves share the cores).
  cv::Mat mirrored_reference, mirrored_neighbor, mirrored_prior;
  if (options.optimizer.left_right_check) {
    cv::flip(pair_neighbor->image, mirrored_reference, 1);
    cv::flip(reference.image, mirrored_neighbor, 1);
  }
  const optimize::MakeTileProblem make_mirrored_problem =
      pair_problem(mirrored_reference, mirrored_neighbor, &mirrored_prior);
  double partner_seconds = 0.0;
  std::future<optimize::TiledResult> partner_result;
  if (options.optimizer.left_right_check) {
    partner_result = std::async(std::launch::async, [&] {
      Timer timer;
      if (use_gcp_energy) {
        std::vector<cv::Point> mirrored_gcp_pixels;
        const cv::Mat sparse =
            MirroredPartnerGcpLabels(gcps, labels, reference.camera, pair_neighbor->camera,
                                     options.gcp.lidar, &mirrored_gcp_pixels);
        mirrored_prior = PriorNearGcps(
            PriorInGcpSegments(
                PropagateLabels(mirrored_reference, sparse, labels, options.propagation).values,
                mirrored_gcp_pixels, mirrored_reference, segmentation),
            mirrored_gcp_pixels, options.optimizer.prior_radius_px);
      }
      optimize::TiledResult result = optimize_view(make_mirrored_problem, "");
      partner_seconds = timer.ElapsedSeconds();
      return result;
    });
  }
  optimize::TiledResult optimized = optimize_view(
      make_problem, options.optimizer.left_right_check ? "graph cuts, both views" : "graph cuts");
  json tiles = json::array();
  for (const auto& tile : optimized.tiles) {
    const auto& e = tile.expansion;
    tiles.push_back(
        {{"region", {tile.region.x, tile.region.y, tile.region.width, tile.region.height}},
         {"cost_seconds", tile.setup_seconds},
         {"expansion_seconds", e.time_seconds},
         {"initial_energy", e.initial_energy},
         {"energy_per_cycle", e.energy_per_cycle},
         {"energy",
          {{"data", e.breakdown.data},
           {"smooth", e.breakdown.smooth},
           {"gcp", e.breakdown.gcp},
           {"total", e.breakdown.total()}}},
         {"cycles", e.cycles},
         {"converged", e.converged},
         {"moves_tried", e.moves_tried},
         {"moves_skipped", e.moves_skipped},
         {"refinement",
          {{"method", optimize::RefinementMethodName(tile.refinement.method)},
           {"pixels_moved", tile.refinement.pixels_moved},
           {"mean_abs_offset", tile.refinement.mean_abs_offset},
           {"iterations", tile.refinement.iterations},
           {"converged", tile.refinement.solver_converged},
           {"seconds", tile.refinement.time_seconds}}}});
  }
  optimize_clock.Done({{"method", options.optimizer.method},
                       {"cost_method", cost_method},
                       {"gcp_energy", use_gcp_energy},
                       {"gcp_energy_pixels_percent", use_gcp_energy ? prior_percent : 0.0},
                       {"tiles", tiles},
                       {"energy_sum", optimized.energy_sum}});

  // 5b. Left-right check (optimizer.left_right_check, rectified pairs): pixels whose disparities
  // from the two solves disagree are filled from the background side of their row
  // (optimize/left_right.h). The stage's time is the wait for the second solve plus the fill;
  // partner_seconds is that solve's own wall time (it overlapped the first).
  cv::Mat inconsistent_preview, plane_fit_preview;
  // For the plane fit (5c): the pixels that support it (left-right consistent or GCP-confirmed) and
  // those it must leave alone (occluded in the right view: the background fill is right there).
  cv::Mat plane_support, plane_frozen;
  if (options.optimizer.left_right_check) {
    StageClock clock(&stages, "left_right_check");
    const optimize::TiledResult partner = partner_result.get();  // rethrows its errors
    cv::Mat partner_labels;
    cv::flip(partner.labels, partner_labels, 1);
    const cv::Mat partner_disparity =
        internal::LabelMapToDisparity(partner_labels, labels, dataset.disparity_numerator);
    cv::Mat own_disparity =
        internal::LabelMapToDisparity(optimized.labels, labels, dataset.disparity_numerator);
    const cv::Mat consistent = optimize::LeftRightConsistent(
        own_disparity, partner_disparity, options.optimizer.left_right_max_difference_px);
    const int inconsistent = size.area() - cv::countNonZero(consistent);
    if (options.optimizer.plane_fit) {
      plane_frozen = optimize::LeftRightOccluded(own_disparity, partner_disparity,
                                                 options.optimizer.left_right_max_difference_px);
    }
    // A half-occluded band is at most as wide as the label range in pixels of disparity.
    const auto [min_disparity, max_disparity] =
        std::minmax_element(pair_disparities.begin(), pair_disparities.end());
    const int max_run_px = static_cast<int>(std::ceil(*max_disparity - *min_disparity));
    const bool restore = options.optimizer.left_right_gcp_radius_px > 0;
    const cv::Mat labels_before_fill = restore ? optimized.labels.clone() : cv::Mat();
    const cv::Mat disparity_before_fill = restore ? own_disparity.clone() : cv::Mat();
    cv::Mat checked = consistent.clone();  // becomes 255 where a GCP keeps the optimised value
    const int filled =
        optimize::FillFromBackground(checked, max_run_px, &optimized.labels, &own_disparity);
    int restored = 0;
    if (restore) {
      restored = optimize::RestoreGcpConfirmed(
          internal::SparseGcpDisparity(gcps, dataset.disparity_numerator, size),
          options.optimizer.left_right_gcp_radius_px, labels_before_fill, disparity_before_fill,
          &checked, &optimized.labels, &own_disparity);
    }
    int smoothed = 0;
    if (options.optimizer.left_right_median_radius_px > 0) {
      smoothed = optimize::WeightedMedianOfFilled(
          reference.image, checked, options.optimizer.left_right_median_radius_px,
          options.optimizer.left_right_median_sigma, &optimized.labels, &own_disparity);
    }
    inconsistent_preview = RenderInconsistent(reference.image, consistent, checked);
    if (options.optimizer.plane_fit) plane_support = checked;
    spdlog::info("left-right check: {} pixels ({:.2f} %) inconsistent, {} filled, {} kept by GCPs",
                 inconsistent, 100.0 * inconsistent / size.area(), filled, restored);
    clock.Done({{"max_difference_px", options.optimizer.left_right_max_difference_px},
                {"inconsistent_pixels", inconsistent},
                {"inconsistent_percent", 100.0 * inconsistent / size.area()},
                {"filled_pixels", filled},
                {"max_fill_run_px", max_run_px},
                {"gcp_restored_pixels", restored},
                {"median_changed_pixels", smoothed},
                {"partner_energy_sum", partner.energy_sum},
                {"partner_seconds", partner_seconds}});
  }

  // 5c. Segment planes (optimizer.plane_fit, rectified data): the pixels of a colour segment that
  // lie nearer than its robustly fitted disparity plane take the plane's value
  // (optimize/plane_fit.h). With the left-right check, only consistent pixels support the fit and
  // pixels occluded in the right view keep their background fill.
  if (options.optimizer.plane_fit) {
    StageClock clock(&stages, "plane_fit");
    cv::Mat fitted =
        internal::LabelMapToDisparity(optimized.labels, labels, dataset.disparity_numerator);
    const cv::Mat before = fitted.clone();
    const optimize::PlaneFitSummary summary = optimize::FitSegmentPlanes(
        reference.image, plane_support, plane_frozen, options.optimizer.plane_fit_options, &fitted);
    plane_fit_preview = RenderPlaneFit(reference.image, summary.segment_labels, before, fitted);
    // Only the changed pixels get new labels: the others keep theirs bit for bit.
    internal::DisparityMapToLabels(fitted, labels, dataset.disparity_numerator)
        .copyTo(optimized.labels, cv::abs(before - fitted) > 0.0f);
    spdlog::info("plane fit: {} of {} colour segments fitted, {} pixels changed",
                 summary.fitted_segments, summary.segments, summary.changed_pixels);
    clock.Done({{"segments", summary.segments},
                {"fitted_segments", summary.fitted_segments},
                {"changed_pixels", summary.changed_pixels},
                {"changed_percent", 100.0 * summary.changed_pixels / size.area()}});
  }

  // 6. Depth (and disparity) maps.
  const cv::Mat depth = internal::LabelMapToDepth(optimized.labels, labels);
  WarnOfLabelsAtTheRangeEnds(optimized.labels, labels);
  cv::Mat disparity;
  if (dataset.rectified) {
    disparity =
        internal::LabelMapToDisparity(optimized.labels, labels, dataset.disparity_numerator);
  }

  // The mesh is built now so that its OBJ text export (with vertex normals; a few seconds for the
  // 3 M faces of a fountain-size map) runs in the background while the evaluation, the previews and
  // the other files are produced; it is joined (and any error rethrown) before the outputs move.
  TriangleMesh triangles;
  mesh::MeshingSummary meshing;
  std::future<double> obj_export;
  if (options.output.mesh) {
    triangles = mesh::MeshFromDepthMap(depth, reference.image, reference.camera,
                                       options.mesh.meshing, &meshing);
    obj_export = std::async(std::launch::async, [&triangles, path = out.Path("mesh.obj")] {
      Timer timer;
      io::WriteMeshObj(path, triangles, mesh::VertexNormals(triangles));
      return timer.ElapsedSeconds();
    });
  }

  const std::vector<std::pair<std::string, cv::Mat>> previews = evaluate(depth, disparity);

  // 7. Outputs, staged and moved into place at the end: the mesh, then the maps and previews.
  std::vector<std::pair<std::string, cv::Mat>> more_previews = {
      {"left_right_check.png", inconsistent_preview}, {"plane_fit.png", plane_fit_preview}};
  io::WritePfm(out.Path("depth.pfm"), depth);
  if (dataset.rectified) io::WritePfm(out.Path("disparity.pfm"), disparity);
  write_prior_and_gcps();
  if (options.output.mesh || options.output.points) {
    StageClock clock(&stages, "mesh");
    json mesh_report = json::object();
    if (options.output.mesh) {
      io::WriteMeshPly(out.Path("mesh.ply"), triangles);
      mesh_report = {{"vertices", meshing.vertices},
                     {"faces", meshing.faces},
                     {"dropped_invalid", meshing.dropped_invalid},
                     {"dropped_depth_ratio", meshing.dropped_depth_ratio},
                     {"dropped_view_angle", meshing.dropped_view_angle}};
      if (options.output.previews && !triangles.faces.empty()) {
        // Small images are rendered larger so that the picture stays legible.
        const double enlarge = std::max(1.0, 960.0 / reference.camera.width);
        const Camera view =
            mesh::OrbitCamera(reference.camera.Rescaled(enlarge), options.mesh.preview_yaw_deg,
                              options.mesh.preview_pitch_deg, mesh::MedianVertex(triangles));
        more_previews.emplace_back("mesh.png",
                                   mesh::RenderMeshPreview(triangles, view, options.mesh.preview));
      }
    }
    if (options.output.points) {
      io::WriteMeshPly(out.Path("points.ply"),
                       mesh::ColoredPointsFromDepthMap(depth, reference.image, reference.camera,
                                                       options.mesh.meshing.stride_px));
    }
    clock.Done(mesh_report);
  }

  StageClock write_clock(&stages, "write");
  more_previews.insert(more_previews.end(), previews.begin(), previews.end());
  const std::vector<std::string> images = write_previews(depth, more_previews);
  json write_report = json::object();
  if (obj_export.valid()) write_report["mesh_obj_export_seconds"] = obj_export.get();
  write_clock.Done(write_report);
  return finish(images);
}

}  // namespace

RunSummary RunPipeline(const LoadedConfig& config, const std::string& output_dir,
                       const std::string& config_path) {
  OutputFolder out(output_dir);
  AddLogFile(out.FinalPath("run.log"));
  struct LogFileGuard {
    ~LogFileGuard() { RemoveLogFiles(); }
  } log_file_guard;
  try {
    return RunInFolder(config, out, config_path);
  } catch (const std::exception& e) {
    // The error ends the run: run.log says so too (stderr has it from the caller).
    LogToFilesOnly("run failed: " + std::string(e.what()));
    throw;
  }
}

}  // namespace gcpstereo::pipeline
