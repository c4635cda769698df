// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/gcp/sweep_motion.h"

#include <cmath>
#include <memory>
#include <vector>

#include <pcl/common/point_tests.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/search/kdtree.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/nearest_points.h"

namespace gcpstereo::gcp {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr size_t kMaxCoarsePoints = 4000;

using PclCloud = pcl::PointCloud<pcl::PointXYZ>;

// The points within [min_range, max_range] of the sensor (horizontal range), voxel-filtered.
PclCloud::Ptr ForRegistration(const PointCloud& scan, const ScanRegistrationOptions& options,
                              double voxel) {
  PclCloud::Ptr kept(new PclCloud);
  kept->reserve(scan.size());
  for (const Eigen::Vector3f& p : scan.points) {
    if (!p.allFinite()) continue;
    const double range = std::hypot(p.x(), p.y());
    if (range < options.min_range || range > options.max_range) continue;
    kept->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  PclCloud::Ptr filtered(new PclCloud);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(kept);
  grid.setLeafSize(static_cast<float>(voxel), static_cast<float>(voxel), static_cast<float>(voxel));
  grid.filter(*filtered);
  return filtered;
}

// pcl::search::KdTree answering its nearest-neighbour queries with NearestPoints: the same tree
// and exact search as PCL's, without the OpenMP region Debian's PCL opens for every query (ICP
// asks one per point and iteration: two thirds of a registration's time went there; KITTI frame
// 20's two registrations 0.78 → 0.29 s, the same results).
class SerialKdTree : public pcl::search::KdTree<pcl::PointXYZ> {
 public:
  using pcl::search::KdTree<pcl::PointXYZ>::nearestKSearch;

  void setInputCloud(const PointCloudConstPtr& cloud,
                     const pcl::IndicesConstPtr& indices = pcl::IndicesConstPtr()) override {
    input_ = cloud;
    indices_ = indices;
    std::vector<Eigen::Vector3f> points;
    cloud_index_.clear();
    auto add = [&](int i) {
      const pcl::PointXYZ& p = (*cloud)[i];
      points.emplace_back(p.x, p.y, p.z);
      cloud_index_.push_back(i);
    };
    if (indices != nullptr) {
      for (const int i : *indices) add(i);
    } else {
      for (int i = 0; i < static_cast<int>(cloud->size()); ++i) add(i);
    }
    nearest_ = NearestPoints(points);
  }

  int nearestKSearch(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override {
    k_indices.resize(std::max(k, 0));
    k_sqr_distances.resize(std::max(k, 0));
    const int found = nearest_.Nearest(Eigen::Vector3f(point.x, point.y, point.z), k,
                                       k_indices.data(), k_sqr_distances.data());
    k_indices.resize(found);
    k_sqr_distances.resize(found);
    for (int& i : k_indices) i = cloud_index_[i];
    return found;
  }

  int radiusSearch(const pcl::PointXYZ&, double, pcl::Indices&, std::vector<float>&,
                   unsigned int) const override {
    throw Error("SerialKdTree: radius search is not implemented (point-to-point ICP needs none)");
  }

 private:
  NearestPoints nearest_;
  std::vector<int> cloud_index_;  // the cloud's index of each point given to nearest_
};

// A tree over `cloud`.
std::shared_ptr<SerialKdTree> TreeOf(const PclCloud::Ptr& cloud) {
  auto tree = std::make_shared<SerialKdTree>();
  tree->setInputCloud(cloud);
  return tree;
}

struct Fit {
  Eigen::Matrix4f transform = Eigen::Matrix4f::Identity();
  double inlier_fraction = 0.0;
  double rmse = 0.0;
};

// Inlier fraction and RMSE of `source` moved by `transform` against `target`.
Fit Score(const PclCloud& source, const SerialKdTree& target,
          const Eigen::Matrix4f& transform, double inlier_distance) {
  Fit fit;
  fit.transform = transform;
  if (source.empty()) return fit;
  std::vector<int> index(1);
  std::vector<float> distance2(1);
  int inliers = 0;
  double sum2 = 0.0;
  const float max2 = static_cast<float>(inlier_distance * inlier_distance);
  for (const pcl::PointXYZ& p : source.points) {
    const Eigen::Vector4f q = transform * Eigen::Vector4f(p.x, p.y, p.z, 1.0f);
    if (target.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, index, distance2) == 1 &&
        distance2[0] <= max2) {
      ++inliers;
      sum2 += distance2[0];
    }
  }
  fit.inlier_fraction = static_cast<double>(inliers) / static_cast<double>(source.size());
  fit.rmse = inliers > 0 ? std::sqrt(sum2 / inliers) : 0.0;
  return fit;
}

// Point-to-point ICP against one target (its k-d tree is built once for every alignment).
class Icp {
 public:
  Icp(const PclCloud::Ptr& source, const PclCloud::Ptr& target,
      const std::shared_ptr<SerialKdTree>& target_tree) {
    icp_.setInputSource(source);
    icp_.setInputTarget(target);
    icp_.setSearchMethodTarget(target_tree, true);  // built over `target` already
    icp_.setTransformationEpsilon(1e-9);
    icp_.setEuclideanFitnessEpsilon(1e-9);
  }
  Eigen::Matrix4f Align(const Eigen::Matrix4f& guess, double max_correspondence, int iterations) {
    icp_.setMaxCorrespondenceDistance(max_correspondence);
    icp_.setMaximumIterations(iterations);
    PclCloud aligned;
    icp_.align(aligned, guess);
    return icp_.getFinalTransformation();
  }

 private:
  pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp_;
};

// reference_from_other by a coarse multi-start ICP and a fine refinement of the best start.
ScanRegistrationSummary Register(const PointCloud& reference, const TimedScan& other,
                                 const ScanRegistrationOptions& options) {
  ScanRegistrationSummary summary;
  summary.name = other.name;
  summary.seconds_after_reference = other.seconds_after_reference;

  const PclCloud::Ptr target_coarse = ForRegistration(reference, options, 2.0 * options.voxel);
  PclCloud::Ptr source_coarse = ForRegistration(*other.scan, options, 2.0 * options.voxel);
  if (target_coarse->size() < 10 || source_coarse->size() < 10) return summary;
  // The starts only have to find the right basin: a few thousand source points do.
  if (source_coarse->size() > kMaxCoarsePoints) {
    PclCloud::Ptr thinned(new PclCloud);
    const size_t stride = (source_coarse->size() + kMaxCoarsePoints - 1) / kMaxCoarsePoints;
    for (size_t i = 0; i < source_coarse->size(); i += stride) {
      thinned->push_back((*source_coarse)[i]);
    }
    source_coarse = thinned;
  }
  // The starts are independent: in parallel (each with its own ICP and k-d tree), the best
  // taken in the starts' order, so the result does not depend on the threads.
  const std::vector<double>& speeds = options.initial_speeds_mps;
  std::vector<Fit> fits(speeds.size());
  tbb::parallel_for(size_t{0}, speeds.size(), [&](size_t i) {
    const std::shared_ptr<SerialKdTree> tree_coarse = TreeOf(target_coarse);
    Icp coarse_icp(source_coarse, target_coarse, tree_coarse);
    // The other scan's points seen from the reference pose: displaced by the distance driven.
    Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
    guess(0, 3) = static_cast<float>(speeds[i] * other.seconds_after_reference);
    Eigen::Matrix4f coarse = coarse_icp.Align(guess, 5.0, 10);
    coarse = coarse_icp.Align(coarse, 1.5, 10);
    fits[i] = Score(*source_coarse, *tree_coarse, coarse, 2.0 * options.inlier_distance);
  });
  Fit best;
  best.inlier_fraction = -1.0;  // any start beats it
  for (const Fit& fit : fits) {
    if (fit.inlier_fraction > best.inlier_fraction) best = fit;
  }

  const PclCloud::Ptr target = ForRegistration(reference, options, options.voxel);
  const PclCloud::Ptr source = ForRegistration(*other.scan, options, options.voxel);
  const std::shared_ptr<SerialKdTree> tree = TreeOf(target);
  Icp fine_icp(source, target, tree);
  Eigen::Matrix4f fine = fine_icp.Align(best.transform, 1.0, 10);
  fine = fine_icp.Align(fine, 3.0 * options.inlier_distance, 15);
  const Fit fit = Score(*source, *tree, fine, options.inlier_distance);

  summary.reference_from_other = fit.transform.cast<double>();
  summary.inlier_fraction = fit.inlier_fraction;
  summary.rmse = fit.rmse;
  summary.used = fit.inlier_fraction >= options.min_inlier_fraction;
  return summary;
}

}  // namespace

void SweepOptions::Check() const {
  if (!(period_s > 0.0) || !std::isfinite(period_s)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.motion.sweep_period_s", FormatNumber(period_s),
                                         "sweep_period_s > 0"));
  }
  if (!(trigger_azimuth_deg >= -180.0 && trigger_azimuth_deg <= 180.0)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.motion.trigger_azimuth_deg",
                                         FormatNumber(trigger_azimuth_deg),
                                         "-180 <= trigger_azimuth_deg <= 180"));
  }
}

void LidarMotionOptions::Check() const {
  if (mode != "off" && mode != "given" && mode != "registration") {
    throw ConfigError(ViolatedConstraint("gcp.lidar.motion.mode", "'" + mode + "'",
                                         "one of 'off', 'given', 'registration'"));
  }
  if (!std::isfinite(speed_mps)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.motion.speed_mps", FormatNumber(speed_mps),
                                         "a finite speed"));
  }
  if (!std::isfinite(yaw_rate_deg_s)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.motion.yaw_rate_deg_s",
                                         FormatNumber(yaw_rate_deg_s), "a finite yaw rate"));
  }
  if (!(max_gap_s > 0.0) || !std::isfinite(max_gap_s)) {
    throw ConfigError(
        ViolatedConstraint("gcp.lidar.motion.max_gap_s", FormatNumber(max_gap_s), "max_gap_s > 0"));
  }
  if (!(registration.min_inlier_fraction >= 0.0 && registration.min_inlier_fraction <= 1.0)) {
    throw ConfigError(ViolatedConstraint("gcp.lidar.motion.min_inlier_fraction",
                                         FormatNumber(registration.min_inlier_fraction),
                                         "0 <= min_inlier_fraction <= 1"));
  }
  sweep.Check();
}

double SweepTimeOffset(const Eigen::Vector3f& point, const SweepOptions& options) {
  const double azimuth = std::atan2(static_cast<double>(point.y()), static_cast<double>(point.x()));
  double delta = azimuth - options.trigger_azimuth_deg * kPi / 180.0;  // wrapped to (−π, π]
  while (delta > kPi) delta -= 2.0 * kPi;
  while (delta <= -kPi) delta += 2.0 * kPi;
  // Clockwise: the azimuth decreases with time, so a point at a larger azimuth came earlier.
  const double turns = (options.clockwise ? -delta : delta) / (2.0 * kPi);
  return turns * options.period_s;
}

PointCloud CompensateSweepMotion(const PointCloud& scan, const SweepMotion& motion,
                                 const SweepOptions& options) {
  options.Check();
  PointCloud out = scan;
  for (Eigen::Vector3f& p : out.points) {
    if (!p.allFinite()) continue;
    const double t = SweepTimeOffset(p, options);
    const Eigen::Vector3d moved =
        Eigen::AngleAxisd(motion.yaw_rate_rad_s * t, Eigen::Vector3d::UnitZ()) * p.cast<double>() +
        motion.velocity * t;
    p = moved.cast<float>();
  }
  return out;
}

SweepMotionEstimate EstimateSweepMotion(const PointCloud& reference,
                                        const std::vector<TimedScan>& others,
                                        const ScanRegistrationOptions& options) {
  SweepMotionEstimate estimate;
  int used = 0;
  Eigen::Vector3d velocity_sum = Eigen::Vector3d::Zero();
  double yaw_rate_sum = 0.0;
  for (const TimedScan& other : others) {
    if (other.scan == nullptr) {
      throw Error("EstimateSweepMotion: scan '" + other.name + "' is null");
    }
    if (!(std::abs(other.seconds_after_reference) > 0.0)) {
      throw Error("EstimateSweepMotion: scan '" + other.name +
                  "' was taken at the reference's time (seconds_after_reference = 0)");
    }
  }
  // The registrations are independent (one per core); their results are combined in input order.
  std::vector<ScanRegistrationSummary> summaries(others.size());
  tbb::parallel_for(size_t{0}, others.size(),
                    [&](size_t i) { summaries[i] = Register(reference, others[i], options); });
  for (size_t i = 0; i < others.size(); ++i) {
    const TimedScan& other = others[i];
    ScanRegistrationSummary& summary = summaries[i];
    if (summary.used) {
      const double dt = other.seconds_after_reference;
      const Eigen::Matrix3d rotation = summary.reference_from_other.topLeftCorner<3, 3>();
      velocity_sum += summary.reference_from_other.topRightCorner<3, 1>() / dt;
      yaw_rate_sum += std::atan2(rotation(1, 0), rotation(0, 0)) / dt;
      ++used;
    }
    estimate.registrations.push_back(std::move(summary));
  }
  if (used == 0) {
    estimate.message = others.empty() ? "no other scan to register with"
                                      : "no registration reached the inlier fraction " +
                                            FormatNumber(options.min_inlier_fraction);
    return estimate;
  }
  estimate.valid = true;
  estimate.motion.velocity = velocity_sum / used;
  estimate.motion.yaw_rate_rad_s = yaw_rate_sum / used;
  return estimate;
}

}  // namespace gcpstereo::gcp
