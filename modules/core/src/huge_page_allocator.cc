// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/huge_page_allocator.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace gcpstereo {

namespace {

// Advises the whole huge pages inside [block, block + bytes).
void AdviseHugePages(void* block, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  const auto begin = reinterpret_cast<std::uintptr_t>(block);
  const std::uintptr_t first = (begin + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  const std::uintptr_t last = (begin + bytes) / kHugePageBytes * kHugePageBytes;
  // Advice only: a kernel without THP answers EINVAL, and the block is then ordinary memory.
  if (last > first) (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)block;
  (void)bytes;
#endif
}

}  // namespace

void* MallocHugePageBacked(std::size_t bytes) noexcept {
  if (bytes < kHugePageBytes) return std::malloc(bytes);
  // Only the whole huge pages of the block are advised: its last partial one stays on 4 KiB
  // pages, so that no memory beyond `bytes` becomes resident.
  void* block = nullptr;
  if (posix_memalign(&block, kHugePageBytes, bytes) != 0) return nullptr;
  AdviseHugePages(block, bytes);
  return block;
}

void* CallocHugePageBacked(std::size_t count, std::size_t size) noexcept {
  if (size != 0 && count > static_cast<std::size_t>(-1) / size) return nullptr;
  const std::size_t bytes = count * size;
  if (bytes < kHugePageBytes) return std::calloc(count, size);
  void* block = MallocHugePageBacked(bytes);
  if (block != nullptr) std::memset(block, 0, bytes);
  return block;
}

void* ReallocHugePageBacked(void* block, std::size_t bytes) noexcept {
  if (block == nullptr) return MallocHugePageBacked(bytes);
  void* moved = std::realloc(block, bytes);
  if (moved != nullptr && bytes >= kHugePageBytes) AdviseHugePages(moved, bytes);
  return moved;
}

void FreeHugePageBacked(void* block) noexcept { std::free(block); }

}  // namespace gcpstereo
