// The simulator's counter-based random numbers: the tabulated normal used for the per-pixel
// sensor noise has the moments, the quantiles and the tails of N(0, 1).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "random.h"

namespace scanmesh::sim::detail {
namespace {

double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }

TEST(SimRandom, TabulatedGaussianHasTheMomentsQuantilesAndTailsOfTheNormal) {
  constexpr int n = 2'000'000;
  double sum = 0, sum2 = 0, sum4 = 0;
  long tail = 0, far_tail = 0;
  const std::vector<double> at = {-2.5, -1.0, -0.3, 0.0, 0.7, 1.6, 3.0};
  std::vector<long> below(at.size(), 0);
  for (int i = 0; i < n; ++i) {
    const double x = gaussian_from_bits(mix64(hash_key(7, 1, 2, static_cast<std::uint64_t>(i))));
    ASSERT_TRUE(std::isfinite(x));
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
    tail += std::fabs(x) > 3.6;
    far_tail += std::fabs(x) > 4.0;
    for (std::size_t k = 0; k < at.size(); ++k) below[k] += x < at[k];
  }
  const double mean = sum / n, var = sum2 / n - mean * mean;
  // Standard errors at n = 2e6: mean 7e-4, variance 1e-3, kurtosis 1.7e-3 (x3 margins and more).
  EXPECT_NEAR(mean, 0.0, 3e-3);
  EXPECT_NEAR(var, 1.0, 5e-3);
  EXPECT_NEAR(sum4 / n / (var * var), 3.0, 3e-2);
  for (std::size_t k = 0; k < at.size(); ++k)
    EXPECT_NEAR(static_cast<double>(below[k]) / n, normal_cdf(at[k]), 1.5e-3) << "at " << at[k];
  // The exact tail sampler beyond the outer quantile (|x| > 3.49): P(|x| > 3.6) = 3.2e-4,
  // P(|x| > 4) = 6.3e-5 (the interpolated table alone gives no values beyond 3.49).
  EXPECT_NEAR(static_cast<double>(tail) / n, 2 * normal_cdf(-3.6), 8e-5);
  EXPECT_NEAR(static_cast<double>(far_tail) / n, 2 * normal_cdf(-4.0), 2.5e-5);
}

TEST(SimRandom, TabulatedGaussianIsAPureFunctionOfItsBits) {
  const std::uint64_t bits = mix64(12345);
  EXPECT_EQ(gaussian_from_bits(bits), gaussian_from_bits(bits));
  EXPECT_NE(gaussian_from_bits(bits), gaussian_from_bits(mix64(bits)));
}

}  // namespace
}  // namespace scanmesh::sim::detail
