// The stages on the real-data corpus (libcgal-demo's scanned clouds and meshes, docs/testing.md,
// "Real-data corpus"). There is no ground truth, so the tests assert what must hold of any
// correct output (topology kept, no defects) and quality floors measured on these files
// (bench_real prints the same figures; docs/benchmarks.md, "Real scans (bench_real)").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "scanmesh/acquisition/scan_import.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/meshing/fans/fans.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/remeshing/remesh.h"
#include "scanmesh/meshing/remeshing/remesh_quality.h"
#include "scanmesh/reconstruction/surface_fields.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

const std::filesystem::path kCorpus(SCANMESH_CORPUS_DIR);

double median_edge_length(const Mesh& m) {
  std::vector<double> l;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i)
      l.push_back((m.positions[t[i]] - m.positions[t[(i + 1) % 3]]).norm());
  std::nth_element(l.begin(), l.begin() + l.size() / 2, l.end());
  return l[l.size() / 2];
}

// ---- remesh: `scanmesh remesh --vertices <input count>` (the CLI's defaults) ----

struct RemeshCase {
  const char* file;
  double min_angle_floor_deg;  // measured minus a margin (values in the comments)
  double ge30_floor;
  double hausdorff_edges;     // bound in input median edge lengths
  double irregular_ceiling;  // share of free and skeleton vertices off their optimal valence
};

// Measured 2026-12-06 (issue 27's goals: >= 99.5 % >= 30 deg, min angle >= 15 deg, <= 10 %
// irregular): min angle, share >= 30 deg, Hausdorff in edges, irregular (evaluate_remesh's
// count): nefertiti 38.3 deg, 100 %, 0.37, 8.4 %; head 30.1, 100 %, 0.26, 7.2 %; elephant
// 30.2, 100 %, 0.46, 9.3 %; lion-head 30.1, 100 %, 0.42, 7.9 %. Before the valence-first
// count adjustment and E_glatt at 75 deg: worst angles 31.0, 29.9, 12.7, 6.5 deg (12/03) and
// 10.7, 10.3, 16.1, 11.0 % irregular (12/05, bench_real's count).
const RemeshCase kRemeshCases[] = {{"nefertiti.off", 30.0, 0.995, 0.5, 0.10},
                                   {"head.off", 29.0, 0.995, 0.5, 0.10},
                                   {"elephant.off", 25.0, 0.995, 0.8, 0.10},
                                   {"lion-head.off", 25.0, 0.995, 0.7, 0.10}};

class RealCorpusRemesh : public ::testing::TestWithParam<RemeshCase> {};

TEST_P(RealCorpusRemesh, KeepsTopologyWithoutDefectsAndStaysClose) {
  const RemeshCase& c = GetParam();
  const Mesh in = read_mesh(kCorpus / "meshes" / c.file);
  remeshing::RemeshOptions o;
  o.target_vertices = static_cast<int>(in.positions.size());
  const remeshing::RemeshResult r = remeshing::remesh(in, o);
  const MeshCheckReport before = check_mesh(in, {.self_intersections = false});
  const MeshCheckReport after = check_mesh(r.mesh);
  EXPECT_TRUE(after.edge_manifold()) << after.to_text();
  EXPECT_EQ(after.self_intersections, 0u);
  EXPECT_EQ(after.topology.boundary_loops, before.topology.boundary_loops);
  EXPECT_EQ(after.topology.euler_characteristic, before.topology.euler_characteristic);
  EXPECT_GT(after.min_angle_deg, c.min_angle_floor_deg);
  EXPECT_GE(after.fraction_min_angle_ge_30, c.ge30_floor);
  const double hausdorff = std::max(remeshing::sampled_distance(r.mesh, in)[0],
                                    remeshing::sampled_distance(in, r.mesh)[0]);
  EXPECT_LT(hausdorff / median_edge_length(in), c.hausdorff_edges);
  const remeshing::RemeshQuality q = remeshing::evaluate_remesh(in, r, false);
  EXPECT_LE(q.fraction_irregular, c.irregular_ceiling);
  // The vertex count is reached within 2 % (measured: exact on all four).
  EXPECT_NEAR(double(r.mesh.positions.size()), double(in.positions.size()),
              0.02 * double(in.positions.size()));
}

INSTANTIATE_TEST_SUITE_P(Meshes, RealCorpusRemesh, ::testing::ValuesIn(kRemeshCases),
                         [](const auto& param_info) {
                           std::string n = param_info.param.file;
                           n = n.substr(0, n.find('.'));
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

// mannequin-devil cuts itself (1,643 intersecting input face pairs, 984 faces). The intersection
// repair split edges without end there (122,703 instead of 12,977 vertices, 80 s); its splits
// now stop at 1 % over the target, and leave the input's own crossings alone. Around them (the
// defect zone, docs/remeshing.md) the operations are checked for degenerate faces only: before
// that the E_glatt / E_dist bounds refused every operation on the folded sheets and left the
// input's 0.03 deg needles (98.2 % >= 30 deg, 11.5 % irregular).
TEST(RealCorpusRemesh, MannequinDevilKeepsItsCountTopologyAndAngles) {
  const Mesh in = read_mesh(kCorpus / "meshes" / "mannequin-devil.off");
  remeshing::RemeshOptions o;
  o.target_vertices = static_cast<int>(in.positions.size());
  const remeshing::RemeshResult r = remeshing::remesh(in, o);
  EXPECT_NEAR(double(r.mesh.positions.size()), double(in.positions.size()),
              0.01 * double(in.positions.size()));
  EXPECT_EQ(r.stats.input_intersecting_faces, 984u);
  EXPECT_GT(r.stats.input_defect_zone_faces, r.stats.input_intersecting_faces);
  const MeshCheckReport rep = check_mesh(r.mesh);
  EXPECT_TRUE(rep.edge_manifold());
  EXPECT_EQ(rep.topology.boundary_loops, 1u);
  EXPECT_EQ(rep.topology.euler_characteristic, 1);
  // Measured 2026-12-06: min angle 26.2 deg, 99.96 % >= 30 deg, 7.9 % irregular, Hausdorff
  // 1.72 input edges, 1,430 intersecting face pairs (CGAL: 17.3 deg, 99.9 %, 2.68 edges, 173).
  EXPECT_GT(rep.min_angle_deg, 20.0);
  EXPECT_GE(rep.fraction_min_angle_ge_30, 0.995);
  EXPECT_LE(remeshing::evaluate_remesh(in, r, false).fraction_irregular, 0.10);
  const double hausdorff = std::max(remeshing::sampled_distance(r.mesh, in)[0],
                                    remeshing::sampled_distance(in, r.mesh)[0]);
  EXPECT_LT(hausdorff / median_edge_length(in), 2.0);
  // The output follows the input's crossings (it does not add to them).
  EXPECT_LT(rep.self_intersections, 1643u);
}

// Known failure, run it with --gtest_also_run_disabled_tests: the output still cuts itself where
// the input does (1,344 intersecting face pairs measured; CGAL's output has 173).
TEST(RealCorpusRemeshKnownFailure, DISABLED_MannequinDevilHasNoIntersections) {
  const Mesh in = read_mesh(kCorpus / "meshes" / "mannequin-devil.off");
  remeshing::RemeshOptions o;
  o.target_vertices = static_cast<int>(in.positions.size());
  const remeshing::RemeshResult r = remeshing::remesh(in, o);
  EXPECT_EQ(check_mesh(r.mesh).self_intersections, 0u);
}

// ---- fans on the scanned clouds ----

class RealCorpusFans : public ::testing::TestWithParam<const char*> {};

TEST_P(RealCorpusFans, CoverTheCloudWithoutDuplicateFacesOrOverfullEdges) {
  const auto pts = read_point_cloud(kCorpus / "points_3" / GetParam()).finite_points().positions;
  const FanResult f = build_fans(pts);
  const MeshCheckReport r = check_mesh(f.mesh);
  // Measured: 1.86 (oni) to 2.0 (kitten, radar) faces per point, every point used.
  EXPECT_GT(double(r.faces), 1.8 * double(pts.size()));
  EXPECT_EQ(f.stats.unused_points, 0u);
  EXPECT_EQ(f.mesh.positions.size(), pts.size());  // the input points are the vertices
  EXPECT_EQ(r.duplicate_faces, 0u);
  // The surface growth keeps every vertex one fan of faces and every edge at most two
  // (docs/fans.md); the comparison with CGAL on the same clouds is test_fans_vs_cgal.
  EXPECT_EQ(r.topology.nonmanifold_edges, 0u);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.self_intersections, 0u);
  EXPECT_EQ(r.topology.inconsistent_edges, 0u);
}

INSTANTIATE_TEST_SUITE_P(Clouds, RealCorpusFans,
                         ::testing::Values("kitten.xyz", "hippo1.ply", "hippo2.ply", "oni.ply",
                                           "radar.xyz"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           return n.substr(0, n.find('.'));
                         });

// ---- curvature of imported grids ----

struct CurvatureCase {
  const char* file;
  double finite_floor;  // share of valid cells with a finite estimate
};

// Grid-quadric at a 4-dh radius (bench_real). Measured shares: kitten 99.4 %, elephant 97.7 %,
// lion-head 99.4 %, mannequin-devil 97.5 %. The small clouds import to ragged grids whose border
// cells have fewer than min_points (12) neighbours within the radius, and those stay undefined:
// hippo1 81.1 %, hippo2 84.2 %, oni 92.8 %, radar 59.6 % (a scene, not one object),
// nefertiti 91.7 %, head 93.6 % — their floors are the lowest measured values minus 1 %. (The
// cloud import's resolution changed on 3 Dec 2026 while this was written; with it the clouds
// measured kitten 99.7 %, hippo1 84.4 %, hippo2 84.9 %, oni 94.0 %, radar 88.3 %.)
const CurvatureCase kCurvatureCases[] = {
    {"points_3/kitten.xyz", 0.95},  {"meshes/elephant.off", 0.95},
    {"meshes/lion-head.off", 0.95}, {"meshes/mannequin-devil.off", 0.95},
    {"points_3/hippo1.ply", 0.80},  {"points_3/hippo2.ply", 0.83},
    {"points_3/oni.ply", 0.91},     {"points_3/radar.xyz", 0.58},
    {"meshes/nefertiti.off", 0.90}, {"meshes/head.off", 0.92}};

class RealCorpusCurvature : public ::testing::TestWithParam<CurvatureCase> {};

TEST_P(RealCorpusCurvature, IsFiniteOnTheValidCells) {
  const ImportResult im = import_scan(kCorpus / GetParam().file);
  const RangeGrid& g = im.grid;
  const SurfaceFields f = compute_fields_grid_quadric(g, {.radius_mm = 4 * g.dh()});
  std::size_t valid = 0, finite = 0;
  for (std::size_t k = 0; k < g.cell_count(); ++k) {
    if (!g.validity()[k]) continue;
    ++valid;
    finite += f.defined[k] && std::isfinite(f.k1[k]) && std::isfinite(f.k2[k]) &&
              std::isfinite(f.normal[k].norm());
  }
  ASSERT_GT(valid, 100u);
  EXPECT_GE(double(finite) / double(valid), GetParam().finite_floor);
  // No estimate is invented where the grid has no data.
  std::size_t defined_without_data = 0;
  for (std::size_t k = 0; k < g.cell_count(); ++k)
    defined_without_data += !g.validity()[k] && f.defined[k];
  EXPECT_EQ(defined_without_data, 0u);
}

INSTANTIATE_TEST_SUITE_P(Imported, RealCorpusCurvature, ::testing::ValuesIn(kCurvatureCases),
                         [](const auto& param_info) {
                           std::string n = param_info.param.file;
                           n = n.substr(n.find('/') + 1);
                           n = n.substr(0, n.find('.'));
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
}  // namespace scanmesh
