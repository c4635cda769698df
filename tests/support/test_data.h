// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo::testing {

// The real benchmark data folder: $GCPSTEREO_DATA if set, else ../shared/data beside the source
// tree. Returns an empty string when it does not exist.
std::string SharedDataDir();

// The path of `relative` under SharedDataDir(), or "" when the data folder or that entry is absent.
std::string SharedDataPath(const std::string& relative);

// A fresh empty temporary directory for one test (removed when the process exits normally).
std::string MakeTempDir(const std::string& prefix);

// The whole content of a file, bytes as they are ("" when it cannot be read).
std::string ReadFile(const std::string& path);

// The message of the gcpstereo::Error `fn` throws, or "(no error)" when it throws none.
template <typename Fn>
std::string ErrorOf(Fn&& fn) {
  try {
    std::forward<Fn>(fn)();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace gcpstereo::testing

// Skips the current test with a clear message when ../shared/data/<relative> is absent; otherwise
// stores its path in `var`.
#define GCPSTEREO_REQUIRE_SHARED_DATA(var, relative)                                      \
  const std::string var = ::gcpstereo::testing::SharedDataPath(relative);                 \
  if (var.empty()) {                                                                      \
    GTEST_SKIP() << "real data '" << (relative)                                           \
                 << "' not found (set GCPSTEREO_DATA or place ../shared/data beside the " \
                    "checkout); skipping";                                                \
  }
