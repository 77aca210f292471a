#include <gtest/gtest.h>

#include <numbers>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/range_grid.h"

namespace scanmesh {
namespace {

constexpr double kPi = std::numbers::pi;

// r(i, j) = 100 + 2 i + 3 j + 0.5 i j is bilinear in (i, j); all values are exact in float.
RangeGrid bilinear_grid(int n_phi, int n_h) {
  RangeGrid g(n_phi, n_h, 0.25, -10.0, 2.0);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) g.set_sample(i, j, 100.0f + 2.0f * i + 3.0f * j + 0.5f * i * j);
  return g;
}

TEST(RangeGrid, WrapPhiTakesColumnsModuloNPhi) {
  RangeGrid g(8, 4);
  EXPECT_EQ(g.wrap_phi(3), 3);
  EXPECT_EQ(g.wrap_phi(8), 0);
  EXPECT_EQ(g.wrap_phi(-1), 7);
  EXPECT_EQ(g.wrap_phi(-9), 7);
  EXPECT_EQ(g.wrap_phi(17), 1);
}

TEST(RangeGrid, NewGridIsAllInvalidAndRejectsImpossibleSizes) {
  RangeGrid g(16, 8);
  EXPECT_EQ(g.cell_count(), 128u);
  EXPECT_EQ(g.valid_count(), 0u);
  EXPECT_THROW(RangeGrid(1, 8), InvalidInputError);
  EXPECT_THROW(RangeGrid(8, 8, 0.0, 0.0, 0.0), InvalidInputError);
  EXPECT_THROW(g.set_sample(0, 0, -1.0f), InvalidInputError);
}

TEST(RangeGrid, CartesianFollowsCylinderConvention) {
  RangeGrid g(4, 3, 0.0, 10.0, 2.0);  // phi_i = i * pi/2, h_j = 10 + 2 j
  g.set_sample(1, 2, 5.0f);
  const Eigen::Vector3d p = g.cartesian(1, 2);
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.y(), 5.0, 1e-12);
  EXPECT_DOUBLE_EQ(p.z(), 14.0);
  EXPECT_DOUBLE_EQ(g.phi(1), kPi / 2);
  EXPECT_EQ(g.index(1, 2), 9u);
}

TEST(RangeGrid, SampleRadiusIsExactForBilinearData) {
  const RangeGrid g = bilinear_grid(16, 10);
  for (double fu : {0.0, 0.25, 0.5, 0.9})
    for (double fv : {0.0, 0.3, 0.75}) {
      const double u = 5 + fu, v = 4 + fv;
      const auto r = g.sample_radius(g.phi0() + u * g.dphi(), g.h0() + v * g.dh());
      ASSERT_TRUE(r.has_value());
      EXPECT_NEAR(*r, 100.0 + 2 * u + 3 * v + 0.5 * u * v, 1e-9);
    }
  // Top row exactly: h = h(n_h - 1) is still inside.
  const auto top = g.sample_radius(g.phi(3), g.h(9));
  ASSERT_TRUE(top.has_value());
  EXPECT_NEAR(*top, 100.0 + 6 + 27 + 13.5, 1e-9);
  EXPECT_FALSE(g.sample_radius(g.phi(3), g.h(9) + 0.01).has_value());
  EXPECT_FALSE(g.sample_radius(g.phi(3), g.h0() - 0.01).has_value());
}

TEST(RangeGrid, SampleRadiusIsNulloptNextToAnInvalidCell) {
  RangeGrid g = bilinear_grid(16, 10);
  g.invalidate(6, 5);
  EXPECT_EQ(g.valid_count(), 159u);
  EXPECT_EQ(g.radius(6, 5), 0.0f);
  // The four quads around (6, 5) touch it; their neighbours do not.
  for (double u : {5.5, 6.5})
    for (double v : {4.5, 5.5})
      EXPECT_FALSE(g.sample_radius(g.phi0() + u * g.dphi(), g.h0() + v * g.dh()).has_value())
          << "u=" << u << " v=" << v;
  EXPECT_TRUE(g.sample_radius(g.phi0() + 4.5 * g.dphi(), g.h0() + 4.5 * g.dh()).has_value());
  EXPECT_TRUE(g.sample_radius(g.phi0() + 7.5 * g.dphi(), g.h0() + 5.5 * g.dh()).has_value());
}

TEST(RangeGrid, SampleRadiusInterpolatesAcrossThePhiSeam) {
  const RangeGrid g = bilinear_grid(16, 10);
  const int j = 3;
  const double expected = 0.5 * (g.radius(15, j) + g.radius(0, j));
  // Half-way between the last column and column 0, reached from either side of 2*pi.
  const auto a = g.sample_radius(g.phi(15) + 0.5 * g.dphi(), g.h(j));
  const auto b = g.sample_radius(g.phi0() - 0.5 * g.dphi(), g.h(j));
  const auto c = g.sample_radius(g.phi(15) + 0.5 * g.dphi() + 4 * kPi, g.h(j));
  ASSERT_TRUE(a && b && c);
  EXPECT_NEAR(*a, expected, 1e-9);
  EXPECT_NEAR(*b, expected, 1e-9);
  EXPECT_NEAR(*c, expected, 1e-9);
}

}  // namespace
}  // namespace scanmesh
