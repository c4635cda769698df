// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/huge_page_allocator.h"

#include <cstdlib>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace gcpstereo {

namespace {
std::size_t RoundUpToHugePages(std::size_t bytes) {
  return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
}
}  // namespace

void* AllocateHugePageBacked(std::size_t bytes) {
  if (bytes < kHugePageBytes) return ::operator new(bytes);
  void* block = std::aligned_alloc(kHugePageBytes, RoundUpToHugePages(bytes));
  if (block == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // Advice only: a kernel without THP answers EINVAL, and the block is then ordinary memory.
  (void)madvise(block, RoundUpToHugePages(bytes), MADV_HUGEPAGE);
#endif
  return block;
}

void FreeHugePageBacked(void* block, std::size_t bytes) noexcept {
  if (block == nullptr) return;
  if (bytes < kHugePageBytes) {
    ::operator delete(block);
  } else {
    std::free(block);
  }
}

}  // namespace gcpstereo
