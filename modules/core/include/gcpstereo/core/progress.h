// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

namespace gcpstereo {

// Called with the fraction done in [0, 1]; returning false asks the algorithm to stop early
// (the Open3D/PCL convention). Algorithms accept an optional callback of this type.
using ProgressCallback = std::function<bool(double fraction_done)>;

// Global switch for terminal progress bars (the CLI's --quiet turns them off).
void SetProgressBarsEnabled(bool enabled);
bool ProgressBarsEnabled();

// A terminal progress bar on stderr for a long loop of `total` steps. It draws only when progress
// bars are enabled and stderr is a terminal, at most a few times a second; Advance() is
// thread-safe.
class ProgressBar {
 public:
  ProgressBar(std::string label, std::int64_t total);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void Advance(std::int64_t steps = 1);
  void Finish();
  // A callback that reports fractions to this bar (for algorithms taking a ProgressCallback).
  ProgressCallback AsCallback();

 private:
  void Draw(bool final_draw);

  std::string label_;
  std::int64_t total_;
  std::atomic<std::int64_t> done_{0};
  bool active_;
  bool finished_ = false;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace gcpstereo
