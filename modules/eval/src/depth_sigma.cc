// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/eval/depth_sigma.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "common.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/types.h"

namespace gcpstereo::eval {
namespace {

void CheckSigmaInputs(const cv::Mat& depth, const cv::Mat& gt_depth, const cv::Mat& gt_sigma,
                      const cv::Mat& mask) {
  internal::CheckFloatMap(depth, "depth estimate");
  internal::CheckFloatMap(gt_depth, "ground-truth depth");
  internal::CheckFloatMap(gt_sigma, "ground-truth sigma");
  internal::CheckMask(mask, "evaluation mask");
  internal::CheckSameSize(gt_depth, "ground-truth depth", depth, "the depth estimate");
  internal::CheckSameSize(gt_sigma, "ground-truth sigma", depth, "the depth estimate");
  internal::CheckSameSize(mask, "evaluation mask", depth, "the depth estimate");
}

void CheckBinIndex(int n) {
  if (n < 1 || n > SigmaHistogram::kNumBins) {
    throw Error("sigma histogram: bin " + std::to_string(n) + " is outside 1 … " +
                std::to_string(SigmaHistogram::kNumBins));
  }
}

// Whether pixel (row, col) is counted: in the mask and with a usable GT depth and sigma.
inline bool GtKnown(float gt, float sigma) {
  return std::isfinite(gt) && gt > 0.0f && std::isfinite(sigma) && sigma > 0.0f;
}

}  // namespace

double SigmaHistogram::WithinPercent(int n) const {
  CheckBinIndex(n);
  return internal::Percent(within_count[n - 1], counted);
}
double SigmaHistogram::BinPercent(int n) const {
  CheckBinIndex(n);
  return internal::Percent(bin_count[n - 1], counted);
}
double SigmaHistogram::MissingPercent() const { return internal::Percent(missing, counted); }
double SigmaHistogram::Beyond10Percent() const { return internal::Percent(beyond_10, counted); }

nlohmann::json SigmaHistogram::ToJson() const {
  nlohmann::json j;
  j["definition"] =
      "e = |depth - gt| / sigma over pixels with known gt and sigma; shares in percent of counted; "
      "missing estimates count as wrong";
  j["counted"] = counted;
  j["gt_unknown"] = gt_unknown;
  j["missing"] = missing;
  j["missing_percent"] = internal::JsonNumber(MissingPercent());
  j["beyond_10_sigma_percent"] = internal::JsonNumber(Beyond10Percent());
  nlohmann::json within = nlohmann::json::array();
  nlohmann::json bins = nlohmann::json::array();
  for (int n = 1; n <= kNumBins; ++n) {
    within.push_back(internal::JsonNumber(WithinPercent(n)));
    bins.push_back(internal::JsonNumber(BinPercent(n)));
  }
  j["within_n_sigma_percent"] = within;  // index 0: n = 1
  j["bin_percent"] = bins;               // index 0: e <= 1, index k: k < e <= k + 1
  j["mean_abs_error"] = internal::JsonNumber(mean_abs_error);
  j["rms_error"] = internal::JsonNumber(rms_error);
  j["mean_error_sigma"] = internal::JsonNumber(mean_error_sigma);
  j["median_error_sigma"] = internal::JsonNumber(median_error_sigma);
  return j;
}

// Strecha et al., CVPR 2008, error histograms; Wang & Yang, CVPR 2011, Figure 4 and §4.2. For each
// counted pixel p the error in units of the laser's standard deviation is
//     e(p) = |D(p) − D_gt(p)| / σ(p),
// and the histogram reports the share of counted pixels with e in each 1σ-wide bin, cumulatively
// within n·σ, beyond 10σ and missing (see the header for the exact definitions).
SigmaHistogram EvaluateDepthSigma(const cv::Mat& depth, const cv::Mat& gt_depth,
                                  const cv::Mat& gt_sigma, const cv::Mat& mask) {
  CheckSigmaInputs(depth, gt_depth, gt_sigma, mask);
  SigmaHistogram h;
  std::vector<double> errors_sigma;
  double sum_abs = 0.0, sum_sq = 0.0, sum_sigma = 0.0;
  for (int row = 0; row < depth.rows; ++row) {
    const float* d = depth.ptr<float>(row);
    const float* g = gt_depth.ptr<float>(row);
    const float* s = gt_sigma.ptr<float>(row);
    const std::uint8_t* m = mask.empty() ? nullptr : mask.ptr<std::uint8_t>(row);
    for (int col = 0; col < depth.cols; ++col) {
      if (m != nullptr && m[col] == 0) continue;
      if (!GtKnown(g[col], s[col])) {
        ++h.gt_unknown;
        continue;
      }
      ++h.counted;
      if (!IsValidDepth(d[col])) {
        ++h.missing;
        continue;
      }
      const double abs_error = std::abs(static_cast<double>(d[col]) - static_cast<double>(g[col]));
      const double e = abs_error / static_cast<double>(s[col]);
      sum_abs += abs_error;
      sum_sq += abs_error * abs_error;
      sum_sigma += e;
      errors_sigma.push_back(e);
      if (e > SigmaHistogram::kNumBins) {
        ++h.beyond_10;
        continue;
      }
      // Bin n: (n−1) < e <= n; e = 0 goes to bin 1.
      const int bin = std::max(1, static_cast<int>(std::ceil(e)));
      ++h.bin_count[bin - 1];
    }
  }
  std::int64_t cumulative = 0;
  for (int n = 0; n < SigmaHistogram::kNumBins; ++n) {
    cumulative += h.bin_count[n];
    h.within_count[n] = cumulative;
  }
  const std::int64_t valid = static_cast<std::int64_t>(errors_sigma.size());
  if (valid > 0) {
    h.mean_abs_error = sum_abs / valid;
    h.rms_error = std::sqrt(sum_sq / valid);
    h.mean_error_sigma = sum_sigma / valid;
    h.median_error_sigma = internal::Median(&errors_sigma);
  }
  return h;
}

void SigmaHistogramPlotOptions::Check() const {
  if (width_px < 320) {
    throw ConfigError(
        ViolatedConstraint("eval.histogram.width_px", std::to_string(width_px), "width_px >= 320"));
  }
  if (height_px < 240) {
    throw ConfigError(ViolatedConstraint("eval.histogram.height_px", std::to_string(height_px),
                                         "height_px >= 240"));
  }
}

cv::Mat RenderSigmaHistogram(const std::vector<NamedHistogram>& series,
                             const SigmaHistogramPlotOptions& options) {
  options.Check();
  if (series.empty()) throw Error("RenderSigmaHistogram: no histogram to draw");
  constexpr int kGroups = SigmaHistogram::kNumBins + 2;  // 1σ … 10σ, >10σ, missing
  const int width = options.width_px, height = options.height_px;
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 60, right = 20, top = 40, bottom = 60;
  const int plot_w = width - left - right, plot_h = height - top - bottom;
  const cv::Scalar black(0, 0, 0), grid(220, 220, 220);
  const int font = cv::FONT_HERSHEY_SIMPLEX;

  // The share of every bar, series-major.
  std::vector<std::vector<double>> values(series.size(), std::vector<double>(kGroups, 0.0));
  double max_value = 0.0;
  for (size_t s = 0; s < series.size(); ++s) {
    const SigmaHistogram& h = series[s].histogram;
    for (int n = 1; n <= SigmaHistogram::kNumBins; ++n) {
      values[s][n - 1] = options.cumulative ? h.WithinPercent(n) : h.BinPercent(n);
    }
    values[s][kGroups - 2] = h.Beyond10Percent();
    values[s][kGroups - 1] = h.MissingPercent();
    for (double v : values[s]) max_value = std::max(max_value, v);
  }
  // y axis: 0 … a multiple of 10 % (at least 10 %, at most 100 %).
  const double y_max = std::min(100.0, std::max(10.0, 10.0 * std::ceil(max_value / 10.0)));
  const double y_step = y_max > 50.0 ? 10.0 : (y_max > 20.0 ? 5.0 : 2.0);
  auto y_of = [&](double percent) {
    return top + plot_h - static_cast<int>(std::lround(percent / y_max * plot_h));
  };
  for (double y = 0.0; y <= y_max + 1e-9; y += y_step) {
    const int py = y_of(y);
    cv::line(image, {left, py}, {left + plot_w, py}, grid, 1);
    char label[16];
    std::snprintf(label, sizeof(label), "%g%%", y);
    cv::putText(image, label, {5, py + 4}, font, 0.4, black, 1, cv::LINE_AA);
  }
  cv::line(image, {left, top}, {left, top + plot_h}, black, 1);
  cv::line(image, {left, top + plot_h}, {left + plot_w, top + plot_h}, black, 1);

  static const cv::Scalar kPalette[] = {{200, 120, 30}, {40, 40, 220},  {50, 160, 50},
                                        {0, 140, 255},  {160, 60, 160}, {120, 120, 120}};
  constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);
  const double group_w = static_cast<double>(plot_w) / kGroups;
  const double bar_w = group_w * 0.8 / static_cast<double>(series.size());
  for (int g = 0; g < kGroups; ++g) {
    const double x0 = left + g * group_w + group_w * 0.1;
    for (size_t s = 0; s < series.size(); ++s) {
      const int xa = static_cast<int>(std::lround(x0 + s * bar_w));
      const int xb = std::max(xa + 1, static_cast<int>(std::lround(x0 + (s + 1) * bar_w)) - 1);
      const int ya = y_of(values[s][g]);
      cv::rectangle(image, cv::Point(xa, ya), cv::Point(xb, top + plot_h),
                    kPalette[s % kPaletteSize], cv::FILLED);
    }
    std::string label = g < SigmaHistogram::kNumBins ? std::to_string(g + 1)
                        : g == kGroups - 2           ? ">10"
                                                     : "miss";
    const cv::Size text = cv::getTextSize(label, font, 0.4, 1, nullptr);
    const int cx = static_cast<int>(std::lround(left + (g + 0.5) * group_w));
    cv::putText(image, label, {cx - text.width / 2, top + plot_h + 16}, font, 0.4, black, 1,
                cv::LINE_AA);
  }
  const std::string x_title =
      options.cumulative ? "n (share within n*sigma)" : "error bin (sigma units: (n-1, n])";
  cv::putText(image, x_title, {left, top + plot_h + 36}, font, 0.45, black, 1, cv::LINE_AA);
  cv::putText(image, options.title, {left, 25}, font, 0.55, black, 1, cv::LINE_AA);

  // Legend, top right: colour, name, within-3σ share.
  int legend_y = top + 15;
  for (size_t s = 0; s < series.size(); ++s) {
    char text[160];
    std::snprintf(text, sizeof(text), "%s (within 3 sigma: %.1f%%)", series[s].name.c_str(),
                  series[s].histogram.WithinPercent(3));
    const cv::Size size = cv::getTextSize(text, font, 0.42, 1, nullptr);
    const int x = std::max(left + 5, left + plot_w - size.width - 25);
    cv::rectangle(image, cv::Point(x, legend_y - 10), cv::Point(x + 12, legend_y),
                  kPalette[s % kPaletteSize], cv::FILLED);
    cv::putText(image, text, {x + 18, legend_y}, font, 0.42, black, 1, cv::LINE_AA);
    legend_y += 18;
  }
  return image;
}

cv::Mat RenderDepthErrorMap(const cv::Mat& depth, const cv::Mat& gt_depth, const cv::Mat& gt_sigma,
                            const cv::Mat& mask, double max_sigma) {
  CheckSigmaInputs(depth, gt_depth, gt_sigma, mask);
  if (!(max_sigma > 0.0)) {
    throw Error("RenderDepthErrorMap: max_sigma = " + internal::FormatDouble(max_sigma) +
                " must be > 0");
  }
  cv::Mat level(depth.size(), CV_8UC1, cv::Scalar(0));
  cv::Mat state(depth.size(), CV_8UC1, cv::Scalar(0));  // 0 excluded, 1 valid, 2 missing
  for (int row = 0; row < depth.rows; ++row) {
    const float* d = depth.ptr<float>(row);
    const float* g = gt_depth.ptr<float>(row);
    const float* s = gt_sigma.ptr<float>(row);
    const std::uint8_t* m = mask.empty() ? nullptr : mask.ptr<std::uint8_t>(row);
    for (int col = 0; col < depth.cols; ++col) {
      if ((m != nullptr && m[col] == 0) || !GtKnown(g[col], s[col])) continue;
      if (!IsValidDepth(d[col])) {
        state.at<std::uint8_t>(row, col) = 2;
        continue;
      }
      const double e = std::abs(static_cast<double>(d[col]) - g[col]) / s[col];
      state.at<std::uint8_t>(row, col) = 1;
      level.at<std::uint8_t>(row, col) =
          static_cast<std::uint8_t>(std::lround(255.0 * std::min(e, max_sigma) / max_sigma));
    }
  }
  cv::Mat colour;
  cv::applyColorMap(level, colour, cv::COLORMAP_TURBO);
  for (int row = 0; row < depth.rows; ++row) {
    for (int col = 0; col < depth.cols; ++col) {
      const std::uint8_t st = state.at<std::uint8_t>(row, col);
      if (st == 0) colour.at<cv::Vec3b>(row, col) = cv::Vec3b(0, 0, 0);
      if (st == 2) colour.at<cv::Vec3b>(row, col) = cv::Vec3b(255, 0, 255);
    }
  }
  return colour;
}

}  // namespace gcpstereo::eval
