// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/error.h"

#include <sstream>

namespace gcpstereo {

std::string FormatNumber(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

std::string ViolatedConstraint(const std::string& name, const std::string& value,
                               const std::string& constraint) {
  return name + " = " + value + ". Violated constraint: " + constraint;
}

}  // namespace gcpstereo
