// Acceptance tests of issue 5 for the seed 002 fan mesher: the thesis's generic clouds and the
// simulated head (ground truth), checked with the shared mesh checker.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "fan_test_clouds.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/meshing/fans/fans.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh {
namespace {

void expect_correct(const MeshCheckReport& r) {
  EXPECT_EQ(r.duplicate_faces, 0u);
  EXPECT_EQ(r.degenerate_faces, 0u);
  EXPECT_EQ(r.topology.nonmanifold_edges, 0u);
  EXPECT_TRUE(r.self_intersections_checked);
  EXPECT_EQ(r.self_intersections, 0u);
  EXPECT_EQ(r.topology.unreferenced_vertices, 0u) << "every input point must be used";
  EXPECT_EQ(r.topology.inconsistent_edges, 0u) << "orientation must be consistent";
}

// A closed genus-0 triangulation of all `points` points: F = 2V - 4.
void expect_closed_sphere(const MeshCheckReport& r, std::size_t points) {
  SCOPED_TRACE(r.to_text());
  expect_correct(r);
  EXPECT_EQ(r.topology.boundary_loops, 0u);
  EXPECT_EQ(r.topology.euler_characteristic, 2);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.faces, 2 * points - 4);
}

class RandomSphere : public ::testing::TestWithParam<int> {};

TEST_P(RandomSphere, IsClosedCorrectAndComplete) {
  const auto pts = test::random_sphere(static_cast<std::size_t>(GetParam()), 2002);
  const FanResult res = build_fans(pts);
  ASSERT_EQ(res.mesh.positions.size(), pts.size());
  expect_closed_sphere(check_mesh(res.mesh), pts.size());
}

INSTANTIATE_TEST_SUITE_P(Fans, RandomSphere, ::testing::Values(5000, 10000, 40000));

// The surface growth in parallel blocks (slabs of space joined across their cuts afterwards):
// on a clean closed surface the blocks are kept and the mesh is as closed and complete.
TEST(FansGrowthInBlocks, SphereGrownInBlocksIsClosedCorrectAndComplete) {
  const auto pts = test::random_sphere(40000, 2002);
  FanOptions options;
  options.growth_block_points = 8000;
  const FanResult res = build_fans(pts, options);
  EXPECT_GE(res.stats.growth_blocks, 3u);
  EXPECT_EQ(res.stats.growth_blocks_discarded, 0u);
  const MeshCheckReport r = check_mesh(res.mesh);
  expect_closed_sphere(r, pts.size());
  // the same share of well-shaped triangles as one growth, within a tenth of a point
  const MeshCheckReport one = check_mesh(build_fans(pts).mesh);
  EXPECT_NEAR(r.fraction_min_angle_ge_30, one.fraction_min_angle_ge_30, 0.001);
}

TEST(FansGrowthInBlocks, SameTrianglesForAnyThreadCount) {
  const auto pts = test::random_sphere(20000, 11);
  FanOptions one;
  one.threads = 1;
  one.growth_block_points = 5000;
  FanOptions two = one;
  two.threads = 2;
  const FanResult with_two = build_fans(pts, two);
  EXPECT_GT(with_two.stats.growth_blocks, 1u);
  EXPECT_EQ(build_fans(pts, one).mesh.triangles, with_two.mesh.triangles);
}

TEST(FansRobustness, NoisySphereStaysEdgeManifoldWithoutIntersections) {
  auto pts = test::random_sphere(20000, 5);
  // radial noise of 10 % of the mean spacing (0.025): 3-NN normals fall back to PCA
  const auto noise = test::random_sphere(20000, 6);
  for (std::size_t i = 0; i < pts.size(); ++i) pts[i] *= 1.0 + 0.0025 * noise[i].x();
  const MeshCheckReport r = check_mesh(build_fans(pts).mesh);
  SCOPED_TRACE(r.to_text());
  EXPECT_EQ(r.duplicate_faces, 0u);
  EXPECT_EQ(r.topology.nonmanifold_edges, 0u);
  EXPECT_EQ(r.self_intersections, 0u);
  EXPECT_EQ(r.topology.inconsistent_edges, 0u);
  EXPECT_LT(r.topology.unreferenced_vertices, pts.size() / 1000);
  EXPECT_GT(r.faces, 2 * pts.size() * 99 / 100);
}

TEST(FansPlane, SquareGrid200HasOneBoundaryLoop) {
  const auto pts = test::square_grid(200, 200);
  const MeshCheckReport r = check_mesh(build_fans(pts).mesh);
  SCOPED_TRACE(r.to_text());
  expect_correct(r);
  EXPECT_EQ(r.topology.boundary_loops, 1u);
  EXPECT_EQ(r.topology.euler_characteristic, 1);
  // a triangulated 199 x 199 square of cells: two right isosceles triangles per cell
  EXPECT_EQ(r.faces, 2u * 199 * 199);
  EXPECT_NEAR(r.min_angle_deg, 45.0, 1e-6);
}

TEST(FansPlane, HexGrid40300HasOneBoundaryLoop) {
  const auto pts = test::hex_grid();
  ASSERT_EQ(pts.size(), 40300u);
  const MeshCheckReport r = check_mesh(build_fans(pts).mesh);
  SCOPED_TRACE(r.to_text());
  expect_correct(r);
  EXPECT_EQ(r.topology.boundary_loops, 1u);
  EXPECT_EQ(r.topology.euler_characteristic, 1);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  // interior triangles are equilateral
  EXPECT_GT(r.fraction_min_angle_ge_30, 0.99);
}

TEST(FansOrientation, SphereFacesPointOutward) {
  const auto pts = test::random_sphere(3000, 7);
  const Mesh m = build_fans(pts).mesh;
  double volume = 0;
  for (const auto& t : m.triangles)
    volume += m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]])) / 6.0;
  EXPECT_NEAR(volume, 4.0 / 3.0 * 3.14159265358979, 0.05);  // positive: outward
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d n =
        (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    EXPECT_GT(n.dot(m.positions[t[0]]), 0.0);
  }
}

TEST(FansNormals, EstimatesAreRadialOnASphereOrientedAlikeAndInInputOrder) {
  const auto pts = test::random_sphere(3000, 13);
  const auto normals = estimate_fan_normals(pts);
  ASSERT_EQ(normals.size(), pts.size());
  // On the unit sphere the true normal at p is p; the orientation is one of the two, the same
  // for every point (propagation over the neighbour graph, outward at the start point).
  int outward = 0, worst_deg = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    EXPECT_NEAR(normals[i].norm(), 1.0, 1e-9);
    const double c = normals[i].dot(pts[i]);
    outward += c > 0;
    worst_deg = std::max(worst_deg, static_cast<int>(std::acos(std::min(1.0, std::abs(c))) *
                                                     180.0 / 3.14159265358979));
  }
  EXPECT_TRUE(outward == 0 || outward == static_cast<int>(pts.size())) << outward;
  EXPECT_LT(worst_deg, 10);
  // The same as the mesh's vertex normals (one estimate serves both).
  const Mesh m = build_fans(pts).mesh;
  ASSERT_EQ(m.normals.size(), pts.size());
  for (std::size_t i = 0; i < pts.size(); i += 97)
    EXPECT_GT(std::abs(m.normals[i].cast<double>().dot(normals[i])), 0.999);
  EXPECT_THROW((void)estimate_fan_normals({pts[0], pts[1]}), InvalidInputError);
}

TEST(FansDeterminism, SameTrianglesForAnyThreadCount) {
  const auto pts = test::random_sphere(8000, 11);
  FanOptions one;
  one.threads = 1;
  FanOptions two;
  two.threads = 2;
  // two threads first: a one-thread region first could leave the pool at one thread
  const auto with_two = build_fans(pts, two).mesh.triangles;
  EXPECT_EQ(build_fans(pts, one).mesh.triangles, with_two);
}

TEST(FansOptions, MaxEdgeIsRespected) {
  auto pts = test::square_grid(40, 40);
  // a second patch 10 units away must not be bridged with a 3-unit edge limit
  for (const auto& p : test::square_grid(10, 10)) pts.push_back(p + Eigen::Vector3d(50, 0, 0));
  FanOptions o;
  o.max_edge = 3.0;
  const Mesh m = build_fans(pts, o).mesh;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      EXPECT_LE((m.positions[t[k]] - m.positions[t[(k + 1) % 3]]).norm(), 3.0 + 1e-12);
  const MeshCheckReport r = check_mesh(m);
  EXPECT_EQ(r.topology.boundary_loops, 2u);
  EXPECT_EQ(r.topology.unreferenced_vertices, 0u);
}

TEST(FansOptions, ImpossibleValuesAreRejected) {
  const auto pts = test::square_grid(5, 5);
  FanOptions o;
  o.alpha_deg = 200;
  EXPECT_THROW(build_fans(pts, o), InvalidInputError);
  o = {};
  o.k = 0;
  EXPECT_THROW(build_fans(pts, o), InvalidInputError);
  EXPECT_THROW(build_fans({Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()}), InvalidInputError);
  std::vector<Eigen::Vector3d> bad = pts;
  bad[3].x() = std::nan("");
  EXPECT_THROW(build_fans(bad), InvalidInputError);
}

// Nearest-point lookup on a uniform hash grid (test helper).
class PointLookup {
 public:
  PointLookup(const std::vector<Eigen::Vector3d>& pts, double cell) : pts_(pts), cell_(cell) {
    for (std::size_t i = 0; i < pts.size(); ++i) cells_[key(pts[i])].push_back(static_cast<int>(i));
  }
  double nearest(const Eigen::Vector3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (int r = 1; r < 64; ++r) {
      const auto c = coords(p);
      for (long long dz = -r; dz <= r; ++dz)
        for (long long dy = -r; dy <= r; ++dy)
          for (long long dx = -r; dx <= r; ++dx) {
            const auto it = cells_.find(pack(c[0] + dx, c[1] + dy, c[2] + dz));
            if (it == cells_.end()) continue;
            for (int i : it->second) best = std::min(best, (pts_[i] - p).norm());
          }
      if (best <= (r - 0.0) * cell_) return best;
    }
    return best;
  }

 private:
  std::array<long long, 3> coords(const Eigen::Vector3d& p) const {
    return {static_cast<long long>(std::floor(p.x() / cell_)),
            static_cast<long long>(std::floor(p.y() / cell_)),
            static_cast<long long>(std::floor(p.z() / cell_))};
  }
  static long long pack(long long x, long long y, long long z) {
    return ((x + 100000) * 200001 + (y + 100000)) * 200001 + (z + 100000);
  }
  long long key(const Eigen::Vector3d& p) const {
    const auto c = coords(p);
    return pack(c[0], c[1], c[2]);
  }
  const std::vector<Eigen::Vector3d>& pts_;
  double cell_;
  std::unordered_map<long long, std::vector<int>> cells_;
};

TEST(FansHead, SimulatedHeadMeshIsCloseToGroundTruth) {
  sim::ScannerConfig cfg = sim::builtin_head_scanner();
  cfg.noise_sigma_mm = 0.05;
  cfg.hair = false;           // hair cells carry 1.5 mm noise by design
  cfg.spike_probability = 0;  // outliers 5-40 mm off are a cleaning problem, not a meshing one
  const sim::SimulatedScan scan = sim::simulate_scan(sim::builtin_head_scene(), cfg);
  std::vector<Eigen::Vector3d> pts, truth;
  double max_r = 0;
  for (int j = 0; j < scan.grid.n_h(); ++j)
    for (int i = 0; i < scan.grid.n_phi(); ++i)
      if (scan.grid.valid(i, j)) {
        pts.push_back(scan.grid.cartesian(i, j));
        truth.push_back(scan.truth[scan.grid.index(i, j)].point);
        max_r = std::max(max_r, scan.truth[scan.grid.index(i, j)].radius);
      }
  ASSERT_GT(pts.size(), 10000u);
  // sampling spacing: the larger of the row distance and the arc between columns
  const double spacing = std::max(scan.grid.dh(), max_r * scan.grid.dphi());
  // The scan has real holes (occlusion, grazing dropout); without an edge limit the fans close
  // them with long triangles, as the thesis reports for the bunny's base (§4.1). GP3 users set
  // mu for the same reason.
  FanOptions options;
  options.max_edge = 2.0 * spacing;
  const FanResult res = build_fans(pts, options);
  ASSERT_EQ(res.mesh.positions, pts) << "vertices are the input points";
  const MeshCheckReport r = check_mesh(res.mesh);
  SCOPED_TRACE(r.to_text());
  // A triangulated disc has ~2 faces per point; the scan's holes and rims take a little off
  // (measured 1.99). An empty or half mesh must fail here, not pass the checks below.
  EXPECT_GT(double(r.faces), 1.9 * double(pts.size()));
  EXPECT_EQ(r.topology.unreferenced_vertices, 0u);
  EXPECT_EQ(r.topology.nonmanifold_edges, 0u);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.self_intersections, 0u);
  EXPECT_EQ(r.topology.inconsistent_edges, 0u);
  EXPECT_EQ(r.duplicate_faces, 0u);
  // Hausdorff distance, approximated on samples: mesh -> truth over vertices, edge midpoints
  // and centroids against the exact truth points; truth -> mesh over truth points against the
  // mesh vertices. The truth points sample the surface at the same spacing, so this
  // over-estimates the distance to the true surface.
  const PointLookup to_truth(truth, spacing);
  double h = 0;
  const auto& P = res.mesh.positions;
  for (const auto& t : res.mesh.triangles) {
    h = std::max(h, to_truth.nearest((P[t[0]] + P[t[1]] + P[t[2]]) / 3.0));
    for (int k = 0; k < 3; ++k)
      h = std::max(h, to_truth.nearest(0.5 * (P[t[k]] + P[t[(k + 1) % 3]])));
  }
  for (const auto& p : P) h = std::max(h, to_truth.nearest(p));
  const PointLookup to_mesh(P, spacing);
  for (const auto& q : truth) h = std::max(h, to_mesh.nearest(q));
  EXPECT_LT(h, 1.5 * spacing) << "spacing " << spacing;
}

}  // namespace
}  // namespace scanmesh

namespace scanmesh {
namespace {

// The cloud's colours and normals become the mesh's; the given normals decide the outside, so
// inward normals turn every face inward (the faces follow what the user's data says).
TEST(Fans, CarriesColoursAndGivenNormalsToTheMesh) {
  PointCloud cloud;
  cloud.positions = test::random_sphere(3000, 7);
  for (const auto& p : cloud.positions) {
    cloud.colors.push_back({static_cast<std::uint8_t>(128 + 127 * p.x()),
                            static_cast<std::uint8_t>(128 + 127 * p.y()),
                            static_cast<std::uint8_t>(128 + 127 * p.z())});
    cloud.normals.push_back(-p.cast<float>());  // inward
  }
  // An organised cloud's missing pixel: dropped before meshing, with its attributes.
  cloud.positions.insert(cloud.positions.begin() + 10, Eigen::Vector3d::Constant(NAN));
  cloud.colors.insert(cloud.colors.begin() + 10, Rgb8{1, 2, 3});
  cloud.normals.insert(cloud.normals.begin() + 10, Eigen::Vector3f::UnitX());
  const FanResult r = build_fans(cloud);
  const PointCloud finite = cloud.finite_points();
  ASSERT_EQ(r.mesh.positions, finite.positions);
  ASSERT_EQ(r.mesh.colors.size(), finite.size());
  for (std::size_t i = 0; i < finite.size(); ++i) {
    EXPECT_EQ(r.mesh.colors[i].r, finite.colors[i].r);
    EXPECT_EQ(r.mesh.colors[i].b, finite.colors[i].b);
    EXPECT_EQ(r.mesh.normals[i], finite.normals[i]);
  }
  std::size_t inward = 0;
  const auto& P = r.mesh.positions;
  for (const auto& t : r.mesh.triangles)
    inward += (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]).dot(P[t[0]]) < 0;
  EXPECT_EQ(inward, r.mesh.face_count());
  EXPECT_EQ(check_mesh(r.mesh).topology.boundary_loops, 0u);
}


// With the scan's hair on, the neighbour graph breaks into pieces and propagated orientation
// can flip whole regions; orienting away from the turntable axis keeps every face outward.
TEST(Fans, AxisOrientationTurnsEveryFaceOfANoisyHeadScanOutward) {
  sim::ScannerConfig cfg = sim::builtin_head_scanner();
  cfg.n_phi = 256;
  cfg.n_h = 256;
  cfg.dh_mm = 0.9;
  const sim::SimulatedScan scan = sim::simulate_scan(sim::builtin_head_scene(), cfg);
  std::vector<Eigen::Vector3d> pts;
  for (int j = 0; j < scan.grid.n_h(); ++j)
    for (int i = 0; i < scan.grid.n_phi(); ++i)
      if (scan.grid.valid(i, j)) pts.push_back(scan.grid.cartesian(i, j));
  FanOptions options;
  options.orient_away_from_axis = true;
  const FanResult res = build_fans(pts, options);
  const auto& P = res.mesh.positions;
  std::size_t outward = 0;
  for (const auto& t : res.mesh.triangles) {
    const Eigen::Vector3d n = (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]);
    const Eigen::Vector3d c = (P[t[0]] + P[t[1]] + P[t[2]]) / 3.0;
    outward += n.dot(Eigen::Vector3d(c.x(), c.y(), 0.0)) > 0;
  }
  ASSERT_GT(res.mesh.face_count(), 50000u);
  const MeshCheckReport check = check_mesh(res.mesh, {.self_intersections = false});
  // The surface growth orients every face from its neighbour across an edge, so the mesh is
  // consistently oriented; faces on the ears' and nose's undersides and in the noisy hair's
  // folds then face the axis legitimately (3.5 % measured).
  EXPECT_EQ(check.topology.inconsistent_edges, 0u);
  EXPECT_GT(static_cast<double>(outward) / res.mesh.face_count(), 0.95);
}

}  // namespace
}  // namespace scanmesh
