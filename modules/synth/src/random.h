// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Counter-based random numbers: every draw is a pure function of (seed, keys), so results never
// depend on the order in which threads visit pixels or scan points.
#pragma once

#include <cmath>
#include <cstdint>

namespace gcpstereo::synth::internal {

// SplitMix64's finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mix.
inline std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

inline std::uint64_t HashKeys(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0,
                              std::uint64_t d = 0) {
  std::uint64_t h = Mix64(a);
  h = Mix64(h ^ b);
  h = Mix64(h ^ c);
  return Mix64(h ^ d);
}

// Uniform in [0, 1) from the top 53 bits.
inline double ToUnit(std::uint64_t x) { return static_cast<double>(x >> 11) * 0x1.0p-53; }

// A small SplitMix64 stream started from a hashed key; one per pixel or scan point.
class KeyedRng {
 public:
  explicit KeyedRng(std::uint64_t key) : state_(key) {}
  std::uint64_t NextU64() {
    state_ += 0x9e3779b97f4a7c15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double Uniform() { return ToUnit(NextU64()); }
  // Standard normal by Box–Muller (one of the pair; simple and exactly reproducible).
  double Gaussian() {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::uint64_t state_;
};

}  // namespace gcpstereo::synth::internal
