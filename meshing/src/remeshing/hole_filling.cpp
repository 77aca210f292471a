// Hole patches for prepare_input: a minimum-area triangulation of the loop in its plane,
// refined, its height smoothed to a membrane.
#include "hole_filling.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::remeshing::detail {

namespace {

using Vec3 = Eigen::Vector3d;
using Tri = std::array<int, 3>;

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

// Twice the signed area of (a, b, c) in the (u, v) plane of the patch frame.
double orient2d(const Vec3& a, const Vec3& b, const Vec3& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

bool segments_meet2d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double o1 = orient2d(a, b, c), o2 = orient2d(a, b, d);
  const double o3 = orient2d(c, d, a), o4 = orient2d(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
    return true;
  auto on = [](const Vec3& p, const Vec3& q, const Vec3& r, double o) {  // r on segment pq
    return o == 0 && std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
           std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
  };
  return on(a, b, c, o1) || on(a, b, d, o2) || on(c, d, a, o3) || on(c, d, b, o4);
}

// The loop seen in the patch plane: no two non-adjacent edges meet.
bool simple_in_plane(const std::vector<Vec3>& p) {
  const int n = static_cast<int>(p.size());
  for (int i = 0; i < n; ++i)
    for (int j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;
      if (segments_meet2d(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n])) return false;
    }
  return true;
}

bool inside2d(const std::vector<Vec3>& p, const Vec3& q) {
  bool in = false;
  const int n = static_cast<int>(p.size());
  for (int i = 0, j = n - 1; i < n; j = i++)
    if ((p[i].y() > q.y()) != (p[j].y() > q.y()) &&
        q.x() < (p[j].x() - p[i].x()) * (q.y() - p[i].y()) / (p[j].y() - p[i].y()) + p[i].x())
      in = !in;
  return in;
}

// Dynamic programming over the diagonals (i, j) of the loop, simple and counter-clockwise in
// the patch plane: W(i, j) = min over k of W(i, k) + W(k, j) + area(i, k, j). A chord is a
// diagonal when it meets no loop edge but at its ends and runs inside, and it must not be an
// edge of the mesh outside the hole (`joined`). Triangles (i, k, j) with i < k < j run the
// loop's way. Empty when no triangulation avoids the joined chords.
std::vector<Tri> min_area_triangulation(const std::vector<Vec3>& p,
                                        const std::function<bool(int, int)>& joined) {
  const int n = static_cast<int>(p.size());
  auto at = [n](int i, int j) { return static_cast<std::size_t>(i) * n + j; };
  std::vector<char> diagonal(static_cast<std::size_t>(n) * n, 1);
  for (int i = 0; i < n; ++i)
    for (int j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;
      bool ok = !joined(i, j) && inside2d(p, 0.5 * (p[i] + p[j]));
      for (int k = 0; k < n && ok; ++k) {
        const int l = (k + 1) % n;
        if (k == i || k == j || l == i || l == j) continue;
        ok = !segments_meet2d(p[i], p[j], p[k], p[l]);
      }
      diagonal[at(i, j)] = ok;
    }
  constexpr double kNever = std::numeric_limits<double>::infinity();
  std::vector<double> w(static_cast<std::size_t>(n) * n, 0);
  std::vector<int> arg(static_cast<std::size_t>(n) * n, -1);
  for (int len = 2; len < n; ++len)
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      double best = kNever;
      if (diagonal[at(i, j)])
        for (int k = i + 1; k < j; ++k) {
          const double c = w[at(i, k)] + w[at(k, j)] + triangle_area(p[i], p[k], p[j]);
          if (c < best) best = c, arg[at(i, j)] = k;
        }
      w[at(i, j)] = best;
    }
  if (!(w[at(0, n - 1)] < kNever)) return {};
  std::vector<Tri> out;
  std::vector<std::pair<int, int>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = arg[at(i, j)];
    out.push_back({i, k, j});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return out;
}

// The patch while it is refined: vertices 0..n_loop-1 are the fixed loop.
class Patch {
 public:
  Patch(std::vector<Vec3> pts, std::vector<Tri> tris, int n_loop,
        const std::function<bool(int, int)>& joined)
      : pos_(std::move(pts)), tri_(std::move(tris)), n_loop_(n_loop), joined_(joined) {}

  // Splits inner edges longer than `limit`, longest first, each face once; returns the count.
  int split_long_edges(double limit) {
    const auto faces = edge_faces();
    std::vector<std::pair<double, std::pair<int, int>>> cand;
    for (const auto& [e, fs] : faces)
      if (fs.size() == 2) {
        const double l = (pos_[e.first] - pos_[e.second]).norm();
        if (l > limit) cand.push_back({-l, e});
      }
    std::sort(cand.begin(), cand.end());
    std::vector<char> touched(tri_.size(), 0);
    int splits = 0;
    for (const auto& [neg_len, e] : cand) {
      const auto& fs = faces.at(e);
      if (touched[fs[0]] || touched[fs[1]]) continue;
      touched[fs[0]] = touched[fs[1]] = 1;
      split(fs[0], fs[1], e.first, e.second);
      ++splits;
    }
    return splits;
  }

  // Max-min-angle flips of inner edges until none improves (bounded passes).
  void flip_to_max_min_angle() {
    for (int pass = 0; pass < 20; ++pass) {
      int flips = 0;
      const auto faces = edge_faces();
      std::vector<char> touched(tri_.size(), 0);
      made_.clear();
      for (const auto& [e, fs] : faces) {
        if (fs.size() != 2 || touched[fs[0]] || touched[fs[1]]) continue;
        if (try_flip(fs[0], fs[1], e.first, e.second, faces)) {
          touched[fs[0]] = touched[fs[1]] = 1;
          ++flips;
        }
      }
      if (flips == 0) return;
    }
  }

  // Gauss-Seidel umbrella steps on the inner vertices: a discrete membrane over the fixed loop.
  void smooth(int iterations) {
    std::vector<std::vector<int>> nb(pos_.size());
    for (const Tri& t : tri_)
      for (int i = 0; i < 3; ++i) {
        nb[t[i]].push_back(t[(i + 1) % 3]);
        nb[t[i]].push_back(t[(i + 2) % 3]);
      }
    for (auto& v : nb) {
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
    }
    std::vector<std::vector<int>> vf(pos_.size());
    for (std::size_t f = 0; f < tri_.size(); ++f)
      for (int c : tri_[f]) vf[c].push_back(static_cast<int>(f));
    for (int it = 0; it < iterations; ++it)
      for (std::size_t v = n_loop_; v < pos_.size(); ++v) {
        if (nb[v].empty()) continue;
        Vec3 c = Vec3::Zero();
        for (int x : nb[v]) c += pos_[x];
        c /= static_cast<double>(nb[v].size());
        // Height: always (a membrane). Position in the plane: only if no face turns over.
        const Vec3 old = pos_[v];
        pos_[v] = c;
        bool upright = true;
        for (int f : vf[v])
          upright = upright && orient2d(pos_[tri_[f][0]], pos_[tri_[f][1]], pos_[tri_[f][2]]) > 0;
        if (!upright) pos_[v] = Vec3(old.x(), old.y(), c.z());
      }
  }

  std::size_t triangle_count() const { return tri_.size(); }

  HolePatch result() const {
    HolePatch out;
    out.new_points.assign(pos_.begin() + n_loop_, pos_.end());
    // Built the loop's way round; the faces around the hole run the other way.
    for (const Tri& t : tri_) out.triangles.push_back({t[2], t[1], t[0]});
    return out;
  }

 private:
  using EdgeFaces = std::map<std::pair<int, int>, std::vector<int>>;

  EdgeFaces edge_faces() const {
    EdgeFaces m;
    for (std::size_t f = 0; f < tri_.size(); ++f)
      for (int i = 0; i < 3; ++i) {
        const int a = tri_[f][i], b = tri_[f][(i + 1) % 3];
        m[{std::min(a, b), std::max(a, b)}].push_back(static_cast<int>(f));
      }
    return m;
  }

  // Rotates face f so that it starts with the directed edge a -> b; false if it has none.
  bool starting_with(int f, int a, int b, Tri& out) const {
    const Tri& t = tri_[f];
    for (int i = 0; i < 3; ++i)
      if (t[i] == a && t[(i + 1) % 3] == b) {
        out = {a, b, t[(i + 2) % 3]};
        return true;
      }
    return false;
  }

  // The two faces of edge {u, v} as (a, b, c) and (b, a, d).
  // On return f1 holds a -> b and f2 holds b -> a.
  bool quad(int& f1, int& f2, int u, int v, Tri& t1, Tri& t2) const {
    if (!starting_with(f1, u, v, t1)) std::swap(f1, f2);
    if (!starting_with(f1, u, v, t1)) return false;
    return starting_with(f2, v, u, t2);
  }

  void split(int f1, int f2, int u, int v) {
    Tri t1, t2;
    if (!quad(f1, f2, u, v, t1, t2)) return;
    const int a = t1[0], b = t1[1], c = t1[2], d = t2[2];
    const int m = static_cast<int>(pos_.size());
    pos_.push_back(0.5 * (pos_[a] + pos_[b]));
    tri_[f1] = {a, m, c};
    tri_.push_back({m, b, c});
    tri_[f2] = {b, m, d};
    tri_.push_back({m, a, d});
  }

  bool try_flip(int f1, int f2, int u, int v, const EdgeFaces& faces) {
    Tri t1, t2;
    if (!quad(f1, f2, u, v, t1, t2)) return false;
    const int a = t1[0], b = t1[1], c = t1[2], d = t2[2];
    const std::pair<int, int> cd{std::min(c, d), std::max(c, d)};
    if (c == d || faces.count(cd) || made_.count(cd)) return false;
    if (c < n_loop_ && d < n_loop_ && joined_(c, d)) return false;  // an edge outside the hole
    const double before = std::min(triangle_min_angle(pos_[a], pos_[b], pos_[c]),
                                   triangle_min_angle(pos_[b], pos_[a], pos_[d]));
    const double after = std::min(triangle_min_angle(pos_[a], pos_[d], pos_[c]),
                                  triangle_min_angle(pos_[d], pos_[b], pos_[c]));
    if (!(after > before + 1e-9)) return false;
    // Only across convex quads in the plane: the patch stays a graph over its plane.
    if (!(orient2d(pos_[a], pos_[d], pos_[c]) > 0 && orient2d(pos_[d], pos_[b], pos_[c]) > 0))
      return false;
    tri_[f1] = {a, d, c};
    tri_[f2] = {d, b, c};
    made_.insert(cd);
    return true;
  }

  std::vector<Vec3> pos_;
  std::vector<Tri> tri_;
  int n_loop_;
  const std::function<bool(int, int)>& joined_;
  std::set<std::pair<int, int>> made_;  // edges made by flips in the current pass
};

}  // namespace

HolePatch fill_hole(const std::vector<Vec3>& loop, const std::function<bool(int, int)>& joined) {
  const int n = static_cast<int>(loop.size());
  if (n < 3) return {};
  // Patch frame: (u, v) = the loop's least-squares plane, oriented so the loop runs counter-
  // clockwise, w = height over it. Everything below works in this frame (a rigid motion, so
  // lengths and angles are those of the surface).
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : loop) centre += p;
  centre /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3& p : loop) cov += (p - centre) * (p - centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Vec3 e1 = eig.eigenvectors().col(2), e2 = eig.eigenvectors().col(1);
  std::vector<Vec3> local;
  auto to_local = [&] {
    local.clear();
    for (const Vec3& p : loop) local.push_back({(p - centre).dot(e1), (p - centre).dot(e2), 0});
  };
  to_local();
  double area2 = 0;
  for (int i = 0; i < n; ++i) area2 += orient2d(Vec3::Zero(), local[i], local[(i + 1) % n]);
  if (area2 < 0) e2 = -e2;
  const Vec3 normal = e1.cross(e2);
  to_local();
  for (int i = 0; i < n; ++i) local[i].z() = (loop[i] - centre).dot(normal);
  std::vector<Tri> start;
  if (simple_in_plane(local)) start = min_area_triangulation(local, joined);
  if (start.empty()) {
    // The loop folds over its plane (or every triangulation needs a joined chord): the centroid
    // fan, unrefined, as before this patch existed.
    // Loop edges i -> i + 1 traversed backwards, to a new vertex n at the centre.
    HolePatch fan;
    fan.new_points = {centre};
    for (int i = 0; i < n; ++i) fan.triangles.push_back({n, (i + 1) % n, i});
    return fan;
  }
  double mean_edge = 0;
  for (int i = 0; i < n; ++i) mean_edge += (loop[(i + 1) % n] - loop[i]).norm();
  mean_edge /= n;
  Patch patch(local, std::move(start), n, joined);
  patch.flip_to_max_min_angle();
  if (!(mean_edge > 0 && std::isfinite(mean_edge))) return patch.result();
  // Each round at least halves the longest inner edge; 30 rounds bound any hole of a scan. The
  // patch's area is at most perimeter^2 / 4 pi, i.e. ~n^2 / 3 triangles of the target size;
  // the cap only guards against a loop no scan produces.
  const std::size_t cap = 20 * static_cast<std::size_t>(n) * n + 100;
  for (int round = 0; round < 30 && patch.triangle_count() < cap; ++round) {
    const int splits = patch.split_long_edges(4.0 / 3.0 * mean_edge);
    patch.flip_to_max_min_angle();
    patch.smooth(5);
    if (splits == 0) break;
  }
  patch.smooth(30);
  patch.flip_to_max_min_angle();
  HolePatch out = patch.result();
  for (Vec3& p : out.new_points) p = centre + p.x() * e1 + p.y() * e2 + p.z() * normal;
  return out;
}

}  // namespace scanmesh::remeshing::detail
