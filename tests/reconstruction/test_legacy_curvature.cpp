// Seed 000's discrete curvature operators (legacy_curvature.h) on shapes with known curvature.
//
// Both operators divide the turning angle at P_i by the SUM of the two chords, so on a circle of
// radius R they give 1 / (2R): half the curvature (docs/reconstruction.md, "Seed 000 legacy
// operators"). The tests therefore compare 2 x value with the true curvature.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>

#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/legacy_curvature.h"

namespace scanmesh {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<Eigen::Vector3d> circle(double radius, int n) {
  std::vector<Eigen::Vector3d> p;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * kPi * k / n;
    // Tilted out of the xy plane: the operator must not depend on the curve's plane.
    p.emplace_back(radius * std::cos(t), radius * std::sin(t) * 0.6, radius * std::sin(t) * 0.8);
  }
  return p;
}

RangeGrid cylinder_grid(double r, int n_phi, int n_h, double dh) {
  RangeGrid g(n_phi, n_h, 0.0, -0.5 * dh * (n_h - 1), dh);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) g.set_sample(i, j, static_cast<float>(r));
  return g;
}

TEST(DiscreteCurveCurvature, CircleGivesHalfTheCurvatureForStencilOneAndTwo) {
  constexpr double R = 40.0;
  const auto points = circle(R, 720);
  for (int stencil : {1, 2, 3}) {
    const auto open = discrete_curve_curvature(points, stencil, false);
    const auto closed = discrete_curve_curvature(points, stencil, true);
    ASSERT_EQ(open.size(), points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      EXPECT_NEAR(2 * closed[i], 1 / R, 0.01 / R) << "stencil " << stencil << " point " << i;
      const bool near_end = static_cast<int>(i) < stencil ||
                            static_cast<int>(i) >= static_cast<int>(points.size()) - stencil;
      if (near_end)
        EXPECT_EQ(open[i], 0.0) << "stencil " << stencil << " point " << i;
      else
        EXPECT_DOUBLE_EQ(open[i], closed[i]);
    }
  }
  // Exact discrete value: s dtheta / (4 R sin(s dtheta / 2)), 1.0000127 x 1/(2R) at s = 2.
  const double dtheta = 2 * kPi / 720;
  EXPECT_NEAR(discrete_curve_curvature(points, 2, true)[100],
              2 * dtheta / (4 * R * std::sin(dtheta)), 1e-12);
}

TEST(DiscreteCurveCurvature, StraightLineIsZeroAndBadStencilThrows) {
  std::vector<Eigen::Vector3d> line;
  for (int k = 0; k < 50; ++k) line.emplace_back(1.5 * k, -0.5 * k, 2.0 * k + 3);
  for (int stencil : {1, 2})
    for (double k : discrete_curve_curvature(line, stencil)) EXPECT_NEAR(k, 0.0, 1e-9);
  EXPECT_THROW(discrete_curve_curvature(line, 0), InvalidInputError);
  // Repeated points (zero chords) give 0, not NaN.
  std::vector<Eigen::Vector3d> repeated(5, Eigen::Vector3d(1, 2, 3));
  for (double k : discrete_curve_curvature(repeated, 1)) EXPECT_EQ(k, 0.0);
}

TEST(Seed000MaxCurvature, CylinderOfRadius60GivesOneOver60) {
  constexpr double R = 60.0;
  const RangeGrid g = cylinder_grid(R, 512, 48, 0.7);
  const MaxCurvatureMap m = seed000_max_curvature(g);
  ASSERT_EQ(m.value.size(), g.cell_count());
  double worst = 0.0;
  for (std::size_t k = 0; k < g.cell_count(); ++k) {
    // Every cell, the seam columns and the top and bottom rows included (the phi direction
    // (3, 0) is always complete on a full cylinder).
    ASSERT_TRUE(m.defined[k]) << k;
    worst = std::max(worst, std::abs(2 * m.value[k] * R - 1.0));
  }
  // The max is the phi direction (the circle of radius R): 2 x value = 1/R x 1.00010.
  EXPECT_LT(worst, 1e-3) << "2 x max curvature deviates from 1/60 by " << worst * 100 << " %";
  RecordProperty("cylinder_relative_error", std::to_string(worst));
}

TEST(Seed000MaxCurvature, SphereIsRightAtTheEquatorAndTooHighAwayFromIt) {
  // r(h) = sqrt(80^2 - h^2), rows from h = -56 to 56 (dh = 0.7). Every normal curvature of the
  // sphere is 1/80, but the operator measures the 3D curvature of the chord pair A-B-C: away
  // from the equator the grid lines are not geodesics (the phi direction follows a latitude
  // circle of radius r(h) < 80), and their geodesic curvature is counted too.
  constexpr double R = 80.0, dh = 0.7;
  constexpr int n_h = 161;
  RangeGrid g(512, n_h, 0.0, -0.5 * dh * (n_h - 1), dh);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < g.n_phi(); ++i)
      g.set_sample(i, j, static_cast<float>(std::sqrt(R * R - g.h(j) * g.h(j))));
  const MaxCurvatureMap m = seed000_max_curvature(g);
  const int equator = n_h / 2;
  for (int i : {0, 1, 200, 511}) {
    EXPECT_NEAR(2 * m.value[g.index(i, equator)] * R, 1.0, 1e-3) << i;
    for (int j : {5, 40, 120, 155}) {
      // At least the latitude circle's curvature 1/r(h); the diagonal directions bend more.
      const double latitude_radius = std::sqrt(R * R - g.h(j) * g.h(j));
      ASSERT_TRUE(m.defined[g.index(i, j)]);
      EXPECT_GE(2 * m.value[g.index(i, j)], 0.999 / latitude_radius)
          << "cell " << i << ", " << j << " (h = " << g.h(j) << ")";
    }
    // Symmetric in h.
    EXPECT_FLOAT_EQ(m.value[g.index(i, 5)], m.value[g.index(i, n_h - 1 - 5)]);
  }
  // h = +-28 mm (latitude 20 deg): 1.13 x the sphere's curvature; h = +-52.5 mm (41 deg): 1.57 x.
  EXPECT_NEAR(2 * m.value[g.index(0, 40)] * R, 1.128, 0.01);
  EXPECT_NEAR(2 * m.value[g.index(0, 5)] * R, 1.575, 0.01);
}

TEST(Seed000MaxCurvature, HolesSkipDirectionsAndIsolatedCellsAreUndefined) {
  RangeGrid g = cylinder_grid(60.0, 64, 20, 0.7);
  g.invalidate(10, 10);
  // A cell alone in an empty row block: no complete direction.
  for (int i = 30; i < 40; ++i)
    for (int j = 0; j < 20; ++j)
      if (!(i == 35 && j == 10)) g.invalidate(i, j);
  const MaxCurvatureMap m = seed000_max_curvature(g);
  EXPECT_FALSE(m.defined[g.index(10, 10)]);
  EXPECT_EQ(m.value[g.index(10, 10)], 0.0f);
  EXPECT_FALSE(m.defined[g.index(35, 10)]);
  EXPECT_EQ(m.value[g.index(35, 10)], 0.0f);
  // (13, 10) lost its phi direction (C = (10, 10)) but keeps the diagonal ones, which on a
  // cylinder bend less: defined, below an intact cell's value (the phi direction).
  EXPECT_TRUE(m.defined[g.index(13, 10)]);
  EXPECT_GT(m.value[g.index(13, 10)], 0.0f);
  EXPECT_LT(m.value[g.index(13, 10)], m.value[g.index(20, 10)]);
}

TEST(Seed000Operators, PixelStaircaseInflatesCurveCurvatureButNotTheGridOperator) {
  // Seed 000 §6.1.2: a pixel curve that runs diagonally in (phi, h) has a staircase, and the curve
  // operator sees its corners as curvature, 40-80x the surface's. Here: the pixel line
  // h index = round(0.4 i) on a cylinder r = 60 (dphi 2 pi / 512, dh 0.7), lifted to 3D.
  constexpr double R = 60.0, dh = 0.7, slope = 0.4;
  const RangeGrid g = cylinder_grid(R, 512, 128, dh);
  std::vector<Eigen::Vector3d> pixels;
  for (int i = 0; i < 200; ++i)
    pixels.push_back(g.cartesian(i, static_cast<int>(std::lround(slope * i))));
  // The smooth curve is a helix of radius R and pitch c = slope dh / dphi per radian.
  const double c = slope * dh / g.dphi();
  const double true_curvature = R / (R * R + c * c);
  for (int stencil : {1, 2}) {
    const auto k = discrete_curve_curvature(pixels, stencil);
    const double ratio = 2 * *std::max_element(k.begin(), k.end()) / true_curvature;
    // Measured: 59.6 (stencil 1) and 19.7 (stencil 2).
    EXPECT_GT(ratio, stencil == 1 ? 40.0 : 15.0) << "stencil " << stencil;
    RecordProperty("staircase_ratio_stencil_" + std::to_string(stencil), std::to_string(ratio));
    std::cout << "pixel staircase, stencil " << stencil << ": max 2 x curve curvature = " << ratio
              << " x the helix curvature\n";
  }
  // The grid operator on the same cylinder has no staircase: every cell within 0.1 % of 1/R.
  const MaxCurvatureMap m = seed000_max_curvature(g);
  for (std::size_t k = 0; k < g.cell_count(); k += 97) EXPECT_NEAR(2 * m.value[k], 1 / R, 1e-3 / R);
}

}  // namespace
}  // namespace scanmesh
