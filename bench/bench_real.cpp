// Every scanmesh stage against its anchor on the real-data corpus (libcgal-demo's scanned clouds
// and meshes, tests/real_corpus.cmake), same input, same run; one Markdown table per file
// (docs/benchmarks.md, "Real scans (bench_real)"):
//   clouds:    fans vs CGAL advancing front vs PCL GP3
//   meshes:    seed 001 remesh (the CLI's defaults) vs CGAL isotropic_remeshing, both at the
//              input's vertex count
//   every file: import_scan to a grid, grid_mesh of it, and grid-quadric / quadric curvature of
//              the grid vs PCL NormalEstimationOMP + PrincipalCurvaturesEstimation on the same
//              grid points (agreement, as there is no ground truth); the grid mesh remeshed
//              to its own count, as `scanmesh remesh` does it, vs CGAL isotropic_remeshing.
// Usage: bench_real [file names, e.g. kitten.xyz head.off] [--runs N]
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "anchors_cgal.h"
#include "anchors_pcl.h"
#include "bench_support.h"
#include "remesh_measure.h"  // irregular_valence_fraction
#include "scanmesh/acquisition/scan_import.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/meshing/fans/fans.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/remeshing/remesh.h"
#include "scanmesh/reconstruction/surface_fields.h"
#include "scanmesh_test_paths.h"

using namespace scanmesh;
using Eigen::Vector3d;
namespace fs = std::filesystem;

namespace {

int g_runs = 3;  // timed runs per measurement; the row keeps the median (the machine is shared)

std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

// One table row; cells that do not apply to a stage stay "–".
struct Row {
  std::string stage, method, threads, seconds, ratio = "–", triangles = "–", nonmanifold = "–",
                                               loops = "–", euler = "–", min_angle = "–",
                                               ge30 = "–", irregular = "–", hausdorff = "–", notes;
};

void print_header() {
  std::printf(
      "| stage | method | threads | time [s] | anchor / this | triangles | non-manifold v / e | "
      "boundary loops | Euler | min angle [deg] | >= 30 deg [%%] | irregular valence [%%] | "
      "Hausdorff | notes |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
}

void print(const Row& r) {
  std::printf("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n",
              r.stage.c_str(), r.method.c_str(), r.threads.c_str(), r.seconds.c_str(),
              r.ratio.c_str(), r.triangles.c_str(), r.nonmanifold.c_str(), r.loops.c_str(),
              r.euler.c_str(), r.min_angle.c_str(), r.ge30.c_str(), r.irregular.c_str(),
              r.hausdorff.c_str(), r.notes.c_str());
  std::fflush(stdout);
}

// Median time of g_runs calls; `f` keeps its last result in the caller's variable.
double timed(const std::function<void()>& f) { return bench::time_median(g_runs, f); }

// The figures every meshed row shares, from check_mesh and the valence count.
void fill_mesh_figures(Row& row, const Mesh& m) {
  const MeshCheckReport r = check_mesh(m);
  row.triangles = std::to_string(r.faces);
  row.nonmanifold =
      std::to_string(r.nonmanifold_vertices) + " / " + std::to_string(r.topology.nonmanifold_edges);
  row.loops = std::to_string(r.topology.boundary_loops);
  row.euler = std::to_string(r.topology.euler_characteristic);
  row.min_angle = fmt("%.2f", r.min_angle_deg);
  row.ge30 = fmt("%.1f", 100 * r.fraction_min_angle_ge_30);
  row.irregular = fmt("%.1f", 100 * bench::irregular_valence_fraction(m));
  if (r.self_intersections) row.notes += std::to_string(r.self_intersections) + " self-int. ";
  if (r.duplicate_faces) row.notes += std::to_string(r.duplicate_faces) + " duplicate faces ";
}

// Vertices, centroids, edge midpoints and one more point per face (the samples of
// remeshing::sampled_distance), for distances to a point cloud.
std::vector<Vector3d> surface_samples(const Mesh& m) {
  std::vector<Vector3d> s = m.positions;
  for (const auto& t : m.triangles) {
    const Vector3d &p = m.positions[t[0]], &q = m.positions[t[1]], &r = m.positions[t[2]];
    s.push_back((p + q + r) / 3);
    s.push_back(0.5 * (p + q));
    s.push_back((4 * p + q + r) / 6);
  }
  return s;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double median_edge_length(const Mesh& m) {
  std::vector<double> l;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i)
      l.push_back((m.positions[t[i]] - m.positions[t[(i + 1) % 3]]).norm());
  return median(l);
}

// ---- clouds: fans vs GP3 vs CGAL advancing front ----

Row mesher_row(const std::string& method, const std::string& threads, double seconds, const Mesh& m,
               const std::vector<Vector3d>& cloud, double spacing) {
  Row row{"mesh cloud", method, threads, fmt("%.3f", seconds)};
  fill_mesh_figures(row, m);
  const auto d = bench::distance_to_points(surface_samples(m), cloud);
  row.hausdorff = fmt("%.2f sp", d[0] / spacing);
  return row;
}

void compare_cloud_meshers(const std::vector<Vector3d>& pts) {
  const double spacing = bench::mean_spacing(pts);
  const int threads = omp_get_max_threads();
  FanResult fans;
  FanOptions fo;
  fo.threads = threads;
  const double t_fans = timed([&] { fans = build_fans(pts, fo); });
  fo.threads = 1;
  FanResult fans1;
  const double t_fans1 = timed([&] { fans1 = build_fans(pts, fo); });
  Mesh gp3;
  const double t_gp3 = timed([&] {
    gp3 = bench::pcl_gp3(pts, estimate_fan_normals(pts, {}), spacing);  // the fans' normals
  });
  Mesh afsr;
  std::string afsr_error;
  const double t_afsr = timed([&] { afsr = bench::cgal_afsr(pts, &afsr_error); });
  const auto ratios = [&](double t) {
    return "GP3 " + fmt("%.2f", t_gp3 / t) + ", AFSR " + fmt("%.2f", t_afsr / t);
  };
  Row f = mesher_row("scanmesh fans", std::to_string(threads), t_fans, fans.mesh, pts, spacing);
  f.ratio = ratios(t_fans);
  f.notes += std::to_string(fans.stats.unused_points) + " unused points";
  Row f1 = mesher_row("scanmesh fans", "1", t_fans1, fans1.mesh, pts, spacing);
  f1.ratio = ratios(t_fans1);
  print(f);
  print(f1);
  print(mesher_row("PCL GP3 (fans' normals)", "1", t_gp3, gp3, pts, spacing));
  Row a = mesher_row("CGAL advancing front", "1", t_afsr, afsr, pts, spacing);
  a.notes += afsr_error;
  print(a);
}

// ---- meshes: seed 001 remesh vs CGAL isotropic_remeshing ----

Row remesh_row(const std::string& method, const std::string& threads, double seconds,
               const Mesh& out, const Mesh& in, double edge) {
  Row row{"remesh", method, threads, fmt("%.3f", seconds)};
  fill_mesh_figures(row, out);
  const double hausdorff =
      std::max(remeshing::sampled_distance(out, in)[0], remeshing::sampled_distance(in, out)[0]);
  row.hausdorff = fmt("%.2f edges", hausdorff / edge);
  row.notes += std::to_string(out.positions.size()) + " vertices";
  return row;
}

// Median of g_runs per thread count, CGAL's too (one run each varied by +-25 % on the shared VM);
// the remesher is serial apart from the density estimate, so the 1-thread row is the
// same-thread-count comparison with CGAL.
void compare_remeshers(const Mesh& in, int target) {
  const double edge = median_edge_length(in);
  remeshing::RemeshOptions o;  // `scanmesh remesh --vertices <input count>`: the CLI's defaults
  o.target_vertices = target;
  Row input{"remesh", "input", "–", "–"};
  fill_mesh_figures(input, in);
  input.notes += std::to_string(target) + " vertices, median edge " + fmt("%.4g", edge);
  print(input);
  remeshing::RemeshResult ours;
  const double t_ours = timed([&] { ours = remeshing::remesh(in, o); });
  Row r = remesh_row("scanmesh remesh", std::to_string(omp_get_max_threads()), t_ours, ours.mesh,
                     in, edge);
  bench::CgalSurfaceMesh base;
  if (!bench::to_cgal(in, base)) {
    r.notes += "; CGAL: input is no polygon mesh";
    print(r);
    return;
  }
  const auto cgal = bench::cgal_remesh_to_count(base, scanmesh::surface_area(in), target, g_runs);
  r.ratio = fmt("%.2f", cgal.seconds / t_ours);
  print(r);
  if (omp_get_max_threads() > 1) {
    // Same thread count as CGAL (serial): only the density's patch fits run in parallel.
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    remeshing::RemeshResult serial;
    const double t1 = timed([&] { serial = remeshing::remesh(in, o); });
    omp_set_num_threads(threads);
    Row r1 = remesh_row("scanmesh remesh", "1", t1, serial.mesh, in, edge);
    r1.ratio = fmt("%.2f", cgal.seconds / t1);
    print(r1);
  }
  Row c = remesh_row("CGAL isotropic_remeshing", "1", cgal.seconds, cgal.mesh, in, edge);
  c.notes += ", L " + fmt("%.4g", cgal.edge_length);
  print(c);
}

// ---- import: import_scan, grid_mesh, distances in cells ----

struct Imported {
  ImportResult result;
  Mesh input;  // the file in the grid frame (a cloud: positions only)
  Mesh grid_mesh;
  bool cloud = false;
};

Mesh input_in_grid_frame(const fs::path& path, const ImportResult& r, bool cloud) {
  Mesh m;
  if (cloud)
    m.positions = read_point_cloud(path).finite_points().positions;
  else
    m = read_mesh(path);
  for (auto& p : m.positions) p = r.to_grid_frame(p);
  return m;
}

Imported import_and_mesh(const fs::path& path, bool cloud) {
  Imported im;
  im.cloud = cloud;
  const double t_import = timed([&] { im.result = import_scan(path); });
  const RangeGrid& g = im.result.grid;
  GridMeshOptions go;
  go.max_depth_jump_mm = 8 * g.dh();  // the default's 8 mm, as cells of the demo's ~1 mm grid
  go.close_seam = im.result.report.coverage.full_turn;
  GridMesh gm;
  const double t_mesh = timed([&] { gm = grid_mesh(g, go); });
  im.input = input_in_grid_frame(path, im.result, cloud);
  const auto out_in = cloud
                          ? bench::distance_to_points(surface_samples(gm.mesh), im.input.positions)
                          : remeshing::sampled_distance(gm.mesh, im.input);
  const auto in_out = remeshing::sampled_distance(im.input, gm.mesh);
  const int threads = omp_get_max_threads();
  Row ri{"import", "import_scan", std::to_string(threads), fmt("%.3f", t_import)};
  ri.notes = std::to_string(g.n_phi()) + " x " + std::to_string(g.n_h()) + " grid, " +
             std::to_string(g.valid_count()) + " valid cells, dh " + fmt("%.4g", g.dh()) + ", " +
             fmt("%.0f", 100 * im.result.report.coverage.covered_fraction()) + " % of the turn";
  print(ri);
  Row rm{"import", "grid_mesh", std::to_string(threads), fmt("%.3f", t_mesh)};
  fill_mesh_figures(rm, gm.mesh);
  rm.hausdorff = "mesh->in " + fmt("%.2f", out_in[0] / g.dh()) + ", in->mesh " +
                 fmt("%.2f", in_out[0] / g.dh()) + " cells";
  rm.notes += "mean in->mesh " + fmt("%.2f", in_out[1] / g.dh()) + " cells";
  print(rm);
  im.grid_mesh = std::move(gm.mesh);
  return im;
}

// The imported grid's mesh remeshed to its own vertex count as `scanmesh remesh` does it (the
// scan clean-up first when the mesh looks like a scan); CGAL gets the same cleaned mesh.
void compare_imported_remesh(const Imported& im) {
  const Mesh& raw = im.grid_mesh;
  const int target = static_cast<int>(raw.positions.size());
  if (target < 4) return;
  const bool scan = remeshing::looks_like_scan(raw);
  const Mesh in =
      scan ? remeshing::prepare_input(raw, remeshing::scan_prepare_options(raw, target)) : raw;
  std::printf("\nimported grid mesh remeshed to its own count (%s):\n\n",
              scan ? "looks like a scan: clean-up first" : "no clean-up");
  print_header();
  compare_remeshers(in, target);
}

// ---- curvature of the imported grid vs PCL ----

std::vector<Vector3d> valid_cell_points(const RangeGrid& g, std::vector<std::size_t>& cell) {
  std::vector<Vector3d> pts;
  for (std::size_t k = 0; k < g.cell_count(); ++k) {
    if (!g.validity()[k]) continue;
    pts.push_back(g.cartesian(static_cast<int>(k % g.n_phi()), static_cast<int>(k / g.n_phi())));
    cell.push_back(k);
  }
  return pts;
}

// Spearman rank correlation: PCL's pc1 is an eigenvalue of projected normals' covariance, not a
// curvature in 1/length (docs/benchmarks.md, "Curvature"), so only the order of the values can
// be compared with scanmesh's |k|max.
double rank_correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const auto ranks = [](const std::vector<double>& v) {
    std::vector<std::size_t> order(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::size_t x, std::size_t y) { return v[x] < v[y]; });
    std::vector<double> r(v.size());
    for (std::size_t i = 0; i < order.size(); ++i) r[order[i]] = static_cast<double>(i);
    return r;
  };
  const auto ra = ranks(a), rb = ranks(b);
  const double mean = (static_cast<double>(a.size()) - 1) / 2;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (ra[i] - mean) * (rb[i] - mean);
    saa += (ra[i] - mean) * (ra[i] - mean);
    sbb += (rb[i] - mean) * (rb[i] - mean);
  }
  return sab / std::sqrt(saa * sbb);
}

// Agreement with PCL where both are defined: rank correlation of |k|max with pc1 and the median
// angle between the unoriented normals.
std::string agreement(const SurfaceFields& f, const std::vector<bench::PclCurvature>& pcl,
                      const std::vector<std::size_t>& cell) {
  std::vector<double> kmax, pc1, angle;
  std::size_t finite = 0;
  for (std::size_t p = 0; p < cell.size(); ++p) {
    const std::size_t k = cell[p];
    finite += f.defined[k] && std::isfinite(f.k1[k]) && std::isfinite(f.k2[k]);
    if (!f.defined[k] || !pcl[p].ok) continue;
    kmax.push_back(std::max(std::abs(f.k1[k]), std::abs(f.k2[k])));
    pc1.push_back(pcl[p].pc1);
    angle.push_back(
        std::acos(std::min(1.0, std::abs(f.normal[k].cast<double>().dot(pcl[p].normal)))) * 180 /
        M_PI);
  }
  return fmt("finite in %.1f %% of valid cells", 100.0 * finite / cell.size()) +
         fmt("; rank correlation of kmax with PCL %.2f", rank_correlation(kmax, pc1)) +
         fmt("; normals %.1f deg", median(angle));
}

void compare_curvature(const RangeGrid& g) {
  const double radius = 4 * g.dh();  // 9 x 9 cells for the grid quadric
  std::vector<std::size_t> cell;
  const auto pts = valid_cell_points(g, cell);
  const int threads = omp_get_max_threads();
  std::vector<bench::PclCurvature> pcl, pcl1;
  const double t_pcl = timed([&] { pcl = bench::pcl_principal_curvatures(pts, radius, threads); });
  const double t_pcl1 = timed([&] { pcl1 = bench::pcl_principal_curvatures(pts, radius, 1); });
  using Method = std::function<SurfaceFields(const RangeGrid&, const QuadricOptions&)>;
  const std::pair<const char*, Method> methods[] = {
      {"scanmesh grid-quadric", compute_fields_grid_quadric},
      {"scanmesh quadric", compute_fields_quadric}};
  for (const auto& [name, method] : methods)
    for (const int n : {threads, 1}) {
      omp_set_num_threads(n);
      SurfaceFields f;
      const double t = timed([&] { f = method(g, {.radius_mm = radius}); });
      const double anchor = n == 1 ? t_pcl1 : t_pcl;
      Row r{"curvature", name, std::to_string(n), fmt("%.3f", t), fmt("%.2f", anchor / t)};
      r.notes = agreement(f, pcl, cell);
      print(r);
    }
  omp_set_num_threads(threads);
  Row p{"curvature", "PCL normals (OMP) + principal curvatures", std::to_string(threads) + " + 1",
        fmt("%.3f", t_pcl)};
  p.notes = "radius " + fmt("%.4g", radius) + " = 4 dh, " + std::to_string(pts.size()) + " points";
  print(p);
  print({"curvature", "PCL normals (OMP) + principal curvatures", "1 + 1", fmt("%.3f", t_pcl1)});
}

void bench_file(const fs::path& path, bool cloud) {
  std::printf("\n### %s\n\n", path.filename().c_str());
  if (cloud) {
    const auto pts = read_point_cloud(path).finite_points().positions;
    std::printf("%zu points\n\n", pts.size());
    print_header();
    compare_cloud_meshers(pts);
  } else {
    const Mesh m = read_mesh(path);
    std::printf("%zu vertices, %zu triangles\n\n", m.positions.size(), m.triangles.size());
    print_header();
    compare_remeshers(m, static_cast<int>(m.positions.size()));
  }
  const Imported im = import_and_mesh(path, cloud);
  compare_curvature(im.result.grid);
  compare_imported_remesh(im);
}

bool wanted(const std::vector<std::string>& picks, const std::string& name) {
  return picks.empty() || std::find(picks.begin(), picks.end(), name) != picks.end();
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> picks;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--runs") && i + 1 < argc)
      g_runs = std::max(1, std::atoi(argv[++i]));
    else
      picks.emplace_back(argv[i]);
  }
  const fs::path corpus(SCANMESH_CORPUS_DIR);
  std::printf(
      "bench_real: corpus %s, %d OpenMP threads by default, median of %d runs per time.\n"
      "sp = mean nearest-neighbour spacing of the cloud; edges = median edge length of the "
      "input mesh; cells = the imported grid's dh.\n",
      corpus.c_str(), omp_get_max_threads(), g_runs);
  for (const char* f : {"kitten.xyz", "hippo1.ply", "hippo2.ply", "oni.ply", "radar.xyz"})
    if (wanted(picks, f)) bench_file(corpus / "points_3" / f, true);
  for (const char* f :
       {"nefertiti.off", "head.off", "elephant.off", "lion-head.off", "mannequin-devil.off"})
    if (wanted(picks, f)) bench_file(corpus / "meshes" / f, false);
  return 0;
}
