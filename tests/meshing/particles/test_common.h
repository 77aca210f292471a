// Shared helpers of the particle tests: surfaces, mesh measures.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <vector>

#include "implicit_adapters.h"
#include "scanmesh/core/mesh.h"
#include "scanmesh/sim/shapes.h"

namespace scanmesh::particles::testing {

inline std::shared_ptr<cli::SceneObjectSurface> surface_of(
    std::shared_ptr<const sim::SceneObject> obj, const Eigen::Vector3d& lo,
    const Eigen::Vector3d& hi) {
  return std::make_shared<cli::SceneObjectSurface>(std::move(obj), Eigen::AlignedBox3d(lo, hi));
}

inline std::vector<double> edge_lengths(const Mesh& m) {
  std::vector<double> out;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < t[(k + 1) % 3])
        out.push_back((m.positions[t[k]] - m.positions[t[(k + 1) % 3]]).norm());
  return out;  // each interior edge once (the face where it runs from lower to higher index)
}

//! Number of vertices per valence (edges counted once per face pair).
inline std::map<int, int> valence_histogram(const Mesh& m) {
  std::vector<std::set<int>> neighbours(m.positions.size());
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      neighbours[t[k]].insert(t[(k + 1) % 3]);
      neighbours[t[(k + 1) % 3]].insert(t[k]);
    }
  std::map<int, int> histogram;
  for (const auto& n : neighbours) ++histogram[static_cast<int>(n.size())];
  return histogram;
}

inline double triangle_min_angle_deg(const Mesh& m, const std::array<int, 3>& t) {
  double best = 180.0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d u = m.positions[t[(k + 1) % 3]] - m.positions[t[k]];
    const Eigen::Vector3d w = m.positions[t[(k + 2) % 3]] - m.positions[t[k]];
    best = std::min(best, std::atan2(u.cross(w).norm(), u.dot(w)) * 180.0 / std::numbers::pi);
  }
  return best;
}

inline double fraction_min_angle_at_least(const Mesh& m, double deg) {
  std::size_t ok = 0;
  for (const auto& t : m.triangles) ok += triangle_min_angle_deg(m, t) >= deg ? 1 : 0;
  return static_cast<double>(ok) / static_cast<double>(m.triangles.size());
}

//! Connected components of the faces (through shared vertices); returns component per face.
inline int face_components(const Mesh& m, std::vector<int>& comp) {
  std::vector<int> parent(m.positions.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& t : m.triangles) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::vector<int> label(m.positions.size(), -1);
  int n = 0;
  comp.assign(m.triangles.size(), -1);
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    const int r = find(m.triangles[f][0]);
    if (label[r] < 0) label[r] = n++;
    comp[f] = label[r];
  }
  return n;
}

//! The sub-mesh of one face component (vertices re-indexed).
inline Mesh component_mesh(const Mesh& m, const std::vector<int>& comp, int c) {
  Mesh out;
  std::vector<int> map(m.positions.size(), -1);
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    if (comp[f] != c) continue;
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      int& v = map[m.triangles[f][k]];
      if (v < 0) {
        v = static_cast<int>(out.positions.size());
        out.positions.push_back(m.positions[m.triangles[f][k]]);
      }
      t[k] = v;
    }
    out.triangles.push_back(t);
  }
  return out;
}

inline double pearson(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= n, my /= n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxy / std::sqrt(sxx * syy);
}

}  // namespace scanmesh::particles::testing
