// Exact distances to a triangle mesh or a point set for the import tests: closest points on
// triangles (Ericson, Real-Time Collision Detection 5.1.5) found through a hash of cells.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include "scanmesh/core/mesh.h"

namespace scanmesh::test {

inline Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                           const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

//! Distance queries to a set of triangles (a point set: degenerate triangles) up to `reach`:
//! answers beyond reach are returned as +infinity.
class DistanceField {
 public:
  DistanceField(const Mesh& mesh, double reach) : mesh_(mesh), cell_(std::max(reach, 1e-12)) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      Eigen::AlignedBox3d box;
      for (int v : mesh.triangles[t]) box.extend(mesh.positions[v]);
      const auto lo = key(box.min()), hi = key(box.max());
      for (long long x = lo[0]; x <= hi[0]; ++x)
        for (long long y = lo[1]; y <= hi[1]; ++y)
          for (long long z = lo[2]; z <= hi[2]; ++z) cells_[{x, y, z}].push_back(static_cast<int>(t));
    }
  }
  double distance(const Eigen::Vector3d& p) const {
    const auto k = key(p);
    double best = std::numeric_limits<double>::infinity();
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == cells_.end()) continue;
          for (int t : it->second) {
            const auto& tri = mesh_.triangles[t];
            const Eigen::Vector3d q = closest_on_triangle(
                p, mesh_.positions[tri[0]], mesh_.positions[tri[1]], mesh_.positions[tri[2]]);
            best = std::min(best, (q - p).norm());
          }
        }
    return best <= cell_ ? best : std::numeric_limits<double>::infinity();
  }

  //! For a point set (degenerate triangles): the distance to the plane fitted through the `k`
  //! samples nearest to p (the cloud's local surface, as cloud comparisons measure it; fewer,
  //! but at least 3, where the cloud is sparse), or +infinity when fewer than 3 lie within reach.
  double local_plane_distance(const Eigen::Vector3d& p, int k_max = 8) const {
    const auto key0 = key(p);
    std::vector<std::pair<double, int>> near;
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find({key0[0] + dx, key0[1] + dy, key0[2] + dz});
          if (it == cells_.end()) continue;
          for (int t : it->second) {
            const int v = mesh_.triangles[t][0];
            const double d = (mesh_.positions[v] - p).norm();
            if (d <= cell_) near.push_back({d, v});
          }
        }
    const int k = std::min<int>(k_max, static_cast<int>(near.size()));
    if (k < 3) return std::numeric_limits<double>::infinity();
    std::partial_sort(near.begin(), near.begin() + k, near.end());
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int n = 0; n < k; ++n) c += mesh_.positions[near[n].second];
    c /= k;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int n = 0; n < k; ++n) {
      const Eigen::Vector3d d = mesh_.positions[near[n].second] - c;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    return std::abs(eig.eigenvectors().col(0).dot(p - c));
  }

 private:
  struct KeyHash {
    std::size_t operator()(const std::array<long long, 3>& k) const {
      return static_cast<std::size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
    }
  };
  std::array<long long, 3> key(const Eigen::Vector3d& p) const {
    return {static_cast<long long>(std::floor(p.x() / cell_)),
            static_cast<long long>(std::floor(p.y() / cell_)),
            static_cast<long long>(std::floor(p.z() / cell_))};
  }
  const Mesh& mesh_;
  double cell_;
  std::unordered_map<std::array<long long, 3>, std::vector<int>, KeyHash> cells_;
};

//! Points as degenerate triangles, for DistanceField.
inline Mesh point_mesh(const std::vector<Eigen::Vector3d>& pts) {
  Mesh m;
  m.positions = pts;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const int v = static_cast<int>(k);
    m.triangles.push_back({v, v, v});
  }
  return m;
}

}  // namespace scanmesh::test
