// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "common.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "gcpstereo/core/error.h"

namespace gcpstereo::eval::internal {

std::string SizeString(const cv::Mat& map) {
  return std::to_string(map.cols) + "x" + std::to_string(map.rows);
}

std::string FormatDouble(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

void CheckFloatMap(const cv::Mat& map, const std::string& what) {
  if (map.empty()) throw Error(what + ": the map is empty");
  if (map.type() != CV_32FC1) {
    throw Error(what + ": expected a single-channel CV_32F map, got OpenCV type " +
                std::to_string(map.type()) + " with " + std::to_string(map.channels()) +
                " channel(s)");
  }
}

void CheckMask(const cv::Mat& mask, const std::string& what) {
  if (!mask.empty() && mask.type() != CV_8UC1) {
    throw Error(what + ": expected a single-channel CV_8U mask, got OpenCV type " +
                std::to_string(mask.type()));
  }
}

void CheckSameSize(const cv::Mat& map, const std::string& what, const cv::Mat& reference,
                   const std::string& reference_name) {
  if (map.empty()) return;
  if (map.size() != reference.size()) {
    throw Error(what + " is " + SizeString(map) + " but " + reference_name + " is " +
                SizeString(reference));
  }
}

nlohmann::json JsonNumber(double value) {
  if (!std::isfinite(value)) return nullptr;
  return value;
}

nlohmann::json JsonNumbers(const std::vector<double>& values) {
  nlohmann::json out = nlohmann::json::array();
  for (double v : values) out.push_back(JsonNumber(v));
  return out;
}

double Median(std::vector<double>* values) {
  if (values->empty()) return 0.0;
  const size_t n = values->size();
  const size_t mid = n / 2;
  std::nth_element(values->begin(), values->begin() + mid, values->end());
  const double upper = (*values)[mid];
  if (n % 2 == 1) return upper;
  const double lower = *std::max_element(values->begin(), values->begin() + mid);
  return 0.5 * (lower + upper);
}

}  // namespace gcpstereo::eval::internal
