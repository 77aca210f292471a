// Non-manifold triangle list with local adjacency updates (seed 001 §1.6).
#include "scanmesh/meshing/remeshing/nm_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh::remeshing {

NmMesh::NmMesh(const Mesh& mesh) {
  const int n = static_cast<int>(mesh.positions.size());
  pos = mesh.positions;
  vfaces.assign(n, {});
  vertex_alive.assign(n, 1);
  valence_cache_.assign(n, -1);
  live_vertices_ = n;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    for (int c : t)
      if (c < 0 || c >= n)
        throw InvalidInputError("remesh: triangle " + std::to_string(f) +
                                " has a vertex index out of range");
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw InvalidInputError("remesh: triangle " + std::to_string(f) + " repeats a corner");
    add_face(t[0], t[1], t[2], mesh.has_face_labels() ? mesh.face_labels[f] : 0);
  }
  // A vertex in no triangle (an OBJ's unused vertex) is not part of the surface: alive it would
  // count toward the remesher's target without ever getting a face, and the output would miss
  // the target by as many.
  for (int v = 0; v < n; ++v)
    if (vfaces[v].empty()) {
      vertex_alive[v] = 0;
      --live_vertices_;
    }
}

int NmMesh::add_vertex(const Eigen::Vector3d& x) {
  pos.push_back(x);
  vfaces.emplace_back();
  vertex_alive.push_back(1);
  valence_cache_.push_back(-1);
  ++live_vertices_;
  return static_cast<int>(pos.size()) - 1;
}

int NmMesh::add_face(int a, int b, int c, int face_label) {
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

void NmMesh::remove_face(int f) {
  if (!face_alive[f]) return;
  for (int c : tri[f]) {
    auto& l = vfaces[c];
    l.erase(std::find(l.begin(), l.end(), f));
  }
  face_alive[f] = 0;
  forget_valences(f);
  --live_faces_;
}

void NmMesh::revive_face(int f) {
  if (face_alive[f]) return;
  face_alive[f] = 1;
  for (int c : tri[f]) vfaces[c].push_back(f);
  forget_valences(f);
  ++live_faces_;
}

void NmMesh::remove_vertex(int v) {
  if (!vertex_alive[v]) return;
  vertex_alive[v] = 0;
  vfaces[v].clear();
  if (v < static_cast<int>(valence_cache_.size())) valence_cache_[v] = -1;
  --live_vertices_;
}

void NmMesh::replace_corner(int f, int from, int to) {
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

void NmMesh::forget_valences(int f) {
  for (int c : tri[f])
    if (c < static_cast<int>(valence_cache_.size())) valence_cache_[c] = -1;
}

int NmMesh::count_neighbours(int v) const {
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

std::vector<std::uint64_t> NmMesh::edges() const {
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

Eigen::Vector3d NmMesh::face_normal(int f) const {
  const auto& t = tri[f];
  const Eigen::Vector3d n = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
  const double l = n.norm();
  return l > 0 ? Eigen::Vector3d(n / l) : Eigen::Vector3d::Zero();
}

double NmMesh::face_area(int f) const {
  const auto& t = tri[f];
  return 0.5 * (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]).norm();
}

Mesh NmMesh::to_mesh(std::vector<int>* old_to_new) const {
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

}  // namespace scanmesh::remeshing
