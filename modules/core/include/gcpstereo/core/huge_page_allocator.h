// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstddef>
#include <new>

namespace gcpstereo {

// Memory for large arrays that are written whole right after they are allocated (cost volumes).
// A block of at least kHugePageBytes is aligned to 2 MiB and, on Linux, advised as transparent
// huge pages (madvise MADV_HUGEPAGE; the kernels of Debian 12 default to THP "madvise" mode), so
// that the first write maps 2 MiB per page fault instead of 4 KiB. A KITTI tile's cost volume
// (31 MB) otherwise takes about 7,600 page faults, each an exit to the hypervisor on a virtual
// machine: measured in the README (Benchmarks, issue 25). Smaller blocks come from operator new.
// Where the kernel has no THP, or refuses the advice, the block is ordinary memory: nothing but
// the speed depends on the advice.
constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

// Throws std::bad_alloc when the memory cannot be had.
void* AllocateHugePageBacked(std::size_t bytes);
// `bytes` must be what was passed to AllocateHugePageBacked.
void FreeHugePageBacked(void* block, std::size_t bytes) noexcept;

template <typename T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}  // NOLINT: allocator conversion

  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(AllocateHugePageBacked(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { FreeHugePageBacked(p, n * sizeof(T)); }

  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
  template <typename U>
  bool operator!=(const HugePageAllocator<U>&) const noexcept { return false; }
};

}  // namespace gcpstereo
