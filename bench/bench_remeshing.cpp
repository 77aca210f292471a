// Seed 001 remesher vs CGAL isotropic_remeshing (Botsch-Kobbelt) on the simulated head's grid
// mesh: same prepared input, same vertex count (CGAL's target edge length calibrated until its
// count is within 1 %), boundary edges constrained in both. Prints a Markdown table.
// Usage: bench_remeshing [target_vertices=20000] [--quick]
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "../tests/meshing/remeshing/remesh_test_meshes.h"
#include "bench_support.h"
#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/remeshing/remesh.h"
#include "scanmesh/meshing/remeshing/remesh_quality.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;
using namespace scanmesh;

namespace {

struct Row {
  std::string method;
  double seconds = 0;
  std::size_t vertices = 0;
  double min_angle = 0, ge30 = 0, mean_q = 0, irregular = 0, hausdorff = 0, mean_dist = 0;
  std::size_t self_intersections = 0;
};

// The same measure for both outputs, from the output alone: optimal valence 6 inside, 4 on a
// boundary; non-manifold vertices are not counted.
Row measure(const std::string& method, double seconds, const Mesh& out, const Mesh& in) {
  Row r;
  r.method = method;
  r.seconds = seconds;
  r.vertices = out.positions.size();
  std::map<std::uint64_t, int> ec;
  std::vector<std::vector<int>> nb(out.positions.size());
  for (const auto& t : out.triangles)
    for (int i = 0; i < 3; ++i) {
      ++ec[remeshing::edge_key(t[i], t[(i + 1) % 3])];
      nb[t[i]].push_back(t[(i + 1) % 3]);
      nb[t[(i + 1) % 3]].push_back(t[i]);
    }
  std::vector<int> boundary(out.positions.size(), 0);
  for (const auto& [k, c] : ec)
    if (c == 1) {
      ++boundary[remeshing::edge_key_first(k)];
      ++boundary[remeshing::edge_key_second(k)];
    }
  std::size_t counted = 0, optimal = 0;
  for (std::size_t v = 0; v < nb.size(); ++v) {
    auto& l = nb[v];
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    if (boundary[v] > 2 || l.empty()) continue;
    ++counted;
    optimal += static_cast<int>(l.size()) == (boundary[v] ? 4 : 6);
  }
  r.irregular = counted ? 1.0 - static_cast<double>(optimal) / counted : 0;
  double amin = 180, qsum = 0;
  std::size_t ge = 0;
  for (const auto& t : out.triangles) {
    const auto &a = out.positions[t[0]], &b = out.positions[t[1]], &c = out.positions[t[2]];
    auto ang = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& s) {
      return std::atan2((q - p).cross(s - p).norm(), (q - p).dot(s - p)) * 180 / M_PI;
    };
    const double m = std::min({ang(a, b, c), ang(b, c, a), ang(c, a, b)});
    amin = std::min(amin, m);
    ge += m >= 30;
    qsum += std::min(remeshing::aspect_ratio(a, b, c), 1e6);
  }
  r.min_angle = amin;
  r.ge30 = static_cast<double>(ge) / out.triangles.size();
  r.mean_q = qsum / out.triangles.size();
  const auto d1 = remeshing::sampled_distance(out, in), d2 = remeshing::sampled_distance(in, out);
  r.hausdorff = std::max(d1[0], d2[0]);
  r.mean_dist = d1[1];
  r.self_intersections = check_mesh(out).self_intersections;
  return r;
}

Mesh from_cgal(const SurfaceMesh& sm) {
  Mesh m;
  std::map<SurfaceMesh::Vertex_index, int> id;
  for (auto v : sm.vertices()) {
    id[v] = static_cast<int>(m.positions.size());
    const auto& p = sm.point(v);
    m.positions.push_back({p.x(), p.y(), p.z()});
  }
  for (auto f : sm.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) t[k++] = id[v];
    m.triangles.push_back(t);
  }
  return m;
}

bool to_cgal(const Mesh& m, SurfaceMesh& sm) {
  std::vector<K::Point_3> pts;
  for (const auto& p : m.positions) pts.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::vector<std::size_t>> polys;
  for (const auto& t : m.triangles)
    polys.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  if (!PMP::is_polygon_soup_a_polygon_mesh(polys)) {
    // Non-manifold vertices are duplicated by the orientation step; non-manifold edges are not
    // representable at all.
    PMP::orient_polygon_soup(pts, polys);
    if (!PMP::is_polygon_soup_a_polygon_mesh(polys)) return false;
  }
  PMP::polygon_soup_to_polygon_mesh(pts, polys, sm);
  return true;
}

void print(const Row& r) {
  std::printf("| %s | %.2f | %zu | %.2f | %.2f | %.3f | %.1f | %.3f | %.4f | %zu |\n",
              r.method.c_str(), r.seconds, r.vertices, r.min_angle, 100 * r.ge30, r.mean_q,
              100 * r.irregular, r.hausdorff, r.mean_dist, r.self_intersections);
}

void compare(const sim::ScannerConfig& cfg, int target, bool uniform_only) {
  const auto scan = sim::simulate_scan(sim::builtin_head_scene(), cfg);
  RangeGrid grid = scan.grid;
  clean_grid(grid);
  const Mesh raw = grid_mesh(grid).mesh;
  remeshing::PrepareStats ps;
  // Scan clean-up as `scanmesh remesh --min-component 500 --fill-holes 100 --needle-angle 5
  // --remove-spikes`: border tips judged at the target edge length.
  double raw_area = 0;
  for (const auto& t : raw.triangles)
    raw_area += 0.5 * (raw.positions[t[1]] - raw.positions[t[0]])
                          .cross(raw.positions[t[2]] - raw.positions[t[0]])
                          .norm();
  const Mesh in = remeshing::prepare_input(
      raw,
      {.min_component_faces = 500,
       .max_hole_edges = 100,
       .needle_angle_deg = 5,
       .remove_spikes = true,
       .tip_reach_mm = std::sqrt(raw_area / (std::sqrt(3.0) / 2 * target))},
      &ps);
  std::printf(
      "head grid mesh: %zu vertices, %zu triangles; prepared: %zu vertices, %zu triangles "
      "(%zu crumbs removed, %zu holes closed, %zu spike / %zu pinch / %zu border-tip faces "
      "removed)\n\n",
      raw.positions.size(), raw.triangles.size(), in.positions.size(), in.triangles.size(),
      ps.components_removed, ps.holes_filled, ps.spike_faces_removed, ps.pinch_faces_removed,
      ps.tip_faces_removed);
  std::printf(
      "| method | time [s] | vertices | min angle [deg] | tri >= 30 deg [%%] | mean Q | "
      "irregular valence [%%] | Hausdorff [mm] | mean dist [mm] | self-intersections |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<Row> rows;
  for (auto [name, gamma] : std::vector<std::pair<std::string, double>>{
           {"seed 001 regularize, uniform", 0.0}, {"seed 001 regularize, gamma 1", 1.0}}) {
    if (uniform_only && gamma != 0) continue;
    remeshing::RemeshOptions o;
    o.target_vertices = target;
    o.density.gamma = gamma;
    remeshing::RemeshResult r;
    const double t = bench::time_median(1, [&] { r = remeshing::remesh(in, o); });
    rows.push_back(measure(name, t, r.mesh, in));
    print(rows.back());
  }
  // CGAL: boundary edges constrained (not protected: split / collapsed along the border like ours,
  // with 1D relaxation), 5 iterations; edge length calibrated to the same vertex count.
  SurfaceMesh base;
  if (!to_cgal(in, base)) {
    std::printf("CGAL: the prepared head is not a polygon mesh\n");
    return;
  }
  double area = 0;
  for (const auto& t : in.triangles)
    area += 0.5 * (in.positions[t[1]] - in.positions[t[0]])
                      .cross(in.positions[t[2]] - in.positions[t[0]])
                      .norm();
  double L = std::sqrt(4 * area / (std::sqrt(3.0) * 2 * target));
  Mesh cgal_out;
  double cgal_t = 0;
  for (int attempt = 0; attempt < 6; ++attempt) {
    SurfaceMesh sm = base;
    auto ecm = sm.add_property_map<SurfaceMesh::Edge_index, bool>("e:constrained", false).first;
    for (auto e : sm.edges()) ecm[e] = sm.is_border(e);
    const double t0 = bench::now();
    PMP::isotropic_remeshing(sm.faces(), L, sm,
                             CGAL::parameters::number_of_iterations(5)
                                 .edge_is_constrained_map(ecm)
                                 .protect_constraints(false)
                                 .relax_constraints(true));
    cgal_t = bench::now() - t0;
    cgal_out = from_cgal(sm);
    const double ratio = static_cast<double>(cgal_out.positions.size()) / target;
    std::fprintf(stderr, "CGAL L = %.4f -> %zu vertices (%.1f s)\n", L, cgal_out.positions.size(),
                 cgal_t);
    if (std::abs(ratio - 1) < 0.01) break;
    L *= std::sqrt(ratio);
  }
  rows.push_back(measure("CGAL isotropic_remeshing (L = " + std::to_string(L).substr(0, 5) + " mm)",
                         cgal_t, cgal_out, in));
  print(rows.back());
  std::printf("\ntime ratio seed 001 uniform / CGAL: %.2f\n\n", rows[0].seconds / cgal_t);
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
    for (int i = 0; i < 3; ++i) ++ec[remeshing::edge_key(tr[i], tr[(i + 1) % 3])];
  for (const auto& [k, c] : ec) seam_edges += c == 3;
  const auto q = remeshing::evaluate_remesh(boxes, r, true);
  std::printf(
      "seed 001: %.2f s, %zu vertices, %zu seam edges with 3 faces, min angle %.1f deg, "
      "%.1f %% >= 30 deg, mean Q %.3f, irregular %.1f %% (2p+2 on seams), Hausdorff %.2g mm, "
      "self-intersections %zu\n",
      t, r.mesh.positions.size(), seam_edges, q.min_angle_deg, 100 * q.fraction_min_angle_ge_30,
      q.q_mean, 100 * q.fraction_irregular, q.hausdorff, q.self_intersections);
  return 0;
}
