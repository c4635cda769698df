// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/optimize/plane_fit.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/core.hpp>
#include <opencv2/ximgproc/segmentation.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::optimize {
namespace {

void Require(bool condition, const char* message) {
  if (!condition) throw Error(message);
}

struct Plane {
  double a = 0.0, b = 0.0, c = 0.0;  // d = a·x + b·y + c
  double At(double x, double y) const { return a * x + b * y + c; }
};

struct Sample {
  double x, y, d;
};

// The plane through three samples; false when they are (nearly) collinear.
bool PlaneThrough(const Sample& p, const Sample& q, const Sample& r, Plane* plane) {
  const double ux = q.x - p.x, uy = q.y - p.y, ud = q.d - p.d;
  const double vx = r.x - p.x, vy = r.y - p.y, vd = r.d - p.d;
  const double det = ux * vy - uy * vx;  // twice the triangle's area in the image
  if (std::abs(det) < 1.0) return false;
  plane->a = (ud * vy - uy * vd) / det;
  plane->b = (ux * vd - ud * vx) / det;
  plane->c = p.d - plane->a * p.x - plane->b * p.y;
  return true;
}

int CountInliers(const std::vector<Sample>& samples, const Plane& plane, double tolerance) {
  int count = 0;
  for (const Sample& s : samples) count += std::abs(s.d - plane.At(s.x, s.y)) <= tolerance;
  return count;
}

// Least squares over the samples within `tolerance` of `plane`, in coordinates centred on their
// mean (well conditioned); false when they do not span a plane.
bool RefitOnInliers(const std::vector<Sample>& samples, double tolerance, Plane* plane) {
  double mx = 0.0, my = 0.0, md = 0.0;
  int n = 0;
  for (const Sample& s : samples) {
    if (std::abs(s.d - plane->At(s.x, s.y)) > tolerance) continue;
    mx += s.x, my += s.y, md += s.d, ++n;
  }
  if (n < 3) return false;
  mx /= n, my /= n, md /= n;
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (const Sample& s : samples) {
    if (std::abs(s.d - plane->At(s.x, s.y)) > tolerance) continue;
    const Eigen::Vector2d g(s.x - mx, s.y - my);
    normal += g * g.transpose();
    rhs += g * (s.d - md);
  }
  if (normal.determinant() < 1e-9 * std::max(1.0, normal.trace() * normal.trace())) return false;
  const Eigen::Vector2d ab = normal.ldlt().solve(rhs);
  plane->a = ab(0);
  plane->b = ab(1);
  plane->c = md - ab(0) * mx - ab(1) * my;
  return true;
}

// RANSAC over random triples, then a least-squares refit on the inliers; false when no plane
// holds the required share of the samples.
bool FitPlane(const std::vector<Sample>& samples, const PlaneFitOptions& options, unsigned seed,
              Plane* plane) {
  const int n = static_cast<int>(samples.size());
  cv::RNG rng(seed);
  int best_count = -1;
  Plane best;
  for (int i = 0; i < options.ransac_iterations; ++i) {
    const int p = rng.uniform(0, n), q = rng.uniform(0, n), r = rng.uniform(0, n);
    Plane candidate;
    if (p == q || q == r || p == r ||
        !PlaneThrough(samples[p], samples[q], samples[r], &candidate)) {
      continue;
    }
    const int count = CountInliers(samples, candidate, options.inlier_px);
    if (count > best_count) best_count = count, best = candidate;
  }
  if (best_count < 3 || !RefitOnInliers(samples, options.inlier_px, &best)) return false;
  const int inliers = CountInliers(samples, best, options.inlier_px);
  if (inliers < options.min_inlier_fraction * n) return false;
  *plane = best;
  return true;
}

}  // namespace

cv::Mat SegmentImage(const cv::Mat& image_bgr, const SegmentationOptions& options) {
  Require(image_bgr.type() == CV_8UC3 && !image_bgr.empty(),
          "SegmentImage: the image must be a non-empty CV_8UC3");
  Require(options.sigma > 0.0 && options.k > 0.0 && options.min_segment_px >= 1,
          "SegmentImage: sigma > 0, k > 0 and a minimum segment size >= 1 are required");
  const cv::Ptr<cv::ximgproc::segmentation::GraphSegmentation> segmentation =
      cv::ximgproc::segmentation::createGraphSegmentation(
          options.sigma, static_cast<float>(options.k), options.min_segment_px);
  cv::Mat segments;
  segmentation->processImage(image_bgr, segments);
  return segments;
}

PlaneFitSummary FitSegmentPlanes(const cv::Mat& image_bgr, const cv::Mat& support,
                                 const cv::Mat& frozen, const PlaneFitOptions& options,
                                 cv::Mat* disparity) {
  Require(disparity != nullptr && disparity->type() == CV_32F,
          "FitSegmentPlanes: the disparity map must be CV_32F");
  Require(image_bgr.size() == disparity->size(),
          "FitSegmentPlanes: the image and the disparity map differ in size");
  Require(support.empty() || (support.type() == CV_8U && support.size() == disparity->size()),
          "FitSegmentPlanes: the support mask must be empty or CV_8U of the map's size");
  Require(frozen.empty() || (frozen.type() == CV_8U && frozen.size() == disparity->size()),
          "FitSegmentPlanes: the frozen mask must be empty or CV_8U of the map's size");
  Require(options.inlier_px > 0.0 && options.min_inlier_fraction > 0.0 &&
              options.min_inlier_fraction <= 1.0 && options.min_support_px >= 3 &&
              options.ransac_iterations >= 1,
          "FitSegmentPlanes: inlier_px > 0, min_inlier_fraction in (0, 1], min_support_px >= 3 "
          "and ransac_iterations >= 1 are required");
  const cv::Mat segments = SegmentImage(image_bgr, options.segmentation);
  double max_label = 0.0;
  cv::minMaxLoc(segments, nullptr, &max_label);
  const int num_segments = static_cast<int>(max_label) + 1;

  // The pixels of each segment, in row-major order. Segments are disjoint, so each task reads and
  // writes its own pixels only.
  std::vector<std::vector<cv::Point>> members(num_segments);
  for (int r = 0; r < segments.rows; ++r) {
    const int* row = segments.ptr<int>(r);
    for (int c = 0; c < segments.cols; ++c) members[row[c]].emplace_back(c, r);
  }
  auto is_set = [](const cv::Mat& mask, const cv::Point& p) {
    return !mask.empty() && mask.at<std::uint8_t>(p) != 0;
  };
  std::atomic<int> fitted{0}, changed{0};
  cv::parallel_for_(cv::Range(0, num_segments), [&](const cv::Range& range) {
    std::vector<Sample> samples;
    for (int s = range.start; s < range.end; ++s) {
      samples.clear();
      for (const cv::Point& p : members[s]) {
        const float d = disparity->at<float>(p);
        if (std::isfinite(d) && (support.empty() || is_set(support, p))) {
          samples.push_back({double(p.x), double(p.y), double(d)});
        }
      }
      if (static_cast<int>(samples.size()) < options.min_support_px) continue;
      Plane plane;
      if (!FitPlane(samples, options, 0x9e3779b9u ^ static_cast<unsigned>(s), &plane)) continue;
      ++fitted;
      int segment_changed = 0;
      for (const cv::Point& p : members[s]) {
        float& d = disparity->at<float>(p);
        if (!std::isfinite(d) || is_set(frozen, p)) continue;
        const double on_plane = plane.At(p.x, p.y);
        if (!options.replace_all && std::abs(d - on_plane) <= options.inlier_px) continue;
        if (options.only_farther && on_plane >= d) continue;
        const float value = static_cast<float>(on_plane);
        if (value != d) {
          d = value;
          ++segment_changed;
        }
      }
      changed += segment_changed;
    }
  });
  PlaneFitSummary summary;
  summary.segments = num_segments;
  summary.fitted_segments = fitted;
  summary.changed_pixels = changed;
  summary.segment_labels = segments;
  return summary;
}

}  // namespace gcpstereo::optimize
