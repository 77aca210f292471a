// The continuous surface: evaluation, holes, intersections, projection, implicit view.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "scanmesh/reconstruction/scan_surface.h"
#include "test_support.h"

namespace scanmesh {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(ScanSurface, EvaluationBetweenCellsReproducesTheSphereWithinAHundredthMillimetre) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  double worst = 0;
  int evaluated = 0;
  // Off-grid points (irrational offsets) over the band where the sphere is not grazing.
  for (double h = 40.0 + 0.173; h < 160.0; h += 0.731)
    for (double phi = 0.011; phi < 2 * kPi; phi += 0.0137) {
      const auto p = surface.position(phi, h);
      if (!p) continue;
      worst = std::max(worst, std::abs((*p - Eigen::Vector3d(0, 0, 100)).norm() - 80.0));
      ++evaluated;
    }
  EXPECT_GT(evaluated, 70000);
  EXPECT_LT(worst, 0.01);
}

TEST(ScanSurface, InterpolatesTheGridExactlyAtNodesAndWrapsInPhi) {
  const auto scan = test::sphere_scan(0.05);
  const ScanSurface surface(scan.grid);
  const RangeGrid& g = scan.grid;
  for (int j = 10; j < 500; j += 37)
    for (int i = 0; i < 512; i += 29) {
      if (!g.valid(i, j)) continue;
      const auto r = surface.radius(g.phi(i), g.h(j));
      ASSERT_TRUE(r.has_value());
      EXPECT_NEAR(r->r, g.radius(i, j), 1e-5);
      // The same point one turn later.
      EXPECT_NEAR(surface.radius(g.phi(i) + 2 * kPi, g.h(j))->r, g.radius(i, j), 1e-5);
    }
  // Across the seam, between column 511 and column 0.
  const double seam_phi = g.phi(511) + 0.5 * g.dphi();
  ASSERT_TRUE(surface.radius(seam_phi, 100.0).has_value());
  EXPECT_NEAR(surface.radius(seam_phi, 100.0)->r, 80.0, 0.2);
}

TEST(ScanSurface, IsContinuouslyDifferentiableAcrossPatchBorders) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  const RangeGrid& g = scan.grid;
  const double eps = 1e-7;
  for (int i = 5; i < 500; i += 50) {
    const double phi = g.phi(i), h = 100.3;
    const auto left = surface.radius(phi - eps, h), right = surface.radius(phi + eps, h);
    ASSERT_TRUE(left && right);
    EXPECT_NEAR(left->r_phi, right->r_phi, 1e-4);
    EXPECT_NEAR(left->r_h, right->r_h, 1e-4);
  }
}

TEST(ScanSurface, NeverInterpolatesAcrossAnInvalidCell) {
  auto scan = test::sphere_scan();
  RangeGrid g = scan.grid;
  g.invalidate(200, 256);
  const ScanSurface surface(g);
  // The four patches around the hole are undefined; the next ones are defined.
  for (double du : {-0.5, 0.5})
    for (double dv : {-0.5, 0.5})
      EXPECT_FALSE(surface.defined(g.phi(200) + du * g.dphi(), g.h(256) + dv * g.dh()));
  EXPECT_TRUE(surface.defined(g.phi(202) + 0.5 * g.dphi(), g.h(256) + 0.5 * g.dh()));
  // Outside the rows there is no surface.
  EXPECT_FALSE(surface.defined(1.0, g.h(0) - 1.0));
  EXPECT_FALSE(surface.defined(1.0, g.h(511) + 1.0));
}

TEST(ScanSurface, CheapEvaluationsEqualTheFullJetBitForBitAndAreUndefinedWhereItIs) {
  // Holes and a rough grid, so one-sided slopes and missing twists are exercised too.
  auto scan = test::sphere_scan(0.05);
  RangeGrid g = scan.grid;
  for (int k = 0; k < 40; ++k) g.invalidate((37 * k) % 512, 60 + (53 * k) % 400);
  const ScanSurface surface(g);
  int compared = 0, undefined = 0;
  for (double h = g.h(0) - 2.0; h < g.h(511) + 2.0; h += 0.613)
    for (double phi = -0.3; phi < 2 * kPi + 0.3; phi += 0.0173) {
      const auto jet = surface.radius(phi, h);
      const auto value = surface.radius_value(phi, h);
      ASSERT_EQ(jet.has_value(), value.has_value()) << phi << " " << h;
      if (!jet) {
        ++undefined;
        continue;
      }
      ASSERT_EQ(jet->r, *value) << phi << " " << h;  // exact, not near
      // The cheaper position and normal are evaluate()'s, exactly.
      const auto full = surface.evaluate(phi, h);
      const auto cheap = surface.point_normal(phi, h);
      ASSERT_TRUE(full && cheap);
      ASSERT_EQ(full->position, cheap->position);
      ASSERT_EQ(full->normal(), cheap->normal);
      ASSERT_EQ(full->d_phi, cheap->d_phi);
      ASSERT_EQ(full->d_h, cheap->d_h);
      ASSERT_EQ(full->position, *surface.position(phi, h));
      ++compared;
    }
  EXPECT_GT(compared, 50000);
  EXPECT_GT(undefined, 1000);
}

TEST(ScanSurface, SegmentThroughTheHeadFindsEveryCrossingAndAMissFindsNone) {
  sim::ScannerConfig c = sim::builtin_head_scanner();
  c.noise_sigma_mm = 0.0;
  c.spike_probability = 0.0;
  c.hair = false;
  c.occlusion = false;
  const auto scan = sim::simulate_scan(sim::builtin_head_scene(), c);
  const ScanSurface surface(scan.grid);
  // A horizontal line through the head at eye height, from the right side to the left, crosses
  // the surface at least twice (in and out); the crossings agree with the exact scene.
  const sim::Scene scene = sim::builtin_head_scene();
  for (double z : {60.0, 100.0, 140.0, 170.0}) {
    const Eigen::Vector3d origin(-20.0, -250.0, z), dir(0.0, 1.0, 0.0);
    const auto hits = surface.intersect_segment(origin, dir, 0.0, 500.0);
    // Exact crossings: cast the same line against the scene repeatedly.
    std::vector<double> exact;
    double t = 0.0;
    while (true) {
      const auto hit = scene.intersect(origin, dir, t, 500.0);
      if (!hit) break;
      exact.push_back(hit->t);
      t = hit->t + 1e-3;
    }
    ASSERT_GE(exact.size(), 2u) << "z = " << z;
    ASSERT_EQ(hits.size(), exact.size()) << "z = " << z;
    for (std::size_t k = 0; k < hits.size(); ++k) {
      EXPECT_NEAR(hits[k].t, exact[k], 0.05) << "z = " << z << " crossing " << k;
      EXPECT_LT(std::abs(surface.implicit(hits[k].point)->value), 1e-3);
    }
  }
  const auto miss = surface.intersect_segment({300, 300, 100}, {1, 0, 0}, 0.0, 200.0);
  EXPECT_TRUE(miss.empty());
}

TEST(ScanSurface, CircleIntersectionFindsBothCrossingsOfASphere) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  // A circle of radius 10 centred on the sphere's surface point (-80, 0, 100) in the xz-plane
  // crosses the sphere twice.
  const auto roots = surface.intersect_circle({-80, 0, 100}, 10.0, {1, 0, 0}, {0, 0, 1});
  ASSERT_EQ(roots.size(), 2u);
  for (double theta : roots) {
    const Eigen::Vector3d p =
        Eigen::Vector3d(-80, 0, 100) + 10.0 * Eigen::Vector3d(std::cos(theta), 0, std::sin(theta));
    EXPECT_NEAR((p - Eigen::Vector3d(0, 0, 100)).norm(), 80.0, 1e-3);
  }
}

TEST(ScanSurface, ProjectionLandsOnTheSphereAlongTheNormal) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  const Eigen::Vector3d centre(0, 0, 100);
  for (const Eigen::Vector3d& dir : {Eigen::Vector3d(1, 0.3, 0.2), Eigen::Vector3d(-0.5, -1, -0.4),
                                     Eigen::Vector3d(0.2, 1, 0.5)}) {
    const Eigen::Vector3d n = dir.normalized();
    for (double offset : {-5.0, 3.0}) {
      const auto proj = surface.project(centre + (80.0 + offset) * n);
      ASSERT_TRUE(proj.has_value());
      EXPECT_LT((proj->point - (centre + 80.0 * n)).norm(), 2e-3);
      EXPECT_NEAR(proj->distance, std::abs(offset), 2e-3);
    }
  }
}

TEST(ScanSurface, ImplicitViewIsPositiveInsideWithAGradientAgainstTheNormal) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  const Eigen::Vector3d n = Eigen::Vector3d(-1, 0.4, 0.3).normalized();
  const Eigen::Vector3d on = Eigen::Vector3d(0, 0, 100) + 80.0 * n;
  EXPECT_GT(surface.implicit(on - 1.0 * n)->value, 0.5);
  EXPECT_LT(surface.implicit(on + 1.0 * n)->value, -0.5);
  const auto s = surface.implicit(on);
  ASSERT_TRUE(s.has_value());
  EXPECT_NEAR(s->value, 0.0, 1e-3);
  // The gradient points inward (F grows toward the axis) and matches finite differences.
  EXPECT_LT(s->gradient.normalized().dot(n), -0.99);
  const double eps = 1e-4;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(a) = eps;
    const double fd =
        (surface.implicit(on + d)->value - surface.implicit(on - d)->value) / (2 * eps);
    EXPECT_NEAR(s->gradient(a), fd, 1e-4);
  }
}

}  // namespace
}  // namespace scanmesh
