// Counter-based random numbers: every random choice is a pure function of (seed, i, j, purpose),
// so results do not depend on evaluation order or thread count (docs/simulator.md).
#pragma once

#include <array>
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

//! The inverse normal CDF at k / kNormalBins, k = 0..kNormalBins (the ends are -/+ infinity and
//! never read), found once by bisection on erfc.
inline constexpr int kNormalBins = 4096;
inline const std::array<double, kNormalBins + 1>& normal_quantiles() {
  static const std::array<double, kNormalBins + 1> table = [] {
    std::array<double, kNormalBins + 1> q{};
    for (int k = 1; k < kNormalBins; ++k) {
      const double p = static_cast<double>(k) / kNormalBins;
      double lo = -10.0, hi = 10.0;
      for (int it = 0; it < 64; ++it) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::numbers::sqrt2) < p ? lo : hi) = mid;
      }
      q[k] = 0.5 * (lo + hi);
    }
    q[0] = -INFINITY;
    q[kNormalBins] = INFINITY;
    return q;
  }();
  return table;
}

//! Standard normal from 64 random bits, several times cheaper than Box-Muller (no log, no cos):
//! the top 12 bits pick one of 4096 equal-probability bins of N(0, 1), the next 32 bits a point
//! in it by linear interpolation of the inverse CDF. The density is piecewise constant between
//! the quantiles (within 1e-4 of N(0, 1) in every quantile). The two outer bins (|x| > 3.49, p < 1/4096 each)
//! are sampled exactly with Marsaglia's tail method, so the tails stay Gaussian. Used for the
//! per-pixel sensor noise, where a frame draws three normals for each of its ~10^6 pixels.
inline double gaussian_from_bits(std::uint64_t bits) {
  const auto& q = normal_quantiles();
  const int bin = static_cast<int>(bits >> 52);
  const double frac = static_cast<double>((bits >> 20) & 0xffffffffULL) * 0x1.0p-32;
  if (bin > 0 && bin < kNormalBins - 1) return q[bin] + frac * (q[bin + 1] - q[bin]);
  // Tail beyond a = |q[1]|: x = a + e1 / a with e1, e2 exponential, accepted if 2 e2 > (e1/a)^2.
  const double a = -q[1];
  std::uint64_t h = bits;
  for (int it = 0; it < 64; ++it) {
    h = mix64(h);
    const double e1 = -std::log(1.0 - to_unit(h)) / a;
    h = mix64(h);
    const double e2 = -std::log(1.0 - to_unit(h));
    if (2 * e2 > e1 * e1) return bin == 0 ? -(a + e1) : a + e1;
  }
  return bin == 0 ? -a : a;  // not reached in practice (acceptance ~ 0.9 per round)
}

}  // namespace scanmesh::sim::detail
