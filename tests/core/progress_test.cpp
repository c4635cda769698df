// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/progress.h"

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo {
namespace {

TEST(Progress, CallbackAdvancesAndNeverCancels) {
  ProgressBar bar("test", 100);
  auto callback = bar.AsCallback();
  EXPECT_TRUE(callback(0.25));
  EXPECT_TRUE(callback(1.0));
  bar.Finish();
  bar.Finish();  // idempotent
}

TEST(Error, ViolatedConstraintFormat) {
  EXPECT_EQ(ViolatedConstraint("optimizer.lambda_s", "-1", "lambda_s >= 0"),
            "optimizer.lambda_s = -1. Violated constraint: lambda_s >= 0");
  const IoError e("/tmp/x.camera", "expected 9 lines, found 4");
  EXPECT_STREQ(e.what(), "/tmp/x.camera: expected 9 lines, found 4");
}

}  // namespace
}  // namespace gcpstereo
