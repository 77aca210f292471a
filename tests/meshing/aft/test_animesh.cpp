// Animation meshes end to end on analytic surfaces: topology, constraints, openings, surface
// fidelity, determinism.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "aft_test_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

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
  // Independently of line_edges: every segment is a complete edge chain; the ear and fold
  // lines are interior, so each of their edges has a face on both sides.
  test::expect_lines_are_edge_chains(b.graph, b.am);
  // Vertices lie on the surface.
  const AnimationMeshQuality q = evaluate_quality(b.am, surface, 3);
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
  EXPECT_GT(q.min_angle_non_exempt_deg, 20.0) << q.to_text();
  EXPECT_GT(q.fraction_min_angle_ge_30, 0.9) << q.to_text();
  EXPECT_LT(q.hausdorff_mesh_to_surface_mm, 0.5) << q.to_text();
  // Every face is labelled with a meshed region.
  for (int l : m.face_labels) EXPECT_FALSE(b.graph.regions[l].opening);
}

// The chain check above must be able to fail: a face missing beside the ear line, and a node
// dropped from a segment chain, are caught.
TEST(AnimationMesh, EdgeChainCheckCatchesAMissingFaceAndALostNode) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  RegionSettings s;
  s.default_unit_mm = 4.0;
  const Built b = build(surface, kScene, s);
  int ear = -1;
  for (std::size_t i = 0; i < b.lines.lines.size(); ++i)
    if (b.lines.lines[i].id == "ear") ear = static_cast<int>(i);
  ASSERT_GE(ear, 0);
  std::size_t ear_segment = 0;
  while (b.graph.segments[ear_segment].line != ear) ++ear_segment;
  const std::vector<int>& chain = b.am.segment_chains[ear_segment];
  ASSERT_GE(chain.size(), 3u);
  AnimationMesh missing_face = b.am;
  auto& T = missing_face.mesh.triangles;
  const auto beside = [&](const std::array<int, 3>& t) {
    const auto has = [&](int v) { return std::find(t.begin(), t.end(), v) != t.end(); };
    return has(chain[0]) && has(chain[1]);
  };
  const auto face = std::find_if(T.begin(), T.end(), beside);
  ASSERT_NE(face, T.end());
  T.erase(face);
  AnimationMesh lost_node = b.am;
  lost_node.segment_chains[ear_segment][1] = -1;
  // The gtest-spi macros run their statement in a local class: it sees statics only.
  static const RegionGraph* graph;
  static const AnimationMesh *with_missing_face, *with_lost_node;
  graph = &b.graph;
  with_missing_face = &missing_face;
  with_lost_node = &lost_node;
  EXPECT_NONFATAL_FAILURE(test::expect_lines_are_edge_chains(*graph, *with_missing_face),
                          "segment");
  EXPECT_FATAL_FAILURE(test::expect_lines_are_edge_chains(*graph, *with_lost_node), "lost node");
}

// 5 mm units and the random front order from `seed`.
RegionSettings random_order(std::uint64_t seed) {
  RegionSettings s;
  s.default_unit_mm = 5.0;
  s.strategy = EdgeStrategy::Random;
  s.seed = seed;
  return s;
}

TEST(AnimationMesh, IdenticalForIdenticalInputAndSeed) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  const Built a = build(surface, kScene, random_order(42));
  const Built b = build(surface, kScene, random_order(42));
  ASSERT_EQ(a.am.mesh.positions.size(), b.am.mesh.positions.size());
  EXPECT_EQ(a.am.mesh.triangles, b.am.mesh.triangles);
  for (std::size_t i = 0; i < a.am.mesh.positions.size(); ++i)
    EXPECT_EQ(a.am.mesh.positions[i], b.am.mesh.positions[i]);
}

// A seam with a user node spacing: its nodes are spaced by it (d' = s / (floor(s / d) + 1),
// between 2/3 d and d for a seam a few spacings long), the exported list runs along the line
// from its first point to its last and is a chain of mesh edges, whatever the regions' units.
TEST(AnimationMesh, SeamNodesFollowTheUserSpacingAndAreExportedInLineOrder) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  RegionSettings s;
  s.default_unit_mm = 6.0;
  const Built b = build(surface,
                        "<polygon points='100,60 300,60 300,300 100,300'/>"
                        "<path id='join' class='seam' data-spacing-mm='3' d='M 200 60 L 200 300'/>",
                        s);
  ASSERT_EQ(b.am.seams.count("join"), 1u);
  const std::vector<int>& seam = b.am.seams.at("join");
  const auto& P = b.am.mesh.positions;
  ASSERT_GE(seam.size(), 10u);
  for (std::size_t k = 1; k < seam.size(); ++k) {
    const double d = (P[seam[k]] - P[seam[k - 1]]).norm();
    EXPECT_GT(d, 2.0) << k;
    EXPECT_LE(d, 3.0 + 1e-6) << k;
  }
  // Line order: from the point drawn first (row 60, low h) to the last (row 300).
  EXPECT_LT(P[seam.front()].z(), P[seam.back()].z());
  for (std::size_t k = 1; k < seam.size(); ++k) EXPECT_GT(P[seam[k]].z(), P[seam[k - 1]].z());
  test::expect_lines_are_edge_chains(b.graph, b.am);
}

// Surface -> mesh over the regions: a hole cut into the mesh shows in the distance (the
// surface there is far from every triangle), which sampling the surface under the mesh's own
// triangles cannot see.
TEST(AnimationMesh, SurfaceToMeshDistanceSeesAGapInTheMesh) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  RegionSettings s;
  s.default_unit_mm = 4.0;
  const Built b = build(surface, "<polygon points='100,60 300,60 300,300 100,300'/>", s);
  const AnimationMeshQuality whole = evaluate_quality(b.am, surface, 2, &b.graph);
  EXPECT_LT(whole.hausdorff_surface_to_mesh_mm, 0.5) << whole.to_text();
  // Remove every triangle with a corner within 15 mm of the region's middle.
  AnimationMesh cut = b.am;
  const Eigen::Vector3d middle = *surface.position(pixel_to_param(surface, {200, 180}).x(),
                                                   pixel_to_param(surface, {200, 180}).y());
  std::vector<std::array<int, 3>> kept;
  std::vector<int> labels;
  for (std::size_t t = 0; t < cut.mesh.triangles.size(); ++t) {
    bool near = false;
    for (int v : cut.mesh.triangles[t]) near |= (cut.mesh.positions[v] - middle).norm() < 15;
    if (near) continue;
    kept.push_back(cut.mesh.triangles[t]);
    labels.push_back(cut.mesh.face_labels[t]);
  }
  ASSERT_LT(kept.size(), cut.mesh.triangles.size());
  cut.mesh.triangles = kept;
  cut.mesh.face_labels = labels;
  const AnimationMeshQuality with_gap = evaluate_quality(cut, surface, 2, &b.graph);
  EXPECT_GT(with_gap.hausdorff_surface_to_mesh_mm, 10.0) << with_gap.to_text();
  EXPECT_LT(evaluate_quality(cut, surface, 2).hausdorff_surface_to_mesh_mm, 0.5);  // blind
}

// Curvature-adaptive size: on a cylinder of radius 15 mm the chordal bound sqrt(8 delta / k)
// with delta = 0.5 mm is 7.7 mm, below the region's unit of 10 mm; the Steiner edges follow
// it. With the chordal control off (tolerance 0) they follow the unit.
TEST(AnimationMesh, ChordalToleranceShrinksTheSizeWhereTheSurfaceBends) {
  const RangeGrid grid = test::cylinder_grid(15.0);
  const ScanSurface surface(grid);
  const char* square = "<polygon points='100,60 400,60 400,300 100,300'/>";
  const auto mean_inner_edge = [&](double tolerance) {
    RegionSettings s;
    s.default_unit_mm = 10.0;
    s.chordal_tolerance_mm = tolerance;
    const Built b = build(surface, square, s);
    EXPECT_EQ(b.am.region_stats.at(0).unmeshed_front_edges, 0);
    double sum = 0;
    int n = 0;
    for (const auto& t : b.am.mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        const int u = t[k], v = t[(k + 1) % 3];
        if (!b.am.steiner[u] || !b.am.steiner[v]) continue;  // edges between Steiner points
        sum += (b.am.mesh.positions[u] - b.am.mesh.positions[v]).norm();
        ++n;
      }
    return sum / std::max(1, n);
  };
  const double chordal = std::sqrt(8 * 0.5 * 15.0);
  const double adaptive = mean_inner_edge(0.5), uniform = mean_inner_edge(0.0);
  EXPECT_NEAR(uniform, 10.0, 1.5);
  EXPECT_NEAR(adaptive, chordal, 0.2 * chordal);
  EXPECT_LT(adaptive, 0.85 * uniform);
}

// The seed drives the random front order: another seed, another (equally valid) mesh.
TEST(AnimationMesh, AnotherSeedGivesAnotherValidMesh) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  const Built a = build(surface, kScene, random_order(42));
  const Built b = build(surface, kScene, random_order(43));
  EXPECT_NE(a.am.mesh.triangles, b.am.mesh.triangles);
  for (const Built* x : {&a, &b}) {
    const MeshCheckReport rep = check_mesh(x->am.mesh);
    EXPECT_TRUE(rep.edge_manifold());
    EXPECT_EQ(rep.self_intersections, 0u);
    EXPECT_EQ(rep.topology.boundary_loops, 2u);
    test::expect_lines_are_edge_chains(x->graph, x->am);
  }
}

// The user picks the mesher per region: one half of the scene by surface Delaunay refinement,
// the other by the advancing front, stitched into one mesh along their shared segment.
TEST(AnimationMesh, AftAndDelaunayRegionsStitchIntoOneMesh) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  RegionSettings s;
  s.default_unit_mm = 4.0;
  RegionRule rule;
  rule.name = "right-half";
  rule.point_px = Eigen::Vector2d(48, 100);  // 560 - 512: right of the splitting line
  rule.mesher = "delaunay";
  s.regions.push_back(rule);
  const Built b = build(surface, kScene, s);
  std::set<std::string> meshers;
  for (const auto& st : b.am.region_stats) {
    meshers.insert(st.mesher);
    EXPECT_EQ(st.unmeshed_front_edges, 0) << st.region;
    if (st.mesher == "delaunay") {
      EXPECT_EQ(b.graph.regions[st.region].name, "right-half");
    }
  }
  EXPECT_EQ(meshers, (std::set<std::string>{"aft", "delaunay"}));
  const MeshCheckReport rep = check_mesh(b.am.mesh);
  EXPECT_TRUE(rep.edge_manifold());
  EXPECT_EQ(rep.self_intersections, 0u);
  EXPECT_EQ(rep.nonmanifold_vertices, 0u);
  EXPECT_EQ(rep.topology.boundary_loops, 2u) << rep.to_text();
  test::expect_lines_are_edge_chains(b.graph, b.am);
  const AnimationMeshQuality q = evaluate_quality(b.am, surface, 2);
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
}

TEST(AnimationMesh, SettingsPointInNoRegionIsAnErrorNamingTheRule) {
  const RangeGrid grid = test::cylinder_grid(100.0, 4.0);
  const ScanSurface surface(grid);
  LineSet lines = parse_lines_svg("<svg>" + std::string(kScene) + "</svg>", "t.svg");
  RegionGraph g = analyze_regions(lines, surface);
  RegionSettings s;
  RegionRule rule;
  rule.name = "nowhere";
  rule.point_px = Eigen::Vector2d(300, 350);  // outside the polygon: no region
  s.regions.push_back(rule);
  try {
    apply_region_settings(g, s, surface);
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("'nowhere'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("lies in no region"), std::string::npos) << e.what();
  }
}

// The sample head (configs/sim/head-lines.svg + head-regions.yaml) on the simulated head scanned
// without occlusion/hair defects (configs/sim/head-scanner-ideal.yaml).

TEST(AnimationMeshHead, SampleLinesGiveAValidMesh) {
  const test::SampleHead head;
  const ScanSurface& surface = head.surface;
  const LineSet& lines = head.lines;
  validate_lines(lines, surface);
  RegionGraph g = analyze_regions(lines, surface);
  int meshed = 0, openings = 0;
  for (const Region& r : g.regions) (r.opening ? openings : meshed)++;
  EXPECT_EQ(meshed, 17);
  EXPECT_EQ(openings, 3);
  const RegionSettings& s = head.settings;
  apply_region_settings(g, s, surface);
  const AnimationMesh am = build_animation_mesh(g, lines, surface, s);
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_TRUE(rep.edge_manifold()) << rep.to_text();
  EXPECT_EQ(rep.duplicate_faces, 0u);
  EXPECT_EQ(rep.self_intersections, 0u);
  const AnimationMeshQuality q = evaluate_quality(am, surface, 2);
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
  EXPECT_GE(q.fraction_min_angle_ge_30, 0.95) << q.to_text();
  // Every front closed: the only holes are the neck, the crown and the three openings.
  int open_edges = 0;
  for (const auto& st : am.region_stats) open_edges += st.unmeshed_front_edges;
  EXPECT_EQ(open_edges, 0);
  EXPECT_EQ(rep.topology.boundary_loops, 5u) << rep.to_text();
  EXPECT_EQ(rep.nonmanifold_vertices, 0u);
  test::expect_lines_are_edge_chains(g, am);
  ASSERT_TRUE(am.seams.count("back-seam"));
  // Every triangle >= 20 deg, except at a corner where two animation-line edges meet at less
  // than 20 deg (the input fixes that angle). Such corners are counted here from the line
  // edges alone, independently of the mesher; each can force at most one triangle.
  std::map<int, std::vector<int>> line_nbrs;
  for (const auto& e : am.line_edges) {
    line_nbrs[e[0]].push_back(e[1]);
    line_nbrs[e[1]].push_back(e[0]);
  }
  int sharp_corners = 0;
  for (const auto& [v, nb] : line_nbrs)
    for (std::size_t i = 0; i < nb.size(); ++i)
      for (std::size_t j = i + 1; j < nb.size(); ++j) {
        const Eigen::Vector3d a = am.mesh.positions[nb[i]] - am.mesh.positions[v],
                              b = am.mesh.positions[nb[j]] - am.mesh.positions[v];
        sharp_corners += std::atan2(a.cross(b).norm(), a.dot(b)) < 20 * M_PI / 180;
      }
  int below_20 = 0;
  for (int bin = 0; bin < 4; ++bin) below_20 += q.min_angle_histogram[bin];
  EXPECT_EQ(below_20, q.small_angle_exempt) << q.to_text();
  EXPECT_LE(q.small_angle_exempt, sharp_corners) << q.to_text();
  EXPECT_GE(q.min_angle_non_exempt_deg, 20.0) << q.to_text();
  EXPECT_EQ(am.repair_left_below_20, 0);
  EXPECT_EQ(am.repair_forced_below_20, q.small_angle_exempt);
  std::printf(
      "sample head: %zu vertices, %zu triangles, min angle %.2f deg, %d sharp input "
      "corners, %d exempt triangles, >= 30 deg %.2f %%\n",
      am.mesh.positions.size(), am.mesh.triangles.size(), q.min_angle_deg, sharp_corners,
      q.small_angle_exempt, 100 * q.fraction_min_angle_ge_30);
}

// The serial post-processing (flips, smoothing and repair on the stitched mesh: the fallback's
// path when a region's own post-processing made a shared edge or a crossing) against the
// default per-region one: the same meshers, the same flips and smoothing, and a repair that
// differs only in what it sees of the neighbouring regions.
TEST(AnimationMeshHead, SerialPostprocessingIsValidAndMatchesTheParallelOne) {
  const test::SampleHead head;
  RegionGraph g = analyze_regions(head.lines, head.surface);
  apply_region_settings(g, head.settings, head.surface);
  const AnimationMesh parallel = build_animation_mesh(g, head.lines, head.surface, head.settings);
  RegionSettings s = head.settings;
  s.parallel_postprocessing = false;
  const AnimationMesh serial = build_animation_mesh(g, head.lines, head.surface, s);
  EXPECT_FALSE(parallel.serial_postprocessing);  // no fallback on the sample head
  EXPECT_TRUE(serial.serial_postprocessing);
  const MeshCheckReport rep = check_mesh(serial.mesh);
  EXPECT_TRUE(rep.defect_free()) << rep.to_text();
  EXPECT_EQ(rep.topology.boundary_loops, 5u) << rep.to_text();
  const AnimationMeshQuality q = evaluate_quality(serial, head.surface, 2);
  const AnimationMeshQuality qp = evaluate_quality(parallel, head.surface, 2);
  EXPECT_GE(q.min_angle_non_exempt_deg, 20.0) << q.to_text();
  EXPECT_GE(q.fraction_min_angle_ge_30, 0.95) << q.to_text();
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
  // The max-min flips see the same edges either way; the valence flips do not: on the stitched
  // mesh a segment node is inside (ideal valence 6), in its region's job on the border (4 on a
  // straight line). So the counts may differ, by a few per cent (measured 558 vs 524).
  EXPECT_NEAR(serial.flips, parallel.flips, 0.15 * parallel.flips);
  const double n_p = static_cast<double>(parallel.mesh.triangles.size());
  EXPECT_NEAR(static_cast<double>(serial.mesh.triangles.size()), n_p, 0.01 * n_p);
  EXPECT_NEAR(q.mean_radius_ratio, qp.mean_radius_ratio, 0.01);
}

// Half the sample unit sizes (4x the triangles): the parameter-plane front search keeps every
// front closed where the surface is steep (ears, nose). Before it, this input left 70 front
// edges open and 33 self-intersecting pairs; at a quarter of the units 1,413 and 39,330.
TEST(AnimationMeshHead, HalfTheUnitsStillClosesEveryFrontWithoutIntersections) {
  const test::SampleHead head;
  const ScanSurface& surface = head.surface;
  const LineSet& lines = head.lines;
  RegionGraph g = analyze_regions(lines, surface);
  const RegionSettings s = head.settings.with_units_scaled(0.5);
  apply_region_settings(g, s, surface);
  const AnimationMesh am = build_animation_mesh(g, lines, surface, s);
  int open_edges = 0;
  for (const auto& st : am.region_stats) open_edges += st.unmeshed_front_edges;
  EXPECT_EQ(open_edges, 0);
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_TRUE(rep.edge_manifold()) << rep.to_text();
  EXPECT_EQ(rep.duplicate_faces, 0u);
  EXPECT_EQ(rep.self_intersections, 0u);
  EXPECT_EQ(rep.topology.boundary_loops, 5u) << rep.to_text();
  EXPECT_GT(am.mesh.triangles.size(), 15000u);  // measured 16,977 (sample units: 5,128)
  const AnimationMeshQuality q = evaluate_quality(am, surface, 2);
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
  EXPECT_GE(q.fraction_min_angle_ge_30, 0.95) << q.to_text();  // measured 98.7 %
  EXPECT_GE(q.min_angle_non_exempt_deg, 20.0) << q.to_text();  // measured 20.71 deg
}

// Valence flips (docs/animation-meshes.md, "Valence flips") make the sample head's mesh more
// regular than the max-min-angle flips alone, without giving up any guarantee.
TEST(AnimationMeshHead, ValenceFlipsGiveMoreRegularVertices) {
  const test::SampleHead head;
  RegionGraph g = analyze_regions(head.lines, head.surface);
  apply_region_settings(g, head.settings, head.surface);
  RegionSettings plain = head.settings;
  plain.valence_flips = false;
  const AnimationMesh with = build_animation_mesh(g, head.lines, head.surface, head.settings);
  const AnimationMesh without = build_animation_mesh(g, head.lines, head.surface, plain);
  const AnimationMeshQuality qw = evaluate_quality(with, head.surface, 2);
  const AnimationMeshQuality qo = evaluate_quality(without, head.surface, 2);
  const auto share_of_6 = [](const AnimationMeshQuality& q) {
    int n = 0;
    for (const auto& [valence, count] : q.valence_histogram) n += count;
    return q.valence_histogram.count(6) ? double(q.valence_histogram.at(6)) / n : 0.0;
  };
  // Measured 0.610 vs 0.589; the mean radius ratio is level here (0.9360 vs 0.9359: at these coarse
  // units a third of the triangles touch a line, whose nodes do not move) and rises from 0.952 to
  // 0.960 at a quarter of the units (bench_aft).
  EXPECT_GT(share_of_6(qw), share_of_6(qo) + 0.01);
  EXPECT_GT(qw.mean_radius_ratio, qo.mean_radius_ratio - 0.002);
  EXPECT_GE(qw.min_angle_non_exempt_deg, 20.0) << qw.to_text();
  EXPECT_TRUE(check_mesh(with.mesh).defect_free());
  std::printf("valence 6: %.3f with valence flips, %.3f without; mean radius ratio %.4f vs %.4f\n",
              share_of_6(qw), share_of_6(qo), qw.mean_radius_ratio, qo.mean_radius_ratio);
}

// repair_goal_deg 30.5: the repair lifts the triangles between 20 and 30 deg as well.
TEST(AnimationMeshHead, RepairGoalOf30LiftsAlmostEveryTriangleTo30) {
  const test::SampleHead head;
  RegionGraph g = analyze_regions(head.lines, head.surface);
  RegionSettings s = head.settings;
  s.repair_goal_deg = 30.5;
  apply_region_settings(g, s, head.surface);
  const AnimationMesh am = build_animation_mesh(g, head.lines, head.surface, s);
  const AnimationMeshQuality q = evaluate_quality(am, head.surface, 2);
  EXPECT_TRUE(check_mesh(am.mesh).defect_free());
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
  EXPECT_GE(q.fraction_min_angle_ge_30, 0.995) << q.to_text();  // measured 99.96 %
  EXPECT_GE(q.min_angle_non_exempt_deg, 22.0) << q.to_text();   // measured 24.5 deg
}

// deviation_goal_mm: the repair also flips and splits where the mesh lies off the surface. The
// distance is measured here by the quality report (exact distances to the grid triangulation,
// an AABB tree), independently of the repair's own estimate.
TEST(AnimationMeshHead, DeviationGoalBringsTheMeshCloserToTheSurface) {
  const test::SampleHead head;
  RegionGraph g = analyze_regions(head.lines, head.surface);
  RegionSettings s = head.settings;
  apply_region_settings(g, s, head.surface);
  s.deviation_goal_mm = 0;
  const AnimationMesh off = build_animation_mesh(g, head.lines, head.surface, s);
  s.deviation_goal_mm = 1.5;
  const AnimationMesh on = build_animation_mesh(g, head.lines, head.surface, s);
  const AnimationMeshQuality q_off = evaluate_quality(off, head.surface, 4);
  const AnimationMeshQuality q_on = evaluate_quality(on, head.surface, 4);
  EXPECT_EQ(off.repair_left_above_deviation_goal, 0);
  // Measured 2.58 -> 1.88 mm. The goal is not reached everywhere (the repair never splits
  // or flips an animation-line edge, nor lowers the smallest angle below 20 deg for it).
  EXPECT_LT(q_on.hausdorff_mesh_to_surface_mm, q_off.hausdorff_mesh_to_surface_mm - 0.3);
  EXPECT_LT(q_on.hausdorff_mesh_to_surface_mm, 2.0) << q_on.to_text();
  EXPECT_GT(on.repair_left_above_deviation_goal, 0);
  // Otherwise the same kind of mesh: a few more vertices, the angle guarantees kept, still
  // on the surface.
  EXPECT_LE(on.mesh.positions.size(), off.mesh.positions.size() * 102 / 100);
  EXPECT_TRUE(check_mesh(on.mesh).defect_free());
  EXPECT_LT(q_on.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q_on.vertices_off_surface, 0);
  EXPECT_GE(q_on.min_angle_non_exempt_deg, 20.0) << q_on.to_text();
  EXPECT_GE(q_on.fraction_min_angle_ge_30, 0.95) << q_on.to_text();
}

// An eighth of the sample units (~127,000 triangles). Before 2 Dec 2026 (late) this is where
// the mesher broke at the ears: the front's step budget grew only linearly with the boundary,
// so the ears' regions stopped with 127 and 208 front edges open (holes), and the smoothing and
// flips moved points along the depth-jump walls until their triangles crossed others a ring
// away (at 0.18: 13 pairs in the chin's region, 3 at the right ear), which cost serial
// re-meshing. Now every front closes and nothing crosses, so nothing is meshed again.
TEST(AnimationMeshHead, AnEighthOfTheUnitsClosesEveryFrontWithoutCrossings) {
  const test::SampleHead head;
  RegionGraph g = analyze_regions(head.lines, head.surface);
  const RegionSettings s = head.settings.with_units_scaled(0.125);
  apply_region_settings(g, s, head.surface);
  const AnimationMesh am = build_animation_mesh(g, head.lines, head.surface, s);
  EXPECT_GT(am.mesh.triangles.size(), 100000u);
  int open_edges = 0;
  for (const auto& st : am.region_stats) open_edges += st.unmeshed_front_edges;
  EXPECT_EQ(open_edges, 0);
  EXPECT_TRUE(am.regions_remeshed.empty());
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_EQ(rep.self_intersections, 0u) << rep.to_text();
  EXPECT_TRUE(rep.edge_manifold()) << rep.to_text();
  const AnimationMeshQuality q = evaluate_quality(am, head.surface, 1);
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
  EXPECT_GE(q.min_angle_non_exempt_deg, 20.0) << q.to_text();
}

// A region that does not close is meshed again with the other front orders, and if none closes
// the least bad attempt is kept and named. A step budget far below the regions' needs forces it
// (the sample head's fronts all close at every unit size tried, so nothing else does).
TEST(AnimationMeshHead, RegionOverItsStepBudgetIsMeshedAgainAndReported) {
  const test::SampleHead head;
  RegionGraph g = analyze_regions(head.lines, head.surface);
  RegionSettings s = head.settings;
  s.max_front_steps = 60;
  apply_region_settings(g, s, head.surface);
  const AnimationMesh am = build_animation_mesh(g, head.lines, head.surface, s);
  ASSERT_FALSE(am.regions_remeshed.empty());
  const std::set<int> remeshed(am.regions_remeshed.begin(), am.regions_remeshed.end());
  int open_regions = 0;
  for (const auto& st : am.region_stats) {
    ASSERT_GE(st.region, 0);
    ASSERT_LT(st.region, static_cast<int>(g.regions.size()));
    EXPECT_FALSE(g.regions[st.region].opening);
    if (st.unmeshed_front_edges > 0) {
      ++open_regions;
      EXPECT_TRUE(remeshed.count(st.region)) << "region " << st.region << " left open";
      EXPECT_LE(st.triangles, 60) << "region " << st.region;  // one triangle per step at most
    }
  }
  EXPECT_GT(open_regions, 0);
  // What was built is still a valid partial mesh on the surface.
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_EQ(rep.self_intersections, 0u) << rep.to_text();
  EXPECT_TRUE(rep.edge_manifold()) << rep.to_text();
  const AnimationMeshQuality q_remeshed = evaluate_quality(am, head.surface, 1);
  EXPECT_LT(q_remeshed.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q_remeshed.vertices_off_surface, 0);
}

}  // namespace
}  // namespace scanmesh::aft
