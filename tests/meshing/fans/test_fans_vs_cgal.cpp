// Fans against CGAL's advancing front on the same points, run live (issue 26): the scanned
// clouds of the real-data corpus (tests/real_corpus.cmake) and the simulated head. The fans must
// be manifold, intersection-free and consistently oriented wherever CGAL's mesh is, with no
// more boundary loops, the same genus, and at least CGAL's share of well-shaped triangles.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../../../bench/anchors_cgal.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/meshing/fans/fans.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

const std::filesystem::path kCorpus(SCANMESH_CORPUS_DIR);

void expect_as_good_as_cgal(const std::vector<Eigen::Vector3d>& pts, const FanOptions& options) {
  const FanResult fans = build_fans(pts, options);
  const MeshCheckReport ours = check_mesh(fans.mesh);
  const MeshCheckReport cgal = check_mesh(bench::cgal_afsr(pts));
  SCOPED_TRACE("fans:\n" + ours.to_text() + "CGAL advancing front:\n" + cgal.to_text());
  ASSERT_GT(cgal.faces, 0u) << "the anchor produced nothing";
  EXPECT_GT(double(ours.faces), 0.95 * double(cgal.faces)) << "the fans must cover the cloud";
  EXPECT_EQ(ours.nonmanifold_vertices, 0u);
  EXPECT_EQ(ours.topology.nonmanifold_edges, 0u);
  EXPECT_EQ(ours.self_intersections, 0u);
  EXPECT_EQ(ours.duplicate_faces, 0u);
  EXPECT_EQ(ours.topology.inconsistent_edges, 0u);
  EXPECT_EQ(fans.stats.bowtie_faces_removed, 0u);
  EXPECT_LE(ours.topology.boundary_loops, cgal.topology.boundary_loops);
  // chi = 2 components - 2 genus - loops: closing a hole CGAL leaves open raises chi by one, so
  // the topology to compare is the genus. CGAL's own varies between runs on the same points
  // (oni: 3 or 4 handles, with 3 or 4 loops) and has one handle on hippo2 that the fans do not
  // make; what must not happen is a handle CGAL does not find (the spurious handles of the old
  // fans, issue 26). With as many loops and components the Euler characteristics must agree.
  ASSERT_TRUE(cgal.defect_free() && cgal.topology.inconsistent_edges == 0);
  EXPECT_LE(ours.topology.genus(), cgal.topology.genus());
  if (ours.topology.boundary_loops == cgal.topology.boundary_loops &&
      ours.topology.components == cgal.topology.components) {
    EXPECT_EQ(ours.topology.euler_characteristic, cgal.topology.euler_characteristic);
  }
  // Measured 0.01-0.17 points below CGAL on hippo1, hippo2, radar and the head (the hole fills
  // CGAL does not make), above on oni, equal on kitten: within half a point.
  EXPECT_GE(ours.fraction_min_angle_ge_30, cgal.fraction_min_angle_ge_30 - 0.005);
}

class FansVsCgalOnRealScans : public ::testing::TestWithParam<const char*> {};

TEST_P(FansVsCgalOnRealScans, ManifoldWithCgalsGenusAndNoMoreHoles) {
  const auto pts = read_point_cloud(kCorpus / "points_3" / GetParam()).finite_points().positions;
  expect_as_good_as_cgal(pts, {});
}

// The growth forced into blocks of a quarter of the cloud: where the blocks' fronts do not
// close at a cut (noisy scans, open borders) the growth runs again as one, with the same mesh
// as without blocks; either way the mesh meets the same bar.
TEST_P(FansVsCgalOnRealScans, InBlocksManifoldWithCgalsGenusAndNoMoreHoles) {
  const auto pts = read_point_cloud(kCorpus / "points_3" / GetParam()).finite_points().positions;
  FanOptions blocks;
  blocks.growth_block_points = pts.size() / 4;
  const FanResult in_blocks = build_fans(pts, blocks);
  EXPECT_GT(in_blocks.stats.growth_blocks + in_blocks.stats.growth_blocks_discarded, 1u)
      << "the cloud must have room for several blocks";
  const FanResult one = build_fans(pts);
  if (in_blocks.stats.growth_blocks_discarded > 0) {
    EXPECT_EQ(in_blocks.mesh.triangles, one.mesh.triangles);
  } else {  // kept: the one growth's topology, and its angles within a fifth of a point
    const MeshCheckReport a = check_mesh(in_blocks.mesh, {.self_intersections = false});
    const MeshCheckReport b = check_mesh(one.mesh, {.self_intersections = false});
    EXPECT_EQ(a.topology.boundary_loops, b.topology.boundary_loops);
    EXPECT_EQ(a.topology.euler_characteristic, b.topology.euler_characteristic);
    EXPECT_NEAR(a.fraction_min_angle_ge_30, b.fraction_min_angle_ge_30, 0.002);
  }
  expect_as_good_as_cgal(pts, blocks);
}

INSTANTIATE_TEST_SUITE_P(Clouds, FansVsCgalOnRealScans,
                         ::testing::Values("kitten.xyz", "hippo1.ply", "hippo2.ply", "oni.ply",
                                           "radar.xyz"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           return n.substr(0, n.find('.'));
                         });

TEST(FansVsCgal, SimulatedHeadIsManifoldWithCgalsGenusAndNoMoreHoles) {
  sim::ScannerConfig cfg = sim::builtin_head_scanner();
  cfg.noise_sigma_mm = 0.05;
  cfg.hair = false;
  cfg.spike_probability = 0;
  const sim::SimulatedScan scan = sim::simulate_scan(sim::builtin_head_scene(), cfg);
  std::vector<Eigen::Vector3d> pts;
  double max_r = 0;
  for (int j = 0; j < scan.grid.n_h(); ++j)
    for (int i = 0; i < scan.grid.n_phi(); ++i)
      if (scan.grid.valid(i, j)) {
        pts.push_back(scan.grid.cartesian(i, j));
        max_r = std::max(max_r, scan.truth[scan.grid.index(i, j)].radius);
      }
  FanOptions options;  // as in FansHead.SimulatedHeadMeshIsCloseToGroundTruth
  options.max_edge = 2.0 * std::max(scan.grid.dh(), max_r * scan.grid.dphi());
  expect_as_good_as_cgal(pts, options);
}

}  // namespace
}  // namespace scanmesh
