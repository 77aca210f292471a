// Seed 001 remeshing on the demo head WITH hair (the simulator's default scan: hair noise,
// dropouts, crumbs and a ragged border), at half the grid resolution to keep the test short:
// the scan clean-up (needles, spikes and pinches, crumbs, small holes) followed by remeshing
// must give the same quality as on the clean head (issue 6 acceptance: >= 99 % of triangles
// with min angle >= 30 deg, >= 90 % optimal valence), no self-intersections (none created by
// the operators, none left for the repair pass), and a Hausdorff distance of about one edge.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/remeshing/remesh.h"
#include "scanmesh/meshing/remeshing/remesh_quality.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh::remeshing {
namespace {

TEST(RemeshHairyHead, CleanUpAndRemeshReachTheCleanHeadQuality) {
  sim::ScannerConfig cfg = sim::builtin_head_scanner();
  ASSERT_TRUE(cfg.hair);
  cfg.n_phi = 256;
  cfg.n_h = 256;
  cfg.dh_mm *= 2;
  const auto scan = sim::simulate_scan(sim::builtin_head_scene(), cfg);
  RangeGrid grid = scan.grid;
  clean_grid(grid);
  const Mesh raw = grid_mesh(grid).mesh;
  const MeshCheckReport raw_rep = check_mesh(raw, {.self_intersections = false});
  ASSERT_GT(raw_rep.nonmanifold_vertices, 0u);  // the hair border pinches

  const int target = 5000;
  double area = 0;
  for (const auto& t : raw.triangles)
    area += 0.5 * (raw.positions[t[1]] - raw.positions[t[0]])
                      .cross(raw.positions[t[2]] - raw.positions[t[0]])
                      .norm();
  const double edge = std::sqrt(area / (std::sqrt(3.0) / 2 * target));  // as scanmesh remesh
  PrepareStats ps;
  const Mesh in = prepare_input(raw,
                                {.min_component_faces = 250,
                                 .max_hole_edges = 50,
                                 .needle_angle_deg = 5,
                                 .remove_spikes = true,
                                 .tip_reach_mm = edge},
                                &ps);
  EXPECT_GT(ps.spike_faces_removed, 0u);
  EXPECT_GT(ps.pinch_faces_removed, 0u);
  EXPECT_GT(ps.tip_faces_removed, 0u);
  // The clean-up takes the hair crumbs and the ragged border only: at most 15 % of the faces.
  EXPECT_GT(in.triangles.size(), raw.triangles.size() * 85 / 100);
  // The hole patches must not cut the surface around them.
  const MeshCheckReport in_rep = check_mesh(in);
  EXPECT_EQ(in_rep.nonmanifold_vertices, 0u);
  EXPECT_TRUE(in_rep.edge_manifold());
  EXPECT_EQ(in_rep.self_intersections, 0u);
  EXPECT_LT(in_rep.topology.boundary_loops, raw_rep.topology.boundary_loops / 4);

  RemeshOptions o;
  o.target_vertices = target;
  o.density.gamma = 0;
  const RemeshResult r = remesh(in, o);
  EXPECT_EQ(r.stats.output_vertices, target);
  const RemeshQuality q = evaluate_remesh(in, r, true);
  std::printf(
      "hairy head (%zu input faces): %.2f %% >= 30 deg (branch %zu, boundary %zu, "
      "interior %zu below), %.2f %% irregular, Hausdorff %.2f mm, %zu faces intersecting "
      "before repair\n",
      in.triangles.size(), 100 * q.fraction_min_angle_ge_30, q.bad_at_branch, q.bad_at_boundary,
      q.bad_interior, 100 * q.fraction_irregular, q.hausdorff,
      r.stats.intersecting_faces_before_repair);
  // 99.42 % with centroid-fan hole fills and no angle polish; 99.89 % measured now.
  EXPECT_GE(q.fraction_min_angle_ge_30, 0.997);
  // At 5000 vertices the border holds a larger share of the vertices than at the acceptance
  // size (20,000 on the full-resolution head: 9.6 % irregular, docs/remeshing.md); measured here
  // 10.8 %.
  EXPECT_LE(q.fraction_irregular, 0.12);
  EXPECT_EQ(q.self_intersections, 0u);
  EXPECT_EQ(r.stats.intersecting_faces_before_repair, 0u);
  // Mean edge ~ 4.5 mm at 5000 vertices on this head; the output stays within about one edge.
  EXPECT_LT(q.hausdorff, 5.0);
  EXPECT_LT(q.mean_distance, 0.2);
}

}  // namespace
}  // namespace scanmesh::remeshing
