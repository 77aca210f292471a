// Non-manifold triangle mesh for remeshing (seed 001 §1.6): a plain triangle list with per-face
// labels and redundant adjacency kept up to date by every local operation. An edge may carry any
// number of faces; its radial edge-face list is edge_faces(v, w). Deleted faces and vertices stay
// in the arrays (marked dead) until compact().
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/meshing/edge_key.h"

namespace scanmesh::remeshing {

//! A short list of indices held inline, spilling to the heap past N: what edge_faces and
//! neighbours return. A remesh asks for them millions of times, and a std::vector each was
//! ~7 % of its time in malloc / free (perf, lion-head at its own vertex count).
template <std::size_t N>
class SmallIndexList {
 public:
  void push_back(int x) {
    if (n_ < N) {
      inline_[n_] = x;
    } else {
      if (n_ == N) heap_.assign(inline_.begin(), inline_.end());
      heap_.push_back(x);
    }
    ++n_;
  }
  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  int operator[](std::size_t i) const { return data()[i]; }
  const int* begin() const { return data(); }
  const int* end() const { return data() + n_; }
  operator std::vector<int>() const { return std::vector<int>(begin(), end()); }

 private:
  const int* data() const { return n_ <= N ? inline_.data() : heap_.data(); }
  std::array<int, N> inline_;
  std::vector<int> heap_;
  std::size_t n_ = 0;
};
using EdgeFaceList = SmallIndexList<6>;    //!< two faces per manifold edge, a few on a seam
using NeighbourList = SmallIndexList<16>;  //!< a ring

class NmMesh {
 public:
  NmMesh() = default;
  //! Copies positions, triangles and labels (label 0 when the mesh has none); vertices in no
  //! triangle are kept in `pos` but not live. Throws InvalidInputError for bad indices or
  //! triangles with a repeated corner.
  explicit NmMesh(const Mesh& mesh);

  std::vector<Eigen::Vector3d> pos;
  std::vector<std::array<int, 3>> tri;
  std::vector<int> label;                //!< per face
  std::vector<std::vector<int>> vfaces;  //!< per vertex: live incident faces
  std::vector<char> face_alive, vertex_alive;

  int vertex_count() const { return live_vertices_; }
  int face_count() const { return live_faces_; }

  int add_vertex(const Eigen::Vector3d& x);
  int add_face(int a, int b, int c, int face_label);
  void remove_face(int f);
  //! Makes a removed face live again with its stored corners (undo of remove_face).
  void revive_face(int f);
  void remove_vertex(int v);  //!< the vertex must have no faces left
  //! Replaces corner `from` of face f by `to` (adjacency updated).
  void replace_corner(int f, int from, int to);

  //! Radial edge-face list: every live face containing both v and w.
  EdgeFaceList edge_faces(int v, int w) const;
  int edge_face_count(int v, int w) const;
  //! Distinct neighbours of v (unsorted, deterministic order).
  NeighbourList neighbours(int v) const;
  //! Number of distinct neighbours. Cached per vertex and forgotten by every change of a face
  //! at the vertex (the regularisation asks for the same valences hundreds of thousands of
  //! times between two changes; not thread-safe, like every other use of an NmMesh).
  int valence(int v) const;
  //! All distinct edges as keys, sorted.
  std::vector<std::uint64_t> edges() const;
  //! The corner of f that is neither v nor w.
  int opposite(int f, int v, int w) const;
  Eigen::Vector3d face_normal(int f) const;  //!< unit (zero for degenerate faces)
  double face_area(int f) const;

  //! Live parts only, labels kept; `old_to_new` receives the vertex map (-1 for dead).
  Mesh to_mesh(std::vector<int>* old_to_new = nullptr) const;

 private:
  void forget_valences(int f);  // the corners of face f
  int count_neighbours(int v) const;
  int live_vertices_ = 0, live_faces_ = 0;
  mutable std::vector<int> valence_cache_;  // per vertex, -1: not known
};

// The adjacency queries are inline: the remesher asks for them millions of times per run
// from another translation unit.

inline EdgeFaceList NmMesh::edge_faces(int v, int w) const {
  EdgeFaceList out;
  for (int f : vfaces[v]) {
    const auto& t = tri[f];
    if (t[0] == w || t[1] == w || t[2] == w) out.push_back(f);
  }
  return out;
}

inline int NmMesh::edge_face_count(int v, int w) const {
  int n = 0;
  for (int f : vfaces[v]) {
    const auto& t = tri[f];
    n += (t[0] == w || t[1] == w || t[2] == w) ? 1 : 0;
  }
  return n;
}

inline NeighbourList NmMesh::neighbours(int v) const {
  NeighbourList out;
  for (int f : vfaces[v])
    for (int c : tri[f])
      if (c != v && std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
  return out;
}

inline int NmMesh::valence(int v) const {
  if (v >= static_cast<int>(valence_cache_.size())) return count_neighbours(v);
  int& cached = valence_cache_[v];
  if (cached < 0) cached = count_neighbours(v);
  return cached;
}

inline int NmMesh::opposite(int f, int v, int w) const {
  for (int c : tri[f])
    if (c != v && c != w) return c;
  return -1;
}

}  // namespace scanmesh::remeshing
