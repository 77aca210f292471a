// Synthetic inputs for the remeshing tests and benchmark: two boxes sharing a face (a
// non-manifold seam where three patches meet), a sphere, a curved sheet with a feature line.
#pragma once

#include <cmath>
#include <map>
#include <numbers>
#include <tuple>

#include "scanmesh/core/mesh.h"

namespace scanmesh::test {

//! Builds meshes from grid-subdivided quads, welding coincident vertices.
class MeshBuilder {
 public:
  int vertex(const Eigen::Vector3d& p) {
    const auto key = std::make_tuple(std::llround(p.x() * 1e6), std::llround(p.y() * 1e6),
                                     std::llround(p.z() * 1e6));
    auto it = ids_.find(key);
    if (it != ids_.end()) return it->second;
    const int id = static_cast<int>(mesh.positions.size());
    mesh.positions.push_back(p);
    ids_[key] = id;
    return id;
  }
  //! Quad origin + [0,1]^2 (u, v), n x n cells, two triangles each, normal along u x v.
  void quad(const Eigen::Vector3d& o, const Eigen::Vector3d& u, const Eigen::Vector3d& v, int n,
            int label) {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        auto p = [&](int a, int b) { return vertex(o + u * a / n + v * b / n); };
        const int a = p(i, j), b = p(i + 1, j), c = p(i + 1, j + 1), d = p(i, j + 1);
        // Alternate diagonals so the input is not biased to one direction.
        if ((i + j) % 2) {
          add(a, b, c, label);
          add(a, c, d, label);
        } else {
          add(a, b, d, label);
          add(b, c, d, label);
        }
      }
  }
  void add(int a, int b, int c, int label) {
    mesh.triangles.push_back({a, b, c});
    mesh.face_labels.push_back(label);
  }
  Mesh mesh;

 private:
  std::map<std::tuple<long long, long long, long long>, int> ids_;
};

//! Box A = [0,s]^3 (label 1) and box B = [s,2s]x[0,s]^2 (label 2) sharing the face x = s
//! (label 3): the four edges of the shared square carry three faces each.
inline Mesh two_boxes(double s = 10.0, int n = 10) {
  using V = Eigen::Vector3d;
  MeshBuilder b;
  const V X(s, 0, 0), Y(0, s, 0), Z(0, 0, s);
  for (int box = 0; box < 2; ++box) {
    const V o = box * X;
    const int l = box + 1;
    b.quad(o, Y, X, n, l);                    // z = 0, normal -z
    b.quad(o + Z, X, Y, n, l);                // z = s, normal +z
    b.quad(o, X, Z, n, l);                    // y = 0, normal -y
    b.quad(o + Y, Z, X, n, l);                // y = s, normal +y
    if (box == 0) b.quad(o, Z, Y, n, l);      // x = 0, normal -x
    if (box == 1) b.quad(o + X, Y, Z, n, l);  // x = 2s, normal +x
  }
  b.quad(X, Y, Z, n, 3);  // the shared wall x = s
  return b.mesh;
}

//! Latitude-longitude sphere of radius r (poles welded).
inline Mesh sphere(double r = 10.0, int rings = 40, int segments = 80) {
  MeshBuilder b;
  auto p = [&](int i, int j) {
    const double th = std::numbers::pi * i / rings, ph = 2 * std::numbers::pi * j / segments;
    if (i == 0) return b.vertex({0, 0, r});
    if (i == rings) return b.vertex({0, 0, -r});
    return b.vertex(
        {r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
  };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = p(i, j), c = p(i + 1, j), d = p(i + 1, (j + 1) % segments),
                e = p(i, (j + 1) % segments);
      if (i > 0) b.add(a, c, e, 0);
      if (i < rings - 1) b.add(c, d, e, 0);
    }
  return b.mesh;
}

//! Height field z = 2 sin(x / 4) over [0, 20]^2, n x n cells; `line` receives the vertex chain
//! of the grid row y = 20 * row / n (a feature line across the sheet).
inline Mesh wavy_sheet(int n, int row, std::vector<int>* line) {
  MeshBuilder b;
  auto p = [&](int i, int j) {
    const double x = 20.0 * i / n, y = 20.0 * j / n;
    return b.vertex({x, y, 2 * std::sin(x / 4)});
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = p(i, j), c = p(i + 1, j), d = p(i + 1, j + 1), e = p(i, j + 1);
      b.add(a, c, d, 0);
      b.add(a, d, e, 0);
    }
  if (line) {
    line->clear();
    for (int i = 0; i <= n; ++i) line->push_back(p(i, row));
  }
  return b.mesh;
}

}  // namespace scanmesh::test
