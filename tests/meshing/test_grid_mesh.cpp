// Grid mesh: topology on analytic and simulated cylinders, holes, depth jumps, seam, UVs.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <set>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/texture_layout.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh {
namespace {

RangeGrid cylinder_grid(int n_phi, int n_h, float radius) {
  RangeGrid grid(n_phi, n_h, 0.0, 0.0, 1.0);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) grid.set_sample(i, j, radius);
  return grid;
}

// The cells a face's vertices came from must be the corners of one grid quad.
bool face_spans_one_quad(const GridMesh& gm, const RangeGrid& grid, const std::array<int, 3>& t) {
  std::set<int> columns, rows;
  for (int v : t) {
    columns.insert(static_cast<int>(gm.vertex_cell[v] % grid.n_phi()));
    rows.insert(static_cast<int>(gm.vertex_cell[v] / grid.n_phi()));
  }
  if (rows.size() != 2 || *rows.rbegin() - *rows.begin() != 1) return false;
  if (columns.size() != 2) return false;
  const int a = *columns.begin(), b = *columns.rbegin();
  return b - a == 1 || (a == 0 && b == grid.n_phi() - 1);
}

TEST(GridMesh, ClosedCylinderIsWatertightApartFromTopAndBottomRims) {
  const RangeGrid grid = cylinder_grid(64, 20, 50.0f);
  const GridMesh gm = grid_mesh(grid);
  EXPECT_EQ(gm.mesh.vertex_count(), 64u * 20u);
  EXPECT_EQ(gm.mesh.face_count(), 2u * 64u * 19u);
  const TopologyStats t = topology_stats(gm.mesh);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  ASSERT_EQ(t.boundary_loops, 2u);
  EXPECT_EQ(t.boundary_loop_lengths[0], 64u);
  EXPECT_EQ(t.boundary_loop_lengths[1], 64u);
  EXPECT_EQ(t.boundary_edges, 128u);
  EXPECT_EQ(t.euler_characteristic, 0);  // an open tube
}

TEST(GridMesh, TrianglesFaceAwayFromTheAxis) {
  const GridMesh gm = grid_mesh(cylinder_grid(32, 8, 40.0f));
  for (const auto& t : gm.mesh.triangles) {
    const auto& p = gm.mesh.positions;
    const Eigen::Vector3d n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    const Eigen::Vector3d c = (p[t[0]] + p[t[1]] + p[t[2]]) / 3.0;
    EXPECT_GT(n.dot(Eigen::Vector3d(c.x(), c.y(), 0.0)), 0.0);
  }
}

TEST(GridMesh, OpenSeamLeavesOneBoundaryLoop) {
  GridMeshOptions options;
  options.close_seam = false;
  const GridMesh gm = grid_mesh(cylinder_grid(16, 6, 30.0f), options);
  const TopologyStats t = topology_stats(gm.mesh);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.boundary_edges, 2u * 15u + 2u * 5u);
}

TEST(GridMesh, NoTriangleSpansAHole) {
  RangeGrid grid = cylinder_grid(48, 24, 45.0f);
  for (int j = 8; j < 12; ++j)
    for (int i = 10; i < 15; ++i) grid.invalidate(i, j);
  grid.invalidate(47, 3);  // a hole on the seam column
  grid.invalidate(0, 20);
  const GridMesh gm = grid_mesh(grid);
  for (const auto& t : gm.mesh.triangles) {
    ASSERT_TRUE(face_spans_one_quad(gm, grid, t));
    for (int v : t) EXPECT_TRUE(grid.validity()[gm.vertex_cell[v]]);
  }
  const TopologyStats t = topology_stats(gm.mesh);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  // rims + one loop around each hole
  EXPECT_EQ(t.boundary_loops, 5u);
  EXPECT_EQ(gm.quads_skipped_for_holes, 6u * 5u + 4u + 4u);
}

TEST(GridMesh, DepthJumpsGetNoTriangles) {
  RangeGrid grid = cylinder_grid(40, 10, 50.0f);
  for (int j = 0; j < 10; ++j)
    for (int i = 20; i < 40; ++i)
      grid.set_sample(i, j, 70.0f);  // a 20 mm step at i = 19|20 and 39|0
  GridMeshOptions options;
  options.max_depth_jump_mm = 5.0;
  const GridMesh gm = grid_mesh(grid, options);
  EXPECT_EQ(gm.quads_skipped_for_depth_jumps, 2u * 9u);
  EXPECT_EQ(gm.mesh.face_count(), 2u * (40u - 2u) * 9u);
  options.max_depth_jump_mm = 25.0;
  EXPECT_EQ(grid_mesh(grid, options).quads_skipped_for_depth_jumps, 0u);
}

TEST(GridMesh, TexcoordsPointAtEachVertexOwnPixelOfTheUprightTextureAcrossTheSeam) {
  const RangeGrid grid = cylinder_grid(32, 12, 50.0f);
  const GridMesh gm = grid_mesh(grid);
  ASSERT_TRUE(gm.mesh.has_texcoords());
  for (std::size_t f = 0; f < gm.mesh.face_count(); ++f) {
    float u_min = 10, u_max = -10;
    for (int k = 0; k < 3; ++k) {
      const std::size_t cell = gm.vertex_cell[gm.mesh.triangles[f][k]];
      const Eigen::Vector2f uv = gm.mesh.texcoords[gm.mesh.face_texcoords[f][k]];
      const int px = static_cast<int>(std::floor(uv.x() * grid.n_phi())) % grid.n_phi();
      const int py = static_cast<int>(std::floor((1.0f - uv.y()) * grid.n_h()));
      EXPECT_EQ(px, static_cast<int>(cell % grid.n_phi()));
      // OBJ's v counts up from the image's bottom; the texture is upright.
      EXPECT_EQ(py, texture_row(static_cast<int>(cell / grid.n_phi()), grid.n_h()));
      u_min = std::min(u_min, uv.x());
      u_max = std::max(u_max, uv.x());
    }
    // No face stretches across the texture: its u span is one column.
    EXPECT_LT(u_max - u_min, 1.5f / grid.n_phi());
  }
}

TEST(GridMesh, RejectsNonPositiveDepthLimit) {
  GridMeshOptions options;
  options.max_depth_jump_mm = 0.0;
  EXPECT_THROW(grid_mesh(cylinder_grid(8, 4, 10.0f), options), InvalidInputError);
}

}  // namespace
}  // namespace scanmesh
