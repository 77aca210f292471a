// The meshing kernel's triangle mesh: adjacency kept by every change, local operations.
#include "scanmesh/meshing/kernel/triangle_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh::kernel {

TriangleMesh::TriangleMesh(const Mesh& mesh, const char* context)
    : TriangleMesh(mesh.positions, mesh.triangles, context) {
  if (mesh.has_face_labels()) label = mesh.face_labels;
}

TriangleMesh::TriangleMesh(std::vector<Eigen::Vector3d> positions,
                           std::span<const std::array<int, 3>> triangles, const char* context) {
  const int n = static_cast<int>(positions.size());
  pos = std::move(positions);
  vfaces.assign(n, {});
  vertex_alive.assign(n, 1);
  valence_cache_.assign(n, -1);
  live_vertices_ = n;
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const auto& t = triangles[f];
    for (int c : t)
      if (c < 0 || c >= n)
        throw InvalidInputError(std::string(context) + ": triangle " + std::to_string(f) +
                                " has a vertex index out of range");
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw InvalidInputError(std::string(context) + ": triangle " + std::to_string(f) +
                              " repeats a corner");
    add_face(t[0], t[1], t[2], 0);
  }
  // A vertex in no triangle (an OBJ's unused vertex) is not part of the surface: alive it would
  // count toward a remesher's target without ever getting a face, and the output would miss
  // the target by as many.
  for (int v = 0; v < n; ++v)
    if (vfaces[v].empty()) {
      vertex_alive[v] = 0;
      --live_vertices_;
    }
}

int TriangleMesh::add_vertex(const Eigen::Vector3d& x) {
  pos.push_back(x);
  vfaces.emplace_back();
  vertex_alive.push_back(1);
  valence_cache_.push_back(-1);
  ++live_vertices_;
  return static_cast<int>(pos.size()) - 1;
}

int TriangleMesh::add_face(int a, int b, int c, int face_label) {
  tri.push_back({a, b, c});
  label.push_back(face_label);
  face_alive.push_back(1);
  const int f = static_cast<int>(tri.size()) - 1;
  vfaces[a].push_back(f);
  vfaces[b].push_back(f);
  vfaces[c].push_back(f);
  forget_valences(f);
  ++live_faces_;
  return f;
}

void TriangleMesh::remove_face(int f) {
  if (!face_alive[f]) return;
  for (int c : tri[f]) {
    auto& l = vfaces[c];
    l.erase(std::find(l.begin(), l.end(), f));
  }
  face_alive[f] = 0;
  forget_valences(f);
  --live_faces_;
}

void TriangleMesh::revive_face(int f) {
  if (face_alive[f]) return;
  face_alive[f] = 1;
  for (int c : tri[f]) vfaces[c].push_back(f);
  forget_valences(f);
  ++live_faces_;
}

void TriangleMesh::remove_vertex(int v) {
  if (!vertex_alive[v]) return;
  vertex_alive[v] = 0;
  vfaces[v].clear();
  if (v < static_cast<int>(valence_cache_.size())) valence_cache_[v] = -1;
  --live_vertices_;
}

void TriangleMesh::replace_corner(int f, int from, int to) {
  forget_valences(f);  // `from` and the two that stay lose a neighbour
  for (int& c : tri[f])
    if (c == from) {
      c = to;
      auto& l = vfaces[from];
      l.erase(std::find(l.begin(), l.end(), f));
      vfaces[to].push_back(f);
      forget_valences(f);  // `to` gains
      return;
    }
}

void TriangleMesh::put_first(int f, int corner) {
  auto& t = tri[f];
  std::rotate(t.begin(), std::find(t.begin(), t.end(), corner), t.end());
}

void TriangleMesh::forget_valences(int f) {
  for (int c : tri[f])
    if (c < static_cast<int>(valence_cache_.size())) valence_cache_[c] = -1;
}

int TriangleMesh::count_neighbours(int v) const {
  std::array<int, 32> seen;
  int n = 0;
  for (int f : vfaces[v])
    for (int c : tri[f]) {
      if (c == v || std::find(seen.begin(), seen.begin() + n, c) != seen.begin() + n) continue;
      if (n == static_cast<int>(seen.size())) return static_cast<int>(neighbours(v).size());
      seen[n++] = c;
    }
  return n;
}

std::vector<std::uint64_t> TriangleMesh::edges() const {
  // Vertex by vertex, each edge from its smaller end: only the few keys of one vertex need
  // sorting (a global sort of all 3F keys was ~15 % of a remesh; called every pass).
  // The few keys of one vertex go straight into their sorted place, each once (insertion into
  // ~3 keys; std::sort and std::unique per vertex were a third of this function's time).
  std::vector<std::uint64_t> out(static_cast<std::size_t>(live_faces_) * 3 + 16);
  std::size_t n = 0;
  for (std::size_t v = 0; v < vfaces.size(); ++v) {
    const std::size_t first = n;
    for (int f : vfaces[v])
      for (int c : tri[f]) {
        if (c <= static_cast<int>(v)) continue;
        const std::uint64_t k = edge_key(static_cast<int>(v), c);
        std::size_t i = n;
        while (i > first && out[i - 1] > k) --i;
        if (i > first && out[i - 1] == k) continue;
        if (n == out.size()) out.resize(2 * n);
        std::copy_backward(out.begin() + i, out.begin() + n, out.begin() + n + 1);
        out[i] = k;
        ++n;
      }
  }
  out.resize(n);
  return out;
}

std::optional<EdgeQuad> TriangleMesh::quad(int v, int w) const {
  const auto ef = edge_faces(v, w);
  if (ef.size() != 2) return std::nullopt;
  int f1 = ef[0], f2 = ef[1];
  if (!traverses(f1, v, w)) std::swap(f1, f2);
  const int a = opposite(f1, v, w), b = opposite(f2, v, w);
  if (a == b) return std::nullopt;
  return EdgeQuad{f1, f2, v, w, a, b};
}

std::optional<EdgeQuad> TriangleMesh::oriented_quad(int v, int w) const {
  const auto q = quad(v, w);
  if (!q || !traverses(q->f1, v, w) || !traverses(q->f2, w, v)) return std::nullopt;
  return q;
}

std::optional<EdgeQuad> TriangleMesh::flip(int v, int w) {
  const auto q = quad(v, w);
  if (!q || edge_face_count(q->a, q->b) > 0) return std::nullopt;
  flip(*q);
  return q;
}

void TriangleMesh::flip(const EdgeQuad& q) {
  replace_corner(q.f1, q.w, q.b);  // (v, b, a)
  replace_corner(q.f2, q.v, q.a);  // (w, a, b)
}

void TriangleMesh::undo(const EdgeQuad& flipped) {
  replace_corner(flipped.f1, flipped.b, flipped.w);
  replace_corner(flipped.f2, flipped.a, flipped.v);
}

EdgeSplit TriangleMesh::split(int v, int w, int u) {
  EdgeSplit s{v, w, u, {}, {}};
  for (int f : edge_faces(v, w)) {
    std::array<int, 3> half = tri[f];
    for (int& c : half)
      if (c == v) c = u;
    replace_corner(f, w, u);
    s.added.push_back(add_face(half[0], half[1], half[2], label[f]));
    s.changed.push_back(f);
  }
  return s;
}

void TriangleMesh::undo(const EdgeSplit& split) {
  for (int f : split.added) remove_face(f);
  for (int f : split.changed) replace_corner(f, split.u, split.w);
}

bool TriangleMesh::link_condition(int v, int w, std::span<const int> star, std::span<const int> nv,
                                  std::span<const int> nw) const {
  for (int x : nv) {
    if (x == w || std::find(nw.begin(), nw.end(), x) == nw.end()) continue;
    const bool opposite_corner =
        std::any_of(star.begin(), star.end(), [&](int f) { return opposite(f, v, w) == x; });
    if (!opposite_corner) return false;
  }
  return true;
}

EdgeCollapse TriangleMesh::collapse(int v, int w) {
  EdgeCollapse c{v, w, {}, {}};
  const std::vector<int> around_v = vfaces[v];
  for (int f : edge_faces(v, w)) {
    remove_face(f);
    c.removed.push_back(f);
  }
  for (int f : around_v)
    if (face_alive[f]) {
      replace_corner(f, v, w);
      c.moved.push_back(f);
    }
  return c;
}

void TriangleMesh::undo(const EdgeCollapse& collapsed) {
  for (int f : collapsed.moved) replace_corner(f, collapsed.w, collapsed.v);
  for (int f : collapsed.removed) revive_face(f);
}

void TriangleMesh::truncate(std::size_t faces, std::size_t vertices) {
  for (std::size_t f = faces; f < tri.size(); ++f)
    if (face_alive[f])
      throw std::logic_error("TriangleMesh::truncate: face " + std::to_string(f) + " is live");
  for (std::size_t v = vertices; v < vfaces.size(); ++v)
    if (!vfaces[v].empty())
      throw std::logic_error("TriangleMesh::truncate: vertex " + std::to_string(v) + " has faces");
  for (std::size_t v = vertices; v < vfaces.size(); ++v) live_vertices_ -= vertex_alive[v] ? 1 : 0;
  if (faces < tri.size()) {
    tri.resize(faces);
    label.resize(faces);
    face_alive.resize(faces);
  }
  if (vertices < vfaces.size()) {
    pos.resize(vertices);
    vfaces.resize(vertices);
    vertex_alive.resize(vertices);
    valence_cache_.resize(std::min(valence_cache_.size(), vertices));
  }
}

std::vector<int> TriangleMesh::compact() {
  std::vector<int> map(pos.size(), -1);
  std::size_t n = 0;
  for (std::size_t v = 0; v < pos.size(); ++v)
    if (vertex_alive[v]) {
      map[v] = static_cast<int>(n);
      pos[n++] = pos[v];
    }
  pos.resize(n);
  std::size_t kept = 0;
  for (std::size_t f = 0; f < tri.size(); ++f) {
    if (!face_alive[f]) continue;
    tri[kept] = {map[tri[f][0]], map[tri[f][1]], map[tri[f][2]]};
    label[kept++] = label[f];
  }
  tri.resize(kept);
  label.resize(kept);
  face_alive.assign(kept, 1);
  vertex_alive.assign(n, 1);
  vfaces.assign(n, {});
  for (std::size_t f = 0; f < kept; ++f)
    for (int c : tri[f]) vfaces[c].push_back(static_cast<int>(f));
  valence_cache_.assign(n, -1);
  return map;
}

Eigen::Vector3d TriangleMesh::face_normal(int f) const {
  const auto& t = tri[f];
  const Eigen::Vector3d n = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
  const double l = n.norm();
  return l > 0 ? Eigen::Vector3d(n / l) : Eigen::Vector3d::Zero();
}

double TriangleMesh::face_area(int f) const {
  const auto& t = tri[f];
  return 0.5 * (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]).norm();
}

Mesh TriangleMesh::to_mesh(std::vector<int>* old_to_new) const {
  Mesh m;
  std::vector<int> map(pos.size(), -1);
  for (std::size_t v = 0; v < pos.size(); ++v)
    if (vertex_alive[v] && !vfaces[v].empty()) {
      map[v] = static_cast<int>(m.positions.size());
      m.positions.push_back(pos[v]);
    }
  for (std::size_t f = 0; f < tri.size(); ++f) {
    if (!face_alive[f]) continue;
    m.triangles.push_back({map[tri[f][0]], map[tri[f][1]], map[tri[f][2]]});
    m.face_labels.push_back(label[f]);
  }
  if (old_to_new) *old_to_new = std::move(map);
  return m;
}

std::vector<int> faces_off_largest_wedge(std::span<const std::array<int, 3>> tri,
                                         std::span<const int> star, int v) {
  if (star.size() < 2) return {};  // one face or none: one wedge at most
  auto share_edge_at_v = [&](int f, int g) {
    for (int a : tri[f])
      if (a != v && (tri[g][0] == a || tri[g][1] == a || tri[g][2] == a)) return true;
    return false;
  };
  std::vector<int> wedge(star.size(), -1), size;
  for (std::size_t s0 = 0; s0 < star.size(); ++s0) {
    if (wedge[s0] >= 0) continue;  // depth-first from each face not in a wedge yet
    const int w = static_cast<int>(size.size());
    size.push_back(0);
    std::vector<std::size_t> stack{s0};
    wedge[s0] = w;
    while (!stack.empty()) {
      const std::size_t s = stack.back();
      stack.pop_back();
      ++size[w];
      for (std::size_t t = 0; t < star.size(); ++t)
        if (wedge[t] < 0 && share_edge_at_v(star[s], star[t])) wedge[t] = w, stack.push_back(t);
    }
  }
  std::vector<int> off;
  if (size.size() < 2) return off;
  const int keep = static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
  for (std::size_t s = 0; s < star.size(); ++s)
    if (wedge[s] != keep) off.push_back(star[s]);
  return off;
}

}  // namespace scanmesh::kernel
