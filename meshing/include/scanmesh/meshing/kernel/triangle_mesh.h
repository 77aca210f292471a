// The meshing kernel's mesh (issue 28): a triangle list with per-face labels and redundant
// adjacency (each vertex's faces) kept up to date by every change, with the local operations the
// meshers share (flip, split, collapse, each with its undo). An edge may carry any number of faces
// (the remesher's seams, seed 001 §1.6); its radial edge-face list is edge_faces(v, w). Removed
// faces and vertices stay in the arrays, marked dead. The operations change topology only: whether
// a change is wanted (lengths, angles, feature lines, a face's distance to the input) is the
// caller's policy, as in pmp-library's remeshing, which asks its mesh for is_collapse_ok / split /
// flip. docs/ARCHITECTURE.md, "The meshing kernel".
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/meshing/edge_key.h"

namespace scanmesh::kernel {

//! A short list of indices held inline, spilling to the heap past N: what edge_faces and
//! neighbours return, and each vertex's face list. A remesh asks for the lists millions of
//! times, and a std::vector each was ~7 % of its time in malloc / free (perf, lion-head at its
//! own vertex count); held in place, a vertex's face list is read without a second cache
//! miss (a remesh at the corpus meshes' own counts took 15-25 % less time).
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
  //! Removes the element at `at`, keeping the order of the others.
  void erase(const int* at) {
    int* d = mutable_data();
    int* hole = d + (at - data());
    std::copy(hole + 1, d + n_, hole);
    --n_;
    if (n_ >= N) {
      heap_.pop_back();
      if (n_ == N) {
        std::copy(heap_.begin(), heap_.end(), inline_.begin());
        heap_.clear();
      }
    }
  }
  void clear() {
    n_ = 0;
    heap_.clear();
  }
  void sort() { std::sort(mutable_data(), mutable_data() + n_); }
  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  int operator[](std::size_t i) const { return data()[i]; }
  const int* data() const { return n_ <= N ? inline_.data() : heap_.data(); }
  const int* begin() const { return data(); }
  const int* end() const { return data() + n_; }
  operator std::vector<int>() const { return std::vector<int>(begin(), end()); }

 private:
  int* mutable_data() { return n_ <= N ? inline_.data() : heap_.data(); }
  std::array<int, N> inline_;
  std::vector<int> heap_;
  std::size_t n_ = 0;
};
using EdgeFaceList = SmallIndexList<6>;    //!< two faces per manifold edge, a few on a seam
using NeighbourList = SmallIndexList<16>;  //!< a ring
using VertexFaceList = SmallIndexList<7>;  //!< six faces around most vertices of a surface

//! The quad around an edge v-w with two faces: f1 = (v, w, a) and f2 = (w, v, b), both
//! counter-clockwise; a-b is the other diagonal.
struct EdgeQuad {
  int f1, f2;
  int v, w, a, b;
};

//! What an edge split changed: each face of v-w kept its corner v and got u for w (`changed`),
//! and a copy of it with u for v was added (`added`, in the same order, same label).
struct EdgeSplit {
  int v, w, u;
  std::vector<int> changed, added;
};

//! What an edge collapse changed: the faces of v-w were removed (`removed`) and v's other faces
//! got w for v (`moved`). v is left without faces, still live.
struct EdgeCollapse {
  int v, w;
  std::vector<int> removed, moved;
};

class TriangleMesh {
 public:
  TriangleMesh() = default;
  //! Copies positions, triangles and labels (label 0 when the mesh has none); vertices in no
  //! triangle are kept in `pos` but not live. Throws InvalidInputError for bad indices or
  //! triangles with a repeated corner, the message starting with `context` (e.g. "remesh").
  explicit TriangleMesh(const Mesh& mesh, const char* context = "mesh");
  //! The same from positions and triangles alone (every label 0).
  TriangleMesh(std::vector<Eigen::Vector3d> positions,
               std::span<const std::array<int, 3>> triangles, const char* context = "mesh");

  std::vector<Eigen::Vector3d> pos;
  std::vector<std::array<int, 3>> tri;
  std::vector<int> label;                //!< per face
  std::vector<VertexFaceList> vfaces;    //!< per vertex: live incident faces
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
  //! Rotates f's corners (the same oriented face) so that `corner` comes first. The meshers
  //! that wrote their own faces started them at a corner of their choosing; the order of the
  //! corners decides the order of later sums, and with it their meshes bit for bit.
  void put_first(int f, int corner);

  //! Radial edge-face list: every live face containing both v and w.
  EdgeFaceList edge_faces(int v, int w) const;
  int edge_face_count(int v, int w) const;
  //! Distinct neighbours of v (unsorted, deterministic order).
  NeighbourList neighbours(int v) const;
  //! Number of distinct neighbours. Cached per vertex and forgotten by every change of a face
  //! at the vertex (the regularisation asks for the same valences hundreds of thousands of
  //! times between two changes; not thread-safe, like every other use of a TriangleMesh).
  int valence(int v) const;
  //! All distinct edges as keys, sorted.
  std::vector<std::uint64_t> edges() const;
  //! The corner of f that is neither v nor w.
  int opposite(int f, int v, int w) const;
  //! True if face f runs from v to w (w follows v in its corner order).
  bool traverses(int f, int v, int w) const {
    const auto& t = tri[f];
    return (t[0] == v && t[1] == w) || (t[1] == v && t[2] == w) || (t[2] == v && t[0] == w);
  }
  Eigen::Vector3d face_normal(int f) const;  //!< unit (zero for degenerate faces)
  double face_area(int f) const;

  // ---- Local operations --------------------------------------------------------------------
  // Each undo restores the faces' corners and which faces are live, but not the order of the
  // vertices' face lists: a caller that keeps anything ordered by them (a ring's starting face)
  // must treat an undone operation as a reordering.

  //! The quad of v-w, oriented from v to w; nullopt unless v-w has exactly two faces with
  //! different opposite corners.
  std::optional<EdgeQuad> quad(int v, int w) const;
  //! The quad of v-w when its faces are oriented alike (f1 runs v -> w and f2 w -> v), as on a
  //! consistently oriented surface; nullopt otherwise.
  std::optional<EdgeQuad> oriented_quad(int v, int w) const;
  //! Turns v-w into the quad's other diagonal a-b: f1 becomes (v, b, a) and f2 (w, a, b), each
  //! keeping the slots of the corners it keeps. nullopt, and nothing changed, when v-w has no
  //! quad or a-b is an edge already (a flip would duplicate it).
  std::optional<EdgeQuad> flip(int v, int w);
  //! The same flip of a quad the caller already has (from quad(), with no change of these
  //! faces since, and a-b not an edge): callers that test the quad before flipping do not
  //! look it up twice.
  void flip(const EdgeQuad& q);
  void undo(const EdgeQuad& flipped);

  //! Splits v-w at u (a vertex the caller added, with no faces yet); every face of the edge is
  //! halved. An edge without faces gives an empty split.
  EdgeSplit split(int v, int w, int u);
  //! Undoes a split; u is left live without faces (the caller that added it removes it).
  void undo(const EdgeSplit& split);

  //! The generalised link condition for collapsing v-w (Dey, Edelsbrunner, Guha, Nekhayev 1999,
  //! for non-manifold edges): every common neighbour of v and w is the opposite corner of a face
  //! of the edge. `nv`, `nw` are v's and w's neighbours and `star` the edge's faces, in any
  //! order (the callers have them already: edge_faces / neighbours lists or sorted vectors).
  bool link_condition(int v, int w, std::span<const int> star, std::span<const int> nv,
                      std::span<const int> nw) const;
  //! Merges v into w: the faces of v-w are removed and v's other faces get w instead. v keeps no
  //! faces and stays live until the caller, keeping the collapse, removes it (remove_vertex).
  EdgeCollapse collapse(int v, int w);
  void undo(const EdgeCollapse& collapsed);

  //! Puts v's face list in increasing order. Undone operations restore the faces but not the
  //! order of the lists; a caller that rolls trials back sorts the lists they touched, so that
  //! what it does next does not depend on the trials.
  void sort_faces(int v) { vfaces[v].sort(); }
  //! Takes the arrays back to `faces` faces and `vertices` vertices, as they were before a
  //! trial added more: every face from `faces` on must be dead and every vertex from
  //! `vertices` on without faces (what undoing each operation of the trial leaves). A caller
  //! that tries and rolls back many candidates keeps its indices from growing with them.
  void truncate(std::size_t faces, std::size_t vertices);

  //! Drops dead vertices and faces from the arrays: the live ones keep their order and each
  //! vertex's face list is rebuilt in face order. Returns the old -> new vertex map (-1 for a
  //! dropped vertex). A live vertex without faces is kept.
  std::vector<int> compact();

  //! Live parts only, labels kept; `old_to_new` receives the vertex map (-1 for dead).
  Mesh to_mesh(std::vector<int>* old_to_new = nullptr) const;

 private:
  void forget_valences(int f);  // the corners of face f
  int count_neighbours(int v) const;
  int live_vertices_ = 0, live_faces_ = 0;
  mutable std::vector<int> valence_cache_;  // per vertex, -1: not known
};

//! The faces of `star` (faces with corner v, in any order) outside its largest wedge: faces are
//! in one wedge when joined, through faces of `star`, across edges that end at v. Several
//! wedges make v a pinch (a bow-tie); the first largest is kept, the others' faces are returned
//! in `star` order (empty for a manifold vertex).
std::vector<int> faces_off_largest_wedge(std::span<const std::array<int, 3>> tri,
                                         std::span<const int> star, int v);

// The adjacency queries are inline: the remesher asks for them millions of times per run
// from another translation unit.

inline EdgeFaceList TriangleMesh::edge_faces(int v, int w) const {
  EdgeFaceList out;
  for (int f : vfaces[v]) {
    const auto& t = tri[f];
    if (t[0] == w || t[1] == w || t[2] == w) out.push_back(f);
  }
  return out;
}

inline int TriangleMesh::edge_face_count(int v, int w) const {
  int n = 0;
  for (int f : vfaces[v]) {
    const auto& t = tri[f];
    n += (t[0] == w || t[1] == w || t[2] == w) ? 1 : 0;
  }
  return n;
}

inline NeighbourList TriangleMesh::neighbours(int v) const {
  NeighbourList out;
  for (int f : vfaces[v])
    for (int c : tri[f])
      if (c != v && std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
  return out;
}

inline int TriangleMesh::valence(int v) const {
  if (v >= static_cast<int>(valence_cache_.size())) return count_neighbours(v);
  int& cached = valence_cache_[v];
  if (cached < 0) cached = count_neighbours(v);
  return cached;
}

inline int TriangleMesh::opposite(int f, int v, int w) const {
  for (int c : tri[f])
    if (c != v && c != w) return c;
  return -1;
}

}  // namespace scanmesh::kernel
