// The quality measure applied alike to every remesher's output (ours and CGAL's), from the
// output and the input alone: min angle, share >= 30 deg, mean aspect ratio R/2r, irregular
// valence, symmetric sampled Hausdorff distance, self-intersections.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "scanmesh/meshing/kernel/triangle_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/remeshing/remesh_quality.h"

namespace scanmesh::bench {

struct RemeshMeasure {
  std::string method;
  double seconds = 0;
  std::size_t vertices = 0;
  double min_angle = 0, ge30 = 0, mean_aspect_ratio = 0, irregular = 0, hausdorff = 0,
         mean_dist = 0;
  std::size_t self_intersections = 0;
};

//! Share of vertices off their optimal valence: 6 inside, 4 on a boundary; vertices with more
//! than two boundary edges (non-manifold) are not counted.
inline double irregular_valence_fraction(const Mesh& out) {
  std::map<std::uint64_t, int> ec;
  std::vector<std::vector<int>> nb(out.positions.size());
  for (const auto& t : out.triangles)
    for (int i = 0; i < 3; ++i) {
      ++ec[edge_key(t[i], t[(i + 1) % 3])];
      nb[t[i]].push_back(t[(i + 1) % 3]);
      nb[t[(i + 1) % 3]].push_back(t[i]);
    }
  std::vector<int> boundary(out.positions.size(), 0);
  for (const auto& [k, c] : ec)
    if (c == 1) {
      ++boundary[edge_key_first(k)];
      ++boundary[edge_key_second(k)];
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
  return counted ? 1.0 - static_cast<double>(optimal) / counted : 0;
}

inline RemeshMeasure measure_remesh(const std::string& method, double seconds, const Mesh& out,
                                    const Mesh& in) {
  RemeshMeasure r;
  r.method = method;
  r.seconds = seconds;
  r.vertices = out.positions.size();
  r.irregular = irregular_valence_fraction(out);
  double amin = 180, qsum = 0;
  std::size_t ge = 0;
  for (const auto& t : out.triangles) {
    const auto &a = out.positions[t[0]], &b = out.positions[t[1]], &c = out.positions[t[2]];
    const double m = triangle_min_angle(a, b, c) * 180 / M_PI;
    amin = std::min(amin, m);
    ge += m >= 30;
    qsum += std::min(aspect_ratio(a, b, c), 1e6);
  }
  r.min_angle = amin;
  r.ge30 = static_cast<double>(ge) / out.triangles.size();
  r.mean_aspect_ratio = qsum / out.triangles.size();
  const auto d1 = remeshing::sampled_distance(out, in), d2 = remeshing::sampled_distance(in, out);
  r.hausdorff = std::max(d1[0], d2[0]);
  r.mean_dist = d1[1];
  r.self_intersections = check_mesh(out).self_intersections;
  return r;
}

}  // namespace scanmesh::bench
