// The meshing kernel's point grid: k nearest neighbours and ball queries against brute force,
// on clouds that stress its cells (a flat sheet, crowded cells, far outliers in the border
// cells, duplicated points).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "point_grid.h"

namespace scanmesh::kernel {
namespace {

using Eigen::Vector3d;
using Neighbours = std::vector<std::pair<double, int>>;

// The K nearest other points of point i by (squared distance, index), as knn() promises.
Neighbours brute_knn(const std::vector<Vector3d>& pts, int i, int K) {
  Neighbours all;
  for (int j = 0; j < static_cast<int>(pts.size()); ++j)
    if (j != i) all.emplace_back((pts[j] - pts[i]).squaredNorm(), j);
  std::sort(all.begin(), all.end());
  all.resize(std::min<std::size_t>(K, all.size()));
  return all;
}

// A wavy sheet (a surface sample, as the fans see), a dense clump, far outliers and a few
// exact duplicates (ties broken by index).
std::vector<Vector3d> awkward_cloud() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vector3d> pts;
  for (int i = 0; i < 3000; ++i) {
    const double x = u(rng), y = u(rng);
    pts.emplace_back(x, y, 0.05 * std::sin(6 * x) * std::cos(5 * y));
  }
  for (int i = 0; i < 400; ++i)
    pts.emplace_back(0.5 + 0.002 * u(rng), 0.5 + 0.002 * u(rng), 0.3 + 0.002 * u(rng));
  for (const double far : {1e6, -3e4, 2e9}) pts.emplace_back(far, 0.2, 0.1);
  for (int i = 0; i < 20; ++i) pts.push_back(pts[static_cast<std::size_t>(i * 97)]);
  return pts;
}

bool is_far_outlier(const Vector3d& p) { return std::abs(p.x()) > 1e3; }

TEST(PointGrid, KnnIsTheBruteForceKNearestWithTiesByIndex) {
  const auto pts = awkward_cloud();
  std::vector<PointGrid> grids;
  for (const double cell : {0.01, 0.04, 0.2}) grids.emplace_back(pts, cell);
  Neighbours got;
  for (int i = 0; i < static_cast<int>(pts.size()); i += 3) {
    const Neighbours nearest10 = brute_knn(pts, i, 10);
    for (const PointGrid& grid : grids) {
      for (const std::size_t K : {1, 10}) {
        grid.knn(i, static_cast<int>(K), got);
        // A far outlier's neighbours lie beyond the search's reach (a thousand times the
        // grid's extent): none rather than a wrong few.
        if (is_far_outlier(pts[i]) && got.empty()) continue;
        const Neighbours want(nearest10.begin(), nearest10.begin() + K);
        ASSERT_EQ(got, want) << "point " << i << ", K " << K << ", cell " << grid.cell_edge();
      }
    }
  }
}

TEST(PointGrid, KnnOfATinyCloudReturnsEveryOtherPoint) {
  const std::vector<Vector3d> pts{{0, 0, 0}, {1, 0, 0}, {0, 2, 0}};
  const PointGrid grid(pts, 0.1);
  Neighbours got;
  grid.knn(0, 10, got);
  EXPECT_EQ(got, brute_knn(pts, 0, 10));
  EXPECT_EQ(got.size(), 2u);
}

TEST(PointGrid, VisitBallFindsExactlyThePointsWithinTheRadius) {
  const auto pts = awkward_cloud();
  const PointGrid grid(pts, 0.03);
  for (int i = 0; i < static_cast<int>(pts.size()); i += 11) {
    for (const double r : {0.005, 0.05, 0.4}) {
      std::vector<int> got, want;
      grid.visit_ball(pts[i], r, [&](int j, double d2) {
        EXPECT_DOUBLE_EQ(d2, (pts[j] - pts[i]).squaredNorm());
        got.push_back(j);
      });
      for (int j = 0; j < static_cast<int>(pts.size()); ++j)
        if ((pts[j] - pts[i]).squaredNorm() <= r * r) want.push_back(j);
      std::sort(got.begin(), got.end());
      ASSERT_EQ(got, want) << "point " << i << ", r " << r;
    }
  }
}

TEST(PointGrid, CollectShellFindsThePointsBetweenTheTwoRadiiExceptTheSkippedOne) {
  const auto pts = awkward_cloud();
  const PointGrid grid(pts, 0.03);
  Neighbours got;
  for (int i = 0; i < static_cast<int>(pts.size()); i += 13) {
    for (const auto& [inner, outer] :
         {std::pair{-1.0, 0.02}, std::pair{0.01, 0.05}, std::pair{0.05, 0.3}}) {
      const double min_d2 = inner < 0 ? -1.0 : inner * inner;
      grid.collect_shell(pts[i], min_d2, outer, i, got);
      Neighbours want;
      for (int j = 0; j < static_cast<int>(pts.size()); ++j) {
        const double d2 = (pts[j] - pts[i]).squaredNorm();
        if (j != i && d2 > min_d2 && d2 <= outer * outer) want.emplace_back(d2, j);
      }
      std::sort(got.begin(), got.end());
      std::sort(want.begin(), want.end());
      ASSERT_EQ(got, want) << "point " << i << ", shell " << inner << " .. " << outer;
    }
  }
}

}  // namespace
}  // namespace scanmesh::kernel
