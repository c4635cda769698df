// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// How much of the reference view a synthetic scene's laser scan covers (laser_test.cpp,
// generator_test.cpp).
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "gcpstereo/synth/generator.h"

namespace gcpstereo::synth {

struct BlockCoverage {
  int covered = 0;  // blocks holding at least one laser point
  int total = 0;    // blocks of the reference view
};

// The reference view's block×block pixel blocks that receive at least one laser point.
inline BlockCoverage LaserCoverageOfReference(const SyntheticScene& s, int block = 8) {
  const Camera& ref = s.views[s.reference_index].camera;
  const int bw = (ref.width + block - 1) / block, bh = (ref.height + block - 1) / block;
  std::vector<int> hits(static_cast<size_t>(bw) * bh, 0);
  for (const auto& p : s.laser.points) {
    Eigen::Vector2d px;
    double depth;
    if (!ref.Project(p.cast<double>(), &px, &depth) || !ref.InImage(px)) continue;
    const int c = static_cast<int>(std::lround(px.x())), r = static_cast<int>(std::lround(px.y()));
    ++hits[static_cast<size_t>((r / block) * bw + c / block)];
  }
  BlockCoverage coverage;
  coverage.total = bw * bh;
  for (int h : hits) coverage.covered += h > 0;
  return coverage;
}

}  // namespace gcpstereo::synth
