// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Internal helpers for the binary little-endian formats (PFM, PLY, KITTI .bin).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>

namespace gcpstereo::io::internal {

inline bool HostIsLittleEndian() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// Appends the little-endian bytes of a trivially copyable value.
template <typename T>
void AppendLittleEndian(std::string* bytes, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (!HostIsLittleEndian()) std::reverse(raw, raw + sizeof(T));
  bytes->append(raw, sizeof(T));
}

}  // namespace gcpstereo::io::internal
