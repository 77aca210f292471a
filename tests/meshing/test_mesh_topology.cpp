#include <gtest/gtest.h>

#include "scanmesh/meshing/mesh_topology.h"
#include "test_meshes.h"

namespace scanmesh {
namespace {

using test::tetrahedron;

TEST(MeshTopology, ClosedTetrahedronHasNoBoundaryAndEulerTwo) {
  const TopologyStats t = topology_stats(tetrahedron());
  EXPECT_EQ(t.edges, 6u);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.boundary_loops, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  EXPECT_EQ(t.euler_characteristic, 2);
}

TEST(MeshTopology, RemovingAFaceOpensOneLoopOfThreeEdges) {
  Mesh m = tetrahedron();
  m.triangles.pop_back();
  const TopologyStats t = topology_stats(m);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.boundary_loop_lengths.at(0), 3u);
  EXPECT_EQ(t.euler_characteristic, 1);
}

TEST(MeshTopology, FlippedFaceIsCountedAsInconsistent) {
  Mesh m = tetrahedron();
  std::swap(m.triangles[0][1], m.triangles[0][2]);
  EXPECT_EQ(topology_stats(m).inconsistent_edges, 3u);
}

TEST(MeshTopology, ThreeFacesOnOneEdgeAreNonManifold) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const TopologyStats t = topology_stats(m);
  EXPECT_EQ(t.nonmanifold_edges, 1u);
}

TEST(MeshTopology, CountsUnreferencedVertices) {
  Mesh m = tetrahedron();
  m.positions.push_back({5, 5, 5});
  EXPECT_EQ(topology_stats(m).unreferenced_vertices, 1u);
}

}  // namespace
}  // namespace scanmesh
