// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

namespace gcpstereo {

// How the discrete hypotheses are spaced (configuration key labels.space).
enum class LabelSpaceKind { kDepth, kInverseDepth, kDisparity };
const char* LabelSpaceKindName(LabelSpaceKind kind);
// Parses "depth", "inverse_depth" or "disparity"; throws ConfigError otherwise.
LabelSpaceKind ParseLabelSpaceKind(const std::string& name);

// `count` labels equally spaced in the chosen space between `min` and `max` (inclusive), in the
// space's own unit: depth in the data set's unit (metres), inverse depth in 1/unit, disparity in
// pixels of the data set's ground-truth convention (disparity = disparity_numerator / depth).
// Label values may be fractional (sub-label refinement): label l has value min + l · step.
class LabelSpace {
 public:
  LabelSpace() = default;
  // Throws ConfigError when count < 2, min >= max, or the range is invalid for the kind
  // (depth min <= 0; inverse depth / disparity min < 0; disparity without a numerator > 0).
  LabelSpace(LabelSpaceKind kind, int count, double min, double max,
             double disparity_numerator = 0.0);

  LabelSpaceKind kind() const { return kind_; }
  int count() const { return count_; }
  double min() const { return min_; }
  double max() const { return max_; }
  double step() const { return (max_ - min_) / (count_ - 1); }

  // Value in the space's unit of (possibly fractional) label `label`.
  double ValueOfLabel(double label) const { return min_ + label * step(); }
  // Continuous label of a value in the space's unit (not clamped).
  double LabelOfValue(double value) const { return (value - min_) / step(); }
  // Depth of a label; +infinity for zero inverse depth or disparity.
  double DepthOfLabel(double label) const;
  // Continuous label of a depth (not clamped; depth > 0).
  double LabelOfDepth(double depth) const;
  // Converts depth to the space's value (depth, 1/depth, or numerator/depth).
  double ValueOfDepth(double depth) const;

 private:
  LabelSpaceKind kind_ = LabelSpaceKind::kDepth;
  int count_ = 2;
  double min_ = 1.0;
  double max_ = 2.0;
  double disparity_numerator_ = 0.0;
};

}  // namespace gcpstereo
