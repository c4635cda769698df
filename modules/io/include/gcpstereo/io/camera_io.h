// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include "gcpstereo/core/camera.h"

namespace gcpstereo::io {

// Strecha's `.camera` text format (EPFL multi-view benchmark, CVPR 2008), 9 lines:
//   K (3 lines of 3 numbers)
//   radial distortion (3 numbers; our images are undistorted: non-zero values are accepted with a
//   warning and ignored)
//   R (3 lines: the camera-to-world rotation, Camera::world_from_camera_rotation)
//   C (1 line: the camera centre in world coordinates)
//   width height
// Projection: x ~ K Rᵀ (X − C).

// Throws IoError naming the file for a missing file, a wrong number of lines ("expected 9 lines,
// found N"), a line with the wrong count of numbers or unparsable text ("line 3: ..."), a
// non-finite number ("line 5: non-finite value"), and an invalid camera (Camera::Validate:
// orthonormal R with det +1 within 1e-3, positive focal lengths, positive size). The rotation is
// then replaced by the nearest exact rotation (the files print ~6 digits; Camera relies on Rᵀ =
// R⁻¹).
Camera ReadStrechaCamera(const std::string& path);

// Writes the 9-line format atomically with 17 significant digits (exact double round trip).
// Validates the camera first (throws Error naming the path).
void WriteStrechaCamera(const std::string& path, const Camera& camera);

}  // namespace gcpstereo::io
