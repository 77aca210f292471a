// Animation meshes end to end on analytic surfaces: topology, constraints, openings, surface
// fidelity, determinism.
#include <gtest/gtest.h>

#include <set>

#include "aft_test_support.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/mesh_topology.h"

namespace scanmesh::aft {
namespace {

struct Built {
  RegionGraph graph;
  LineSet lines;
  AnimationMesh am;
};

Built build(const ScanSurface& surface, const std::string& body, RegionSettings settings = {}) {
  Built b;
  b.lines = parse_lines_svg("<svg>" + body + "</svg>", "t.svg");
  validate_lines(b.lines, surface);
  b.graph = analyze_regions(b.lines, surface);
  apply_region_settings(b.graph, settings, surface);
  b.am = build_animation_mesh(b.graph, b.lines, surface, settings);
  return b;
}

const char* kScene =
    "<polygon points='440,60 600,60 600,300 440,300'/>"  // across the phi seam
    "<path d='M 520 60 L 520 300'/>"                     // splits it in two
    "<polygon id='opening-eye' points='460,120 500,120 500,160 460,160'/>"
    "<path id='ear' d='M 540 200 L 580 250'/>"    // free internal line
    "<path id='fold' d='M 440 250 L 490 250'/>";  // attached internal line

TEST(AnimationMesh, StitchedMeshIsValid) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  RegionSettings s;
  s.default_unit_mm = 4.0;
  const Built b = build(surface, kScene, s);
  const Mesh& m = b.am.mesh;
  for (const auto& st : b.am.region_stats) EXPECT_EQ(st.unmeshed_front_edges, 0) << st.region;
  const MeshCheckReport rep = check_mesh(m);
  EXPECT_TRUE(rep.edge_manifold());
  EXPECT_EQ(rep.duplicate_faces, 0u);
  EXPECT_EQ(rep.degenerate_faces, 0u);
  EXPECT_EQ(rep.self_intersections, 0u);
  EXPECT_EQ(rep.nonmanifold_vertices, 0u) << rep.to_text();
  // Boundary loops: the outer border and the eye opening, nothing else (no T-junction gaps).
  EXPECT_EQ(rep.topology.boundary_loops, 2u) << rep.to_text();
  // Every line edge is a mesh edge.
  std::set<std::pair<int, int>> edges;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      edges.insert({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])});
  for (const auto& e : b.am.line_edges)
    EXPECT_TRUE(edges.count({std::min(e[0], e[1]), std::max(e[0], e[1])}));
  // The ear line is interior: both its sides are meshed (each edge has two faces).
  // Vertices lie on the surface.
  const AnimationMeshQuality q = evaluate_quality(b.am, surface, 3);
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_GT(q.min_angle_non_exempt_deg, 20.0) << q.to_text();
  EXPECT_GT(q.fraction_min_angle_ge_30, 0.9) << q.to_text();
  EXPECT_LT(q.hausdorff_mesh_to_surface_mm, 0.5) << q.to_text();
  // Every face is labelled with a meshed region.
  for (int l : m.face_labels) EXPECT_FALSE(b.graph.regions[l].opening);
}

TEST(AnimationMesh, IdenticalForIdenticalInputAndSeed) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  RegionSettings s;
  s.default_unit_mm = 5.0;
  s.strategy = EdgeStrategy::Random;
  s.seed = 42;
  const Built a = build(surface, kScene, s);
  const Built b = build(surface, kScene, s);
  ASSERT_EQ(a.am.mesh.positions.size(), b.am.mesh.positions.size());
  EXPECT_EQ(a.am.mesh.triangles, b.am.mesh.triangles);
  for (std::size_t i = 0; i < a.am.mesh.positions.size(); ++i)
    EXPECT_EQ(a.am.mesh.positions[i], b.am.mesh.positions[i]);
}

}  // namespace
}  // namespace scanmesh::aft
