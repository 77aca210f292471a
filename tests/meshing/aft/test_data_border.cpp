// The data border of a partial scan (issue 25 item 2; docs/animation-meshes.md, "Partial scans:
// the data border"): the simulated head with every column outside a quarter turn round the
// face invalidated, as an imported face scan would be.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "aft_test_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/data_border.h"
#include "scanmesh/meshing/grid_mesh.h"

namespace scanmesh::aft {
namespace {

// The face is round x = 256 (phi = pi): its lines in configs/sim/head-lines.svg.
constexpr int kFirstColumn = 192, kEndColumn = 320;

RangeGrid quarter_turn_of(RangeGrid grid) {
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i)
      if (i < kFirstColumn || i >= kEndColumn) grid.invalidate(i, j);
  return grid;
}

// The simulated head and its quarter turn, simulated once for the whole suite.
struct PartialHead {
  test::SampleHead full;
  RangeGrid grid = quarter_turn_of(full.scan.grid);
  ScanSurface surface{grid};
};

const PartialHead& partial_head() {
  static const PartialHead head;
  return head;
}

// A horizontal line under the eyes across the whole patch and a vertical one from it down
// through the chin: neither closes on its own, both run off the data.
LineSet crossing_lines() {
  return parse_lines_json(R"({"lines": [
      {"id": "across", "points": [[150, 235], [360, 235]]},
      {"id": "down", "points": [[256, 235], [256, 1]]}]})",
                          "crossing.json");
}

RegionGraph regions_of(const LineSet& lines, const ScanSurface& surface) {
  validate_lines(lines, surface);
  return analyze_regions(lines, surface);
}

int meshed_regions(const RegionGraph& g) {
  int n = 0;
  for (const Region& r : g.regions) n += !r.opening;
  return n;
}

// Largest distance, in texture pixels (cells), from a defined cell centre (every second one)
// to the mesh's footprint in the texture: what the margin and the meshing leave uncovered. In
// the texture, not in 3D: the 3D distance also measures the chords' deviation from the curved
// surface (the sample head's 6 mm at the ears), which is not coverage.
double uncovered_cells(const ScanSurface& s, const AnimationMesh& am) {
  std::vector<Eigen::Vector3d> px;
  for (const auto& p : am.params) {
    const Eigen::Vector2d q = param_to_pixel(s, p);
    px.emplace_back(q.x(), q.y(), 0.0);
  }
  double worst = 0;
  for (int j = 1; j + 1 < s.n_h(); j += 2)
    for (int i = 0; i < s.n_phi(); i += 2) {
      const Eigen::Vector2d c(i + 1.0, j + 1.0);  // a patch centre
      const Eigen::Vector2d q = pixel_to_param(s, c);
      if (!s.defined(q.x(), q.y())) continue;
      double best = 1e300;
      for (const auto& t : am.mesh.triangles)
        best = std::min(best, point_triangle_squared_distance({c.x(), c.y(), 0.0}, px[t[0]],
                                                              px[t[1]], px[t[2]]));
      worst = std::max(worst, std::sqrt(best));
    }
  return worst;
}

TEST(DataBorder, AutoIsOnForAQuarterTurnAndOffForTheFullHead) {
  const PartialHead& head = partial_head();
  EXPECT_TRUE(misses_part_of_the_turn(head.surface));
  EXPECT_FALSE(misses_part_of_the_turn(head.full.surface));
  const DataBorderResult full =
      with_data_border(head.full.lines, head.full.surface, DataBorderMode::Auto);
  EXPECT_FALSE(full.border_on);
  ASSERT_EQ(full.lines.lines.size(), head.full.lines.lines.size());
  for (std::size_t l = 0; l < full.lines.lines.size(); ++l)
    EXPECT_EQ(full.lines.lines[l].pixels, head.full.lines.lines[l].pixels);
  EXPECT_EQ(parse_data_border_mode("on"), DataBorderMode::On);
  EXPECT_THROW(parse_data_border_mode("yes"), InvalidInputError);
}

TEST(DataBorder, QuarterTurnHasOneSimpleBorderInsideTheData) {
  const PartialHead& head = partial_head();
  const std::vector<AnimationLine> border = trace_data_border(head.surface);
  // The data fill every row of the quarter turn: a rectangle, one line per side so that its
  // four corners become graph nodes, each side ending where the next begins.
  ASSERT_EQ(border.size(), 4u);
  std::size_t vertices = 0;
  double xmin = 1e9, xmax = -1e9;
  for (std::size_t k = 0; k < border.size(); ++k) {
    const AnimationLine& b = border[k];
    EXPECT_EQ(b.kind, LineKind::DataBorder);
    EXPECT_EQ(b.id, "data-border-1." + std::to_string(k + 1));
    EXPECT_FALSE(b.closed);
    EXPECT_EQ(b.pixels.back(), border[(k + 1) % border.size()].pixels.front());
    vertices += b.pixels.size() - 1;
    for (const auto& p : b.pixels) {
      xmin = std::min(xmin, p.x());
      xmax = std::max(xmax, p.x());
    }
  }
  EXPECT_NO_THROW(validate_lines(LineSet{"border", border}, head.surface));
  // The margin: no vertex closer than a pixel to the invalid columns (the patches there end
  // at x = 192.5 and 319.5).
  EXPECT_GE(xmin, kFirstColumn + 0.5 + 1.0);
  EXPECT_LE(xmax, kEndColumn - 0.5 - 1.0);
  EXPECT_LE(xmin, kFirstColumn + 0.5 + 2.0);  // and not far inside either
  EXPECT_GE(xmax, kEndColumn - 0.5 - 2.0);
  // Simplified: not one vertex per cell edge; the patch's outline is ~1,200 cells long.
  EXPECT_LT(vertices, 150u);
  std::printf("quarter turn: data border of %zu vertices, x %.2f..%.2f\n", vertices, xmin, xmax);
}

TEST(DataBorder, NoLinesGiveTheWholePatchAsOneRegion) {
  const PartialHead& head = partial_head();
  const DataBorderResult r = with_data_border(LineSet{}, head.surface, DataBorderMode::Auto);
  EXPECT_TRUE(r.border_on);
  EXPECT_EQ(r.border_lines, 4);
  const RegionGraph g = regions_of(r.lines, head.surface);
  ASSERT_EQ(g.regions.size(), 1u);
  EXPECT_FALSE(g.regions[0].opening);
  // The region is the patch: its label point lies in the data.
  const Eigen::Vector2d px = param_to_pixel(head.surface, g.regions[0].label_point);
  EXPECT_GT(px.x(), kFirstColumn);
  EXPECT_LT(px.x(), kEndColumn);
}

TEST(DataBorder, OffKeepsTodaysBehaviourOfNoRegions) {
  const PartialHead& head = partial_head();
  const LineSet inside = parse_lines_json(
      R"({"lines": [{"id": "inside", "points": [[210, 235], [300, 235]]}]})", "inside.json");
  const DataBorderResult off = with_data_border(inside, head.surface, DataBorderMode::Off);
  EXPECT_FALSE(off.border_on);
  EXPECT_EQ(regions_of(off.lines, head.surface).regions.size(), 0u);
  // And a line that runs off the data is still an error without the border.
  EXPECT_THROW(validate_lines(crossing_lines(), head.surface), FileFormatError);
}

TEST(DataBorder, LinesRunningOffTheDataAreClippedAndSplitThePatch) {
  const PartialHead& head = partial_head();
  const DataBorderResult r = with_data_border(crossing_lines(), head.surface, DataBorderMode::On);
  EXPECT_EQ(r.clipped_lines, 2);
  EXPECT_EQ(r.dropped_lines, 0);
  ASSERT_EQ(r.lines.lines.size(), 6u);  // across, down, the border's four sides
  for (int l = 0; l < 2; ++l) {
    const AnimationLine& line = r.lines.lines[l];
    EXPECT_FALSE(line.closed);
    for (const auto& p : line.pixels) {
      EXPECT_GT(p.x(), kFirstColumn + 0.5) << line.id;
      EXPECT_LT(p.x(), kEndColumn - 0.5) << line.id;
    }
  }
  const RegionGraph g = regions_of(r.lines, head.surface);
  EXPECT_EQ(meshed_regions(g), 3);
  // The cut ends are T-junctions on the border, not dangling ends.
  EXPECT_TRUE(g.dangling_ends.empty()) << g.to_text();
  // Only the horizontal line: two regions.
  LineSet across = crossing_lines();
  across.lines.pop_back();
  const DataBorderResult one = with_data_border(across, head.surface, DataBorderMode::On);
  EXPECT_EQ(meshed_regions(regions_of(one.lines, head.surface)), 2);
}

TEST(DataBorder, LinesWhollyOutsideTheDataAreDropped) {
  const PartialHead& head = partial_head();
  const LineSet outside = parse_lines_json(
      R"({"lines": [{"id": "back", "points": [[20, 235], [120, 235]]}]})", "outside.json");
  const DataBorderResult r = with_data_border(outside, head.surface, DataBorderMode::Auto);
  EXPECT_EQ(r.dropped_lines, 1);
  ASSERT_EQ(r.lines.lines.size(), 4u);
  for (const AnimationLine& line : r.lines.lines) EXPECT_EQ(line.kind, LineKind::DataBorder);
}

// The face's own eye openings, a seam running off the data and a settings point per region.
TEST(DataBorder, OpeningsSeamsAndSettingsPointsWorkOnAPartialGrid) {
  const PartialHead& head = partial_head();
  LineSet lines = parse_lines_json(R"({"lines": [
      {"id": "across", "points": [[150, 235], [360, 235]]},
      {"id": "chin-seam", "kind": "seam", "spacing_mm": 4, "points": [[150, 120], [360, 120]]},
      {"id": "opening-eye", "kind": "opening", "closed": true, "smooth": true,
       "points": [[237, 271], [232, 280], [224, 280], [219, 271], [219, 259], [224, 250],
                  [232, 250], [237, 259]]}]})",
                                   "face.json");
  const DataBorderResult r = with_data_border(lines, head.surface, DataBorderMode::Auto);
  RegionGraph g = regions_of(r.lines, head.surface);
  EXPECT_EQ(meshed_regions(g), 3);
  EXPECT_EQ(g.regions.size() - meshed_regions(g), 1u);  // the eye
  RegionSettings s = parse_region_settings(R"(
unit_mm: 10
regions:
  - {name: upper, point: [256, 400], unit_mm: 12}
  - {name: middle, point: [256, 180], unit_mm: 8}
  - {name: chin, point: [256, 60]}
)",
                                           "face.yaml");
  apply_region_settings(g, s, head.surface);
  const auto middle = g.region_at(pixel_to_param(head.surface, {256, 180}));
  ASSERT_TRUE(middle);
  EXPECT_EQ(g.regions[*middle].name, "middle");
  EXPECT_EQ(g.regions[*middle].unit_mm, 8);
  const AnimationMesh am = build_animation_mesh(g, r.lines, head.surface, s);
  ASSERT_TRUE(am.seams.count("chin-seam"));
  test::expect_lines_are_edge_chains(g, am);
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_TRUE(rep.edge_manifold()) << rep.to_text();
  EXPECT_EQ(rep.self_intersections, 0u);
  EXPECT_EQ(rep.topology.boundary_loops, 2u) << rep.to_text();  // the border and the eye
}

TEST(DataBorder, AnimeshOnAQuarterTurnCoversTheDataWithAValidMesh) {
  const PartialHead& head = partial_head();
  const DataBorderResult r = with_data_border(crossing_lines(), head.surface, DataBorderMode::Auto);
  RegionGraph g = regions_of(r.lines, head.surface);
  ASSERT_EQ(meshed_regions(g), 3);
  RegionSettings s;
  s.default_unit_mm = 8;
  apply_region_settings(g, s, head.surface);
  const AnimationMesh am = build_animation_mesh(g, r.lines, head.surface, s);
  int open_edges = 0;
  for (const auto& st : am.region_stats) open_edges += st.unmeshed_front_edges;
  EXPECT_EQ(open_edges, 0);
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_TRUE(rep.edge_manifold()) << rep.to_text();
  EXPECT_EQ(rep.duplicate_faces, 0u);
  EXPECT_EQ(rep.self_intersections, 0u);
  EXPECT_EQ(rep.nonmanifold_vertices, 0u);
  EXPECT_EQ(rep.topology.boundary_loops, 1u) << rep.to_text();  // the data border only
  test::expect_lines_are_edge_chains(g, am);
  const AnimationMeshQuality q = evaluate_quality(am, head.surface, 2, &g);
  EXPECT_LT(q.max_vertex_offset_mm, 0.01);
  EXPECT_EQ(q.vertices_off_surface, 0);
  EXPECT_GE(q.min_angle_non_exempt_deg, 20.0) << q.to_text();
  // Coverage: the grid mesh of the same patch is the data; the border's margin of ~1.5 cells
  // round an outline of ~1,200 cells costs a few per cent of it.
  GridMeshOptions gopt;
  gopt.with_colors = gopt.with_texcoords = false;
  gopt.max_depth_jump_mm = 1e9;  // the AFT meshes across the nose's and chin's jumps too
  const double grid_area = surface_area(grid_mesh(head.grid, gopt).mesh);
  const double mesh_area = surface_area(am.mesh);
  EXPECT_GT(mesh_area, 0.93 * grid_area);
  EXPECT_LT(mesh_area, 1.01 * grid_area);
  // Every defined patch within two cells of the mesh (the margin is 1.5).
  const double gap = uncovered_cells(head.surface, am);
  EXPECT_LT(gap, 2.0);
  std::printf(
      "quarter turn, 2 crossing lines: %d regions, %zu triangles, min angle %.2f deg, "
      "%.2f %% >= 30 deg, area %.0f of %.0f mm^2 (%.1f %%), uncovered %.2f cells, "
      "boundary loops %zu, manifold %d\n",
      meshed_regions(g), am.mesh.triangles.size(), q.min_angle_deg,
      100 * q.fraction_min_angle_ge_30, mesh_area, grid_area, 100 * mesh_area / grid_area, gap,
      rep.topology.boundary_loops, rep.edge_manifold());
}

// A round patch of data on a cylinder (cells valid inside an ellipse of 120 x 240 cells): the
// border must follow the curve without the cells' staircase and without sharp corners.
RangeGrid elliptic_patch() {
  RangeGrid g = test::cylinder_grid(100.0, 0.0, 512, 400, 0.5);
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i)
      if (std::pow((i - 256) / 60.0, 2) + std::pow((j - 200) / 120.0, 2) >= 1) g.invalidate(i, j);
  return g;
}

TEST(DataBorder, RoundPatchGetsOneSmoothBorderWithoutStairs) {
  const RangeGrid grid = elliptic_patch();
  const ScanSurface surface(grid);
  const std::vector<AnimationLine> border = trace_data_border(surface);
  ASSERT_EQ(border.size(), 1u);
  const AnimationLine& b = border[0];
  EXPECT_TRUE(b.closed);  // no corner: one closed line
  EXPECT_NO_THROW(validate_lines(LineSet{"border", border}, surface));
  const std::size_t n = b.pixels.size();
  double worst_turn = 0, shortest = 1e9, area_px = 0, closest = 1e9, farthest = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d a = b.pixels[(k + n - 1) % n], p = b.pixels[k], c = b.pixels[(k + 1) % n];
    const Eigen::Vector2d u = p - a, v = c - p;
    worst_turn =
        std::max(worst_turn, std::atan2(std::fabs(u.x() * v.y() - u.y() * v.x()), u.dot(v)));
    shortest = std::min(shortest, v.norm());
    area_px += 0.5 * (p.x() * c.y() - c.x() * p.y());
    // Cell (i, j) is pixel (i + 0.5, j + 0.5): distance to the ellipse in cells, roughly.
    const double e = std::hypot((p.x() - 256.5) / 60.0, (p.y() - 200.5) / 120.0);
    closest = std::min(closest, (1 - e) * 60);
    farthest = std::max(farthest, (1 - e) * 60);
  }
  // The staircase of single cells would turn by 90 deg at every step; the Douglas-Peucker
  // chords of 0.6 px on the ellipse's tight ends (radius of curvature 30 px) turn by ~25-35.
  EXPECT_LT(worst_turn, 45 * M_PI / 180) << worst_turn * 180 / M_PI;
  EXPECT_GT(shortest, 1.0);
  EXPECT_LT(n, 120u);  // the ellipse is ~1,200 cell edges round
  // The defined patches fill the ellipse less a ~1 cell rim; the margin takes 1.5 more.
  const double ellipse_px = M_PI * 60 * 120;
  EXPECT_GT(area_px, 0.93 * ellipse_px);
  EXPECT_LT(area_px, 0.99 * ellipse_px);
  std::printf(
      "round patch: %zu border vertices, sharpest turn %.1f deg, shortest side %.2f px, area "
      "%.1f %% of the ellipse, %.2f..%.2f cells inside it (at the vertices)\n",
      n, worst_turn * 180 / M_PI, shortest, 100 * area_px / ellipse_px, closest, farthest);
  // No lines: one region, meshed with every front closed and one boundary loop.
  const DataBorderResult r = with_data_border(LineSet{}, surface, DataBorderMode::Auto);
  RegionGraph g = regions_of(r.lines, surface);
  ASSERT_EQ(meshed_regions(g), 1);
  RegionSettings s;
  s.default_unit_mm = 5;
  apply_region_settings(g, s, surface);
  const AnimationMesh am = build_animation_mesh(g, r.lines, surface, s);
  EXPECT_EQ(am.region_stats.at(0).unmeshed_front_edges, 0);
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_TRUE(rep.edge_manifold());
  EXPECT_EQ(rep.self_intersections, 0u);
  EXPECT_EQ(rep.topology.boundary_loops, 1u);
  const AnimationMeshQuality q = evaluate_quality(am, surface, 2, &g);
  EXPECT_GE(q.min_angle_deg, 20.0) << q.to_text();
  EXPECT_LT(q.max_vertex_offset_mm, 1e-6);
  EXPECT_LT(uncovered_cells(surface, am), 2.5);
  std::printf("round patch, no lines: %zu triangles, min angle %.2f deg, %.2f %% >= 30 deg\n",
              am.mesh.triangles.size(), q.min_angle_deg, 100 * q.fraction_min_angle_ge_30);
}

// clip_lines_to_border on its own (with_data_border counts; this is the bare clip), on the
// round patch: a line crossing it loses both ends, one leaving and re-entering it becomes two
// lines, one inside is kept as it is and one outside is dropped.
TEST(DataBorder, ClipKeepsThePartsInsideTheBorderAndNamesTheExtraParts) {
  const RangeGrid grid = elliptic_patch();
  const ScanSurface surface(grid);
  const std::vector<AnimationLine> border = trace_data_border(surface);
  ASSERT_EQ(border.size(), 1u);
  const LineSet lines = parse_lines_json(R"({"lines": [
      {"id": "across", "points": [[150, 200], [360, 200]]},
      {"id": "zig", "points": [[150, 150], [250, 150], [250, 40], [262, 40], [262, 150],
                               [360, 150]]},
      {"id": "inside", "points": [[230, 260], [280, 260]]},
      {"id": "outside", "points": [[20, 200], [100, 200]]}]})",
                                         "clip.json");
  const LineSet clipped = clip_lines_to_border(lines, border, surface);
  std::vector<std::string> ids;
  for (const AnimationLine& l : clipped.lines) ids.push_back(l.id);
  EXPECT_EQ(ids, (std::vector<std::string>{"across", "zig", "zig.2", "inside"}));
  ASSERT_EQ(clipped.lines.size(), 4u);
  // The ellipse (centre 256.5, 200.5; half-axes 60 and 120 cells) less the border's margin.
  auto ellipse = [](const Eigen::Vector2d& p) {
    return std::hypot((p.x() - 256.5) / 60.0, (p.y() - 200.5) / 120.0);
  };
  for (int l = 0; l < 3; ++l) {
    const AnimationLine& line = clipped.lines[l];
    EXPECT_FALSE(line.closed) << line.id;
    for (const auto& p : line.pixels) EXPECT_LT(ellipse(p), 1.0) << line.id;
    // Cut ends lie on the border: within the margin and a cell of the ellipse.
    for (const auto& end : {line.pixels.front(), line.pixels.back()})
      EXPECT_GT(ellipse(end), 0.9) << line.id << " end " << end.transpose();
  }
  const auto& across = clipped.lines[0].pixels;
  EXPECT_NEAR(across.front().x(), 256.5 - 60, 4.0);
  EXPECT_NEAR(across.back().x(), 256.5 + 60, 4.0);
  EXPECT_EQ(clipped.lines[3].pixels, lines.lines[2].pixels);  // wholly inside: unchanged
  // The clipped lines pass the checks the region analysis makes, with the border added.
  LineSet with_border = clipped;
  with_border.lines.insert(with_border.lines.end(), border.begin(), border.end());
  EXPECT_NO_THROW(validate_lines(with_border, surface));
}

TEST(DataBorder, AutoOnTheFullHeadGivesTodaysMesh) {
  const PartialHead& head = partial_head();
  const test::SampleHead& full = head.full;
  const DataBorderResult r = with_data_border(full.lines, full.surface, DataBorderMode::Auto);
  RegionGraph today = analyze_regions(full.lines, full.surface);
  RegionGraph with_auto = analyze_regions(r.lines, full.surface);
  apply_region_settings(today, full.settings, full.surface);
  apply_region_settings(with_auto, full.settings, full.surface);
  const AnimationMesh a = build_animation_mesh(today, full.lines, full.surface, full.settings);
  const AnimationMesh b = build_animation_mesh(with_auto, r.lines, full.surface, full.settings);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
}

}  // namespace
}  // namespace scanmesh::aft
