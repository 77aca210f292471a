// Shared by bench_aft's translation units: the CGAL mesh types, the result table's rows and
// the conversion of a CGAL mesh into the AnimationMesh that evaluate_quality reads.
#pragma once

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "scanmesh/meshing/aft/animesh.h"

namespace scanmesh::bench_aft {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SM = CGAL::Surface_mesh<K::Point_3>;

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Row {
  const char* name;
  double time_s;
  std::size_t vertices, triangles;
  aft::AnimationMeshQuality q;
};

inline void print(const Row& r) {
  std::printf("%-36s %8.3f %9zu %9zu %8.2f %8.2f %7.3f %9.3f %9.3f\n", r.name, r.time_s, r.vertices,
              r.triangles, r.q.min_angle_deg, 100 * (1 - r.q.fraction_min_angle_ge_30),
              r.q.mean_radius_ratio, r.q.hausdorff_mesh_to_surface_mm,
              r.q.hausdorff_surface_to_mesh_mm);
}

inline double mean_edge(const Mesh& m) {
  double s = 0;
  std::size_t n = 0;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      s += (m.positions[t[k]] - m.positions[t[(k + 1) % 3]]).norm();
      ++n;
    }
  return n ? s / n : 0;
}

// One CGAL mesh -> the AnimationMesh that evaluate_quality reads (garbage collected first).
inline aft::AnimationMesh to_animation_mesh(SM& m) {
  m.collect_garbage();
  aft::AnimationMesh out;
  std::map<SM::Vertex_index, int> idx;
  for (auto v : m.vertices()) {
    const auto& p = m.point(v);
    idx[v] = static_cast<int>(out.mesh.positions.size());
    out.mesh.positions.emplace_back(p.x(), p.y(), p.z());
    out.params.emplace_back(std::atan2(p.y(), p.x()), p.z());
  }
  for (auto f : m.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (auto v : vertices_around_face(m.halfedge(f), m)) t[k++] = idx[v];
    out.mesh.triangles.push_back(t);
    out.mesh.face_labels.push_back(0);
  }
  return out;
}

}  // namespace scanmesh::bench_aft
