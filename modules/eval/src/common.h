// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Internal helpers shared by the eval sources (input checks, percentages, JSON numbers).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

namespace gcpstereo::eval::internal {

// Throws Error("<what>: expected a single-channel CV_32F map, got ...") unless `map` is CV_32FC1
// and non-empty.
void CheckFloatMap(const cv::Mat& map, const std::string& what);
// Throws Error unless `mask` is empty or CV_8UC1.
void CheckMask(const cv::Mat& mask, const std::string& what);
// Throws Error("<what> is WxH but <reference_name> is WxH") unless the sizes agree (empty `map`
// ok).
void CheckSameSize(const cv::Mat& map, const std::string& what, const cv::Mat& reference,
                   const std::string& reference_name);

std::string SizeString(const cv::Mat& map);
std::string FormatDouble(double value);

// 100 · part / whole, 0 when whole == 0.
inline double Percent(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

// A JSON number, or null when not finite (JSON has no inf/NaN).
nlohmann::json JsonNumber(double value);
nlohmann::json JsonNumbers(const std::vector<double>& values);

// Median of `values` (reorders them); 0 for an empty vector. Even count: mean of the two middle.
double Median(std::vector<double>* values);

}  // namespace gcpstereo::eval::internal
