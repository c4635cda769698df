// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Adaptive propagation of Wang & Yang, "Global Stereo Matching Leveraged by Sparse Ground Control
// Points", CVPR 2011, §3.1, eq. 5 (see propagation.h for the system solved).
//
// The two backends solve the same equations:
//  * umfpack: A x = b exactly as in the paper, over the reached pixels: A_pp = 1, A_pq = −α_pq
//    (non-GCP rows), identity rows at the GCPs. A is not symmetric (α is normalised per row).
//  * cholmod: multiply each non-GCP row by d_p = Σ_q w_pq > 0 (does not change the solution):
//    d_p x_p − Σ_q w_pq x_q = 0 — a row of the weighted graph Laplacian L = D − W, symmetric since
//    w_pq = w_qp. Substituting x_q = G_q for the GCP neighbours leaves L_UU x_U = W_UG G over the
//    non-GCP unknowns U. L_UU is symmetric, weakly diagonally dominant and irreducibly so in every
//    region that contains a GCP (unreached regions are removed first), hence positive definite.
//    This is algebraically the paper's system, not an approximation; the tests check both
//    backends agree to 1e-6 on real and synthetic images.
#include "gcpstereo/propagation/propagation.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/propagation/sparse_solver.h"
#include "propagation_internal.h"

namespace gcpstereo::propagation {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The 8 neighbour offsets in raster order of the neighbour (so that row indices within a CSC
// column come out sorted): NW, N, NE, W, E, SW, S, SE.
constexpr std::array<int, 8> kDr = {-1, -1, -1, 0, 0, 1, 1, 1};
constexpr std::array<int, 8> kDc = {-1, 0, 1, -1, 1, -1, 0, 1};

// Symmetric 8-connected affinities w_pq stored once per undirected link, for the four "forward"
// directions E, SW, S, SE of each pixel. Weight(p, k) returns the link of p to its k-th neighbour
// (0 when outside the image or cut).
class Affinities {
 public:
  Affinities(const cv::Mat& image_bgr, const PropagationOptions& options)
      : width_(image_bgr.cols), height_(image_bgr.rows) {
    const size_t n = static_cast<size_t>(width_) * height_;
    for (auto& w : forward_) w.assign(n, 0.0);
    // Forward directions: E (0, 1), SW (1, −1), S (1, 0), SE (1, 1).
    constexpr std::array<int, 4> kFr = {0, 1, 1, 1};
    constexpr std::array<int, 4> kFc = {1, -1, 0, 1};
    for (int r = 0; r < height_; ++r) {
      const cv::Vec3b* row = image_bgr.ptr<cv::Vec3b>(r);
      for (int c = 0; c < width_; ++c) {
        for (int k = 0; k < 4; ++k) {
          const int rq = r + kFr[k];
          const int cq = c + kFc[k];
          if (rq < 0 || rq >= height_ || cq < 0 || cq >= width_) continue;
          const cv::Vec3b& ip = row[c];
          const cv::Vec3b& iq = image_bgr.ptr<cv::Vec3b>(rq)[cq];
          double squared = 0.0;
          for (int ch = 0; ch < 3; ++ch) {
            const double diff = static_cast<double>(ip[ch]) - static_cast<double>(iq[ch]);
            squared += diff * diff;
          }
          double w = std::max(std::exp(-std::sqrt(squared) / options.gamma), options.epsilon);
          if (w < options.min_weight) w = 0.0;
          forward_[k][static_cast<size_t>(r) * width_ + c] = w;
        }
      }
    }
  }

  // Link of pixel (r, c) to neighbour k of kDr/kDc (caller guarantees the neighbour is inside).
  double Weight(int r, int c, int k) const {
    const size_t p = static_cast<size_t>(r) * width_ + c;
    switch (k) {
      case 0:
        return forward_[3][p - width_ - 1];  // NW = SE of (r−1, c−1)
      case 1:
        return forward_[2][p - width_];  // N  = S of (r−1, c)
      case 2:
        return forward_[1][p - width_ + 1];  // NE = SW of (r−1, c+1)
      case 3:
        return forward_[0][p - 1];  // W  = E of (r, c−1)
      case 4:
        return forward_[0][p];  // E
      case 5:
        return forward_[1][p];  // SW
      case 6:
        return forward_[2][p];  // S
      default:
        return forward_[3][p];  // SE
    }
  }

  bool Inside(int r, int c, int k) const {
    const int rq = r + kDr[k];
    const int cq = c + kDc[k];
    return rq >= 0 && rq < height_ && cq >= 0 && cq < width_;
  }

 private:
  int width_;
  int height_;
  std::array<std::vector<double>, 4> forward_;
};

// Geometric nested dissection of the pixel grid (George 1973): split the rectangle across its
// longer side by a one-pixel line — a separator for 8-connectivity too — order both halves
// recursively, then the line. Appends the unknown indices (unknown[p] >= 0) in elimination order.
// Optimal-order fill for grid graphs, computed in O(n) instead of running AMD or METIS on 1.6 M
// nodes.
void NestedDissection(int r0, int r1, int c0, int c1, int width, const std::vector<int>& unknown,
                      std::vector<int>* order) {
  const int rows = r1 - r0;
  const int cols = c1 - c0;
  if (rows <= 0 || cols <= 0) return;
  auto emit = [&](int ra, int rb, int ca, int cb) {
    for (int r = ra; r < rb; ++r) {
      for (int c = ca; c < cb; ++c) {
        const int u = unknown[static_cast<size_t>(r) * width + c];
        if (u >= 0) order->push_back(u);
      }
    }
  };
  if (rows * cols <= 8 || (rows < 3 && cols < 3)) {
    emit(r0, r1, c0, c1);
    return;
  }
  if (cols >= rows) {
    const int mid = c0 + cols / 2;
    NestedDissection(r0, r1, c0, mid, width, unknown, order);
    NestedDissection(r0, r1, mid + 1, c1, width, unknown, order);
    emit(r0, r1, mid, mid + 1);
  } else {
    const int mid = r0 + rows / 2;
    NestedDissection(r0, mid, c0, c1, width, unknown, order);
    NestedDissection(mid + 1, r1, c0, c1, width, unknown, order);
    emit(mid, mid + 1, c0, c1);
  }
}

}  // namespace

void PropagationOptions::Check() const {
  if (method != "linear_system" && method != "weighted_median" && method != "local_plane") {
    throw ConfigError(ViolatedConstraint("propagation.method", "'" + method + "'",
                                         "one of 'linear_system', 'weighted_median', "
                                         "'local_plane'"));
  }
  if (!(plane_radius_px >= 1 && plane_radius_px <= 100)) {
    throw ConfigError(ViolatedConstraint("propagation.plane_radius_px",
                                         std::to_string(plane_radius_px), "1 <= radius <= 100"));
  }
  if (!(plane_sigma_px > 0.0) || !std::isfinite(plane_sigma_px)) {
    throw ConfigError(ViolatedConstraint("propagation.plane_sigma_px", FormatNumber(plane_sigma_px),
                                         "sigma > 0"));
  }
  if (!(plane_sigma_colour > 0.0) || !std::isfinite(plane_sigma_colour)) {
    throw ConfigError(ViolatedConstraint("propagation.plane_sigma_colour",
                                         FormatNumber(plane_sigma_colour), "sigma > 0"));
  }
  if (!(median_radius_px >= 1 && median_radius_px <= 100)) {
    throw ConfigError(ViolatedConstraint("propagation.median_radius_px",
                                         std::to_string(median_radius_px), "1 <= radius <= 100"));
  }
  if (!(median_sigma_px > 0.0) || !std::isfinite(median_sigma_px)) {
    throw ConfigError(ViolatedConstraint("propagation.median_sigma_px",
                                         FormatNumber(median_sigma_px), "sigma > 0"));
  }
  if (!(median_sigma_colour > 0.0) || !std::isfinite(median_sigma_colour)) {
    throw ConfigError(ViolatedConstraint("propagation.median_sigma_colour",
                                         FormatNumber(median_sigma_colour), "sigma > 0"));
  }
  if (!(median_colour_floor >= 0.0 && median_colour_floor <= 1.0)) {
    throw ConfigError(ViolatedConstraint("propagation.median_colour_floor",
                                         FormatNumber(median_colour_floor), "0 <= floor <= 1"));
  }
  if (!(median_edge_stretch >= 1.0 && median_edge_stretch <= 100.0)) {
    throw ConfigError(ViolatedConstraint("propagation.median_edge_stretch",
                                         FormatNumber(median_edge_stretch), "1 <= stretch <= 100"));
  }
  if (!(gamma > 0.0) || !std::isfinite(gamma)) {
    throw ConfigError(ViolatedConstraint("propagation.gamma", FormatNumber(gamma), "gamma > 0"));
  }
  if (!(epsilon >= 0.0 && epsilon < 1.0)) {
    throw ConfigError(
        ViolatedConstraint("propagation.epsilon", FormatNumber(epsilon), "0 <= epsilon < 1"));
  }
  if (!(min_weight >= 0.0 && min_weight <= 1e-3)) {
    throw ConfigError(ViolatedConstraint("propagation.min_weight", FormatNumber(min_weight),
                                         "0 <= min_weight <= 1e-3"));
  }
  ParseSparseSolverKind(solver);
  if (ordering != "nested_dissection" && ordering != "amd") {
    throw ConfigError(ViolatedConstraint("propagation.ordering", "'" + ordering + "'",
                                         "one of 'nested_dissection', 'amd'"));
  }
}

void internal::CheckPropagationInputs(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                                      const PropagationOptions& options) {
  options.Check();
  if (image_bgr.empty() || image_bgr.type() != CV_8UC3) {
    throw Error("Propagate: the image must be a non-empty CV_8UC3 (BGR) image");
  }
  if (sparse_values.type() != CV_32F || sparse_values.size() != image_bgr.size()) {
    throw Error("Propagate: sparse_values must be CV_32F of the image size " +
                std::to_string(image_bgr.cols) + "x" + std::to_string(image_bgr.rows));
  }
}

int internal::CountGcps(const cv::Mat& sparse_values) {
  int count = 0;
  for (int r = 0; r < sparse_values.rows; ++r) {
    const float* row = sparse_values.ptr<float>(r);
    count += static_cast<int>(
        std::count_if(row, row + sparse_values.cols, [](float v) { return std::isfinite(v); }));
  }
  return count;
}

void internal::CountUnreached(PropagationResult* result) {
  result->num_unknowns = static_cast<int>(result->values.total()) - result->num_gcps;
  const cv::Mat unreached = result->reached == 0;
  result->num_unreached_pixels = cv::countNonZero(unreached);
  if (result->num_unreached_pixels > 0) {
    cv::Mat components;
    result->num_unreached_regions = cv::connectedComponents(unreached, components, 8, CV_32S) - 1;
  }
}

namespace {

PropagationResult PropagateWith(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                                const PropagationOptions& options) {
  internal::CheckPropagationInputs(image_bgr, sparse_values, options);
  const SparseSolverKind kind = ParseSparseSolverKind(options.solver);
  const auto setup_start = std::chrono::steady_clock::now();
  const int width = image_bgr.cols;
  const int height = image_bgr.rows;
  const int num_pixels = width * height;
  auto index = [width](int r, int c) { return r * width + c; };

  PropagationResult result;
  result.solver = SparseSolverKindName(kind);
  const Affinities affinities(image_bgr, options);

  std::vector<char> is_gcp(num_pixels, 0);
  std::vector<double> gcp_value(num_pixels, 0.0);
  for (int r = 0; r < height; ++r) {
    const float* row = sparse_values.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      if (std::isfinite(row[c])) {
        is_gcp[index(r, c)] = 1;
        gcp_value[index(r, c)] = row[c];
        ++result.num_gcps;
      }
    }
  }

  // Regions: connected components over links w > 0 (breadth-first, raster-order seeds).
  std::vector<int> region(num_pixels, -1);
  std::vector<char> region_has_gcp;
  std::vector<int> queue;
  queue.reserve(num_pixels);
  for (int seed = 0; seed < num_pixels; ++seed) {
    if (region[seed] >= 0) continue;
    const int label = static_cast<int>(region_has_gcp.size());
    bool has_gcp = false;
    queue.clear();
    queue.push_back(seed);
    region[seed] = label;
    for (size_t head = 0; head < queue.size(); ++head) {
      const int p = queue[head];
      has_gcp = has_gcp || is_gcp[p];
      const int r = p / width;
      const int c = p % width;
      for (int k = 0; k < 8; ++k) {
        if (!affinities.Inside(r, c, k) || affinities.Weight(r, c, k) <= 0.0) continue;
        const int q = index(r + kDr[k], c + kDc[k]);
        if (region[q] < 0) {
          region[q] = label;
          queue.push_back(q);
        }
      }
    }
    region_has_gcp.push_back(has_gcp ? 1 : 0);
    if (!has_gcp) {
      ++result.num_unreached_regions;
      result.num_unreached_pixels += static_cast<int>(queue.size());
    }
  }

  // Unknowns: umfpack solves every reached pixel (GCP rows are identity rows); cholmod solves the
  // reached non-GCP pixels only.
  std::vector<int> unknown(num_pixels, -1);
  int num_unknowns = 0;
  for (int p = 0; p < num_pixels; ++p) {
    if (!region_has_gcp[region[p]]) continue;
    if (kind == SparseSolverKind::kCholmod && is_gcp[p]) continue;
    unknown[p] = num_unknowns++;
  }
  result.num_unknowns = num_unknowns;

  std::vector<double> degree(num_pixels, 0.0);  // d_p = Σ_q w_pq
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      double sum = 0.0;
      for (int k = 0; k < 8; ++k) {
        if (affinities.Inside(r, c, k)) sum += affinities.Weight(r, c, k);
      }
      degree[index(r, c)] = sum;
    }
  }

  CscMatrix a;
  a.size = num_unknowns;
  a.col_starts.reserve(num_unknowns + 1);
  a.row_indices.reserve(static_cast<size_t>(num_unknowns) *
                        (kind == SparseSolverKind::kUmfpack ? 9 : 5));
  a.values.reserve(a.row_indices.capacity());
  std::vector<double> b(num_unknowns, 0.0);
  a.col_starts.push_back(0);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const int q = index(r, c);  // the column's pixel
      if (unknown[q] < 0) continue;
      if (kind == SparseSolverKind::kUmfpack) {
        // Column q: A(p, q) = −α_pq for non-GCP neighbours p (w_pq > 0), A(q, q) = 1.
        for (int k = 0; k < 8; ++k) {
          if (k == 4) {  // the diagonal sits between W and E in raster order
            a.row_indices.push_back(unknown[q]);
            a.values.push_back(1.0);
            if (is_gcp[q]) b[unknown[q]] = gcp_value[q];
          }
          if (!affinities.Inside(r, c, k)) continue;
          const double w = affinities.Weight(r, c, k);
          const int p = index(r + kDr[k], c + kDc[k]);
          if (w <= 0.0 || is_gcp[p]) continue;
          a.row_indices.push_back(unknown[p]);
          a.values.push_back(-w / degree[p]);
        }
      } else {
        // Lower triangle of L_UU: diagonal d_q, then −w_pq for unknown neighbours p after q;
        // GCP neighbours move to the right-hand side.
        a.row_indices.push_back(unknown[q]);
        a.values.push_back(degree[q]);
        for (int k = 0; k < 8; ++k) {
          if (!affinities.Inside(r, c, k)) continue;
          const double w = affinities.Weight(r, c, k);
          if (w <= 0.0) continue;
          const int p = index(r + kDr[k], c + kDc[k]);
          if (is_gcp[p]) {
            b[unknown[q]] += w * gcp_value[p];
          } else if (p > q) {  // E, SW, S, SE: below the diagonal
            a.row_indices.push_back(unknown[p]);
            a.values.push_back(-w);
          }
        }
      }
      a.col_starts.push_back(static_cast<int>(a.row_indices.size()));
    }
  }
  result.setup_seconds = SecondsSince(setup_start);

  std::vector<double> x;
  if (num_unknowns > 0) {
    const auto solve_start = std::chrono::steady_clock::now();
    std::vector<int> order;
    if (options.ordering == "nested_dissection") {
      order.reserve(num_unknowns);
      NestedDissection(0, height, 0, width, width, unknown, &order);
    }
    x = SolveSparseLinearSystem(a, b, kind, order);
    result.solve_seconds = SecondsSince(solve_start);
  }

  result.values =
      cv::Mat(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  result.reached = cv::Mat::zeros(height, width, CV_8U);
  std::vector<double> solution(num_pixels, std::numeric_limits<double>::quiet_NaN());
  for (int p = 0; p < num_pixels; ++p) {
    if (!region_has_gcp[region[p]]) continue;
    solution[p] = is_gcp[p] ? gcp_value[p] : x[unknown[p]];
    result.values.ptr<float>(p / width)[p % width] = static_cast<float>(solution[p]);
    result.reached.ptr<unsigned char>(p / width)[p % width] = 255;
  }

  // Residual of eq. 5 over the solved non-GCP pixels (in double, before rounding to float).
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const int p = index(r, c);
      if (is_gcp[p] || !region_has_gcp[region[p]] || degree[p] <= 0.0) continue;
      double average = 0.0;
      for (int k = 0; k < 8; ++k) {
        if (!affinities.Inside(r, c, k)) continue;
        const double w = affinities.Weight(r, c, k);
        if (w > 0.0) average += w / degree[p] * solution[index(r + kDr[k], c + kDc[k])];
      }
      result.residual = std::max(result.residual, std::abs(solution[p] - average));
    }
  }
  return result;
}

}  // namespace

PropagationResult Propagate(const cv::Mat& image_bgr, const cv::Mat& sparse_values,
                            const PropagationOptions& options) {
  if (options.method == "weighted_median") {
    return PropagateByWeightedMedian(image_bgr, sparse_values, options);
  }
  if (options.method == "local_plane") {
    return PropagateByLocalPlanes(image_bgr, sparse_values, options);
  }
  if (ParseSparseSolverKind(options.solver) != SparseSolverKind::kCholmod) {
    return PropagateWith(image_bgr, sparse_values, options);
  }
  try {
    return PropagateWith(image_bgr, sparse_values, options);
  } catch (const Error& e) {
    // L_UU is positive definite in exact arithmetic when every region holds a GCP, but a region
    // tied to its GCPs only by links of w ≈ exp(−‖ΔRGB‖/γ) ~ 1e-48 (a bright speck on black) can
    // lose definiteness in rounding. UMFPACK (LU with pivoting) solves such systems; its solution
    // is the same where both succeed (tests), so fall back to it and say so in `solver`.
    const std::string what = e.what();
    if (what.find("not positive definite") == std::string::npos) throw;
    PropagationOptions lu = options;
    lu.solver = "umfpack";
    PropagationResult result = PropagateWith(image_bgr, sparse_values, lu);
    result.solver = "umfpack (fallback: " + what + ")";
    return result;
  }
}

}  // namespace gcpstereo::propagation
