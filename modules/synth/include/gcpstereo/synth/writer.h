// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include "gcpstereo/synth/generator.h"

namespace gcpstereo::synth {

// Writes `scene` to `dir` (created if needed) in the Strecha layout plus ground truth:
//   images/NNNN.png, cameras/NNNN.png.camera,
//   gt/NNNN.depth.pfm, gt/NNNN.sigma.pfm (per view), gt/laser.ply (world, with sigma),
//   gt/mesh.ply (the exact surface), gt/scene.json (preset, seed, reference, neighbours, depth
//   range of the reference view, scanner position, laser model, summary).
// Every file is written atomically through the io module. Throws IoError on failure, Error when
// `dir` is empty.
void WriteScene(const SyntheticScene& scene, const SynthOptions& options, const std::string& dir);

}  // namespace gcpstereo::synth
