// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/core/cost_volume.h"
#include "gcpstereo/core/huge_page_allocator.h"

namespace gcpstereo {
namespace {

TEST(CostVolume, StartsAsTheFillValue) {
  const CostVolume no_data(cv::Rect(3, 4, 5, 6), 7, 10.0f);
  const CostVolume largest(cv::Rect(3, 4, 5, 6), 7, 10.0f, 65534);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 5; ++c) {
      for (int l = 0; l < 7; ++l) {
        ASSERT_FALSE(no_data.HasData(r, c, l));
        ASSERT_TRUE(largest.HasData(r, c, l));
        ASSERT_EQ(largest.PixelData(r, c)[l], 65534);
        ASSERT_FLOAT_EQ(largest.Cost(r, c, l), 10.0f);
      }
    }
  }
}

// Blocks from 2 MiB up are 2 MiB-aligned; smaller ones come from operator new. Either keeps what
// is written, and a volume that large reads back its entries.
TEST(HugePageAllocator, KeepsWhatIsWrittenAtAnySize) {
  for (const std::size_t n : {std::size_t{1}, std::size_t{1000}, kHugePageBytes / 2 - 1,
                              kHugePageBytes / 2, 3 * kHugePageBytes + 17}) {
    std::vector<std::uint16_t, HugePageAllocator<std::uint16_t>> values(n);
    for (std::size_t i = 0; i < n; ++i) values[i] = static_cast<std::uint16_t>(i * 7919);
    if (n * sizeof(std::uint16_t) >= kHugePageBytes) {
      EXPECT_EQ(reinterpret_cast<std::uintptr_t>(values.data()) % kHugePageBytes, 0u) << n;
    }
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(values[i], static_cast<std::uint16_t>(i * 7919)) << n << " " << i;
    }
  }
  // calloc's and realloc's contracts, across the 2 MiB boundary.
  for (const std::size_t n : {std::size_t{10}, kHugePageBytes + 3}) {
    auto* zeros = static_cast<unsigned char*>(CallocHugePageBacked(n, 1));
    ASSERT_NE(zeros, nullptr);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(zeros[i], 0) << n << " " << i;
    zeros[n - 1] = 42;
    auto* grown = static_cast<unsigned char*>(ReallocHugePageBacked(zeros, 3 * kHugePageBytes));
    ASSERT_NE(grown, nullptr);
    EXPECT_EQ(grown[n - 1], 42);
    grown[3 * kHugePageBytes - 1] = 7;
    FreeHugePageBacked(grown);
  }
  EXPECT_EQ(CallocHugePageBacked(static_cast<std::size_t>(-1) / 2, 4), nullptr);
  CostVolume volume(cv::Rect(0, 0, 300, 200), 40, 1.0f);  // 4.8 MB
  volume.SetCost(199, 299, 39, 0.5f);
  EXPECT_NEAR(volume.Cost(199, 299, 39), 0.5f, volume.cost_step());
  EXPECT_FALSE(volume.HasData(0, 0, 0));
}

}  // namespace
}  // namespace gcpstereo
