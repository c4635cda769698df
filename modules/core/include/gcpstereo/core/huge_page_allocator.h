// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstddef>
#include <new>

namespace gcpstereo {

// Memory for large arrays that are written whole right after they are allocated (cost volumes,
// the stereo GCPs' difference volume, a sparse factorisation). A block of at least
// kHugePageBytes is aligned to 2 MiB and, on Linux, advised as transparent huge pages (madvise
// MADV_HUGEPAGE; Debian 12's kernels default to THP "madvise" mode), so that the first write maps
// 2 MiB per page fault instead of 4 KiB: a KITTI tile's cost volume (31 MB) otherwise takes about
// 7,600 page faults, each an exit to the hypervisor on a virtual machine (README, Benchmarks,
// issue 25). Smaller blocks are plain malloc. Where the kernel has no THP or refuses the advice,
// the block is ordinary memory: only the speed depends on the advice. Every block is released
// with std::free.
constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

// malloc's contract (nullptr when the memory cannot be had; `bytes` 0 gives a unique block).
void* MallocHugePageBacked(std::size_t bytes) noexcept;
// calloc's and realloc's contracts, with MallocHugePageBacked's blocks (SuiteSparse's memory
// functions, UseHugePagesInSuiteSparse in the propagation module). A block that realloc moves
// to 2 MiB or more is advised too.
void* CallocHugePageBacked(std::size_t count, std::size_t size) noexcept;
void* ReallocHugePageBacked(void* block, std::size_t bytes) noexcept;
void FreeHugePageBacked(void* block) noexcept;  // std::free

template <typename T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}  // NOLINT: allocator conversion

  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    void* block = MallocHugePageBacked(n * sizeof(T));
    if (block == nullptr) throw std::bad_alloc();
    return static_cast<T*>(block);
  }
  void deallocate(T* p, std::size_t) noexcept { FreeHugePageBacked(p); }

  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
  template <typename U>
  bool operator!=(const HugePageAllocator<U>&) const noexcept { return false; }
};

}  // namespace gcpstereo
