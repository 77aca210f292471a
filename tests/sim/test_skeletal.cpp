// Skeleton-based implicit surface, seed 003 §2.1-2.2 (sim/src/skeletal.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "scanmesh/sim/scene.h"
#include "scanmesh/sim/shapes.h"

using namespace scanmesh::sim;
using Eigen::Vector3d;

TEST(Skeletal, WyvillKernelKnownValues) {
  EXPECT_DOUBLE_EQ(wyvill_kernel(0.0, 10.0).e, 1.0);
  EXPECT_NEAR(wyvill_kernel(25.0, 10.0).e, 0.5, 1e-15);  // e(R/2) = 1/2
  EXPECT_DOUBLE_EQ(wyvill_kernel(100.0, 10.0).e, 0.0);
  EXPECT_NEAR(wyvill_max_slope(), 1.5844, 1e-3);
  // The stated bound really bounds |de/dr|.
  double worst = 0.0;
  for (int k = 1; k < 10000; ++k) {
    const double r = k * 1e-4;
    worst = std::max(worst, std::abs(wyvill_kernel(r * r, 1.0).de_ds * 2.0 * r));
  }
  EXPECT_LE(worst, wyvill_max_slope() + 1e-12);
  EXPECT_GT(worst, wyvill_max_slope() - 1e-6);
}

TEST(Skeletal, SinglePointIsSphereOfHalfRadius) {
  SkeletonElement e;
  e.a = {5, -3, 100};
  e.radius = 60.0;
  const auto s = make_skeletal({e}, 0.5);
  for (int k = 0; k < 24; ++k) {
    const double phi = k * 2.0 * std::numbers::pi / 24.0;
    const Vector3d dir(-std::cos(phi), -std::sin(phi), 0.0);
    const Vector3d origin = Vector3d(5, -3, 110) - 300.0 * dir;
    const auto t = s->intersect(origin, dir, 0.0, 600.0);
    ASSERT_TRUE(t);
    const Vector3d p = origin + *t * dir;
    EXPECT_NEAR((p - e.a).norm(), 30.0, 1e-6);
    const auto g = geometry_from_field(s->field(p));
    EXPECT_NEAR(g.k1, 1.0 / 30.0, 1e-9);
    EXPECT_NEAR(g.k2, 1.0 / 30.0, 1e-9);
    EXPECT_NEAR((g.normal - (p - e.a).normalized()).norm(), 0.0, 1e-9);
  }
}

TEST(Skeletal, SingleSegmentIsCapsule) {
  SkeletonElement e;
  e.type = SkeletonElement::Type::Segment;
  e.a = {0, 0, 0};
  e.b = {0, 0, 50};
  e.radius = 40.0;
  const auto s = make_skeletal({e}, 0.5);
  const auto t = s->intersect({300, 0, 25}, {-1, 0, 0}, 0.0, 300.0);
  ASSERT_TRUE(t);
  EXPECT_NEAR(300.0 - *t, 20.0, 1e-6);
  const auto g = geometry_from_field(s->field({20, 0, 25}));
  EXPECT_NEAR(g.k1, 1.0 / 20.0, 1e-9);
  EXPECT_NEAR(g.k2, 0.0, 1e-9);
  const auto cap = s->intersect({0, 0, 300}, {0, 0, -1}, 0.0, 300.0);
  ASSERT_TRUE(cap);
  EXPECT_NEAR(300.0 - *cap, 70.0, 1e-6);
}

TEST(Skeletal, GradientAndHessianMatchFiniteDifferences) {
  std::vector<SkeletonElement> els(3);
  els[0].a = {0, 0, 0};
  els[0].radius = 40;
  els[1].type = SkeletonElement::Type::Segment;
  els[1].a = {10, 5, -10};
  els[1].b = {30, -5, 20};
  els[1].radius = 30;
  els[1].weight = 1.3;
  els[2].a = {-15, 5, 5};
  els[2].radius = 20;
  els[2].weight = -0.7;
  const auto s = make_skeletal(els, 0.5);
  const double h = 1e-4;
  const Vector3d pts[] = {{5, 3, 2}, {20, 8, 10}, {-8, 2, 4}, {35, -2, 28}, {12, -6, -14}};
  for (const Vector3d& x : pts) {
    const FieldSample f = s->field(x);
    for (int k = 0; k < 3; ++k) {
      const Vector3d dx = h * Vector3d::Unit(k);
      const FieldSample fp = s->field(x + dx), fm = s->field(x - dx);
      EXPECT_NEAR(f.gradient[k], (fp.value - fm.value) / (2 * h), 1e-7) << x.transpose();
      const Vector3d col = (fp.gradient - fm.gradient) / (2 * h);
      for (int r = 0; r < 3; ++r) EXPECT_NEAR(f.hessian(r, k), col[r], 1e-6) << x.transpose();
    }
  }
}

TEST(Skeletal, RayDoesNotMissThinEar) {
  // A big head-like blob plus a thin plate sticking out (like an ear seen edge-on).
  std::vector<SkeletonElement> els(2);
  els[0].a = {0, 0, 0};
  els[0].radius = 120;
  els[1].type = SkeletonElement::Type::Segment;
  els[1].a = {0, 60, 0};
  els[1].b = {0, 170, 0};
  els[1].radius = 4;
  els[1].weight = 1.0;
  const auto s = make_skeletal(els, 0.5);
  // Beyond the blob's support (|y| > 120) the plate is a capsule of radius 2.
  const auto t = s->intersect({300, 150, 0.5}, {-1, 0, 0}, 0.0, 600.0);
  ASSERT_TRUE(t);
  EXPECT_NEAR(300.0 - *t, std::sqrt(4.0 - 0.25), 1e-6);
}

TEST(Skeletal, RejectsImpossibleElements) {
  SkeletonElement e;
  e.radius = -1.0;
  EXPECT_THROW(make_skeletal({e}), scanmesh::InvalidInputError);
  EXPECT_THROW(make_skeletal({}), scanmesh::InvalidInputError);
  e.radius = 1.0;
  EXPECT_THROW(make_skeletal({e}, 0.0), scanmesh::InvalidInputError);
}
