// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "thread_limit.h"

#include <optional>

#include <tbb/global_control.h>
#include <opencv2/core.hpp>

namespace gcpstereo::pipeline {

struct ScopedThreadLimit::State {
  std::optional<tbb::global_control> tbb_limit;
  int opencv_threads = -1;
};

ScopedThreadLimit::ScopedThreadLimit(int threads) : state_(std::make_unique<State>()) {
  if (threads <= 0) return;
  state_->tbb_limit.emplace(tbb::global_control::max_allowed_parallelism,
                            static_cast<std::size_t>(threads));
  state_->opencv_threads = cv::getNumThreads();
  cv::setNumThreads(threads);
}

ScopedThreadLimit::~ScopedThreadLimit() {
  if (state_ && state_->opencv_threads >= 0) cv::setNumThreads(state_->opencv_threads);
}

}  // namespace gcpstereo::pipeline
