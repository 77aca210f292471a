// Counter-based random numbers: every random choice is a pure function of (seed, i, j, purpose),
// so results do not depend on evaluation order or thread count (docs/simulator.md).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

namespace scanmesh::sim::detail {

//! splitmix64 finaliser (Steele, Lea, Flood 2014): a good 64-bit mixing function.
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

inline std::uint64_t hash_key(std::uint64_t seed, std::uint64_t a, std::uint64_t b, std::uint64_t c,
                              std::uint64_t d = 0) {
  std::uint64_t h = mix64(seed);
  h = mix64(h ^ a);
  h = mix64(h ^ b);
  h = mix64(h ^ c);
  return mix64(h ^ d);
}

//! Uniform in [0, 1) from the top 53 bits.
inline double to_unit(std::uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

//! Standard normal from a key (Box-Muller on two derived uniforms).
inline double gaussian(std::uint64_t key) {
  const double u1 = 1.0 - to_unit(mix64(key ^ 0x1234567ULL));  // (0, 1]
  const double u2 = to_unit(mix64(key ^ 0x89abcdefULL));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace scanmesh::sim::detail
