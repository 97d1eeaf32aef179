// Portable pseudo-random numbers for the procedural scenes: xoshiro256**
// seeded through splitmix64 (Blackman & Vigna, "Scrambled linear pseudorandom
// number generators", 2018). Only integer arithmetic and an exact mapping to
// doubles, so every machine and standard library draws the same sequence
// (std::uniform_*_distribution is not portable across libraries).
#pragma once

#include <algorithm>
#include <cstdint>

#include "stages/geometry.h"

namespace cellbake {

// One splitmix64 step: returns a well-mixed 64-bit value of `x` (a pure hash).
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Maps the top 53 bits of `bits` to a double in [0, 1), exactly.
inline double unit_from_bits(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

class SceneRng {
 public:
  explicit SceneRng(std::uint64_t seed) {
    std::uint64_t x = seed;
    for (auto& word : s_) {
      x = splitmix64(x);
      word = x;
    }
  }

  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  // Uniform double in [0, 1).
  double unit() { return unit_from_bits(next()); }
  // Uniform double in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  // Uniform integer in [0, n); n must be > 0 (multiply-shift, tiny bias is irrelevant here).
  std::uint32_t below(std::uint32_t n) {
    return static_cast<std::uint32_t>(((next() >> 32) * static_cast<std::uint64_t>(n)) >> 32);
  }
  bool chance(double p) { return unit() < p; }

  // `base` with each channel shifted by up to +-`amount` (clamped to 0..255); alpha kept.
  Rgba8 vary(Rgba8 base, int amount) {
    auto shift = [&](std::uint8_t c) {
      const int delta = static_cast<int>(below(static_cast<std::uint32_t>(2 * amount + 1))) - amount;
      return static_cast<std::uint8_t>(std::clamp(static_cast<int>(c) + delta, 0, 255));
    };
    return {shift(base.r), shift(base.g), shift(base.b), base.a};
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
};

}  // namespace cellbake
