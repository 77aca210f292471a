// Exact differential geometry of the analytic scene objects (sim/src/shapes.cpp).
#include <gtest/gtest.h>

#include <cmath>

#include "scanmesh/sim/scene.h"
#include "scanmesh/sim/shapes.h"

using namespace scanmesh::sim;
using Eigen::Vector3d;

namespace {

SurfaceGeometry geometry_at(const SceneObject& o, const Vector3d& p) {
  return geometry_from_field(o.field(p));
}

}  // namespace

TEST(Shapes, SphereCurvatureIsOneOverRadius) {
  const auto s = make_sphere({1, 2, 3}, 40.0);
  const Vector3d p = Vector3d(1, 2, 3) + 40.0 * Vector3d(1, -2, 0.5).normalized();
  const auto g = geometry_at(*s, p);
  EXPECT_NEAR(g.k1, 1.0 / 40.0, 1e-12);
  EXPECT_NEAR(g.k2, 1.0 / 40.0, 1e-12);
  EXPECT_NEAR((g.normal - Vector3d(1, -2, 0.5).normalized()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(s->field(p).value), 0.0, 1e-12);
  EXPECT_LT(s->field({1, 2, 3}).value, 0.0);
}

TEST(Shapes, SphereRayHitIsExact) {
  const auto s = make_sphere({0, 0, 0}, 80.0);
  const auto t = s->intersect({300, 0, 30}, {-1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(t);
  EXPECT_NEAR(300.0 - *t, std::sqrt(80.0 * 80.0 - 30.0 * 30.0), 1e-12);
  // From inside the first crossing is the exit.
  const auto exit = s->intersect({0, 0, 0}, {1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(exit);
  EXPECT_NEAR(*exit, 80.0, 1e-12);
  EXPECT_FALSE(s->intersect({300, 0, 90}, {-1, 0, 0}, 0.0, 300.0));
}

TEST(Shapes, CylinderCurvaturesAreOneOverRadiusAndZero) {
  const auto c = make_cylinder({0, 0, 0}, {0, 0, 1}, 25.0, std::nullopt);
  const auto g = geometry_at(*c, {0, 25, 7});
  EXPECT_NEAR(g.k1, 1.0 / 25.0, 1e-12);
  EXPECT_NEAR(g.k2, 0.0, 1e-12);
  EXPECT_NEAR(std::abs(g.dir2.z()), 1.0, 1e-12);  // zero curvature along the axis
  EXPECT_NEAR(std::abs(g.dir1.x()), 1.0, 1e-12);
  const auto t = c->intersect({300, 0, 5}, {-1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 275.0, 1e-12);
}

TEST(Shapes, CappedCylinderHitsItsCap) {
  const auto c = make_cylinder({0, 0, 0}, {0, 0, 1}, 25.0, 10.0);
  const auto t = c->intersect({3, 4, 100}, {0, 0, -1}, 0.0, 300.0);
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 90.0, 1e-12);
  EXPECT_FALSE(c->intersect({300, 0, 11}, {-1, 0, 0}, 0.0, 300.0));
  const auto g = geometry_at(*c, {3, 4, 10});
  EXPECT_NEAR(g.normal.z(), 1.0, 1e-12);
  EXPECT_NEAR(g.k1, 0.0, 1e-12);
}

TEST(Shapes, TorusCurvaturesOnOuterAndInnerEquator) {
  const double big = 50.0, small = 10.0;
  const auto t = make_torus({0, 0, 0}, {0, 0, 1}, big, small);
  const auto outer = geometry_at(*t, {big + small, 0, 0});
  EXPECT_NEAR(outer.k1, 1.0 / small, 1e-12);
  EXPECT_NEAR(outer.k2, 1.0 / (big + small), 1e-12);
  const auto inner = geometry_at(*t, {0, big - small, 0});
  EXPECT_NEAR(inner.k1, 1.0 / small, 1e-12);
  EXPECT_NEAR(inner.k2, -1.0 / (big - small), 1e-12);
  const auto top = geometry_at(*t, {big, 0, small});  // top circle: k = 1/r and 0
  EXPECT_NEAR(top.k1, 1.0 / small, 1e-12);
  EXPECT_NEAR(top.k2, 0.0, 1e-12);
  const auto hit = t->intersect({300, 0, 0}, {-1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(*hit, 300.0 - big - small, 1e-9);
  // A ray along the axis passes through the hole.
  EXPECT_FALSE(t->intersect({0, 0, 300}, {0, 0, -1}, 0.0, 600.0));
  // A ray at height 6 hits the tube at rho = big + sqrt(small^2 - 36).
  const auto h6 = t->intersect({300, 0, 6}, {-1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(h6);
  EXPECT_NEAR(300.0 - *h6, big + 8.0, 1e-9);
}

TEST(Shapes, EllipsoidCurvaturesAtAxisEnds) {
  const double a = 30, b = 20, c = 10;
  const auto e = make_ellipsoid({0, 0, 0}, {a, b, c});
  // At (a, 0, 0) the normal sections have curvatures a/b^2 and a/c^2.
  const auto g = geometry_at(*e, {a, 0, 0});
  EXPECT_NEAR(g.k1, a / (c * c), 1e-12);
  EXPECT_NEAR(g.k2, a / (b * b), 1e-12);
  EXPECT_NEAR(std::abs(g.dir1.z()), 1.0, 1e-12);
  // Gaussian curvature at (0, 0, c) is c^2 / (a^2 b^2).
  const auto top = geometry_at(*e, {0, 0, c});
  EXPECT_NEAR(top.gauss(), c * c / (a * a * b * b), 1e-12);
  const auto hit = e->intersect({300, 0, 0}, {-1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(*hit, 300.0 - a, 1e-12);
}

TEST(Shapes, BoxSlabHitAndEdgeCurvature) {
  const auto b = make_box({10, 0, 0}, {5, 6, 7});
  const auto t = b->intersect({300, 1, 2}, {-1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 300.0 - 15.0, 1e-12);
  EXPECT_LT(b->field({10, 0, 0}).value, 0.0);
  // Outside an edge the level set is a cylinder around the edge: k = 1/d and 0.
  const auto g = geometry_at(*b, {10 + 5 + 3, 6 + 4, 0});
  EXPECT_NEAR(b->field({18, 10, 0}).value, 5.0, 1e-12);
  EXPECT_NEAR(g.k1, 1.0 / 5.0, 1e-12);
  EXPECT_NEAR(g.k2, 0.0, 1e-12);
}

namespace scanmesh::sim {
namespace {

TEST(Shapes, BoundsContainEverySurfacePointTheRaysFind) {
  const Scene scene = builtin_head_scene();
  std::vector<std::shared_ptr<const SceneObject>> objects = {
      make_sphere({1, 2, 3}, 5),
      make_ellipsoid({0, 0, 0}, {3, 4, 5}),
      make_torus({0, 0, 1}, Eigen::Vector3d(1, 1, 0).normalized(), 6, 2),
      make_box({2, 0, 0}, {1, 2, 3}),
      make_cylinder({0, 0, 0}, Eigen::Vector3d(0, 1, 1).normalized(), 2, 5.0),
      scene.objects.front()};
  for (const auto& object : objects) {
    const Eigen::AlignedBox3d box = object->bounds();
    ASSERT_FALSE(box.isEmpty());
    const Eigen::Vector3d centre = box.center();
    const double reach = box.diagonal().norm() + 10.0;
    int hits = 0;
    for (int k = 0; k < 200; ++k) {
      // Rays from far outside toward the box centre, from directions on a spiral.
      const double z = -1.0 + 2.0 * (k + 0.5) / 200.0, a = 2.39996 * k;
      const Eigen::Vector3d dir(std::sqrt(1 - z * z) * std::cos(a),
                                std::sqrt(1 - z * z) * std::sin(a), z);
      const auto t = object->intersect(centre + reach * dir, -dir, 0.0, 2 * reach);
      if (!t) continue;
      ++hits;
      const Eigen::Vector3d p = centre + reach * dir - *t * dir;
      EXPECT_TRUE(box.exteriorDistance(p) < 1e-6) << object->name;
    }
    EXPECT_GT(hits, 30) << object->name;  // a ring lets rays through its hole
  }
  EXPECT_TRUE(scene.bounds().contains(Eigen::Vector3d(0, 0, 150)));
}

}  // namespace
}  // namespace scanmesh::sim
