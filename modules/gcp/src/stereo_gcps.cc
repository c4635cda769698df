// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// Stereo GCPs of Wang & Yang, CVPR 2011, §4.1 (see stereo_gcps.h for the procedure and the
// deliberate deviations). The three local matchers are private to this file:
//  * Birchfield–Tomasi [3]: the cost module's volume (no aggregation, integer disparities).
//  * NCC over an n×n RGB patch from integer box sums (exact: sums of squares of 75 values up to
//    255² would lose digits in float); only the sum of reference × target needs a new box sum
//    per disparity beside the shifted target's.
//  * Yoon–Kweon adaptive support weights, exact formula, window sampled every aw_stride_px: in
//    adaptive_weights.cc, both views at once.
#include "gcpstereo/gcp/stereo_gcps.h"

#include "adaptive_weights.h"

#include "gcpstereo/cost/birchfield_tomasi.h"
#include "gcpstereo/cost/winner_take_all.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::gcp {
namespace {

// WTA of BT (sum over channels, untruncated), reference = `ref`, target pixel x − d: the cost
// module's Birchfield–Tomasi volume over the whole image, ties to the smallest disparity.
void WtaBirchfieldTomasi(const cv::Mat& ref, const cv::Mat& target, int dmin, int dmax,
                         cv::Mat* wta_out, cv::Mat* uniqueness) {
  std::vector<double> disparities;
  for (int d = dmin; d <= dmax; ++d) disparities.push_back(d);
  const CostVolume volume = cost::ComputeBirchfieldTomasiCost(ref, target, disparities,
                                                              cv::Rect(0, 0, ref.cols, ref.rows),
                                                              cost::BirchfieldTomasiOptions{});
  cv::Mat wta = cost::WinnerTakeAll(volume);
  *uniqueness = cv::Mat(ref.size(), CV_32F, cv::Scalar(0.0f));
  const int num_d = dmax - dmin + 1;
  std::vector<double> curve(num_d);
  std::unique_ptr<bool[]> valid(new bool[num_d]);
  // Labels index `disparities`: shift to disparities, keeping −1 (no valid disparity).
  for (int y = 0; y < wta.rows; ++y) {
    int* row = wta.ptr<int>(y);
    for (int x = 0; x < wta.cols; ++x) {
      if (row[x] < 0) continue;
      for (int i = 0; i < num_d; ++i) {
        valid[i] = volume.HasData(y, x, i);
        curve[i] = volume.Cost(y, x, i);
      }
      uniqueness->at<float>(y, x) =
          internal::UniquenessOfCurve(curve.data(), valid.get(), num_d, row[x]);
      row[x] += dmin;
    }
  }
  *wta_out = wta;
}

// Unnormalised box sums over a window×window neighbourhood with BORDER_REFLECT_101 (as
// cv::boxFilter), of an int32 image given row by row: out(y, x) = Σ value(refl(y + i), refl(x +
// j)). The NCC's sums are of integers (grey levels, their squares and products), so integer sums
// give exactly the doubles the floating-point box filter would.
class BoxSums {
 public:
  BoxSums(int width, int height, int window)
      : width_(width),
        height_(height),
        window_(window),
        row_index_(height * window),
        col_index_(width * window),
        vertical_(static_cast<std::size_t>(width) * height) {
    const int r = window / 2;
    for (int y = 0; y < height; ++y)
      for (int k = 0; k < window; ++k)
        row_index_[y * window + k] =
            cv::borderInterpolate(y + k - r, height, cv::BORDER_REFLECT_101);
    for (int x = 0; x < width; ++x)
      for (int k = 0; k < window; ++k)
        col_index_[x * window + k] =
            cv::borderInterpolate(x + k - r, width, cv::BORDER_REFLECT_101);
  }
  // Box sums of `image` (width × height int32, row-major) into `out` (the same size).
  void Sum(const std::int32_t* image, std::int32_t* out) {
    for (int y = 0; y < height_; ++y) {
      std::int32_t* v = &vertical_[static_cast<std::size_t>(y) * width_];
      std::fill(v, v + width_, 0);
      for (int k = 0; k < window_; ++k) {
        const std::int32_t* row =
            image + static_cast<std::size_t>(row_index_[y * window_ + k]) * width_;
        for (int x = 0; x < width_; ++x) v[x] += row[x];
      }
    }
    for (int y = 0; y < height_; ++y) {
      const std::int32_t* v = &vertical_[static_cast<std::size_t>(y) * width_];
      std::int32_t* o = out + static_cast<std::size_t>(y) * width_;
      for (int x = 0; x < width_; ++x) {
        std::int32_t sum = 0;
        for (int k = 0; k < window_; ++k) sum += v[col_index_[x * window_ + k]];
        o[x] = sum;
      }
    }
  }

 private:
  int width_, height_, window_;
  std::vector<int> row_index_, col_index_;
  std::vector<std::int32_t> vertical_;
};

// The four lowest costs seen so far at one pixel, ascending (ties: the earlier, i.e. smaller, d).
// Only b − 1 and b + 1 can be within 1 px of the best b, so the best cost more than 1 px away from
// b is among these four: the exact uniqueness without storing the whole curve.
struct TopFour {
  std::array<double, 4> cost;
  std::array<int, 4> d;
  int size = 0;
  void Insert(double c, int disparity) {
    int pos = size;
    while (pos > 0 && c < cost[pos - 1]) --pos;
    if (pos >= 4) return;
    for (int k = std::min(size, 3); k > pos; --k) {
      cost[k] = cost[k - 1];
      d[k] = d[k - 1];
    }
    cost[pos] = c;
    d[pos] = disparity;
    size = std::min(size + 1, 4);
  }
  float Uniqueness() const {
    for (int k = 1; k < size; ++k) {
      if (std::abs(d[k] - d[0]) > 1) {
        return cost[k] > 0.0 ? static_cast<float>(std::max(0.0, (cost[k] - cost[0]) / cost[k]))
                             : 0.0f;
      }
    }
    return 0.0f;
  }
};

void WtaNcc(const cv::Mat& ref, const cv::Mat& target, int dmin, int dmax, int window, cv::Mat* wta,
            cv::Mat* uniqueness) {
  const int width = ref.cols, height = ref.rows;
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  const double n = 3.0 * window * window;
  // Per pixel, the sums over the RGB channels of the values and of their squares.
  std::vector<std::int32_t> ref1(pixels), ref2(pixels), tgt1(pixels), tgt2(pixels);
  for (int y = 0; y < height; ++y) {
    const cv::Vec3b* r = ref.ptr<cv::Vec3b>(y);
    const cv::Vec3b* t = target.ptr<cv::Vec3b>(y);
    for (int x = 0; x < width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * width + x;
      ref1[i] = r[x][0] + r[x][1] + r[x][2];
      ref2[i] = r[x][0] * r[x][0] + r[x][1] * r[x][1] + r[x][2] * r[x][2];
      tgt1[i] = t[x][0] + t[x][1] + t[x][2];
      tgt2[i] = t[x][0] * t[x][0] + t[x][1] * t[x][1] + t[x][2] * t[x][2];
    }
  }
  BoxSums box(width, height, window);
  std::vector<std::int32_t> s_ref(pixels), s_ref2(pixels);
  box.Sum(ref1.data(), s_ref.data());
  box.Sum(ref2.data(), s_ref2.data());
  // The target shifted by d, shifted(x) = target(x − d) (its first column repeated where x − d
  // leaves the image), and its product with the reference, box-summed per disparity.
  std::vector<std::int32_t> shifted1(pixels), shifted2(pixels), product(pixels);
  std::vector<std::int32_t> s_t(pixels), s_t2(pixels), s_rt(pixels);
  std::vector<TopFour> top(pixels);
  for (int d = dmin; d <= dmax; ++d) {
    for (int y = 0; y < height; ++y) {
      const cv::Vec3b* r = ref.ptr<cv::Vec3b>(y);
      const cv::Vec3b* t = target.ptr<cv::Vec3b>(y);
      const std::size_t row = static_cast<std::size_t>(y) * width;
      for (int x = 0; x < width; ++x) {
        const int xt = std::min(width - 1, std::max(0, x - d));
        shifted1[row + x] = tgt1[row + xt];
        shifted2[row + x] = tgt2[row + xt];
        product[row + x] = r[x][0] * t[xt][0] + r[x][1] * t[xt][1] + r[x][2] * t[xt][2];
      }
    }
    box.Sum(shifted1.data(), s_t.data());
    box.Sum(shifted2.data(), s_t2.data());
    box.Sum(product.data(), s_rt.data());
    for (int y = 0; y < height; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * width;
      for (int x = std::max(0, d); x < std::min(width, width + d); ++x) {
        const std::size_t i = row + x;
        const double sr = s_ref[i], st = s_t[i];
        const double var_r = s_ref2[i] - sr * sr / n;
        const double var_t = s_t2[i] - st * st / n;
        const double denominator = std::sqrt(std::max(0.0, var_r) * std::max(0.0, var_t));
        if (denominator < 1e-6) continue;  // a flat patch has no correlation
        const double ncc = (s_rt[i] - sr * st / n) / denominator;
        top[i].Insert(1.0 - ncc, d);
      }
    }
  }
  *wta = cv::Mat(ref.size(), CV_32S, cv::Scalar(-1));
  *uniqueness = cv::Mat(ref.size(), CV_32F, cv::Scalar(0.0f));
  for (int y = 0; y < ref.rows; ++y) {
    for (int x = 0; x < ref.cols; ++x) {
      const TopFour& t = top[static_cast<size_t>(y) * ref.cols + x];
      if (t.size == 0) continue;
      wta->at<int>(y, x) = t.d[0];
      uniqueness->at<float>(y, x) = t.Uniqueness();
    }
  }
}

cv::Mat EdgeMask(const cv::Mat& bgr, const StereoGcpOptions& options) {
  cv::Mat grey, edges;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  cv::Canny(grey, edges, options.canny_low, options.canny_high, 3, true);
  if (options.edge_margin_px > 0) {
    const int side = 2 * options.edge_margin_px + 1;
    cv::dilate(edges, edges, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(side, side)));
  }
  return edges;
}

cv::Mat TextureStd(const cv::Mat& bgr, int window) {
  cv::Mat grey, grey64, mean, mean2;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(grey64, CV_64F);
  const cv::Size ksize(window, window);
  cv::boxFilter(grey64, mean, CV_64F, ksize, cv::Point(-1, -1), true, cv::BORDER_REFLECT_101);
  cv::boxFilter(grey64.mul(grey64), mean2, CV_64F, ksize, cv::Point(-1, -1), true,
                cv::BORDER_REFLECT_101);
  cv::Mat variance = mean2 - mean.mul(mean);
  variance = cv::max(variance, 0.0);
  cv::Mat std64, std32;
  cv::sqrt(variance, std64);
  std64.convertTo(std32, CV_32F);
  return std32;
}

// Evidence of `ref` against `target` (target pixel x − d), all but the adaptive weights (which
// internal::AdaptiveWeightEvidence computes for both views at once).
StereoViewEvidence ComputeViewEvidence(const cv::Mat& ref, const cv::Mat& target, int dmin,
                                       int dmax, const StereoGcpOptions& options) {
  StereoViewEvidence e;
  WtaBirchfieldTomasi(ref, target, dmin, dmax, &e.wta_bt, &e.uniqueness_bt);
  WtaNcc(ref, target, dmin, dmax, options.ncc_window_px, &e.wta_ncc, &e.uniqueness_ncc);
  e.texture_std = TextureStd(ref, options.texture_window_px);
  e.edges = EdgeMask(ref, options);
  return e;
}

void FlipEvidence(StereoViewEvidence* e) {
  for (cv::Mat* m : {&e->wta_bt, &e->wta_ncc, &e->uniqueness_bt, &e->uniqueness_ncc,
                     &e->texture_std, &e->edges}) {
    cv::flip(*m, *m, 1);
  }
}

// True when pixel (y, x) with disparity d lies within margin px of the band occluded by a farther
// pixel x' (AW WTA d' < d − 1) on the side the occlusions are on (left view: x' < x, right view:
// x' > x): |x − x'| <= d − d' + margin.
bool InOccludedBand(const cv::Mat& wta_aw, int y, int x, int d, int margin, bool search_left) {
  const int* row = wta_aw.ptr<int>(y);
  const int step = search_left ? -1 : 1;
  // |x − x'| <= d − d' + margin <= d + margin.
  for (int k = 1; k <= d + margin; ++k) {
    const int xq = x + step * k;
    if (xq < 0 || xq >= wta_aw.cols) break;
    const int dq = row[xq];
    if (dq >= 0 && dq < d - 1 && k <= d - dq + margin) return true;
  }
  return false;
}

struct CandidateCounts {
  int candidates = 0, near_edges = 0, low_texture = 0, occluded = 0, ambiguous = 0;
};

// Candidates of one view: CV_32F median disparity, NaN = not a candidate.
cv::Mat Candidates(const StereoViewEvidence& e, const StereoGcpOptions& options, bool search_left,
                   CandidateCounts* counts) {
  cv::Mat candidates(e.wta_bt.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  *counts = CandidateCounts{};
  for (int y = 0; y < candidates.rows; ++y) {
    for (int x = 0; x < candidates.cols; ++x) {
      std::array<int, 3> d = {e.wta_bt.at<int>(y, x), e.wta_ncc.at<int>(y, x),
                              e.wta_aw.at<int>(y, x)};
      if (d[0] < 0 || d[1] < 0 || d[2] < 0) continue;
      std::sort(d.begin(), d.end());
      if (d[2] - d[0] > options.max_spread_px) continue;
      if (e.edges.at<uchar>(y, x)) {
        ++counts->near_edges;
        continue;
      }
      if (e.texture_std.at<float>(y, x) < options.min_texture_std) {
        ++counts->low_texture;
        continue;
      }
      if (options.occlusion_margin_px >= 0 &&
          InOccludedBand(e.wta_aw, y, x, d[1], options.occlusion_margin_px, search_left)) {
        ++counts->occluded;
        continue;
      }
      if (e.uniqueness_aw.at<float>(y, x) < options.min_uniqueness_aw ||
          e.uniqueness_ncc.at<float>(y, x) < options.min_uniqueness_ncc ||
          e.uniqueness_bt.at<float>(y, x) < options.min_uniqueness_bt) {
        ++counts->ambiguous;
        continue;
      }
      candidates.at<float>(y, x) =
          static_cast<float>(options.value == "ncc" ? e.wta_ncc.at<int>(y, x) : d[1]);
      ++counts->candidates;
    }
  }
  return candidates;
}

void CheckEvidence(const StereoViewEvidence& e, cv::Size size) {
  for (const cv::Mat* m : {&e.wta_bt, &e.wta_ncc, &e.wta_aw, &e.uniqueness_bt, &e.uniqueness_ncc,
                           &e.uniqueness_aw, &e.texture_std, &e.edges}) {
    if (m->size() != size) {
      throw Error("SelectStereoGcps: evidence maps are missing or of different sizes");
    }
  }
  if (e.wta_bt.type() != CV_32S || e.wta_ncc.type() != CV_32S || e.wta_aw.type() != CV_32S ||
      e.uniqueness_bt.type() != CV_32F || e.uniqueness_ncc.type() != CV_32F ||
      e.uniqueness_aw.type() != CV_32F || e.texture_std.type() != CV_32F ||
      e.edges.type() != CV_8U) {
    throw Error("SelectStereoGcps: evidence maps have the wrong types");
  }
}

}  // namespace

void StereoGcpOptions::Check() const {
  auto fail = [](const std::string& key, const std::string& value, const std::string& bound) {
    throw ConfigError(ViolatedConstraint("gcp.stereo." + key, value, bound));
  };
  if (max_spread_px < 0 || max_spread_px > 10) {
    fail("max_spread_px", std::to_string(max_spread_px), "0 <= max_spread_px <= 10");
  }
  if (lr_tolerance_px < 0 || lr_tolerance_px > 10) {
    fail("lr_tolerance_px", std::to_string(lr_tolerance_px), "0 <= lr_tolerance_px <= 10");
  }
  if (!(canny_low >= 0.0)) fail("canny_low", FormatNumber(canny_low), "canny_low >= 0");
  if (!(canny_high >= canny_low))
    fail("canny_high", FormatNumber(canny_high), "canny_high >= canny_low");
  if (edge_margin_px < 0 || edge_margin_px > 20) {
    fail("edge_margin_px", std::to_string(edge_margin_px), "0 <= edge_margin_px <= 20");
  }
  if (ncc_window_px < 3 || ncc_window_px > 15 || ncc_window_px % 2 == 0) {
    fail("ncc_window_px", std::to_string(ncc_window_px), "odd, 3 <= ncc_window_px <= 15");
  }
  if (aw_window_px < 3 || aw_window_px > 71 || aw_window_px % 2 == 0) {
    fail("aw_window_px", std::to_string(aw_window_px), "odd, 3 <= aw_window_px <= 71");
  }
  if (aw_stride_px < 1 || aw_stride_px > 4) {
    fail("aw_stride_px", std::to_string(aw_stride_px), "1 <= aw_stride_px <= 4");
  }
  if (!(aw_gamma_c > 0.0)) fail("aw_gamma_c", FormatNumber(aw_gamma_c), "aw_gamma_c > 0");
  if (!(aw_gamma_p > 0.0)) fail("aw_gamma_p", FormatNumber(aw_gamma_p), "aw_gamma_p > 0");
  if (!(aw_truncation > 0.0))
    fail("aw_truncation", FormatNumber(aw_truncation), "aw_truncation > 0");
  if (!(sigma_px >= 0.0)) fail("sigma_px", FormatNumber(sigma_px), "sigma_px >= 0");
  for (const auto& [key, value] :
       {std::pair<const char*, double>{"min_uniqueness_aw", min_uniqueness_aw},
        {"min_uniqueness_ncc", min_uniqueness_ncc},
        {"min_uniqueness_bt", min_uniqueness_bt}}) {
    if (!(value >= 0.0 && value < 1.0)) {
      fail(key, FormatNumber(value), std::string("0 <= ") + key + " < 1");
    }
  }
  if (!(min_texture_std >= 0.0 && min_texture_std <= 128.0)) {
    fail("min_texture_std", FormatNumber(min_texture_std), "0 <= min_texture_std <= 128");
  }
  if (occlusion_margin_px < -1 || occlusion_margin_px > 50) {
    fail("occlusion_margin_px", std::to_string(occlusion_margin_px),
         "-1 <= occlusion_margin_px <= 50");
  }
  if (max_neighbors < 1 || max_neighbors > 20) {
    fail("max_neighbors", std::to_string(max_neighbors), "1 <= max_neighbors <= 20");
  }
  if (min_confirmations < 0 || min_confirmations > 19) {
    fail("min_confirmations", std::to_string(min_confirmations), "0 <= min_confirmations <= 19");
  }
  if (confirm_radius_px < 0 || confirm_radius_px > 10) {
    fail("confirm_radius_px", std::to_string(confirm_radius_px), "0 <= confirm_radius_px <= 10");
  }
  if (!(confirm_sigma > 0.0))
    fail("confirm_sigma", FormatNumber(confirm_sigma), "confirm_sigma > 0");
  if (!(image_scale > 0.0 && image_scale <= 1.0))
    fail("image_scale", FormatNumber(image_scale), "0 < image_scale <= 1");
  if (!(refine_px >= 0.0 && refine_px <= 10.0)) {
    fail("refine_px", FormatNumber(refine_px), "0 <= refine_px <= 10");
  }
  if (refine_px > 0.0 && !(sigma_px > 0.0)) {
    fail("refine_px", FormatNumber(refine_px), "refine_px > 0 needs sigma_px > 0");
  }
  if (refine_window_px < 1 || refine_window_px > 15 || refine_window_px % 2 == 0) {
    fail("refine_window_px", std::to_string(refine_window_px), "odd, 1 <= refine_window_px <= 15");
  }
  if (value != "median" && value != "ncc") fail("value", value, "one of median, ncc");
  if (texture_window_px < 3 || texture_window_px > 31 || texture_window_px % 2 == 0) {
    fail("texture_window_px", std::to_string(texture_window_px),
         "odd, 3 <= texture_window_px <= 31");
  }
}

StereoPairEvidence ComputeStereoEvidence(const cv::Mat& left_bgr, const cv::Mat& right_bgr,
                                         int min_disparity_px, int max_disparity_px,
                                         const StereoGcpOptions& options,
                                         const ProgressCallback& progress) {
  options.Check();
  if (left_bgr.empty() || left_bgr.type() != CV_8UC3 || right_bgr.type() != CV_8UC3 ||
      left_bgr.size() != right_bgr.size()) {
    throw Error("ExtractStereoGcps: left and right must be non-empty CV_8UC3 images of one size");
  }
  if (min_disparity_px < 0 || max_disparity_px <= min_disparity_px ||
      max_disparity_px >= left_bgr.cols) {
    throw Error("ExtractStereoGcps: disparity range [" + std::to_string(min_disparity_px) + ", " +
                std::to_string(max_disparity_px) + "] must satisfy 0 <= min < max < width (" +
                std::to_string(left_bgr.cols) + ")");
  }
  const auto start = std::chrono::steady_clock::now();
  StereoPairEvidence evidence;
  // The right view as reference: mirror both images, so that right pixel x ↔ left x + d becomes
  // the left-reference case x' ↔ x' − d, and mirror the result back. (OpenCV calls stay on this
  // thread: run on TBB's workers, OpenCV's per-thread buffers were reported as leaks under
  // LeakSanitizer.)
  evidence.left =
      ComputeViewEvidence(left_bgr, right_bgr, min_disparity_px, max_disparity_px, options);
  cv::Mat left_flipped, right_flipped;
  cv::flip(left_bgr, left_flipped, 1);
  cv::flip(right_bgr, right_flipped, 1);
  evidence.right = ComputeViewEvidence(right_flipped, left_flipped, min_disparity_px,
                                       max_disparity_px, options);
  FlipEvidence(&evidence.right);
  if (progress && !progress(0.25)) throw Error("ExtractStereoGcps: cancelled");
  internal::AdaptiveWeightEvidence(left_bgr, right_bgr, min_disparity_px, max_disparity_px, options,
                                   &evidence.left, &evidence.right);
  if (progress && !progress(1.0)) throw Error("ExtractStereoGcps: cancelled");
  evidence.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return evidence;
}

StereoGcpResult SelectStereoGcps(const StereoPairEvidence& evidence,
                                 const StereoGcpOptions& options) {
  options.Check();
  const cv::Size size = evidence.left.wta_bt.size();
  if (size.empty()) throw Error("SelectStereoGcps: evidence maps are missing");
  CheckEvidence(evidence.left, size);
  CheckEvidence(evidence.right, size);
  const auto start = std::chrono::steady_clock::now();
  StereoGcpResult result;
  CandidateCounts left_counts, right_counts;
  const cv::Mat left_candidates = Candidates(evidence.left, options, true, &left_counts);
  const cv::Mat right_candidates = Candidates(evidence.right, options, false, &right_counts);
  result.num_candidates_left = left_counts.candidates;
  result.num_candidates_right = right_counts.candidates;
  result.num_near_edges_left = left_counts.near_edges;
  result.num_low_texture_left = left_counts.low_texture;
  result.num_ambiguous_left = left_counts.ambiguous;
  result.num_occlusion_left = left_counts.occluded;
  result.disparity = cv::Mat(size, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const float d_left = left_candidates.at<float>(y, x);
      if (std::isnan(d_left)) continue;
      const int xr = x - static_cast<int>(d_left);
      if (xr < 0 || xr >= size.width) continue;
      const float d_right = right_candidates.at<float>(y, xr);
      if (std::isnan(d_right) || std::abs(d_left - d_right) > options.lr_tolerance_px) continue;
      result.disparity.at<float>(y, x) = d_left;
      ++result.num_gcps;
    }
  }
  result.wta_bt = evidence.left.wta_bt;
  result.wta_ncc = evidence.left.wta_ncc;
  result.wta_aw = evidence.left.wta_aw;
  result.edges = evidence.left.edges;
  result.density_percent = 100.0 * result.num_gcps / (static_cast<double>(size.area()));
  result.seconds = evidence.seconds +
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

StereoGcpResult ExtractStereoGcps(const cv::Mat& left_bgr, const cv::Mat& right_bgr,
                                  int min_disparity_px, int max_disparity_px,
                                  const StereoGcpOptions& options,
                                  const ProgressCallback& progress) {
  const StereoPairEvidence evidence = ComputeStereoEvidence(left_bgr, right_bgr, min_disparity_px,
                                                            max_disparity_px, options, progress);
  return SelectStereoGcps(evidence, options);
}

GcpSet StereoGcpsToGcpSet(const cv::Mat& disparity, double disparity_numerator, double sigma_px,
                          GcpSourceSummary* summary) {
  if (disparity.empty() || disparity.type() != CV_32F) {
    throw Error("StereoGcpsToGcpSet: the disparity map must be a non-empty CV_32F image");
  }
  if (!(disparity_numerator > 0.0) || !std::isfinite(disparity_numerator)) {
    throw Error("StereoGcpsToGcpSet: disparity_numerator = " + FormatNumber(disparity_numerator) +
                " must be > 0");
  }
  GcpSourceSummary local;
  local.source = GcpSourceName(GcpSource::kStereo);
  GcpSet gcps;
  for (int row = 0; row < disparity.rows; ++row) {
    for (int col = 0; col < disparity.cols; ++col) {
      const float d = disparity.at<float>(row, col);
      if (!std::isfinite(d)) continue;
      ++local.num_input;
      if (d <= 0.0f) {
        ++local.num_invalid;
        continue;
      }
      Gcp gcp;
      gcp.col = col;
      gcp.row = row;
      gcp.depth = disparity_numerator / d;
      gcp.sigma = disparity_numerator * sigma_px / (static_cast<double>(d) * d);
      gcp.source = GcpSource::kStereo;
      gcps.points.push_back(gcp);
    }
  }
  local.num_gcps = static_cast<int>(gcps.size());
  local.density_percent = DensityPercent(gcps, disparity.cols, disparity.rows);
  if (summary) *summary = local;
  return gcps;
}

GcpOutlierStats ComputeOutlierStats(const cv::Mat& sparse, const cv::Mat& ground_truth,
                                    double threshold, const cv::Mat& mask) {
  if (sparse.type() != CV_32F || ground_truth.type() != CV_32F ||
      sparse.size() != ground_truth.size() ||
      (!mask.empty() && (mask.type() != CV_8U || mask.size() != sparse.size()))) {
    throw Error(
        "ComputeOutlierStats: sparse and ground truth must be CV_32F of one size, the "
        "mask empty or CV_8U of that size");
  }
  GcpOutlierStats stats;
  for (int y = 0; y < sparse.rows; ++y) {
    for (int x = 0; x < sparse.cols; ++x) {
      const float d = sparse.at<float>(y, x);
      const float gt = ground_truth.at<float>(y, x);
      if (!std::isfinite(d) || !std::isfinite(gt)) continue;
      if (!mask.empty() && mask.at<uchar>(y, x) == 0) continue;
      ++stats.num_evaluated;
      if (std::abs(d - gt) > threshold) ++stats.num_outliers;
    }
  }
  stats.outlier_percent =
      stats.num_evaluated > 0 ? 100.0 * stats.num_outliers / stats.num_evaluated : 0.0;
  return stats;
}

}  // namespace gcpstereo::gcp
