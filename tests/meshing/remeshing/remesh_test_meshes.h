// Synthetic inputs for the remeshing tests and benchmark: two boxes sharing a face (a
// non-manifold seam where three patches meet), a sphere, a curved sheet with a feature line.
#pragma once

#include <cmath>
#include <map>
#include <numbers>
#include <random>
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

//! Prolate ellipsoid x^2/b^2 + y^2/b^2 + z^2/a^2 = 1 (a > b: kappa_max is a / b^2 at the
//! tips, 1 / b on the equator): an icosahedron subdivided `levels` times, pushed to the unit
//! sphere and scaled (no poles where hundreds of slivers meet, as a scanner's mesh has none),
//! each vertex moved along the ray from the centre by Gaussian noise of `noise` (deterministic
//! in `seed`), as a scanner's range noise.
inline Mesh ellipsoid(double a, double b, int levels, double noise = 0, unsigned seed = 1) {
  using V = Eigen::Vector3d;
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<V> pos = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                        {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<int, 3>> tri = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (V& p : pos) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int i, int j) {
      const auto key = std::minmax(i, j);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      pos.push_back((pos[i] + pos[j]).normalized());
      return mid[key] = static_cast<int>(pos.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& t : tri) {
      const int x = midpoint(t[0], t[1]), y = midpoint(t[1], t[2]), z = midpoint(t[2], t[0]);
      next.push_back({t[0], x, z});
      next.push_back({x, t[1], y});
      next.push_back({z, y, t[2]});
      next.push_back({x, y, z});
    }
    tri = std::move(next);
  }
  Mesh m;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise > 0 ? noise : 1.0);
  for (const V& p : pos) {
    V q(b * p.x(), b * p.y(), a * p.z());
    if (noise > 0) q += gauss(rng) * q.normalized();
    m.positions.push_back(q);
  }
  m.triangles = tri;
  m.face_labels.assign(tri.size(), 0);
  return m;
}

//! kappa_max of that ellipsoid at the point of polar parameter t found from p: a surface of
//! revolution with meridian (b sin t, a cos t), meridian curvature a b / |c'|^3 and parallel
//! curvature a / (b |c'|), |c'|^2 = b^2 cos^2 t + a^2 sin^2 t.
inline double ellipsoid_kappa_max(double a, double b, const Eigen::Vector3d& p) {
  // Parametrise by the polar angle of the point: (b sin t, a cos t) in the meridian plane.
  const double rho = std::hypot(p.x(), p.y());
  const double t = std::atan2(rho / b, p.z() / a);
  const double s = std::sin(t), c = std::cos(t);
  const double speed2 = b * b * c * c + a * a * s * s;
  const double meridian = a * b / std::pow(speed2, 1.5);
  const double parallel = s > 1e-9 ? a / (b * std::sqrt(speed2)) : meridian;
  return std::max(meridian, parallel);
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

//! A 10 x 10 sheet (n x n cells) with a tuck: the vertices near x = 5 are pushed along x by up
//! to `push` (past their neighbours: the faces there fold over and cut each other) and lifted a
//! little (so that the folded faces cross instead of lying in one plane). push 0: a flat sheet.
inline Mesh tucked_sheet(double push, int n = 40) {
  MeshBuilder b;
  b.quad({0, 0, 0}, {10, 0, 0}, {0, 10, 0}, n, 1);
  Mesh m = b.mesh;
  for (auto& p : m.positions) {
    const double w =
        std::exp(-std::pow((p.x() - 5) / 0.3, 2)) * std::exp(-std::pow((p.y() - 5) / 2.0, 2));
    p.x() += push * w;
    p.z() += 0.05 * w * std::sin(7 * p.y());
  }
  return m;
}

}  // namespace scanmesh::test
