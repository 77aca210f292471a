// Seed 001 remesher vs CGAL isotropic_remeshing (Botsch-Kobbelt) on the simulated head's grid
// mesh: same prepared input, same vertex count (CGAL's target edge length calibrated until its
// count is within 1 %), boundary edges constrained in both. Prints a Markdown table.
// Usage: bench_remeshing [target_vertices=20000] [--quick]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "../tests/meshing/remeshing/remesh_test_meshes.h"
#include "anchors_cgal.h"
#include "bench_support.h"
#include "remesh_measure.h"
#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/remeshing/remesh.h"
#include "scanmesh/meshing/remeshing/remesh_quality.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

using SurfaceMesh = scanmesh::bench::CgalSurfaceMesh;
namespace PMP = CGAL::Polygon_mesh_processing;
using namespace scanmesh;

namespace {

using Row = bench::RemeshMeasure;
using bench::measure_remesh;

void print(const Row& r) {
  std::printf("| %s | %.2f | %zu | %.2f | %.2f | %.3f | %.1f | %.3f | %.4f | %zu |\n",
              r.method.c_str(), r.seconds, r.vertices, r.min_angle, 100 * r.ge30,
              r.mean_aspect_ratio, 100 * r.irregular, r.hausdorff, r.mean_dist,
              r.self_intersections);
}

void compare(const sim::ScannerConfig& cfg, int target, bool uniform_only) {
  const auto scan = sim::simulate_scan(sim::builtin_head_scene(), cfg);
  RangeGrid grid = scan.grid;
  clean_grid(grid);
  const Mesh raw = grid_mesh(grid).mesh;
  remeshing::PrepareStats ps;
  // The scan clean-up `scanmesh remesh` runs by default on such a mesh (looks_like_scan), at the
  // output's scale.
  const Mesh in = remeshing::prepare_input(raw, remeshing::scan_prepare_options(raw, target), &ps);
  std::printf(
      "head grid mesh: %zu vertices, %zu triangles; prepared: %zu vertices, %zu triangles "
      "(%zu crumbs removed, %zu holes closed, %zu spike / %zu pinch / %zu border-tip faces "
      "removed)\n\n",
      raw.positions.size(), raw.triangles.size(), in.positions.size(), in.triangles.size(),
      ps.components_removed, ps.holes_filled, ps.spike_faces_removed, ps.pinch_faces_removed,
      ps.tip_faces_removed);
  std::printf(
      "| method | time [s] | vertices | min angle [deg] | tri >= 30 deg [%%] | mean aspect ratio "
      "R/2r | "
      "irregular valence [%%] | Hausdorff [mm] | mean dist [mm] | self-intersections |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<Row> rows;
  for (auto [name, gamma] : std::vector<std::pair<std::string, double>>{
           {"scanmesh remesh, uniform", 0.0}, {"scanmesh remesh, defaults (gamma 0.5)", 0.5}}) {
    if (uniform_only && gamma != 0) continue;
    remeshing::RemeshOptions o;
    o.target_vertices = target;
    o.density.gamma = gamma;
    remeshing::RemeshResult r;
    const double t = bench::time_median(1, [&] { r = remeshing::remesh(in, o); });
    rows.push_back(measure_remesh(name, t, r.mesh, in));
    print(rows.back());
  }
  // CGAL: boundary edges constrained (not protected: split / collapsed along the border like ours,
  // with 1D relaxation), 5 iterations; edge length calibrated to the same vertex count.
  SurfaceMesh base;
  if (!bench::to_cgal(in, base)) {
    std::printf("CGAL: the prepared head is not a polygon mesh\n");
    return;
  }
  const auto cgal = bench::cgal_remesh_to_count(base, scanmesh::surface_area(in), target);
  const double cgal_t = cgal.seconds;
  rows.push_back(measure_remesh(
      "CGAL isotropic_remeshing (L = " + std::to_string(cgal.edge_length).substr(0, 5) + " mm)",
      cgal_t, cgal.mesh, in));
  print(rows.back());
  std::printf("\ntime ratio scanmesh / CGAL: uniform %.2f", rows[0].seconds / cgal_t);
  if (rows.size() > 2) std::printf(", defaults %.2f", rows[1].seconds / cgal_t);
  std::printf("\n\n");
}

}  // namespace

int main(int argc, char** argv) {
  int target = 20000;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick"))
      quick = true;
    else
      target = std::atoi(argv[i]);
  }
  // The demo's head (with its hair crumbs), and the same head scanned without hair.
  for (const bool hair : {true, false}) {
    if (quick && !hair) continue;
    sim::ScannerConfig cfg = sim::builtin_head_scanner();
    cfg.hair = hair;
    std::printf("### %s\n\n", hair ? "demo head (hair on)" : "head scanned without hair");
    compare(cfg, target, quick && hair);
  }

  // Non-manifold input: two boxes sharing a face.
  const Mesh boxes = test::two_boxes(10, 20);
  std::vector<std::vector<std::size_t>> soup;
  for (const auto& tr : boxes.triangles)
    soup.push_back({std::size_t(tr[0]), std::size_t(tr[1]), std::size_t(tr[2])});
  std::printf(
      "two boxes sharing a face (%zu triangles, 4 seams x 20 edges with 3 faces): "
      "is_polygon_soup_a_polygon_mesh = %s, so CGAL's Surface_mesh cannot hold it "
      "(orient_polygon_soup would cut every seam edge apart into separate borders)\n",
      boxes.triangles.size(), PMP::is_polygon_soup_a_polygon_mesh(soup) ? "true" : "false");
  remeshing::RemeshOptions o;
  o.target_vertices = 600;
  o.density.gamma = 0;
  o.skeleton.sharp_angle_deg = 45;
  remeshing::RemeshResult r;
  const double t = bench::time_median(1, [&] { r = remeshing::remesh(boxes, o); });
  std::size_t seam_edges = 0;
  std::map<std::uint64_t, int> ec;
  for (const auto& tr : r.mesh.triangles)
    for (int i = 0; i < 3; ++i) ++ec[edge_key(tr[i], tr[(i + 1) % 3])];
  for (const auto& [k, c] : ec) seam_edges += c == 3;
  const auto q = remeshing::evaluate_remesh(boxes, r, true);
  std::printf(
      "seed 001: %.2f s, %zu vertices, %zu seam edges with 3 faces, min angle %.1f deg, "
      "%.1f %% >= 30 deg, mean aspect ratio R/2r %.3f, irregular %.1f %% (2p+2 on seams), "
      "Hausdorff %.2g mm, "
      "self-intersections %zu\n",
      t, r.mesh.positions.size(), seam_edges, q.min_angle_deg, 100 * q.fraction_min_angle_ge_30,
      q.aspect_ratio_mean, 100 * q.fraction_irregular, q.hausdorff, q.self_intersections);
  return 0;
}
