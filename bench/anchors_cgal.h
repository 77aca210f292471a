// The CGAL anchors shared by the benchmarks (docs/benchmarks.md): advancing front surface
// reconstruction of a cloud, and Polygon_mesh_processing::isotropic_remeshing calibrated to a
// vertex count (boundary edges constrained, not protected). Header-only CGAL.
#pragma once

#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "bench_support.h"
#include "scanmesh/core/mesh.h"

namespace scanmesh::bench {

using CgalKernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalSurfaceMesh = CGAL::Surface_mesh<CgalKernel::Point_3>;

//! CGAL's advancing front on the points (vertices = the input points). An exception is caught
//! and its message returned in `error` (the mesh then holds what was produced, maybe nothing).
inline Mesh cgal_afsr(const std::vector<Eigen::Vector3d>& pts, std::string* error = nullptr) {
  std::vector<CgalKernel::Point_3> cp;
  cp.reserve(pts.size());
  for (const auto& p : pts) cp.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::array<std::size_t, 3>> facets;
  try {
    CGAL::advancing_front_surface_reconstruction(cp.begin(), cp.end(), std::back_inserter(facets));
  } catch (const std::exception& e) {
    if (error) *error = e.what();
  }
  Mesh m;
  m.positions = pts;
  for (const auto& f : facets) m.triangles.push_back({int(f[0]), int(f[1]), int(f[2])});
  return m;
}

inline Mesh from_cgal(const CgalSurfaceMesh& sm) {
  Mesh m;
  std::map<CgalSurfaceMesh::Vertex_index, int> id;
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

//! False when the mesh is no polygon mesh even after orienting the soup.
inline bool to_cgal(const Mesh& m, CgalSurfaceMesh& sm) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<CgalKernel::Point_3> pts;
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

struct CgalRemeshRun {
  Mesh mesh;
  double seconds = 0;      //!< of the last (kept) run
  double edge_length = 0;  //!< its target edge length
};

//! isotropic_remeshing of `base` (5 iterations, boundary edges constrained but not protected: split
//! and collapsed along the border with 1D relaxation), its target edge length calibrated over up
//! to 6 runs until the output has `target` vertices within 1 %. `area`: the input's area. With
//! `timed_runs` > 1 the calibrated length is run that many times in all and the time is the
//! median (the runs give the same mesh).
inline CgalRemeshRun cgal_remesh_to_count(const CgalSurfaceMesh& base, double area, int target,
                                          int timed_runs = 1) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  CgalRemeshRun run;
  auto remesh_once = [&] {
    CgalSurfaceMesh sm = base;
    auto ecm = sm.add_property_map<CgalSurfaceMesh::Edge_index, bool>("e:constrained", false).first;
    for (auto e : sm.edges()) ecm[e] = sm.is_border(e);
    const double t0 = now();
    PMP::isotropic_remeshing(sm.faces(), run.edge_length, sm,
                             CGAL::parameters::number_of_iterations(5)
                                 .edge_is_constrained_map(ecm)
                                 .protect_constraints(false)
                                 .relax_constraints(true));
    run.seconds = now() - t0;
    run.mesh = from_cgal(sm);
  };
  run.edge_length = std::sqrt(4 * area / (std::sqrt(3.0) * 2 * target));
  for (int attempt = 0; attempt < 6; ++attempt) {
    remesh_once();
    const double ratio = static_cast<double>(run.mesh.positions.size()) / target;
    std::fprintf(stderr, "CGAL L = %.4f -> %zu vertices (%.1f s)\n", run.edge_length,
                 run.mesh.positions.size(), run.seconds);
    if (std::abs(ratio - 1) < 0.01) break;
    run.edge_length *= std::sqrt(ratio);
  }
  std::vector<double> times = {run.seconds};
  for (int k = 1; k < timed_runs; ++k) {
    remesh_once();
    times.push_back(run.seconds);
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  run.seconds = times[times.size() / 2];
  return run;
}

}  // namespace scanmesh::bench
