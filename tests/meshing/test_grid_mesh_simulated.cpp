// Grid mesh of simulated scans, checked against the simulator's exact geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh {
namespace {

sim::Scene cylinder_scene() {
  return sim::Scene::from_yaml_text(
      "name: cylinder\n"
      "objects:\n"
      "  - {type: cylinder, center: [0, 0, 100], axis: [0, 0, 1], radius: 60, half_length: 80}\n",
      "test cylinder");
}

sim::ScannerConfig side_scanner() {
  sim::ScannerConfig c;
  c.n_phi = 128;
  c.n_h = 64;
  c.h0_mm = 40.0;  // rows 40..166 mm: the side of the cylinder only
  c.dh_mm = 2.0;
  c.noise_sigma_mm = 0.05;
  c.hair = false;
  c.height_band = false;
  return c;
}

TEST(GridMeshSimulated, ClosedCylinderScanIsWatertightApartFromTopAndBottomRims) {
  const auto scan = sim::simulate_scan(cylinder_scene(), side_scanner());
  ASSERT_EQ(scan.grid.valid_count(), 128u * 64u);
  const GridMesh gm = grid_mesh(scan.grid);
  const TopologyStats t = topology_stats(gm.mesh);
  EXPECT_EQ(gm.mesh.face_count(), 2u * 128u * 63u);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  ASSERT_EQ(t.boundary_loops, 2u);
  EXPECT_EQ(t.boundary_loop_lengths[0], 128u);
  EXPECT_EQ(t.boundary_loop_lengths[1], 128u);
  // Every vertex lies on the true cylinder within the simulated noise (6 sigma).
  for (const auto& p : gm.mesh.positions) EXPECT_NEAR(std::hypot(p.x(), p.y()), 60.0, 0.3);
  // Vertex normals agree with the exact surface normals.
  for (std::size_t v = 0; v < gm.mesh.vertex_count(); ++v) {
    const Eigen::Vector3d truth = scan.truth[gm.vertex_cell[v]].geometry.normal;
    EXPECT_GT(gm.mesh.normals[v].cast<double>().dot(truth), 0.99);
  }
}

TEST(GridMeshSimulated, CylinderScanWithCapsKeepsHolesAtGrazingCaps) {
  sim::ScannerConfig c = side_scanner();
  c.h0_mm = 0.0;  // rows 0..126 mm: the bottom cap (z = 20) is seen edge-on and dropped
  const auto scan = sim::simulate_scan(cylinder_scene(), c);
  const GridMesh gm = grid_mesh(scan.grid);
  for (const auto& t : gm.mesh.triangles)
    for (int v : t) EXPECT_TRUE(scan.grid.validity()[gm.vertex_cell[v]]);
  const TopologyStats t = topology_stats(gm.mesh);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.boundary_loops, 2u);
}

}  // namespace
}  // namespace scanmesh
