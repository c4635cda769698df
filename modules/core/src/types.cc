// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/types.h"

namespace gcpstereo {

const char* GcpSourceName(GcpSource source) {
  switch (source) {
    case GcpSource::kLidar:
      return "lidar";
    case GcpSource::kDepthMap:
      return "depth_map";
    case GcpSource::kStereo:
      return "stereo";
    case GcpSource::kSfm:
      return "sfm";
  }
  return "unknown";
}

}  // namespace gcpstereo
