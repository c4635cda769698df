// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/error.h"

namespace gcpstereo {

std::string ViolatedConstraint(const std::string& name, const std::string& value,
                               const std::string& constraint) {
  return name + " = " + value + ". Violated constraint: " + constraint;
}

}  // namespace gcpstereo
