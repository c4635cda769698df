// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/align/similarity_alignment.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <utility>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/nearest_points.h"

namespace gcpstereo::align {
namespace {

constexpr double kPi = 3.14159265358979323846;
using PclCloud = pcl::PointCloud<pcl::PointXYZ>;

// `count` rotations drawn uniformly from SO(3) (Shoemake's subgroup algorithm on three uniform
// numbers), from std::mt19937's raw output so that every platform draws the same ones.
std::vector<Eigen::Matrix3d> UniformRotations(int count, unsigned seed) {
  std::mt19937 rng(seed);
  auto uniform = [&rng]() { return (static_cast<double>(rng()) + 0.5) / 4294967296.0; };
  std::vector<Eigen::Matrix3d> rotations;
  for (int k = 0; k < count; ++k) {
    const double u1 = uniform(), u2 = uniform(), u3 = uniform();
    const Eigen::Quaterniond q(
        std::sqrt(u1) * std::cos(2.0 * kPi * u3), std::sqrt(1.0 - u1) * std::sin(2.0 * kPi * u2),
        std::sqrt(1.0 - u1) * std::cos(2.0 * kPi * u2), std::sqrt(u1) * std::sin(2.0 * kPi * u3));
    rotations.push_back(q.normalized().toRotationMatrix());
  }
  return rotations;
}

// Scan registration constants (not keys: they shape the search, not the acceptance).
constexpr size_t kCoarseModelPoints = 400;   // model points of each coarse hypothesis's ICP
constexpr size_t kCoarseScanPoints = 20000;  // scan points the coarse hypotheses are scored on
// Coarse ICP by successive halving: every hypothesis gets kCoarseIterations steps, the best
// kCoarseKeepShare of them (by score) as many again, then the best share of those up to
// kCoarseFinalIterations more, until they stop moving. Trimmed point-to-point ICP with scale
// converges slowly from 20-25° off: on a COLMAP model of the synthetic fountain the hypotheses
// in the true pose's basin ranked 5th-11th of 360 after 10 steps, still 19-24° and 20-40 % in
// scale off, and the best after 10 steps was a wrong pose 77° away (README, "COLMAP models").
constexpr int kCoarseIterations = 10;        // ICP steps of every coarse hypothesis
constexpr double kCoarseKeepShare = 0.25;    // the share kept at each halving (at least one)
constexpr int kCoarseFinalIterations = 100;  // at most, for the last share
constexpr double kCoarseTolerance = 1e-6;    // relative change that counts as converged
// The principal axes of a model that covers part of the scan, or samples it unevenly (SfM points
// lie where the images are textured), need not pair with the scan's: on a second COLMAP model
// no axis pairing started within 20° of the true pose. The first round adds rotations drawn
// uniformly (Shoemake 1992; fixed seed, so deterministic) at these scales × the spreads' ratio.
constexpr int kRandomRotations = 200;
constexpr std::array<double, 3> kRandomScaleFactors = {0.5, 0.7, 1.0};
constexpr unsigned kRandomSeed = 20111;
// The fine stage starts from the best few distinct coarse results (distinct: the aligned model's
// centroid kDistinctShift of its spread apart, or turned kDistinctDeg): the coarse score, on
// 400 model and 20 000 scan points, ranked first a pose 6° off from which the fine stage slid
// 0.9 m on one COLMAP model; with the next two tried as well, it converged there.
constexpr int kFineCandidates = 3;
constexpr double kDistinctShift = 0.05;
constexpr double kDistinctDeg = 5.0;
constexpr double kCoarseKeep = 0.6;         // coarse ICP: the closest 60 % of the pairs
constexpr double kFineKeep = 0.7;           // final ICP: at least the closest 70 %
constexpr size_t kFineSubsetPoints = 2000;  // final ICP, first on this many model points
constexpr int kPlaneIterations = 30;        // final point-to-plane steps
constexpr int kMaxFineIterations = 300;     // per stage of the final ICP
constexpr std::array<double, 5> kScaleFactors = {0.35, 0.5, 0.7, 1.0, 1.4};  // × spreads' ratio
constexpr int kCoarseRounds = 3;  // coarse searches, each on the scan part the last one covered
// The fine stage's restarts: the aligned model turned by this about each of its principal axes,
// shifted by this fraction of its spread along each, and scaled by 1 ± this (both signs: 14
// restarts). A few degrees and per cent: a wrong minimum along a wall lay 3-3.6° and 0.64 % in
// scale from the truth on a COLMAP model of the synthetic fountain.
constexpr double kRestartRotationDeg = 3.0;
constexpr double kRestartShift = 0.03;
constexpr double kRestartScale = 0.03;
// Point-to-point steps of a restart before its point-to-plane steps: enough to pull the pairs back
// within max_residual, not to crawl along a plane (which the plane steps do not need).
constexpr int kRestartIterations = 50;
// "About as good": a median distance to the scan's tangent planes within the two-sided 95 %
// confidence interval of the best's median, from the order statistics (ranks n/2 ± 1.96 √n / 2,
// distribution-free): the objective cannot tell two such transforms apart.
constexpr double kMedianConfidenceZ = 1.96;

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The q-quantile (nearest rank) of `values` (not empty).
double Quantile(std::vector<double> values, double q) {
  const size_t n = values.size();
  const size_t rank = std::min(
      n - 1, static_cast<size_t>(std::max(0.0, std::ceil(q * static_cast<double>(n)) - 1.0)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(rank),
                   values.end());
  return values[rank];
}

// Every k-th element, at most `max_count` of them.
template <typename T>
std::vector<T> EveryKth(const std::vector<T>& all, size_t max_count) {
  if (all.size() <= max_count) return all;
  const size_t step = (all.size() + max_count - 1) / max_count;
  std::vector<T> kept;
  for (size_t i = 0; i < all.size(); i += step) kept.push_back(all[i]);
  return kept;
}

// The similarity in a 4×4 matrix, without the checks of FromMatrix (a degenerate sample's fit
// is rejected by its caller).
Similarity Decompose(const Eigen::Matrix4d& m) {
  Similarity s;
  const Eigen::Matrix3d sr = m.topLeftCorner<3, 3>();
  s.scale = std::sqrt((sr.transpose() * sr).trace() / 3.0);
  s.rotation = s.scale > 0.0 ? Eigen::Matrix3d(sr / s.scale) : Eigen::Matrix3d::Identity();
  s.translation = m.topRightCorner<3, 1>();
  return s;
}

bool IsValid(const Similarity& s) {
  return std::isfinite(s.scale) && s.scale > 0.0 && s.rotation.allFinite() &&
         s.translation.allFinite() && s.rotation.determinant() > 0.5;
}

Similarity FitSimilarity(const std::vector<Eigen::Vector3d>& model,
                         const std::vector<Eigen::Vector3d>& world, const std::vector<int>& which) {
  Eigen::Matrix3Xd src(3, which.size()), dst(3, which.size());
  for (size_t i = 0; i < which.size(); ++i) {
    src.col(static_cast<Eigen::Index>(i)) = model[which[i]];
    dst.col(static_cast<Eigen::Index>(i)) = world[which[i]];
  }
  return Decompose(Eigen::umeyama(src, dst, /*with_scaling=*/true));
}

// σ₂ / σ₁ of the centred points: 0 for collinear points.
double NonCollinearity(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& which) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : which) mean += points[i];
  mean /= static_cast<double>(which.size());
  Eigen::Matrix3Xd centred(3, which.size());
  for (size_t i = 0; i < which.size(); ++i) {
    centred.col(static_cast<Eigen::Index>(i)) = points[which[i]] - mean;
  }
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3Xd>(centred).singularValues();
  return sv(0) > 0.0 ? sv(1) / sv(0) : 0.0;
}

// Residual statistics of `residuals` (world units) and the aligned points' spread.
void FillStatistics(const std::vector<double>& residuals,
                    const std::vector<Eigen::Vector3d>& aligned, double max_residual,
                    AlignmentResult* result) {
  result->num_correspondences = static_cast<int>(residuals.size());
  result->num_inliers = static_cast<int>(std::count_if(
      residuals.begin(), residuals.end(), [max_residual](double r) { return r <= max_residual; }));
  result->inlier_share = residuals.empty() ? 0.0
                                           : static_cast<double>(result->num_inliers) /
                                                 static_cast<double>(residuals.size());
  result->median_residual = Quantile(residuals, 0.5);
  result->p90_residual = Quantile(residuals, 0.9);
  double sum2 = 0.0;
  for (double r : residuals) sum2 += r * r;
  result->rms_residual = std::sqrt(sum2 / static_cast<double>(residuals.size()));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : aligned) mean += p;
  mean /= static_cast<double>(aligned.size());
  double spread2 = 0.0;
  for (const Eigen::Vector3d& p : aligned) spread2 += (p - mean).squaredNorm();
  result->model_spread = std::sqrt(spread2 / static_cast<double>(aligned.size()));
  result->relative_median_residual = result->model_spread > 0.0
                                         ? result->median_residual / result->model_spread
                                         : std::numeric_limits<double>::infinity();
}

// ---- Registration to a scan ---------------------------------------------------------------

// A scan with its k-d tree (NearestPoints: the tree PCL builds, without its per-query OpenMP
// region).
class ScanIndex {
 public:
  explicit ScanIndex(PclCloud::Ptr cloud) : cloud_(std::move(cloud)), tree_(Points(*cloud_)) {}
  // The nearest scan point to `x` and its distance.
  double Nearest(const Eigen::Vector3d& x, Eigen::Vector3d* nearest) const {
    const int i = NearestIndex(x);
    if (i < 0) return std::numeric_limits<double>::infinity();
    const pcl::PointXYZ& p = (*cloud_)[i];
    *nearest = Eigen::Vector3d(p.x, p.y, p.z);
    return (*nearest - x).norm();
  }
  const PclCloud& cloud() const { return *cloud_; }

  // The nearest scan point's index (-1 when none).
  int NearestIndex(const Eigen::Vector3d& x) const {
    int index = -1;
    float distance2 = 0.0f;
    return tree_.Nearest(x.cast<float>(), 1, &index, &distance2) == 1 ? index : -1;
  }
  Eigen::Vector3d Point(int i) const {
    const pcl::PointXYZ& p = (*cloud_)[i];
    return Eigen::Vector3d(p.x, p.y, p.z);
  }
  // The scan's surface normal at point i: the least principal axis of its kNormalNeighbours
  // nearest points (computed once per point, when first asked); zero where they are collinear.
  Eigen::Vector3d Normal(int i) const {
    if (normals_.empty()) normals_.assign(cloud_->size(), Eigen::Vector3f::Constant(NAN));
    Eigen::Vector3f& n = normals_[i];
    if (std::isnan(n.x())) {
      int neighbours[kNormalNeighbours];
      float distances[kNormalNeighbours];
      const int found =
          tree_.Nearest(Point(i).cast<float>(), kNormalNeighbours, neighbours, distances);
      std::vector<Eigen::Vector3d> points;
      for (int k = 0; k < found; ++k) points.push_back(Point(neighbours[k]));
      n.setZero();
      if (points.size() >= 3) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const auto& p : points) mean += p;
        mean /= static_cast<double>(points.size());
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        for (const auto& p : points) covariance += (p - mean) * (p - mean).transpose();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
        if (eigen.eigenvalues()(1) > 1e-12 * eigen.eigenvalues()(2)) {
          n = eigen.eigenvectors().col(0).cast<float>();
        }
      }
    }
    return n.cast<double>();
  }

 private:
  static constexpr int kNormalNeighbours = 12;
  static std::vector<Eigen::Vector3f> Points(const PclCloud& cloud) {
    std::vector<Eigen::Vector3f> points;
    points.reserve(cloud.size());
    for (const pcl::PointXYZ& p : cloud.points) points.emplace_back(p.x, p.y, p.z);
    return points;
  }
  PclCloud::Ptr cloud_;
  NearestPoints tree_;
  mutable std::vector<Eigen::Vector3f> normals_;
};

// One point-to-plane step (Chen & Medioni 1992) with scale: the small update
// x -> (1 + σ)(x + ω × x) + τ minimising Σ (n · (x' − q))² over the pairs within `limit`
// (q the nearest scan point, n the scan's normal there), linearised and solved by least squares,
// then composed with `s`. Point-to-point ICP slides slowly along planes and stops short (a degree
// off on the synthetic fountain); the plane distances converge in a few steps.
Similarity PlaneStep(const std::vector<Eigen::Vector3d>& model, const ScanIndex& scan,
                     const Similarity& s, double limit) {
  Eigen::Matrix<double, 7, 7> normal_matrix = Eigen::Matrix<double, 7, 7>::Zero();
  Eigen::Matrix<double, 7, 1> rhs = Eigen::Matrix<double, 7, 1>::Zero();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : model) centre += s.Apply(p);
  centre /= static_cast<double>(model.size());
  int used = 0;
  for (const Eigen::Vector3d& p : model) {
    const Eigen::Vector3d x = s.Apply(p) - centre;  // about the centre: a better-conditioned σ
    const int i = scan.NearestIndex(x + centre);
    if (i < 0) continue;
    const Eigen::Vector3d q = scan.Point(i) - centre;
    if ((q - x).norm() > limit) continue;
    const Eigen::Vector3d n = scan.Normal(i);
    if (n.isZero()) continue;
    Eigen::Matrix<double, 7, 1> row;
    row << x.cross(n), n, n.dot(x);  // ω, τ, σ
    const double r = n.dot(q - x);
    normal_matrix += row * row.transpose();
    rhs += row * r;
    ++used;
  }
  if (used < 7) return s;
  const Eigen::Matrix<double, 7, 1> d = normal_matrix.ldlt().solve(rhs);
  if (!d.allFinite()) return s;
  const Eigen::Vector3d omega = d.head<3>();
  const Eigen::Matrix3d r =
      omega.norm() > 0.0 ? Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix()
                         : Eigen::Matrix3d::Identity();
  const double sigma = d(6);
  const Eigen::Vector3d tau = d.segment<3>(3);
  // x' = (1 + σ) R (x_w − c) + τ + c with x_w = s R_s p + t_s.
  Similarity next;
  next.scale = (1.0 + sigma) * s.scale;
  next.rotation = r * s.rotation;
  next.translation = (1.0 + sigma) * (r * (s.translation - centre)) + tau + centre;
  return IsValid(next) ? next : s;
}

// Each model point's residual (distance to its nearest scan point) under `s`; the nearest points
// in `nearest` when given.
std::vector<double> ScanResiduals(const std::vector<Eigen::Vector3d>& model, const ScanIndex& scan,
                                  const Similarity& s,
                                  std::vector<Eigen::Vector3d>* nearest = nullptr) {
  std::vector<double> residuals(model.size());
  if (nearest) nearest->resize(model.size());
  Eigen::Vector3d y = Eigen::Vector3d::Zero();  // set by Nearest unless no point is found
  for (size_t i = 0; i < model.size(); ++i) {
    residuals[i] = scan.Nearest(s.Apply(model[i]), &y);
    if (nearest) (*nearest)[i] = y;
  }
  return residuals;
}

// Each model point's residual under `s` as the point-to-plane steps see it: for a point within
// `limit` of its nearest scan point, its distance to that point's tangent plane (to the point
// where the scan has no normal there); beyond, its distance to the point. Unlike the distance to
// the nearest point it does not change as the model slides along a surface, so it neither rewards
// nor penalises where the model sits relative to the scan's sampling grid; a point that leaves
// the scan's surfaces keeps its whole distance.
std::vector<double> PlaneResiduals(const std::vector<Eigen::Vector3d>& model, const ScanIndex& scan,
                                   const Similarity& s, double limit) {
  std::vector<double> residuals(model.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < model.size(); ++i) {
    const Eigen::Vector3d x = s.Apply(model[i]);
    const int k = scan.NearestIndex(x);
    if (k < 0) continue;
    const double distance = (scan.Point(k) - x).norm();
    const Eigen::Vector3d n = distance <= limit ? scan.Normal(k) : Eigen::Vector3d::Zero();
    residuals[i] = n.isZero() ? distance : std::abs(n.dot(scan.Point(k) - x));
  }
  return residuals;
}

// One ICP step: the pairs whose residual is at most max(floor, the keep-quantile) refitted by
// Umeyama with scale; `s` unchanged when fewer than three pairs remain or the fit degenerates.
Similarity IcpStep(const std::vector<Eigen::Vector3d>& model, const ScanIndex& scan,
                   const Similarity& s, double keep, double floor) {
  std::vector<Eigen::Vector3d> nearest;
  const std::vector<double> residuals = ScanResiduals(model, scan, s, &nearest);
  const double limit = std::max(floor, Quantile(residuals, keep));
  std::vector<Eigen::Vector3d> src, dst;
  for (size_t i = 0; i < model.size(); ++i) {
    if (std::isfinite(residuals[i]) && residuals[i] <= limit) {
      src.push_back(model[i]);
      dst.push_back(nearest[i]);
    }
  }
  if (src.size() < 3) return s;
  std::vector<int> all(src.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  const Similarity next = FitSimilarity(src, dst, all);
  return IsValid(next) ? next : s;
}

// How far one ICP step moved `from` to `to`: the relative scale change, plus the rotation's change
// (Frobenius norm), plus the translation's relative to the aligned model's size (`size`: the
// model's spread in model units). The iterations stop when it falls below their tolerance.
double StepChange(const Similarity& from, const Similarity& to, double size) {
  return std::abs(to.scale / from.scale - 1.0) + (to.rotation - from.rotation).norm() +
         (to.translation - from.translation).norm() / (to.scale * size);
}

// Orders hypotheses (anything with a `score`) best first.
constexpr auto kByScore = [](const auto& a, const auto& b) { return a.score < b.score; };

struct Moments {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // principal axes, ascending variance
  double variance = 0.0;                               // trace of the covariance
};

Moments MomentsOf(const std::vector<Eigen::Vector3d>& points) {
  Moments m;
  for (const Eigen::Vector3d& p : points) m.centroid += p;
  m.centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) {
    covariance += (p - m.centroid) * (p - m.centroid).transpose();
  }
  covariance /= static_cast<double>(points.size());
  m.axes = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors();
  m.variance = covariance.trace();
  return m;
}

// The rotations taking the model's principal axes onto the scan's, in any order and direction
// (24 proper rotations: the axes of two clouds of different extent need not pair up by size).
std::vector<Eigen::Matrix3d> AxisRotations(const Eigen::Matrix3d& model_axes,
                                           const Eigen::Matrix3d& scan_axes) {
  std::vector<Eigen::Matrix3d> rotations;
  std::array<int, 3> order = {0, 1, 2};
  do {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d target;
      for (int k = 0; k < 3; ++k) {
        target.col(k) = scan_axes.col(order[k]) * (((signs >> k) & 1) ? -1.0 : 1.0);
      }
      const Eigen::Matrix3d r = target * model_axes.transpose();
      if (r.determinant() > 0.0) rotations.push_back(r);
    }
  } while (std::next_permutation(order.begin(), order.end()));
  return rotations;
}

// The model points registration uses: the finite ones, every k-th down to max_model_points.
std::vector<Eigen::Vector3d> UsedModelPoints(const std::vector<Eigen::Vector3d>& model_points,
                                             const AlignmentOptions& options) {
  std::vector<Eigen::Vector3d> finite;
  for (const Eigen::Vector3d& p : model_points) {
    if (p.allFinite()) finite.push_back(p);
  }
  return EveryKth(finite, static_cast<size_t>(options.max_model_points));
}

PclCloud::Ptr FiniteScan(const PointCloud& scan) {
  PclCloud::Ptr cloud(new PclCloud);
  cloud->reserve(scan.size());
  for (const Eigen::Vector3f& p : scan.points) {
    if (p.allFinite()) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  return cloud;
}

void CheckSizes(const std::vector<Eigen::Vector3d>& model, const PclCloud& scan) {
  if (model.size() < 3 || scan.size() < 3) {
    throw Error("alignment to the scan: " + std::to_string(model.size()) + " model points and " +
                std::to_string(scan.size()) + " scan points: at least 3 finite points of each");
  }
}

// The result of `s` (method "scan") with its residual statistics over every model point.
AlignmentResult ScanResult(const std::vector<Eigen::Vector3d>& model, const ScanIndex& scan,
                           const Similarity& s, double max_residual) {
  AlignmentResult result;
  result.method = "scan";
  result.world_from_model = s;
  const std::vector<double> residuals = ScanResiduals(model, scan, s);
  std::vector<Eigen::Vector3d> aligned(model.size());
  for (size_t i = 0; i < model.size(); ++i) aligned[i] = s.Apply(model[i]);
  FillStatistics(residuals, aligned, max_residual, &result);
  return result;
}

// The upper end of the two-sided confidence interval (kMedianConfidenceZ) of the median of
// `residuals` (not empty), from the order statistics.
double MedianUpperConfidence(const std::vector<double>& residuals) {
  const double n = static_cast<double>(residuals.size());
  return Quantile(residuals, std::min(1.0, 0.5 + 0.5 * kMedianConfidenceZ / std::sqrt(n)));
}

// `s` followed by a turn `q` about, a shift `d` from, and a scaling by `f` about the world point
// `c`: x' = f q (x − c) + c + d.
Similarity Perturbed(const Similarity& s, const Eigen::Vector3d& c, const Eigen::Matrix3d& q,
                     const Eigen::Vector3d& d, double f) {
  Similarity next;
  next.scale = f * s.scale;
  next.rotation = q * s.rotation;
  next.translation = f * (q * (s.translation - c)) + c + d;
  return next;
}

}  // namespace

Similarity Similarity::FromMatrix(const Eigen::Matrix4d& m) {
  const Similarity s = Decompose(m);
  const bool rotation_ok =
      (s.rotation.transpose() * s.rotation - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
      std::abs(s.rotation.determinant() - 1.0) < 1e-6;
  const bool last_row_ok = m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1));
  if (!IsValid(s) || !rotation_ok || !last_row_ok) {
    std::ostringstream text;
    text << m.format(Eigen::IOFormat(Eigen::StreamPrecision, Eigen::DontAlignCols, " ", "; "));
    throw Error("not a similarity transform [sR t; 0 1]: " + text.str());
  }
  return s;
}

Eigen::Matrix4d Similarity::Matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = scale * rotation;
  m.topRightCorner<3, 1>() = translation;
  return m;
}

Similarity Similarity::Inverse() const {
  Similarity inverse;
  inverse.scale = 1.0 / scale;
  inverse.rotation = rotation.transpose();
  inverse.translation = -(rotation.transpose() * translation) / scale;
  return inverse;
}

double Similarity::RotationAngleDeg() const {
  const double c = std::clamp((rotation.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / kPi;
}

Camera Similarity::Apply(const Camera& camera_model) const {
  Camera camera = camera_model;
  camera.center_world = Apply(camera_model.center_world);
  camera.world_from_camera_rotation = rotation * camera_model.world_from_camera_rotation;
  return camera;
}

void AlignmentOptions::Check() const {
  if (!(max_residual > 0.0) || !std::isfinite(max_residual)) {
    throw ConfigError(
        ViolatedConstraint("dataset.align_max_residual", FormatNumber(max_residual), "> 0"));
  }
  if (!(min_inlier_share >= 0.0 && min_inlier_share <= 1.0)) {
    throw ConfigError(ViolatedConstraint("dataset.align_min_inlier_share",
                                         FormatNumber(min_inlier_share), "in [0, 1]"));
  }
  if (!(max_relative_residual > 0.0 && max_relative_residual <= 1.0)) {
    throw ConfigError(ViolatedConstraint("dataset.align_max_relative_residual",
                                         FormatNumber(max_relative_residual), "in (0, 1]"));
  }
  if (ransac_iterations < 1) {
    throw ConfigError(ViolatedConstraint("dataset.align_ransac_iterations",
                                         std::to_string(ransac_iterations), ">= 1"));
  }
  if (max_model_points < 3) {
    throw ConfigError(ViolatedConstraint("dataset.align_max_model_points",
                                         std::to_string(max_model_points), ">= 3"));
  }
}

std::string AlignmentResult::Describe() const {
  std::ostringstream s;
  s.precision(4);
  const Eigen::Vector3d& t = world_from_model.translation;
  s << "scale " << world_from_model.scale << ", rotation " << world_from_model.RotationAngleDeg()
    << " deg, translation (" << t.x() << ", " << t.y() << ", " << t.z() << "); residuals median "
    << median_residual << ", 90th percentile " << p90_residual << ", RMS " << rms_residual
    << " (median " << 100.0 * relative_median_residual << " % of the model's spread "
    << model_spread << "); " << num_inliers << " of " << num_correspondences << " "
    << (method == "centres" ? "centres" : "model points") << " inliers (" << 100.0 * inlier_share
    << " %)";
  if (method == "scan") {
    s << "; " << hypotheses << " hypotheses, " << iterations << " ICP steps; " << restarts_alike
      << " of " << restarts << " restarts fit as well, moving the " << ambiguity_probes
      << " by up to " << ambiguity;
  }
  return s.str();
}

AlignmentResult AlignToKnownPoints(const std::vector<Eigen::Vector3d>& model,
                                   const std::vector<Eigen::Vector3d>& world,
                                   const AlignmentOptions& options) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  if (model.size() != world.size()) {
    throw Error("alignment to known points: " + std::to_string(model.size()) +
                " model points but " + std::to_string(world.size()) + " known positions");
  }
  const int n = static_cast<int>(model.size());
  if (n < 3) {
    throw Error("alignment to known points: " + std::to_string(n) +
                " matched points, at least 3 non-collinear ones are needed");
  }
  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  if (NonCollinearity(model, all) < 1e-6 || NonCollinearity(world, all) < 1e-6) {
    throw Error("alignment to known points: the " + std::to_string(n) +
                " matched points are collinear: a similarity needs 3 non-collinear ones");
  }
  const double threshold = options.max_residual;
  auto inliers_of = [&](const Similarity& s, double* cost) {
    std::vector<int> inliers;
    *cost = 0.0;
    for (int i = 0; i < n; ++i) {
      const double r2 = (s.Apply(model[i]) - world[i]).squaredNorm();
      if (r2 <= threshold * threshold) inliers.push_back(i);
      *cost += std::min(r2, threshold * threshold);  // MSAC: ties go to the tighter fit
    }
    return inliers;
  };
  // Every triple when there are few (deterministic and complete), else seeded random samples.
  std::vector<std::array<int, 3>> samples;
  const double triples = static_cast<double>(n) * (n - 1) * (n - 2) / 6.0;
  if (triples <= options.ransac_iterations) {
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) {
        for (int c = b + 1; c < n; ++c) samples.push_back({a, b, c});
      }
    }
  } else {
    std::mt19937_64 random(options.seed);
    std::uniform_int_distribution<int> pick(0, n - 1);
    while (static_cast<int>(samples.size()) < options.ransac_iterations) {
      const int a = pick(random), b = pick(random), c = pick(random);
      if (a != b && b != c && a != c) samples.push_back({a, b, c});
    }
  }
  Similarity best;
  std::vector<int> best_inliers;
  double best_cost = std::numeric_limits<double>::infinity();
  for (const std::array<int, 3>& sample : samples) {
    const std::vector<int> which(sample.begin(), sample.end());
    if (NonCollinearity(model, which) < 1e-3) continue;  // an ill-conditioned minimal sample
    const Similarity s = FitSimilarity(model, world, which);
    if (!IsValid(s)) continue;
    double cost = 0.0;
    const std::vector<int> inliers = inliers_of(s, &cost);
    if (inliers.size() > best_inliers.size() ||
        (inliers.size() == best_inliers.size() && cost < best_cost)) {
      best = s;
      best_inliers = inliers;
      best_cost = cost;
    }
  }
  // Local optimisation: refit on the consensus until it no longer grows.
  for (int round = 0;
       round < 10 && best_inliers.size() >= 3 && NonCollinearity(model, best_inliers) >= 1e-6;
       ++round) {
    const Similarity s = FitSimilarity(model, world, best_inliers);
    if (!IsValid(s)) break;
    double cost = 0.0;
    std::vector<int> inliers = inliers_of(s, &cost);
    if (inliers.size() < best_inliers.size()) break;
    const bool same = inliers == best_inliers;
    best = s;
    best_inliers = std::move(inliers);
    if (same) break;
  }
  if (best_inliers.size() < 3) best = FitSimilarity(model, world, all);

  AlignmentResult result;
  result.method = "centres";
  result.world_from_model = best;
  result.hypotheses = static_cast<int>(samples.size());
  std::vector<Eigen::Vector3d> aligned(n);
  result.residuals.resize(n);
  for (int i = 0; i < n; ++i) {
    aligned[i] = best.Apply(model[i]);
    result.residuals[i] = (aligned[i] - world[i]).norm();
  }
  FillStatistics(result.residuals, aligned, threshold, &result);
  result.seconds = Seconds(start);
  return result;
}

AlignmentResult AlignToScan(const std::vector<Eigen::Vector3d>& model_points,
                            const PointCloud& scan, const AlignmentOptions& options,
                            const std::vector<Eigen::Vector3d>& model_centres) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Eigen::Vector3d> model = UsedModelPoints(model_points, options);
  const PclCloud::Ptr full = FiniteScan(scan);
  CheckSizes(model, *full);
  std::vector<Eigen::Vector3d> scan_points;
  for (size_t i = 0, step = std::max<size_t>(1, full->size() / kCoarseScanPoints); i < full->size();
       i += step) {
    const pcl::PointXYZ& p = (*full)[i];
    scan_points.emplace_back(p.x, p.y, p.z);
  }
  PclCloud::Ptr coarse_cloud(new PclCloud);
  for (const Eigen::Vector3d& p : scan_points) {
    coarse_cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                          static_cast<float>(p.z())));
  }
  const ScanIndex coarse_scan(coarse_cloud);
  const std::vector<Eigen::Vector3d> coarse_model = EveryKth(model, kCoarseModelPoints);

  // Coarse: the model's centroid on the scan's, its principal axes on the scan's (any pairing),
  // its spread scaled to the scan's (times kScaleFactors: the scan usually covers more than the
  // model); in the first round also kRandomRotations uniform rotations. The hypotheses refined
  // by trimmed ICP on subsets with successive halving and scored by their median residual
  // relative to the model's size there (scale-free, so a shrunk model does not win by its small
  // residuals). The scan's moments are then taken again over the part of the scan the best
  // hypothesis covers (its box, widened by a quarter on each side), whose extent is the
  // model's, and the search repeated from them while the score improves.
  const Moments model_moments = MomentsOf(model);
  Moments scan_moments = MomentsOf(scan_points);
  if (!(model_moments.variance > 0.0) || !(scan_moments.variance > 0.0)) {
    throw Error("alignment to the scan: the model's or the scan's points all coincide");
  }
  const double size = std::sqrt(model_moments.variance);  // the model's spread
  // A hypothesis refined by up to `steps` coarse ICP steps (fewer once it stops moving) and
  // scored by its median residual relative to the model's size there.
  struct Hypothesis {
    Similarity s;
    double score = std::numeric_limits<double>::infinity();
  };
  auto advance = [&](Hypothesis* h, int steps) {
    for (int i = 0; i < steps; ++i) {
      const Similarity next = IcpStep(coarse_model, coarse_scan, h->s, kCoarseKeep, 0.0);
      const double change = StepChange(h->s, next, size);
      h->s = next;
      if (change < kCoarseTolerance) break;
    }
    h->score = Quantile(ScanResiduals(coarse_model, coarse_scan, h->s), 0.5) / (h->s.scale * size);
  };
  auto keep_best = [](std::vector<Hypothesis>* hs) {
    const size_t keep = std::max<size_t>(
        1, static_cast<size_t>(std::ceil(kCoarseKeepShare * static_cast<double>(hs->size()))));
    std::stable_sort(hs->begin(), hs->end(), kByScore);
    hs->resize(std::min(keep, hs->size()));
  };
  Similarity best;
  double best_score = std::numeric_limits<double>::infinity();
  int hypotheses = 0;
  std::vector<Hypothesis> finalists;  // every round's last share
  for (int round = 0; round < kCoarseRounds; ++round) {
    const double spread_ratio = std::sqrt(scan_moments.variance / model_moments.variance);
    std::vector<Hypothesis> round_hypotheses;
    auto add = [&](const Eigen::Matrix3d& rotation, double factor) {
      Hypothesis h;
      h.s.scale = spread_ratio * factor;
      h.s.rotation = rotation;
      h.s.translation = scan_moments.centroid - h.s.scale * (rotation * model_moments.centroid);
      round_hypotheses.push_back(h);
    };
    for (const Eigen::Matrix3d& rotation : AxisRotations(model_moments.axes, scan_moments.axes)) {
      for (const double factor : kScaleFactors) add(rotation, factor);
    }
    if (round == 0) {
      for (const Eigen::Matrix3d& rotation : UniformRotations(kRandomRotations, kRandomSeed)) {
        for (const double factor : kRandomScaleFactors) add(rotation, factor);
      }
    }
    hypotheses += static_cast<int>(round_hypotheses.size());
    for (Hypothesis& h : round_hypotheses) advance(&h, kCoarseIterations);
    keep_best(&round_hypotheses);
    for (Hypothesis& h : round_hypotheses) advance(&h, kCoarseIterations);
    keep_best(&round_hypotheses);
    for (Hypothesis& h : round_hypotheses) advance(&h, kCoarseFinalIterations);
    keep_best(&round_hypotheses);
    finalists.insert(finalists.end(), round_hypotheses.begin(), round_hypotheses.end());
    bool improved = false;
    if (round_hypotheses.front().score < best_score) {
      best_score = round_hypotheses.front().score;
      best = round_hypotheses.front().s;
      improved = true;
    }
    if (!improved && round > 0) break;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (const Eigen::Vector3d& p : coarse_model) {
      lo = lo.cwiseMin(best.Apply(p));
      hi = hi.cwiseMax(best.Apply(p));
    }
    const Eigen::Vector3d margin = 0.25 * (hi - lo);
    std::vector<Eigen::Vector3d> covered;
    for (const Eigen::Vector3d& p : scan_points) {
      if ((p.array() >= (lo - margin).array()).all() &&
          (p.array() <= (hi + margin).array()).all()) {
        covered.push_back(p);
      }
    }
    if (covered.size() < 100) break;
    scan_moments = MomentsOf(covered);
  }

  // Fine: against the whole scan, the closest 70 % of the pairs and at least those within
  // max_residual, until the transform no longer changes: first on a subset of the model points,
  // then on all of them.
  const ScanIndex full_scan(full);
  Similarity s = best;
  int iterations = 0;
  auto refine = [&](const std::vector<Eigen::Vector3d>& points, double tolerance,
                    int max_iterations = kMaxFineIterations) {
    for (int i = 0; i < max_iterations; ++i, ++iterations) {
      const Similarity next = IcpStep(points, full_scan, s, kFineKeep, options.max_residual);
      const double change = StepChange(s, next, size);
      s = next;
      if (change < tolerance) break;
    }
  };
  // Point-to-point ICP on a sparse scan stops in a local minimum a few per cent off in scale
  // when it starts there: it is started again from the coarse result's scale times 0.9, 0.95,
  // 1.05 and 1.1 on the subset, and the start with the least relative median residual is kept.
  // The same for each of the best kFineCandidates distinct coarse results.
  std::stable_sort(finalists.begin(), finalists.end(), kByScore);
  std::vector<Similarity> candidates;
  for (const Hypothesis& h : finalists) {
    if (static_cast<int>(candidates.size()) == kFineCandidates) break;
    bool distinct = true;
    for (const Similarity& c : candidates) {
      const double shift =
          (h.s.Apply(model_moments.centroid) - c.Apply(model_moments.centroid)).norm() /
          (c.scale * size);
      const double turn =
          Similarity{1.0, h.s.rotation * c.rotation.transpose(), {}}.RotationAngleDeg();
      if (shift < kDistinctShift && turn < kDistinctDeg) distinct = false;
    }
    if (distinct) candidates.push_back(h.s);
  }
  const std::vector<Eigen::Vector3d> subset = EveryKth(model, kFineSubsetPoints);
  Similarity chosen;
  double chosen_score = std::numeric_limits<double>::infinity();
  for (const Similarity& candidate : candidates) {
    for (const double factor : {1.0, 0.9, 0.95, 1.05, 1.1}) {
      s = candidate;
      s.scale *= factor;
      s.translation =
          candidate.Apply(model_moments.centroid) - s.scale * (s.rotation * model_moments.centroid);
      refine(subset, 1e-8);
      const double score = Quantile(ScanResiduals(subset, full_scan, s), 0.5) / s.scale;
      if (score < chosen_score) {
        chosen_score = score;
        chosen = s;
      }
    }
  }
  // Then point-to-plane steps, pairs within max_residual.
  auto plane_steps = [&](const std::vector<Eigen::Vector3d>& points) {
    for (int i = 0; i < kPlaneIterations; ++i, ++iterations) {
      const Similarity next = PlaneStep(points, full_scan, s, options.max_residual);
      const double change = StepChange(s, next, size);
      s = next;
      if (change < 1e-10) break;
    }
  };
  s = chosen;
  refine(model, 1e-10);
  plane_steps(model);
  AlignmentResult result = ScanResult(model, full_scan, s, options.max_residual);

  // Restarts of the fine stage from perturbed poses (fixed, so deterministic): on the subset,
  // point-to-point to convergence, then point-to-plane; each scored on every model point by the
  // median of its distances to the scan's tangent planes relative to the model's size there
  // (scale-free, and blind to the scan's sampling grid). A better one replaces the result
  // (refined on every point as the first was); those about as good as the result measure how far
  // the scan lets the model move.
  const Eigen::Matrix3d axes = s.rotation * model_moments.axes;  // world, of the aligned model
  const Eigen::Vector3d centre = s.Apply(model_moments.centroid);
  const double spread_world = s.scale * size;
  std::vector<Similarity> starts;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double sign : {-1.0, 1.0}) {
      const Eigen::Matrix3d turn =
          Eigen::AngleAxisd(sign * kRestartRotationDeg * kPi / 180.0, axes.col(axis))
              .toRotationMatrix();
      starts.push_back(Perturbed(s, centre, turn, Eigen::Vector3d::Zero(), 1.0));
      starts.push_back(Perturbed(s, centre, Eigen::Matrix3d::Identity(),
                                 sign * kRestartShift * spread_world * axes.col(axis), 1.0));
    }
  }
  for (const double sign : {-1.0, 1.0}) {
    starts.push_back(Perturbed(s, centre, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(),
                               1.0 + sign * kRestartScale));
  }
  auto relative_median = [&](const Similarity& t) {
    return Quantile(PlaneResiduals(model, full_scan, t, options.max_residual), 0.5) /
           (t.scale * size);
  };
  std::vector<Similarity> restarted = {s};  // the first, unperturbed, then the restarts
  for (const Similarity& from : starts) {
    s = from;
    refine(subset, 1e-8, kRestartIterations);
    plane_steps(subset);
    restarted.push_back(s);
  }
  std::vector<double> scores;
  for (const Similarity& t : restarted) scores.push_back(relative_median(t));
  const size_t best_index =
      static_cast<size_t>(std::min_element(scores.begin(), scores.end()) - scores.begin());
  if (best_index > 0) {
    s = restarted[best_index];
    refine(model, 1e-10);
    plane_steps(model);
    if (relative_median(s) <= scores[best_index]) restarted[best_index] = s;
    scores[best_index] = relative_median(restarted[best_index]);
    result = ScanResult(model, full_scan, restarted[best_index], options.max_residual);
  }
  const Similarity chosen_transform = restarted[best_index];
  const double alike_limit = MedianUpperConfidence(PlaneResiduals(
                                 model, full_scan, chosen_transform, options.max_residual)) /
                             (chosen_transform.scale * size);
  std::vector<Eigen::Vector3d> probes = model_centres;
  result.ambiguity_probes = "camera centres";
  if (probes.empty()) {
    result.ambiguity_probes = "model points";
    const std::vector<double> residuals = ScanResiduals(model, full_scan, chosen_transform);
    for (size_t i = 0; i < model.size(); ++i) {
      if (residuals[i] <= options.max_residual) probes.push_back(model[i]);
    }
  }
  result.restarts = static_cast<int>(starts.size());
  for (size_t k = 0; k < restarted.size(); ++k) {
    if (scores[k] > alike_limit) continue;
    if (k > 0) ++result.restarts_alike;
    for (const Eigen::Vector3d& p : probes) {
      if (!p.allFinite()) continue;
      result.ambiguity =
          std::max(result.ambiguity, (restarted[k].Apply(p) - chosen_transform.Apply(p)).norm());
    }
  }

  result.hypotheses = hypotheses;
  result.iterations = iterations;
  result.seconds = Seconds(start);
  return result;
}

AlignmentResult EvaluateOnScan(const std::vector<Eigen::Vector3d>& model_points,
                               const PointCloud& scan, const Similarity& world_from_model,
                               const AlignmentOptions& options) {
  options.Check();
  const std::vector<Eigen::Vector3d> model = UsedModelPoints(model_points, options);
  const PclCloud::Ptr full = FiniteScan(scan);
  CheckSizes(model, *full);
  return ScanResult(model, ScanIndex(full), world_from_model, options.max_residual);
}

void CheckAlignment(const AlignmentResult& result, const AlignmentOptions& options,
                    const std::string& what) {
  std::vector<std::string> failures;
  if (result.inlier_share < options.min_inlier_share) {
    failures.push_back("inlier share " + FormatNumber(100.0 * result.inlier_share) +
                       " % < dataset.align_min_inlier_share " +
                       FormatNumber(100.0 * options.min_inlier_share) + " %");
  }
  if (result.median_residual > options.max_residual) {
    failures.push_back("median residual " + FormatNumber(result.median_residual) +
                       " > dataset.align_max_residual " + FormatNumber(options.max_residual));
  }
  if (result.method == "scan" && result.relative_median_residual > options.max_relative_residual) {
    failures.push_back("median residual " + FormatNumber(100.0 * result.relative_median_residual) +
                       " % of the model's spread > dataset.align_max_relative_residual " +
                       FormatNumber(100.0 * options.max_relative_residual) + " %");
  }
  bool ambiguous = false;
  if (result.method == "scan" && result.ambiguity > options.max_residual) {
    ambiguous = true;
    failures.push_back("ambiguous: " + std::to_string(result.restarts_alike) + " of " +
                       std::to_string(result.restarts) +
                       " restarts from perturbed poses fit the scan about as well and move the " +
                       result.ambiguity_probes + " by up to " + FormatNumber(result.ambiguity) +
                       " > dataset.align_max_residual " + FormatNumber(options.max_residual));
  }
  if (failures.empty()) return;
  std::string reasons;
  for (const std::string& f : failures) reasons += (reasons.empty() ? "" : "; ") + f;
  throw Error(what + ": alignment refused (" + reasons + "): " + result.Describe() +
              (ambiguous ? ". The scan's surfaces do not pin the model down; use dataset.align: "
                           "centres with known camera centres (dataset.align_centres)"
                         : ""));
}

}  // namespace gcpstereo::align
