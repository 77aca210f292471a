// Triangles by 3D grid cell, for the post-processing's local crossing tests (aft_internal.h).
#include <algorithm>
#include <cmath>

#include "aft_internal.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::aft::detail {

TriangleCells::CellBox TriangleCells::cells_of(const std::array<int, 3>& f,
                                               std::span<const Eigen::Vector3d> P) const {
  CellBox box;
  for (int v : f) {
    const auto c = cell_of(P[v], cell_);
    box.extend(Eigen::Matrix<std::int64_t, 3, 1>(c[0], c[1], c[2]));
  }
  return box;
}

double TriangleCells::cell_size_for(std::span<const std::array<int, 3>> T,
                                    std::span<const Eigen::Vector3d> P) {
  double sum = 0;
  for (const auto& f : T) sum += (P[f[1]] - P[f[0]]).norm();
  return std::max(0.5, 1.5 * sum / std::max<std::size_t>(1, T.size()));
}

void TriangleCells::insert(int t, const std::array<int, 3>& f, std::span<const Eigen::Vector3d> P,
                           Undo* undo) {
  const CellBox box = cells_of(f, P);
  // Already filed under every cell it overlaps now (most small moves and many flips stay in
  // the cells of the last filing): nothing to add. (Without this the repair's lists grew with
  // every trial move of a Steiner point, since a star's triangles interleave: ~345 entries per
  // visited cell at an eighth of the sample units, and its crossing tests took most of its 1.2
  // thread-seconds there.)
  if (static_cast<std::size_t>(t) < filed_.size() && filed_[t].contains(box)) return;
  if (static_cast<std::size_t>(t) >= filed_.size()) filed_.resize(t + 1);
  if (undo) undo->filed.push_back({t, filed_[t]});
  filed_[t] = box;
  for (std::int64_t x = box.min().x(); x <= box.max().x(); ++x)
    for (std::int64_t y = box.min().y(); y <= box.max().y(); ++y)
      for (std::int64_t z = box.min().z(); z <= box.max().z(); ++z) {
        const std::int64_t k = pack_cell(x, y, z);
        std::vector<int>& list = lists_[k];
        if (!list.empty() && list.back() == t) continue;
        list.push_back(t);
        if (undo) undo->keys.push_back(k);
      }
}

void TriangleCells::take_back(Undo& undo) {
  for (auto it = undo.keys.rbegin(); it != undo.keys.rend(); ++it) lists_[*it].pop_back();
  for (auto it = undo.filed.rbegin(); it != undo.filed.rend(); ++it) filed_[it->first] = it->second;
  undo.clear();
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
                                const std::vector<Eigen::Vector3d>& P, int also_self) const {
  Eigen::AlignedBox3d box;
  for (int v : f) box.extend(P[v]);
  const Eigen::Vector3d nf = normal_of(P, f);
  const double tol = 1e-9 * box.diagonal().squaredNorm() * std::sqrt(box.diagonal().squaredNorm());
  return any_near(f, self, T.size(), P, [&](int u) {
    const std::array<int, 3>& g = T[u];
    if (u == also_self || g[0] < 0 || shares_edge(f, g)) return false;
    Eigen::AlignedBox3d gbox;
    for (int v : g) gbox.extend(P[v]);
    if (!box.intersects(gbox)) return false;
    if (strictly_one_side(P, f, nf, g, tol) || strictly_one_side(P, g, normal_of(P, g), f, tol))
      return false;
    return triangles_intersect(P, f, g);
  });
}

}  // namespace scanmesh::aft::detail
