// The mesh checker on hand-made meshes: each defect is detected, a clean mesh reports none.
#include <gtest/gtest.h>

#include <filesystem>

#include "../test_meshes.h"
#include "scanmesh/core/image.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

using test::tetrahedron;

TEST(MeshCheck, CleanTetrahedronHasNoDefects) {
  const MeshCheckReport r = check_mesh(tetrahedron());
  EXPECT_TRUE(r.defect_free()) << r.to_text();
  EXPECT_EQ(r.topology.boundary_loops, 0u);
  EXPECT_EQ(r.topology.euler_characteristic, 2);
  EXPECT_EQ(r.self_intersections, 0u);
  EXPECT_EQ(r.topology.inconsistent_edges, 0u);
}

TEST(MeshCheck, DuplicateTriangleIsCounted) {
  Mesh m = tetrahedron();
  m.triangles.push_back({2, 1, 0});  // same vertex set, other orientation
  const MeshCheckReport r = check_mesh(m);
  EXPECT_EQ(r.duplicate_faces, 1u);
  EXPECT_FALSE(r.defect_free());
}

TEST(MeshCheck, EdgeWithThreeFacesIsNonManifold) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshCheckReport r = check_mesh(m);
  EXPECT_EQ(r.topology.nonmanifold_edges, 1u);
  EXPECT_FALSE(r.edge_manifold());
}

TEST(MeshCheck, BowtieVertexIsNonManifold) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 1, 0}, {1, -1, 0}, {-1, 1, 0}, {-1, -1, 0}};
  m.triangles = {{0, 2, 1}, {0, 3, 4}};
  const MeshCheckReport r = check_mesh(m);
  EXPECT_EQ(r.nonmanifold_vertices, 1u);
  EXPECT_TRUE(r.edge_manifold());
  EXPECT_EQ(r.self_intersections, 0u);
}

TEST(MeshCheck, CrossingTrianglesWithoutSharedCornerIntersect) {
  Mesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(check_mesh(m).self_intersections, 1u);
}

TEST(MeshCheck, LabelledAndMaskedCountsSkipPairs) {
  // Two crossing pairs: faces 0-1 (labels 7 and 8) and faces 2-3 (both label 9), far apart.
  Mesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0}};
  for (int k = 0; k < 6; ++k) m.positions.push_back(m.positions[k] + Eigen::Vector3d(50, 0, 0));
  m.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 10, 11}};
  EXPECT_EQ(count_intersecting_faces(m), 2u);
  const std::vector<int> labels{7, 8, 9, 9};
  EXPECT_EQ(count_intersecting_faces(m, &labels), 1u);
  const std::vector<int> one_label(4, 3);
  EXPECT_EQ(count_intersecting_faces(m, &one_label), 0u);
  // Only pairs with an involved face: one face of the second pair, then none.
  const std::vector<char> third{0, 0, 1, 0}, none(4, 0);
  EXPECT_EQ(count_intersecting_faces(m, nullptr, &third), 1u);
  EXPECT_EQ(count_intersecting_faces(m, nullptr, &none), 0u);
  EXPECT_EQ(count_intersecting_faces(m, &labels, &third), 0u);  // that pair shares label 9
}

TEST(MeshCheck, FoldThroughSharedCornerIntersects) {
  Mesh m;
  // both faces share vertex 0; the second one's far edge pierces the first face
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}};
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(check_mesh(m).self_intersections, 1u);
}

TEST(MeshCheck, CoplanarOverlapIntersectsButNeighboursDoNot) {
  Mesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0}, {0.5, 0.5, 0}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};  // a proper square
  EXPECT_EQ(check_mesh(m).self_intersections, 0u);
  m.triangles.push_back({4, 1, 3});  // folds back over the first face (shares vertex 1)
  EXPECT_GE(check_mesh(m).self_intersections, 1u);
}

TEST(MeshCheck, FoldedPairOnSharedEdgeIntersects) {
  Mesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, 2, 0}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}};  // both on the same side of edge 0-1
  EXPECT_EQ(check_mesh(m).self_intersections, 1u);
}

TEST(MeshCheck, BoundaryLoopsAndUnreferencedPoints) {
  Mesh m;
  // a square annulus: outer 4 corners, inner 4 corners, 8 triangles, plus one stray point
  m.positions = {{0, 0, 0}, {3, 0, 0}, {3, 3, 0}, {0, 3, 0}, {1, 1, 0},
                 {2, 1, 0}, {2, 2, 0}, {1, 2, 0}, {9, 9, 9}};
  m.triangles = {{0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5},
                 {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  const MeshCheckReport r = check_mesh(m);
  EXPECT_EQ(r.topology.boundary_loops, 2u);
  ASSERT_EQ(r.topology.boundary_loop_lengths.size(), 2u);
  EXPECT_EQ(r.topology.boundary_loop_lengths[0], 4u);
  EXPECT_EQ(r.topology.boundary_loop_lengths[1], 4u);
  EXPECT_EQ(r.topology.unreferenced_vertices, 1u);
  EXPECT_EQ(r.topology.euler_characteristic, 0);
  EXPECT_EQ(r.self_intersections, 0u);
}

TEST(MeshCheck, QualityOfEquilateralAndThinTriangles) {
  const double s3 = std::sqrt(3.0);
  EXPECT_NEAR(radius_ratio({0, 0, 0}, {1, 0, 0}, {0.5, s3 / 2, 0}), 1.0, 1e-12);
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, s3 / 2, 0}, {10, 0, 0}, {10, 1, 0}, {30, 0, 0}};
  m.triangles = {{0, 1, 2}, {3, 5, 4}};
  const MeshCheckReport r = check_mesh(m);
  EXPECT_NEAR(r.fraction_min_angle_ge_30, 0.5, 1e-12);
  EXPECT_EQ(r.min_angle_histogram[11], 1u);  // 60 deg
  EXPECT_EQ(r.min_angle_histogram[0], 1u);   // ~2.9 deg
  EXPECT_LT(r.min_angle_deg, 5.0);
}

TEST(MeshCheck, DegenerateFaceIsCounted) {
  Mesh m = tetrahedron();
  m.positions.push_back({2, 0, 0});
  m.triangles.push_back({0, 1, 4});  // collinear
  EXPECT_EQ(check_mesh(m).degenerate_faces, 1u);
}

TEST(MeshCheck, HistogramPngIsWritten) {
  const auto path = std::filesystem::path(SCANMESH_BINARY_DIR) / "test_quality_histogram.png";
  write_min_angle_histogram_png(path, check_mesh(tetrahedron()));
  const Image8 img = read_png(path);
  EXPECT_EQ(img.width, 640);
  EXPECT_EQ(img.height, 400);
}

}  // namespace
}  // namespace scanmesh
