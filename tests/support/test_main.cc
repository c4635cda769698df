// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// The main() of every test executable: quiet logs, no progress bars. Random generators in tests are
// seeded explicitly in each test, so runs are reproducible.
#include <gtest/gtest.h>

#include "gcpstereo/core/logging.h"
#include "gcpstereo/core/progress.h"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  gcpstereo::SetLogLevel("warn");
  gcpstereo::SetProgressBarsEnabled(false);
  return RUN_ALL_TESTS();
}
