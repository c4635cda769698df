// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// Everything of the eval module, plus nlohmann::json itself, for callers that write report.json:
// every result struct has `nlohmann::json ToJson() const`. Non-finite numbers are written as null.
#include <nlohmann/json.hpp>

#include "gcpstereo/eval/depth_sigma.h"
#include "gcpstereo/eval/lidar.h"
#include "gcpstereo/eval/mesh_accuracy.h"
#include "gcpstereo/eval/middlebury.h"
#include "gcpstereo/eval/render.h"
