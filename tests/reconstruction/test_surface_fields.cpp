// Normals and principal curvatures against the simulator's exact differential geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/legacy_curvature.h"
#include "scanmesh/reconstruction/surface_fields.h"
#include "test_support.h"

namespace scanmesh {
namespace {

using test::away_from_holes;
using test::median;

struct RelativeErrors {
  std::vector<double> k1, k2, mean;
  std::vector<double> normal_deg;
};

RelativeErrors compare(const sim::SimulatedScan& scan, const SurfaceFields& f, int margin,
                       double k_scale) {
  RelativeErrors e;
  const RangeGrid& g = scan.grid;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i) {
      const std::size_t k = g.index(i, j);
      if (!f.defined[k] || !away_from_holes(g, i, j, margin)) continue;
      const auto& t = scan.truth[k].geometry;
      e.k1.push_back(std::abs(f.k1[k] - t.k1) / k_scale);
      e.k2.push_back(std::abs(f.k2[k] - t.k2) / k_scale);
      const double c = std::clamp(f.normal[k].cast<double>().dot(t.normal), -1.0, 1.0);
      e.normal_deg.push_back(std::acos(c) * 180.0 / M_PI);
    }
  return e;
}

TEST(SurfaceFields, AnalyticSphereCurvatureWithinOnePercent) {
  const auto scan = test::sphere_scan();
  const SurfaceFields f = compute_fields_analytic(scan.grid);
  const RelativeErrors e = compare(scan, f, 3, 1.0 / 80.0);
  ASSERT_GT(e.k1.size(), 100000u);
  EXPECT_LT(median(e.k1), 0.01);
  EXPECT_LT(median(e.k2), 0.01);
  EXPECT_LT(median(e.normal_deg), 0.05);
}

TEST(SurfaceFields, AnalyticCylinderCurvatureK1WithinOnePercentK2Small) {
  const auto scan =
      test::scan_yaml("  - {type: cylinder, center: [0, 0, 100], axis: [0, 0, 1], radius: 60}\n",
                      test::clean_scanner(512, 512, 20.0, 0.3));
  const SurfaceFields f = compute_fields_analytic(scan.grid);
  std::vector<double> k1, k2;
  for (std::size_t k = 0; k < f.size(); ++k)
    if (f.defined[k]) {
      k1.push_back(std::abs(f.k1[k] - 1.0 / 60.0) * 60.0);
      k2.push_back(std::abs(f.k2[k]) * 60.0);
    }
  ASSERT_GT(k1.size(), 200000u);
  EXPECT_LT(median(k1), 0.01);
  EXPECT_LT(median(k2), 0.02);
}

TEST(SurfaceFields, AnalyticTorusCurvatureWithinTwoPercentOfExact) {
  // A ring around the axis: the scanner sees its outer half.
  const auto scan = test::scan_yaml(
      "  - {type: torus, center: [0, 0, 100], axis: [0, 0, 1], major_radius: 60, minor_radius: "
      "25}\n",
      test::clean_scanner(512, 512, 80.0, 40.0 / 511));
  const SurfaceFields f = compute_fields_analytic(scan.grid);
  std::vector<double> k1, k2;
  for (int j = 0; j < scan.grid.n_h(); ++j)
    for (int i = 0; i < scan.grid.n_phi(); ++i) {
      const std::size_t k = scan.grid.index(i, j);
      if (!f.defined[k] || !away_from_holes(scan.grid, i, j, 3)) continue;
      const auto& t = scan.truth[k].geometry;
      k1.push_back(std::abs(f.k1[k] - t.k1) / std::abs(t.k1));
      k2.push_back(std::abs(f.k2[k] - t.k2) / std::abs(t.k2));
    }
  ASSERT_GT(k1.size(), 50000u);
  EXPECT_LT(median(k1), 0.02);
  EXPECT_LT(median(k2), 0.02);
}

TEST(SurfaceFields, AnalyticHeadMeanCurvatureAndNormalsMatchTheImplicitSurface) {
  sim::ScannerConfig c = sim::builtin_head_scanner();
  c.noise_sigma_mm = 0.0;
  c.spike_probability = 0.0;
  c.hair = false;
  const auto scan = sim::simulate_scan(sim::builtin_head_scene(), c);
  const SurfaceFields f = compute_fields_analytic(scan.grid);
  std::vector<double> abs_h;
  for (std::size_t k = 0; k < f.size(); ++k)
    if (f.defined[k]) abs_h.push_back(std::abs(scan.truth[k].geometry.mean()));
  const double h10 = test::percentile(abs_h, 0.10);
  std::vector<double> h_err, normal_deg;
  for (int j = 0; j < scan.grid.n_h(); ++j)
    for (int i = 0; i < scan.grid.n_phi(); ++i) {
      const std::size_t k = scan.grid.index(i, j);
      if (!f.defined[k] || !away_from_holes(scan.grid, i, j, 2)) continue;
      const auto& t = scan.truth[k].geometry;
      const double c_n = std::clamp(f.normal[k].cast<double>().dot(t.normal), -1.0, 1.0);
      normal_deg.push_back(std::acos(c_n) * 180.0 / M_PI);
      if (std::abs(t.mean()) <= h10) continue;
      h_err.push_back(std::abs(f.mean(k) - t.mean()) / std::abs(t.mean()));
    }
  ASSERT_GT(h_err.size(), 50000u);
  EXPECT_LT(median(h_err), 0.05);
  EXPECT_LT(median(normal_deg), 0.5);
}

TEST(SurfaceFields, QuadricSphereWithNoiseWithinFivePercent) {
  const auto scan = test::sphere_scan(0.05);
  const SurfaceFields f = compute_fields_quadric(scan.grid);
  const RelativeErrors e = compare(scan, f, 8, 1.0 / 80.0);
  ASSERT_GT(e.k1.size(), 100000u);
  EXPECT_LT(median(e.k1), 0.05);
  EXPECT_LT(median(e.k2), 0.05);
  EXPECT_LT(median(e.normal_deg), 0.5);
}

TEST(SurfaceFields, GridQuadricSphereWithNoiseWithinFivePercent) {
  const auto scan = test::sphere_scan(0.05);
  const SurfaceFields f = compute_fields_grid_quadric(scan.grid);
  const RelativeErrors e = compare(scan, f, 8, 1.0 / 80.0);
  ASSERT_GT(e.k1.size(), 100000u);
  EXPECT_LT(median(e.k1), 0.05);
  EXPECT_LT(median(e.k2), 0.05);
  EXPECT_LT(median(e.normal_deg), 0.5);
}

TEST(SurfaceFields, GridQuadricOnExactDataAgreesWithTheAnalyticMethod) {
  const auto scan = test::sphere_scan();
  const SurfaceFields a = compute_fields_analytic(scan.grid);
  const SurfaceFields g = compute_fields_grid_quadric(scan.grid);
  const RelativeErrors e = compare(scan, g, 3, 1.0 / 80.0);
  EXPECT_LT(median(e.k1), 0.01);
  EXPECT_LT(median(e.k2), 0.01);
  // Next to holes and rims it falls back to the 3D fit, so it defines at least as many cells.
  EXPECT_GE(g.defined_count(), a.defined_count());
}

TEST(SurfaceFields, PrincipalDirectionsAreOrthonormalTangents) {
  const auto scan = test::sphere_scan();
  const SurfaceFields f = compute_fields(scan.grid, CurvatureMethod::Analytic);
  std::size_t checked = 0;
  for (std::size_t k = 0; k < f.size(); k += 97) {
    if (!f.defined[k]) continue;
    EXPECT_NEAR(f.dir1[k].norm(), 1.0, 1e-4);
    EXPECT_NEAR(f.dir1[k].dot(f.normal[k]), 0.0, 1e-4);
    EXPECT_NEAR(f.dir2[k].dot(f.normal[k]), 0.0, 1e-4);
    EXPECT_GE(f.k1[k], f.k2[k]);
    ++checked;
  }
  EXPECT_GT(checked, 1000u);
}

TEST(SurfaceFields, NoEstimateNextToHoles) {
  auto scan = test::sphere_scan();
  RangeGrid g = scan.grid;
  g.invalidate(100, 256);
  const SurfaceFields f = compute_fields_analytic(g);
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) EXPECT_FALSE(f.defined[g.index(100 + di, 256 + dj)]);
  EXPECT_TRUE(f.defined[g.index(102, 256)]);
}

TEST(SurfaceFields, SeedMethodReportsTheLegacyOperatorOnTheCurvatureScale) {
  // On a cylinder the legacy maximum-curvature operator is exact up to its factor 1/2, which
  // compute_fields undoes so every method reports 1/mm.
  const auto scan =
      test::scan_yaml("  - {type: cylinder, center: [0, 0, 100], axis: [0, 0, 1], radius: 60}\n",
                      test::clean_scanner(256, 64, 60.0, 0.7));
  const SurfaceFields f = compute_fields(scan.grid, CurvatureMethod::Seed000);
  const MaxCurvatureMap raw = seed000_max_curvature(scan.grid);
  std::vector<double> err;
  for (std::size_t k = 0; k < f.size(); ++k) {
    if (!f.defined[k]) continue;
    EXPECT_FLOAT_EQ(f.k1[k], 2.0f * raw.value[k]);
    err.push_back(std::abs(f.k1[k] * 60.0 - 1.0));
  }
  ASSERT_GT(err.size(), 10000u);
  EXPECT_LT(median(err), 0.01);
}

TEST(SurfaceFields, QuadricRejectsImpossibleRadius) {
  const auto scan = test::sphere_scan();
  EXPECT_THROW(compute_fields_quadric(scan.grid, {.radius_mm = -1.0}), InvalidInputError);
  EXPECT_THROW(compute_fields_quadric(scan.grid, {.radius_mm = 5.0, .min_points = 3}),
               InvalidInputError);
}

}  // namespace
}  // namespace scanmesh
