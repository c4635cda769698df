// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/labels.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "gcpstereo/core/error.h"

namespace gcpstereo {
const char* LabelSpaceKindName(LabelSpaceKind kind) {
  switch (kind) {
    case LabelSpaceKind::kDepth:
      return "depth";
    case LabelSpaceKind::kInverseDepth:
      return "inverse_depth";
    case LabelSpaceKind::kDisparity:
      return "disparity";
  }
  return "unknown";
}

LabelSpaceKind ParseLabelSpaceKind(const std::string& name) {
  if (name == "depth") return LabelSpaceKind::kDepth;
  if (name == "inverse_depth") return LabelSpaceKind::kInverseDepth;
  if (name == "disparity") return LabelSpaceKind::kDisparity;
  throw ConfigError(
      ViolatedConstraint("labels.space", name, "one of depth, inverse_depth, disparity"));
}

LabelSpace::LabelSpace(LabelSpaceKind kind, int count, double min, double max,
                       double disparity_numerator)
    : kind_(kind), count_(count), min_(min), max_(max), disparity_numerator_(disparity_numerator) {
  if (count < 2)
    throw ConfigError(ViolatedConstraint("labels.count", FormatNumber(count), "count >= 2"));
  if (!std::isfinite(min) || !std::isfinite(max) || !(min < max)) {
    throw ConfigError(ViolatedConstraint("labels.min, labels.max",
                                         FormatNumber(min) + ", " + FormatNumber(max),
                                         "finite and min < max"));
  }
  if (kind == LabelSpaceKind::kDepth && !(min > 0.0)) {
    throw ConfigError(
        ViolatedConstraint("labels.min", FormatNumber(min), "min > 0 for depth labels"));
  }
  if (kind != LabelSpaceKind::kDepth && min < 0.0) {
    throw ConfigError(ViolatedConstraint("labels.min", FormatNumber(min), "min >= 0"));
  }
  if (kind == LabelSpaceKind::kDisparity && !(disparity_numerator > 0.0)) {
    throw ConfigError("disparity labels need rectified data (a positive focal length × baseline)");
  }
}

double LabelSpace::DepthOfLabel(double label) const {
  const double v = ValueOfLabel(label);
  switch (kind_) {
    case LabelSpaceKind::kDepth:
      return v;
    case LabelSpaceKind::kInverseDepth:
      return v > 0.0 ? 1.0 / v : std::numeric_limits<double>::infinity();
    case LabelSpaceKind::kDisparity:
      return v > 0.0 ? disparity_numerator_ / v : std::numeric_limits<double>::infinity();
  }
  return v;
}

double LabelSpace::ValueOfDepth(double depth) const {
  switch (kind_) {
    case LabelSpaceKind::kDepth:
      return depth;
    case LabelSpaceKind::kInverseDepth:
      return 1.0 / depth;
    case LabelSpaceKind::kDisparity:
      return disparity_numerator_ / depth;
  }
  return depth;
}

double LabelSpace::LabelOfDepth(double depth) const { return LabelOfValue(ValueOfDepth(depth)); }

}  // namespace gcpstereo
