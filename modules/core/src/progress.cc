// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace gcpstereo {
namespace {
std::atomic<bool> g_progress_enabled{true};
}  // namespace

void SetProgressBarsEnabled(bool enabled) { g_progress_enabled = enabled; }
bool ProgressBarsEnabled() { return g_progress_enabled; }

ProgressBar::ProgressBar(std::string label, std::int64_t total)
    : label_(std::move(label)),
      total_(std::max<std::int64_t>(total, 1)),
      active_(g_progress_enabled && isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Advance(std::int64_t steps) {
  done_ += steps;
  if (!active_) return;
  const auto now = std::chrono::steady_clock::now();
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || finished_) return;
  if (now - last_draw_ < std::chrono::milliseconds(200)) return;
  last_draw_ = now;
  Draw(false);
}

void ProgressBar::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (active_) Draw(true);
}

ProgressCallback ProgressBar::AsCallback() {
  return [this](double fraction) {
    const auto target = static_cast<std::int64_t>(fraction * static_cast<double>(total_));
    const std::int64_t current = done_;
    if (target > current) Advance(target - current);
    return true;
  };
}

void ProgressBar::Draw(bool final_draw) {
  constexpr int kWidth = 30;
  const double fraction =
      std::clamp(static_cast<double>(done_) / static_cast<double>(total_), 0.0, 1.0);
  const int filled = static_cast<int>(fraction * kWidth);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::string bar(static_cast<size_t>(filled), '#');
  bar.append(static_cast<size_t>(kWidth - filled), '.');
  std::fprintf(stderr, "\r%-24s [%s] %3d%%  %6.1fs", label_.c_str(), bar.c_str(),
               static_cast<int>(fraction * 100.0 + 0.5), elapsed);
  if (final_draw) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace gcpstereo
