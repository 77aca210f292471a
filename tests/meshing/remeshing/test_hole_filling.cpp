// Hole patches of prepare_input (meshing/src/remeshing/hole_filling.h): orientation, manifold
// patch, the chords that must not be used, the fallback for loops that fold over their plane.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>

#include "hole_filling.h"

namespace scanmesh::remeshing::detail {
namespace {

using Vec3 = Eigen::Vector3d;

std::vector<Vec3> circle(int n, double r, double wave = 0) {
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    p.push_back({r * std::cos(a), r * std::sin(a), wave * std::sin(2 * a)});
  }
  return p;
}

auto never_joined = [](int, int) { return false; };

// Directed edge -> count over the patch triangles.
std::map<std::pair<int, int>, int> directed_edges(const HolePatch& h) {
  std::map<std::pair<int, int>, int> e;
  for (const auto& t : h.triangles)
    for (int i = 0; i < 3; ++i) ++e[{t[i], t[(i + 1) % 3]}];
  return e;
}

TEST(HoleFilling, PlanarCircleGivesAFlatManifoldPatchOrientedAgainstTheLoop) {
  const int n = 40;
  const auto loop = circle(n, 10);
  const HolePatch h = fill_hole(loop, never_joined);
  ASSERT_FALSE(h.new_points.empty());
  const auto e = directed_edges(h);
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(e.count({i, (i + 1) % n}), 0u) << "loop edge kept the loop's direction";
    EXPECT_EQ(e.count({(i + 1) % n, i}), 1u) << "loop edge " << i;
  }
  for (const auto& [d, c] : e) {
    EXPECT_EQ(c, 1) << "directed edge used twice";
    const bool loop_edge =
        d.first < n && d.second < n &&
        (std::abs(d.first - d.second) == 1 || std::abs(d.first - d.second) == n - 1);
    if (!loop_edge) {
      EXPECT_EQ(e.count({d.second, d.first}), 1u) << "inner edge without its twin";
    }
  }
  double area = 0, longest = 0;
  auto point = [&](int k) { return k < n ? loop[k] : h.new_points[k - n]; };
  for (const auto& t : h.triangles) {
    area += 0.5 * (point(t[1]) - point(t[0])).cross(point(t[2]) - point(t[0])).norm();
    for (int i = 0; i < 3; ++i)
      longest = std::max(longest, (point(t[i]) - point(t[(i + 1) % 3])).norm());
  }
  for (const Vec3& p : h.new_points) EXPECT_NEAR(p.z(), 0, 1e-9);
  const double polygon_area = 0.5 * n * 100 * std::sin(2 * std::numbers::pi / n);
  EXPECT_NEAR(area, polygon_area, 1e-6 * polygon_area);  // the patch covers the disk once
  // Refined to 4/3 of the loop edge; the smoothing afterwards may stretch a few a little.
  EXPECT_LT(longest, 1.5 * 2 * 10 * std::sin(std::numbers::pi / n));
}

TEST(HoleFilling, WavyLoopGivesAMembraneBetweenItsHeights) {
  const auto loop = circle(48, 10, 2);
  const HolePatch h = fill_hole(loop, never_joined);
  ASSERT_FALSE(h.new_points.empty());
  for (const Vec3& p : h.new_points) {
    EXPECT_LT(std::hypot(p.x(), p.y()), 10.0);
    EXPECT_LT(std::abs(p.z()), 2.0);  // harmonic: no higher than the rim
  }
}

TEST(HoleFilling, ChordsJoinedOutsideTheHoleAreNeverUsed) {
  // A square whose diagonal 0-2 is an edge of the mesh outside the hole.
  const std::vector<Vec3> square{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const HolePatch h = fill_hole(square, [](int i, int j) { return i + j == 2 && i != j; });
  for (const auto& [d, c] : directed_edges(h))
    EXPECT_FALSE((d.first == 0 && d.second == 2) || (d.first == 2 && d.second == 0));
  // Both diagonals joined: no triangulation of the square is possible without a new vertex.
  const HolePatch fan = fill_hole(square, [](int i, int j) { return (i + j) % 2 == 0 && i != j; });
  ASSERT_EQ(fan.new_points.size(), 1u);
  EXPECT_EQ(fan.triangles.size(), 4u);
  for (const auto& t : fan.triangles) EXPECT_TRUE(t[0] == 4 || t[1] == 4 || t[2] == 4);
}

TEST(HoleFilling, LoopThatCrossesItselfInItsPlaneFallsBackToAFan) {
  const std::vector<Vec3> bow_tie{{0, 0, 0}, {2, 2, 0.1}, {2, 0, 0}, {0, 2, 0.1}};
  const HolePatch h = fill_hole(bow_tie, never_joined);
  ASSERT_EQ(h.new_points.size(), 1u);
  EXPECT_EQ(h.triangles.size(), 4u);
}

}  // namespace
}  // namespace scanmesh::remeshing::detail
