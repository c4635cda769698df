// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <memory>

namespace gcpstereo::pipeline {

// runtime.threads for the whole run (0 = all cores: no limit): TBB's parallel loops (the tiles,
// the plane sweep, meshing, fusion, rendering) through a tbb::global_control and OpenCV's through
// cv::setNumThreads, restored when the object goes. Results do not depend on it (tests/pipeline/
// determinism_test.cpp); it bounds the cores a run takes on a shared machine. BLAS (OpenBLAS,
// under CHOLMOD/UMFPACK) keeps its own OPENBLAS_NUM_THREADS: its results were measured the same
// bytes with 1 and 2 (README, "Same bytes whatever the threads").
class ScopedThreadLimit {
 public:
  explicit ScopedThreadLimit(int threads);
  ~ScopedThreadLimit();
  ScopedThreadLimit(const ScopedThreadLimit&) = delete;
  ScopedThreadLimit& operator=(const ScopedThreadLimit&) = delete;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace gcpstereo::pipeline
