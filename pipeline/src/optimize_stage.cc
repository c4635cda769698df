// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Stages 4–5c of one view's run: the prior of the GCP energy, matching costs and global
// optimisation per tile (with the neighbour's own solve for the left-right check), the left-right
// check and the segment-plane fit (view_stages.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/cost/birchfield_tomasi.h"
#include "gcpstereo/cost/plane_sweep.h"
#include "gcpstereo/cost/winner_take_all.h"
#include "gcpstereo/gcp/gcp_sources.h"
#include "gcpstereo/optimize/left_right.h"
#include "stages.h"
#include "view_stages.h"

namespace gcpstereo::pipeline::internal {
namespace {

using nlohmann::json;

optimize::ExpansionOptions ExpansionOptionsOf(const PipelineConfig& options) {
  optimize::ExpansionOptions expansion = options.optimizer.expansion;
  expansion.candidate_labels = optimize::ParseCandidateLabels(options.optimizer.candidate_labels);
  expansion.initialization = options.optimizer.initialization == "prior"
                                 ? optimize::Initialization::kPrior
                                 : optimize::Initialization::kWinnerTakeAll;
  expansion.num_threads = options.runtime.threads;
  return expansion;
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
// pair's disparity convention holds with that image as reference (the left-right check). Each GCP
// is back-projected from the reference and projected into `partner` with the visibility tests of
// the LiDAR source (z-buffer and depth-consistency window): a point the partner cannot see —
// background next to a pole, hidden behind it from the other camera — would otherwise tie the
// occluder's pixels to the background. Values are labels (NaN elsewhere); `pixels` receives the
// occupied pixels.
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

// The prior of the GCP energy from D̂ seen from `image_bgr` (see EnergyPriorStage).
cv::Mat EnergyPriorOf(const PipelineConfig& options, const cv::Mat& propagated,
                      const std::vector<cv::Point>& gcp_pixels, const cv::Mat& image_bgr,
                      const std::optional<optimize::SegmentationOptions>& segmentation) {
  return PriorNearGcps(PriorInGcpSegments(propagated, gcp_pixels, image_bgr,
                                          segmentation ? &*segmentation : nullptr),
                       gcp_pixels, options.optimizer.prior_radius_px);
}

// How one view's problem is solved, tile by tile: winner-take-all or graph cuts.
struct ViewSolver {
  const PipelineConfig& options;
  cv::Size size;
  optimize::TilingOptions tiling;
  optimize::EnergyOptions energy;
  optimize::ExpansionOptions expansion;

  // An empty title shows no progress bar.
  optimize::TiledResult Solve(const optimize::MakeTileProblem& make_problem,
                              const std::string& progress_title) const {
    if (options.optimizer.method == "wta") return WinnerTakeAllTiled(make_problem);
    std::optional<ProgressBar> bar;
    if (!progress_title.empty()) bar.emplace(progress_title, 1000);
    optimize::RefinementOptions refinement = options.optimizer.refinement;
    refinement.method = optimize::ParseRefinementMethod(options.optimizer.refinement_method);
    return optimize::OptimizeTiled(size, make_problem, energy, expansion, tiling, {},
                                   bar ? bar->AsCallback() : ProgressCallback(), refinement);
  }

  // Winner-take-all per tile: the same tiling and cost code, no energy minimisation.
  optimize::TiledResult WinnerTakeAllTiled(const optimize::MakeTileProblem& make_problem) const {
    optimize::TiledResult optimized;
    optimized.labels = cv::Mat(size, CV_32F, cv::Scalar(0));
    cv::Mat weight(size, CV_32F, cv::Scalar(0));
    for (const cv::Rect& region : optimize::TileLayout(size, tiling)) {
      optimize::OwnedMrfProblem problem = make_problem(region);
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
    return optimized;
  }
};

ViewSolver ViewSolverOf(const PipelineConfig& options, cv::Size size, bool use_gcp_energy) {
  ViewSolver solver{options, size, {}, options.optimizer.energy, ExpansionOptionsOf(options)};
  solver.energy.use_gcp_energy = use_gcp_energy;
  solver.tiling.rows = options.tiling.tiles[0];
  solver.tiling.cols = options.tiling.tiles[1];
  solver.tiling.overlap_px = options.tiling.tile_overlap;
  solver.tiling.blend = options.optimizer.blend;
  return solver;
}

// A tile's share of the GCP energy's prior and its weights ρ_p (either may be empty).
void CropPrior(const EnergyPrior* prior, const cv::Rect& region,
               optimize::OwnedMrfProblem* problem) {
  if (prior == nullptr) return;
  if (!prior->prior.empty()) problem->prior = prior->prior(region).clone();
  if (!prior->weight.empty()) problem->prior_weight = prior->weight(region).clone();
}

// The tile problem of a rectified pair seen from `left` (Birchfield–Tomasi against `right`) with
// `prior` as the GCP energy's prior (none when null). With `solver` (graph cuts), only the labels
// its α-expansion and refinement can read are computed (optimize::CandidateLabelBands; every
// label unless its options allow fewer). `prior` is read when a tile is built, so it may be
// filled in after this call; it, `disparities` and `solver` must outlive the problem.
optimize::MakeTileProblem PairTileProblem(const cv::Mat& left, const cv::Mat& right,
                                          const std::vector<double>& disparities,
                                          const cost::BirchfieldTomasiOptions& options,
                                          const EnergyPrior* prior, const ViewSolver* solver) {
  return [left, right, &disparities, &options, prior, solver](const cv::Rect& region) {
    optimize::OwnedMrfProblem problem;
    problem.image = left(region).clone();
    CropPrior(prior, region, &problem);
    LabelBands bands;
    if (solver != nullptr && solver->options.optimizer.method != "wta") {
      bands = optimize::CandidateLabelBands(problem.prior, problem.prior_weight,
                                            static_cast<int>(disparities.size()), solver->expansion,
                                            solver->energy, false);
    }
    problem.data =
        cost::ComputeBirchfieldTomasiCost(left, right, disparities, region, options, &bands);
    problem.data_computed_share =
        bands.Fraction(region.size(), static_cast<int>(disparities.size()));
    return problem;
  };
}

// The tile problem of the plane sweep over every neighbour; as above for `prior`.
optimize::MakeTileProblem PlaneSweepTileProblem(const Dataset& dataset, const LabelSpace& labels,
                                                const cost::PlaneSweepOptions& options,
                                                const EnergyPrior* prior) {
  return [&dataset, &labels, &options, prior](const cv::Rect& region) {
    optimize::OwnedMrfProblem problem;
    problem.data =
        cost::ComputePlaneSweepCost(dataset.reference, dataset.neighbors, labels, region, options);
    problem.image = dataset.reference.image(region).clone();
    CropPrior(prior, region, &problem);
    return problem;
  };
}

// The segmentation that limits the GCP energy to the colour segments holding a GCP
// (optimizer.prior_segment_k > 0), else none.
std::optional<optimize::SegmentationOptions> PriorSegmentation(const PipelineConfig& options) {
  if (options.optimizer.prior_segment_k <= 0.0) return std::nullopt;
  optimize::SegmentationOptions segmentation = options.optimizer.plane_fit_options.segmentation;
  segmentation.k = options.optimizer.prior_segment_k;
  return segmentation;
}

// The left-right check's second problem: the neighbour as reference, solved on mirrored images so
// that every cost and GCP routine keeps its disparity convention; with the GCP energy, its prior
// is D̂ of the GCPs the neighbour sees, propagated over its mirrored image.
PartnerSolve SolveMirroredPartner(const PartnerInputs& in) {
  Timer timer;
  const PipelineConfig& options = in.options;
  const View& reference = in.dataset.reference;
  const bool use_gcp_energy = options.optimizer.energy.use_gcp_energy && !in.gcps.empty();
  ViewSolver solver = ViewSolverOf(options, reference.image.size(), use_gcp_energy);
  cv::Mat mirrored_reference, mirrored_neighbor;
  cv::flip(in.pair.neighbor->image, mirrored_reference, 1);
  cv::flip(reference.image, mirrored_neighbor, 1);
  EnergyPrior mirrored_prior;
  if (solver.energy.use_gcp_energy) {
    std::vector<cv::Point> mirrored_gcp_pixels;
    const cv::Mat sparse =
        MirroredPartnerGcpLabels(in.gcps, in.labels, reference.camera, in.pair.neighbor->camera,
                                 options.gcp.lidar, &mirrored_gcp_pixels);
    mirrored_prior.prior = EnergyPriorOf(
        options, PropagateLabels(mirrored_reference, sparse, in.labels, options.propagation).values,
        mirrored_gcp_pixels, mirrored_reference, PriorSegmentation(options));
    mirrored_prior.weight = optimize::SpreadPriorWeights(sparse, mirrored_reference, solver.energy);
  }
  const optimize::MakeTileProblem make_problem = PairTileProblem(
      mirrored_reference, mirrored_neighbor, in.pair.disparities, options.cost.birchfield_tomasi,
      solver.energy.use_gcp_energy ? &mirrored_prior : nullptr, &solver);
  PartnerSolve partner;
  partner.result = solver.Solve(make_problem, "");
  partner.seconds = timer.ElapsedSeconds();
  return partner;
}

json TilesJson(const optimize::TiledResult& optimized) {
  json tiles = json::array();
  for (const auto& tile : optimized.tiles) {
    const auto& e = tile.expansion;
    tiles.push_back(
        {{"region", {tile.region.x, tile.region.y, tile.region.width, tile.region.height}},
         {"cost_seconds", tile.setup_seconds},
         {"cost_entries_computed_percent", 100.0 * tile.data_computed_share},
         {"expansion_seconds", e.time_seconds},
         {"initial_energy", e.initial_energy},
         {"energy_per_cycle", e.energy_per_cycle},
         {"seconds_per_cycle", e.seconds_per_cycle},
         {"energy",
          {{"data", e.breakdown.data},
           {"smooth", e.breakdown.smooth},
           {"gcp", e.breakdown.gcp},
           {"total", e.breakdown.total()}}},
         {"cycles", e.cycles},
         {"converged", e.converged},
         {"moves_tried", e.moves_tried},
         {"moves_skipped", e.moves_skipped},
         {"mean_candidates_per_block", e.mean_candidates_per_block},
         {"unconfident_pixels", e.unconfident_pixels},
         {"refinement",
          {{"method", optimize::RefinementMethodName(tile.refinement.method)},
           {"pixels_moved", tile.refinement.pixels_moved},
           {"mean_abs_offset", tile.refinement.mean_abs_offset},
           {"iterations", tile.refinement.iterations},
           {"converged", tile.refinement.solver_converged},
           {"seconds", tile.refinement.time_seconds},
           {"initial_cost", tile.refinement.initial_cost},
           {"final_cost", tile.refinement.final_cost},
           {"linear_iterations", tile.refinement.linear_iterations},
           {"build_seconds", tile.refinement.build_seconds},
           {"solve_seconds", tile.refinement.solve_seconds}}}});
  }
  return tiles;
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

}  // namespace

std::future<PartnerSolve> StartPartnerSolve(const PartnerInputs& inputs) {
  // The load stage has checked that the check has a rectified pair (inputs.pair.neighbor).
  return std::async(std::launch::async, SolveMirroredPartner, std::cref(inputs));
}

EnergyPrior EnergyPriorStage(const PipelineConfig& options, const View& reference,
                             const GcpSet& gcps, const LabelSpace& labels,
                             const cv::Mat& propagated) {
  EnergyPrior result;
  std::vector<cv::Point> gcp_pixels;
  for (const Gcp& g : gcps.points) gcp_pixels.emplace_back(g.col, g.row);
  result.segmentation = PriorSegmentation(options);
  result.prior =
      EnergyPriorOf(options, propagated, gcp_pixels, reference.image, result.segmentation);
  const cv::Size size = reference.image.size();
  result.pixels_percent =
      propagated.empty() ? 0.0
                         : 100.0 * cv::countNonZero(result.prior == result.prior) / size.area();
  // ρ_p of eq. (10), as for the left-right partner (empty when optimizer.gcp_spread is 0).
  if (!propagated.empty()) {
    result.weight = optimize::SpreadPriorWeights(SparseGcpLabels(gcps, labels, size),
                                                 reference.image, options.optimizer.energy);
  }
  if (!result.weight.empty()) {
    const cv::Mat acts = result.prior == result.prior;
    if (cv::countNonZero(acts) > 0) result.weight_mean = cv::mean(result.weight, acts)[0];
    spdlog::info(
        "GCP weights from the GCPs' spread (τ {} labels): mean {:.3f} where the prior acts",
        options.optimizer.energy.gcp_spread, result.weight_mean);
  }
  if (!propagated.empty() &&
      (options.optimizer.prior_radius_px > 0.0 || result.segmentation.has_value())) {
    spdlog::info("GCP energy on {:.1f} % of the pixels (within {} px of a GCP{})",
                 result.pixels_percent, options.optimizer.prior_radius_px,
                 result.segmentation ? ", in colour segments holding one" : "");
  }
  return result;
}

cv::Mat GcpWeightPreview(const EnergyPrior& prior, const cv::Mat& image_bgr) {
  if (prior.weight.empty() || prior.prior.empty()) return {};
  cv::Mat picture;
  cv::cvtColor(image_bgr, picture, cv::COLOR_BGR2GRAY);
  cv::cvtColor(picture * 0.3, picture, cv::COLOR_GRAY2BGR);  // no prior: the image, dimmed
  for (int r = 0; r < picture.rows; ++r) {
    const float* value = prior.prior.ptr<float>(r);
    const float* weight = prior.weight.ptr<float>(r);
    for (int c = 0; c < picture.cols; ++c) {
      if (!std::isfinite(value[c])) continue;
      const auto grey = cv::saturate_cast<std::uint8_t>(255.0f * weight[c]);
      picture.at<cv::Vec3b>(r, c) = cv::Vec3b(grey, grey, grey);
    }
  }
  return picture;
}

PairLabels PairLabelsOf(const Dataset& dataset, const LabelSpace& labels,
                        const std::string& cost_method) {
  PairLabels pair;
  if (cost_method != "birchfield_tomasi") return pair;
  const RectifiedPair rectified = FindRectifiedPair(dataset, "cost.method");
  pair.neighbor = rectified.neighbor;
  for (int l = 0; l < labels.count(); ++l) {
    const double depth = labels.DepthOfLabel(l);
    pair.disparities.push_back(std::isfinite(depth) ? rectified.numerator / depth : 0.0);
  }
  return pair;
}

OptimizeResult OptimizeStage(const OptimizeInputs& in) {
  const PipelineConfig& options = in.options;
  const View& reference = in.dataset.reference;
  const bool use_gcp_energy = options.optimizer.energy.use_gcp_energy && !in.gcps.empty();
  const ViewSolver solver = ViewSolverOf(options, reference.image.size(), use_gcp_energy);
  const EnergyPrior* prior = use_gcp_energy ? &in.prior : nullptr;
  const optimize::MakeTileProblem make_problem =
      in.cost_method == "birchfield_tomasi"
          ? PairTileProblem(reference.image, in.pair.neighbor->image, in.pair.disparities,
                            options.cost.birchfield_tomasi, prior, &solver)
          : PlaneSweepTileProblem(in.dataset, in.labels, options.cost.plane_sweep, prior);
  OptimizeResult result;
  result.optimized = solver.Solve(
      make_problem, options.optimizer.left_right_check ? "graph cuts, both views" : "graph cuts");
  result.stage_report = {
      {"method", options.optimizer.method},
      {"cost_method", in.cost_method},
      {"gcp_energy", use_gcp_energy},
      {"gcp_energy_pixels_percent", use_gcp_energy ? in.prior.pixels_percent : 0.0},
      {"gcp_spread_weight_mean", in.prior.weight_mean},
      {"tiles", TilesJson(result.optimized)},
      {"energy_sum", result.optimized.energy_sum}};
  return result;
}

LeftRightCheckResult LeftRightCheckStage(const PipelineConfig& options, const Dataset& dataset,
                                         const LabelSpace& labels, const GcpSet& gcps,
                                         const PairLabels& pair, OptimizeResult& optimized) {
  const cv::Mat& image = dataset.reference.image;
  const cv::Size size = image.size();
  const double numerator = dataset.disparity_numerator;
  // The stage's time is the wait for the second solve plus the fill; partner.seconds is that
  // solve's own wall time (it overlapped the first).
  const PartnerSolve partner = optimized.partner.get();  // rethrows its errors
  cv::Mat partner_labels;
  cv::flip(partner.result.labels, partner_labels, 1);
  const cv::Mat partner_disparity = LabelMapToDisparity(partner_labels, labels, numerator);
  LeftRightCheckResult result;
  result.labels = optimized.optimized.labels.clone();
  cv::Mat own_disparity = LabelMapToDisparity(result.labels, labels, numerator);
  const double max_difference_px = options.optimizer.left_right_max_difference_px;
  const cv::Mat consistent =
      optimize::LeftRightConsistent(own_disparity, partner_disparity, max_difference_px);
  const int inconsistent = size.area() - cv::countNonZero(consistent);
  if (options.optimizer.plane_fit) {
    result.frozen =
        optimize::LeftRightOccluded(own_disparity, partner_disparity, max_difference_px);
  }
  // A half-occluded band is at most as wide as the label range in pixels of disparity.
  const auto [min_disparity, max_disparity] =
      std::minmax_element(pair.disparities.begin(), pair.disparities.end());
  const int max_run_px = static_cast<int>(std::ceil(*max_disparity - *min_disparity));
  const bool restore = options.optimizer.left_right_gcp_radius_px > 0;
  const cv::Mat labels_before_fill = restore ? result.labels.clone() : cv::Mat();
  const cv::Mat disparity_before_fill = restore ? own_disparity.clone() : cv::Mat();
  cv::Mat checked = consistent.clone();  // becomes 255 where a GCP keeps the optimised value
  const int filled =
      optimize::FillFromBackground(checked, max_run_px, &result.labels, &own_disparity);
  int restored = 0;
  if (restore) {
    restored = optimize::RestoreGcpConfirmed(
        SparseGcpDisparity(gcps, numerator, size), options.optimizer.left_right_gcp_radius_px,
        labels_before_fill, disparity_before_fill, &checked, &result.labels, &own_disparity);
  }
  int smoothed = 0;
  if (options.optimizer.left_right_median_radius_px > 0) {
    smoothed = optimize::WeightedMedianOfFilled(
        image, checked, options.optimizer.left_right_median_radius_px,
        options.optimizer.left_right_median_sigma, &result.labels, &own_disparity);
  }
  result.preview = RenderInconsistent(image, consistent, checked);
  if (options.optimizer.plane_fit) result.support = checked;
  spdlog::info("left-right check: {} pixels ({:.2f} %) inconsistent, {} filled, {} kept by GCPs",
               inconsistent, 100.0 * inconsistent / size.area(), filled, restored);
  result.stage_report = {{"max_difference_px", max_difference_px},
                         {"inconsistent_pixels", inconsistent},
                         {"inconsistent_percent", 100.0 * inconsistent / size.area()},
                         {"filled_pixels", filled},
                         {"max_fill_run_px", max_run_px},
                         {"gcp_restored_pixels", restored},
                         {"median_changed_pixels", smoothed},
                         {"partner_energy_sum", partner.result.energy_sum},
                         {"partner_seconds", partner.seconds}};
  return result;
}

PlaneFitResult PlaneFitStage(const PipelineConfig& options, const Dataset& dataset,
                             const LabelSpace& labels, const cv::Mat& label_map,
                             const LeftRightCheckResult& left_right) {
  const cv::Mat& image = dataset.reference.image;
  // With the left-right check, only consistent pixels support the fit and pixels occluded in the
  // right view keep their background fill.
  cv::Mat fitted = LabelMapToDisparity(label_map, labels, dataset.disparity_numerator);
  const cv::Mat before = fitted.clone();
  const optimize::PlaneFitSummary summary = optimize::FitSegmentPlanes(
      image, left_right.support, left_right.frozen, options.optimizer.plane_fit_options, &fitted);
  PlaneFitResult result;
  result.preview = RenderPlaneFit(image, summary.segment_labels, before, fitted);
  // Only the changed pixels get new labels: the others keep theirs bit for bit.
  result.labels = label_map.clone();
  DisparityMapToLabels(fitted, labels, dataset.disparity_numerator)
      .copyTo(result.labels, cv::abs(before - fitted) > 0.0f);
  spdlog::info("plane fit: {} of {} colour segments fitted, {} pixels changed",
               summary.fitted_segments, summary.segments, summary.changed_pixels);
  result.stage_report = {{"segments", summary.segments},
                         {"fitted_segments", summary.fitted_segments},
                         {"changed_pixels", summary.changed_pixels},
                         {"changed_percent", 100.0 * summary.changed_pixels / image.size().area()}};
  return result;
}

}  // namespace gcpstereo::pipeline::internal
