// Triangles by 3D grid cell, for the post-processing's local crossing tests (aft_internal.h).
#include <cmath>

#include "aft_internal.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::aft::detail {

TriangleCells::CellBox TriangleCells::cells_of(const std::array<int, 3>& f,
                                               std::span<const Eigen::Vector3d> P) const {
  CellBox box;
  for (int v : f) {
    const Eigen::Vector3d c = P[v] / cell_;
    box.extend(Eigen::Matrix<std::int64_t, 3, 1>(static_cast<std::int64_t>(std::floor(c.x())),
                                                 static_cast<std::int64_t>(std::floor(c.y())),
                                                 static_cast<std::int64_t>(std::floor(c.z()))));
  }
  return box;
}

void TriangleCells::insert(int t, const std::array<int, 3>& f, std::span<const Eigen::Vector3d> P) {
  const auto box = cells_of(f, P);
  // Already filed under every cell it overlaps now (most small moves and many flips stay in
  // the cells of the last filing): nothing to add.
  if (static_cast<std::size_t>(t) < filed_.size() && filed_[t].contains(box)) return;
  if (static_cast<std::size_t>(t) >= filed_.size()) filed_.resize(t + 1);
  filed_[t] = box;
  for (std::int64_t x = box.min().x(); x <= box.max().x(); ++x)
    for (std::int64_t y = box.min().y(); y <= box.max().y(); ++y)
      for (std::int64_t z = box.min().z(); z <= box.max().z(); ++z) {
        std::vector<int>& list = lists_[key(x, y, z)];
        if (list.empty() || list.back() != t) list.push_back(t);
      }
}

namespace {
// Triangles on a common edge meet only on it unless they are coplanar and folded onto each
// other, which the callers' normal tests already refuse; skipping them saves about a quarter of
// the full tests.
bool shares_edge(const std::array<int, 3>& f, const std::array<int, 3>& g) {
  int shared = 0;
  for (int a : f)
    for (int b : g) shared += a == b;
  return shared >= 2;
}

Eigen::Vector3d normal_of(std::span<const Eigen::Vector3d> P, const std::array<int, 3>& f) {
  return (P[f[1]] - P[f[0]]).cross(P[f[2]] - P[f[0]]);
}

// The corners of g that are not corners of f lie all clearly on one side of f's plane (normal
// n, not normalised): then g meets f's plane at most in their shared corner, so they cannot
// cross. Most neighbours are dismissed so, with a few dot products instead of the full test.
// `tol` (length^3, like n . d) keeps near-coplanar pairs for the full test.
bool strictly_one_side(std::span<const Eigen::Vector3d> P, const std::array<int, 3>& f,
                       const Eigen::Vector3d& n, const std::array<int, 3>& g, double tol) {
  int above = 0, below = 0, own = 0;
  for (int v : g) {
    if (v == f[0] || v == f[1] || v == f[2]) {
      ++own;
      continue;
    }
    const double d = n.dot(P[v] - P[f[0]]);
    if (d > tol) {
      ++above;
    } else if (d < -tol) {
      ++below;
    } else {
      return false;
    }
  }
  return own < 3 && (above == 0 || below == 0);
}
}  // namespace

bool TriangleCells::crosses_any(const std::array<int, 3>& f, int self,
                                std::span<const std::array<int, 3>> T,
                                const std::vector<Eigen::Vector3d>& P, int also_self) {
  if (stamp_.size() < T.size()) stamp_.resize(T.size(), 0);
  if (++epoch_ == 0) {  // wrapped: forget every stamp
    std::fill(stamp_.begin(), stamp_.end(), 0);
    epoch_ = 1;
  }
  Eigen::AlignedBox3d box;
  for (int v : f) box.extend(P[v]);
  const Eigen::Vector3d nf = normal_of(P, f);
  const double tol = 1e-9 * box.diagonal().squaredNorm() * std::sqrt(box.diagonal().squaredNorm());
  const auto cells = cells_of(f, P);
  for (std::int64_t x = cells.min().x(); x <= cells.max().x(); ++x)
    for (std::int64_t y = cells.min().y(); y <= cells.max().y(); ++y)
      for (std::int64_t z = cells.min().z(); z <= cells.max().z(); ++z) {
        const std::vector<int>* list = lists_.find(key(x, y, z));
        if (!list) continue;
        for (int u : *list) {
          if (u == self || u == also_self || u >= static_cast<int>(T.size()) || stamp_[u] == epoch_)
            continue;
          stamp_[u] = epoch_;
          const std::array<int, 3>& g = T[u];
          if (g[0] < 0 || shares_edge(f, g)) continue;
          Eigen::AlignedBox3d gbox;
          for (int v : g) gbox.extend(P[v]);
          if (!box.intersects(gbox)) continue;
          if (strictly_one_side(P, f, nf, g, tol) ||
              strictly_one_side(P, g, normal_of(P, g), f, tol))
            continue;
          if (triangles_intersect(P, f, g)) return true;
        }
      }
  return false;
}

}  // namespace scanmesh::aft::detail
