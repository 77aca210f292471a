// Benchmark of seed 003's spring network against CGAL's Delaunay-refinement implicit surface
// mesher (make_surface_mesh + Implicit_surface_3), VTK's marching cubes (vtkMarchingCubes) and
// this project's marching tetrahedra, on the same skeletal implicit surface at about the same
// vertex count; plus the per-frame update rate of a moving ~10,000-vertex mesh. Prints a
// Markdown table (docs/benchmarks.md).
//
// q: the mean ratio 4 sqrt(3) A / (l1^2 + l2^2 + l3^2) (core/triangle_quality.h): 1 for an
// equilateral triangle, 0 for a degenerate one.
// Distance: Newton projection distance to F = 0 of every vertex and every triangle centroid.
// Last, scan mode on the full 512 x 512 sample head (issue 31): time, iterations, convergence.
#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/facets_in_complex_2_to_triangle_mesh.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>

#include <omp.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkMarchingCubes.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "bench_support.h"
#include "implicit_adapters.h"
#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/acquisition/scan_cleaning.h"
#include "scanmesh/core/triangle_quality.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/particles/particles.h"
#include "scanmesh/reconstruction/scan_surface.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/shapes.h"

using namespace scanmesh;
using Eigen::Vector3d;

namespace {

using bench::now;

struct Row {
  std::string name;
  double seconds = 0;
  Mesh mesh;
};

void print_row(const Row& r, const particles::ImplicitSurface& s) {
  double min_angle = 180, q_sum = 0, max_dist = 0, dist_sum = 0;
  std::size_t below30 = 0, samples = 0;
  auto dist = [&](const Vector3d& x) {
    const auto p = particles::project_to_surface(s, x, 30, 1e-14);
    return p ? (*p - x).norm() : 1e9;
  };
  for (const auto& p : r.mesh.positions) {
    const double d = dist(p);
    max_dist = std::max(max_dist, d), dist_sum += d, ++samples;
  }
  for (const auto& t : r.mesh.triangles) {
    const Vector3d a = r.mesh.positions[t[0]], b = r.mesh.positions[t[1]],
                   c = r.mesh.positions[t[2]];
    q_sum += mean_ratio(a, b, c);
    const double mn = triangle_min_angle(a, b, c) * 180 / std::numbers::pi;
    min_angle = std::min(min_angle, mn);
    below30 += mn < 30 ? 1 : 0;
    const double d = dist((a + b + c) / 3);
    max_dist = std::max(max_dist, d), dist_sum += d, ++samples;
  }
  const TopologyStats st = topology_stats(r.mesh);
  std::printf("| %s | %.3f | %zu | %zu | %.1f | %.2f%% | %.3f | %.2e | %.2e | %lld |\n",
              r.name.c_str(), r.seconds, r.mesh.vertex_count(), r.mesh.face_count(), min_angle,
              100.0 * below30 / std::max<std::size_t>(r.mesh.face_count(), 1),
              q_sum / std::max<std::size_t>(r.mesh.face_count(), 1), max_dist,
              dist_sum / std::max<std::size_t>(samples, 1), st.euler_characteristic);
}

// CGAL's surface mesher on the same field.
using Tr = CGAL::Surface_mesh_default_triangulation_3;
using C2t3 = CGAL::Complex_2_in_triangulation_3<Tr>;
using GT = Tr::Geom_traits;
using FT = GT::FT;
using Point = GT::Point_3;
struct Field {
  const particles::ImplicitSurface* s;
  FT operator()(const Point& p) const { return s->evaluate(Vector3d(p.x(), p.y(), p.z()))->value; }
};

Mesh run_cgal(const particles::ImplicitSurface& s, double radius_bound, double distance_bound) {
  Tr tr;
  C2t3 c2t3(tr);
  const Vector3d c = s.bounds().center();
  const double r = 0.5 * s.bounds().diagonal().norm();
  CGAL::Implicit_surface_3<GT, Field> surface(Field{&s},
                                              GT::Sphere_3(Point(c.x(), c.y(), c.z()), r * r));
  CGAL::Surface_mesh_default_criteria_3<Tr> criteria(30.0, radius_bound, distance_bound);
  CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_tag());
  CGAL::Surface_mesh<Point> sm;
  CGAL::facets_in_complex_2_to_triangle_mesh(c2t3, sm);
  Mesh m;
  for (const auto v : sm.vertices()) {
    const Point& p = sm.point(v);
    m.positions.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto f : sm.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(sm.halfedge(f), sm))
      if (k < 3) t[k++] = static_cast<int>(v.idx());
    m.triangles.push_back(t);
  }
  return m;
}

// VTK's classic marching cubes on the field sampled at grid spacing h over the bounds; the
// sampling counts in the time, as it does for marching tetrahedra.
Mesh run_vtk_marching_cubes(const particles::ImplicitSurface& s, double h) {
  const Eigen::AlignedBox3d box = s.bounds();
  const Eigen::Vector3i n = (box.sizes() / h).array().ceil().cast<int>() + 1;
  vtkNew<vtkImageData> image;
  image->SetDimensions(n.x(), n.y(), n.z());
  image->SetSpacing(h, h, h);
  image->SetOrigin(box.min().x(), box.min().y(), box.min().z());
  vtkNew<vtkDoubleArray> values;
  values->SetNumberOfTuples(static_cast<vtkIdType>(n.x()) * n.y() * n.z());
  vtkIdType index = 0;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) {
        const auto f = s.evaluate(box.min() + h * Vector3d(i, j, k));
        values->SetValue(index++, f ? f->value : 1.0);  // undefined: outside
      }
  image->GetPointData()->SetScalars(values);
  vtkNew<vtkMarchingCubes> mc;
  mc->SetInputData(image);
  mc->SetValue(0, 0.0);
  mc->ComputeNormalsOff();
  mc->ComputeGradientsOff();
  mc->ComputeScalarsOff();
  mc->Update();
  vtkPolyData* out = mc->GetOutput();
  Mesh m;
  for (vtkIdType i = 0; i < out->GetNumberOfPoints(); ++i) {
    double p[3];
    out->GetPoint(i, p);
    m.positions.emplace_back(p[0], p[1], p[2]);
  }
  vtkCellArray* polys = out->GetPolys();
  vtkIdType count = 0;
  const vtkIdType* ids = nullptr;
  for (polys->InitTraversal(); polys->GetNextCell(count, ids);)
    if (count == 3)
      m.triangles.push_back(
          {static_cast<int>(ids[0]), static_cast<int>(ids[1]), static_cast<int>(ids[2])});
  return m;
}

// Issue 31's bound for scan mode on the head: converged, within this time on the project's
// 2-core machine (measured 1-3 s at 512 x 512, R = 4 mm, since decision 43).
constexpr double kScanModeBoundSeconds = 30.0;

// `scanmesh sim` (built-in head, the given scanner), `clean [--fill-holes N]`,
// `particles --grid --edge R`.
void scan_mode_row(const char* name, const sim::ScannerConfig& scanner, double R,
                   int fill_holes = 0) {
  sim::SimulatedScan scan = sim::simulate_scan(sim::builtin_head_scene(), scanner);
  clean_grid(scan.grid);
  if (fill_holes > 0) fill_small_holes(scan.grid, fill_holes);
  const ScanSurface surface(scan.grid);
  const particles::ScanImplicitSurface implicit(surface);
  const double t0 = now();
  const auto r = particles::particle_mesh(implicit, {.edge_length = R});
  const double seconds = now() - t0;
  const TopologyStats st = topology_stats(r.mesh);
  const bool within = r.converged && seconds <= kScanModeBoundSeconds;
  std::printf("| %s | %d x %d | %.0f | %.1f | %d | %s | %zu | %zu | %zu | %s |\n", name,
              scan.grid.n_phi(), scan.grid.n_h(), R, seconds, r.iterations,
              r.converged ? "yes" : "no", r.mesh.vertex_count(), st.boundary_loops,
              st.nonmanifold_edges, within ? "yes" : "**NO**");
}

}  // namespace

int main() {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  // A three-blob skeletal surface (Wyvill kernels, iso 0.5).
  std::vector<sim::SkeletonElement> el(3);
  el[0].a = Vector3d(-0.7, 0, 0), el[0].radius = 2.0;
  el[1].a = Vector3d(0.7, 0, 0), el[1].radius = 2.0;
  el[2].a = Vector3d(0, 0.8, 0.3), el[2].radius = 1.6;
  const cli::SceneObjectSurface surface(
      sim::make_skeletal(el),
      Eigen::AlignedBox3d(Vector3d(-2.0, -1.3, -1.3), Vector3d(2.0, 1.9, 1.6)));
  const double R = 0.08;
  std::printf("Surface: 3 Wyvill point primitives (iso 0.5), about 3.2 x 2.5 x 2.2 units.\n\n");
  std::printf(
      "| method | time (s) | vertices | triangles | min angle (deg) | triangles < 30 deg | mean q "
      "| max distance | mean distance | Euler char. "
      "|\n|---|---|---|---|---|---|---|---|---|---|\n");
  Row p{"scanmesh particles (R = 0.08)"};
  double t0 = now();
  const auto pr = particles::particle_mesh(surface, {.edge_length = R});
  p.mesh = pr.mesh;
  p.seconds = now() - t0;
  std::fprintf(stderr, "particles: %d iterations, %s\n", pr.iterations,
               pr.converged ? "converged" : "NOT converged");
  print_row(p, surface);
  {
    // CGAL's mesher is single-threaded: the same particle run on one OpenMP thread too (on a
    // loaded machine OpenMP's barriers can cost more than the second thread saves).
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    Row p1{"scanmesh particles (R = 0.08, 1 thread)"};
    t0 = now();
    p1.mesh = particles::particle_mesh(surface, {.edge_length = R}).mesh;
    p1.seconds = now() - t0;
    omp_set_num_threads(threads);
    print_row(p1, surface);
  }
  const double target = static_cast<double>(p.mesh.vertex_count());
  std::fprintf(stderr, "particles done\n");

  // CGAL: radius bound tuned (two rounds, count ~ 1 / r^2) to the same vertex count; distance
  // bound R / 10 (the chord error of an R-chord on the surface is far smaller).
  double rb = R;
  Row cg{"CGAL make_surface_mesh (30 deg, radius bound tuned)"};
  for (int round = 0; round < 3; ++round) {
    t0 = now();
    cg.mesh = run_cgal(surface, rb, R / 10);
    cg.seconds = now() - t0;
    std::fprintf(stderr, "cgal radius bound %g: %zu vertices, %.2f s\n", rb, cg.mesh.vertex_count(),
                 cg.seconds);
    rb *= std::sqrt(static_cast<double>(cg.mesh.vertex_count()) / target);
  }
  print_row(cg, surface);

  Row mt{"marching tetrahedra (spacing tuned)"};
  double h = R;
  for (int round = 0; round < 3; ++round) {
    t0 = now();
    mt.mesh = particles::marching_tetrahedra(surface, h);
    mt.seconds = now() - t0;
    h *= std::sqrt(static_cast<double>(mt.mesh.vertex_count()) / target);
  }
  print_row(mt, surface);

  Row vmc{"VTK marching cubes (vtkMarchingCubes, spacing tuned)"};
  h = R;
  for (int round = 0; round < 3; ++round) {
    t0 = now();
    vmc.mesh = run_vtk_marching_cubes(surface, h);
    vmc.seconds = now() - t0;
    h *= std::sqrt(static_cast<double>(vmc.mesh.vertex_count()) / target);
  }
  print_row(vmc, surface);

  // Per-frame update of a moving mesh of ~10,000 vertices: blob_glide-like skeleton moving.
  auto sk = std::make_shared<sim::AnimatedSkeleton>(sim::AnimatedSkeleton::from_yaml_text(R"(
name: bench_glide
elements:
  - {name: body, type: segment, a: [-0.6, 0, 0], b: [0.6, 0, 0], radius: 2.0}
  - {name: head, type: point, center: [1.0, 0.3, 0], radius: 1.4}
keyframes:
  - time: 0
  - time: 1
    positions: {body: [[-0.5, 0.1, 0], [0.7, 0, 0.1]], head: [1.4, 0.6, 0.2]}
)",
                                                                                          "bench"));
  const std::shared_ptr<const sim::AnimatedSkeleton> csk = sk;
  auto at = [csk](double t) { return std::make_shared<cli::AnimatedSkeletonSurface>(csk, t); };
  const double r10k = 0.053;
  auto first = at(0);
  particles::SpringNetwork net = particles::relaxed_network(*first, {.edge_length = r10k});
  const int frames = 100;
  t0 = now();
  for (int f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / frames;
    net.step(*at(t), 1.0 / frames);
  }
  const double per = (now() - t0) / frames;
  std::printf(
      "\nMoving mesh: %zu vertices, one iteration (field evaluation, springs, eq. 8, "
      "collapse/split/flip, topology tests) per frame: %.1f ms -> %.1f frames per second (%d "
      "frames, surface time 0..1).\n",
      net.vertex_count(), 1000 * per, 1.0 / per, frames);

  std::printf(
      "\nScan mode (relax() on the range surface of the cleaned sample head; the iteration limit "
      "is 3,000; bound: converged within %.0f s):\n\n| scanner | grid | R (mm) | time (s) | "
      "iterations | converged | vertices | border loops | non-manifold edges | within bound "
      "|\n|---|---|---|---|---|---|---|---|---|---|\n",
      kScanModeBoundSeconds);
  sim::ScannerConfig coarse = sim::builtin_head_scanner();
  coarse.n_phi = coarse.n_h = 128;
  coarse.dh_mm *= 4.0;
  scan_mode_row("built-in, 128 x 128", coarse, 4.0);
  // As configs/sim/head-scanner-ideal.yaml: no hair, spikes, dropouts or occlusion.
  sim::ScannerConfig ideal = sim::builtin_head_scanner();
  ideal.noise_sigma_mm = 0.05;
  ideal.grazing_dropout = ideal.occlusion = ideal.hair = false;
  ideal.spike_probability = 0;
  scan_mode_row("built-in without defects but noise 0.05 mm", ideal, 4.0);
  scan_mode_row("built-in (hair noise)", sim::builtin_head_scanner(), 4.0);
  // The rough hair zone given back by filling holes up to 200 cells (decision 44).
  scan_mode_row("built-in, holes up to 200 cells filled", sim::builtin_head_scanner(), 4.0, 200);
  return 0;
}
