// The meshing kernel's mesh: adjacency after each local operation, undo, refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <stdexcept>
#include <vector>

#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/kernel/triangle_mesh.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "test_meshes.h"

namespace scanmesh::kernel {
namespace {

using Eigen::Vector3d;

// The unit square split along 0-2: faces (0, 1, 2) and (0, 2, 3), both facing +z.
TriangleMesh unit_square() {
  const std::vector<std::array<int, 3>> t{{0, 1, 2}, {0, 2, 3}};
  return TriangleMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, t);
}

// A regular hexagon around vertex 0 (ring 1..6), six faces facing +z.
TriangleMesh hexagon_fan() {
  std::vector<Vector3d> p{{0, 0, 0}};
  std::vector<std::array<int, 3>> t;
  for (int i = 0; i < 6; ++i) {
    p.emplace_back(std::cos(i * M_PI / 3), std::sin(i * M_PI / 3), 0.0);
    t.push_back({0, 1 + i, 1 + (i + 1) % 6});
  }
  return TriangleMesh(p, t);
}

// The live faces as sorted corner triples in a canonical rotation (smallest corner first, the
// cyclic order kept), so that two meshes compare equal when they hold the same oriented faces.
std::vector<std::array<int, 3>> oriented_faces(const TriangleMesh& m) {
  std::vector<std::array<int, 3>> out;
  for (std::size_t f = 0; f < m.tri.size(); ++f) {
    if (!m.face_alive[f]) continue;
    auto t = m.tri[f];
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Every live face of v lists v, and every corner of a live face lists the face once.
void expect_adjacency_consistent(const TriangleMesh& m) {
  for (std::size_t f = 0; f < m.tri.size(); ++f)
    for (int c : m.tri[f]) {
      const auto n = std::count(m.vfaces[c].begin(), m.vfaces[c].end(), static_cast<int>(f));
      EXPECT_EQ(n, m.face_alive[f] ? 1 : 0) << "face " << f << " corner " << c;
    }
  for (std::size_t v = 0; v < m.vfaces.size(); ++v)
    for (int f : m.vfaces[v]) {
      EXPECT_TRUE(m.face_alive[f]);
      EXPECT_NE(std::find(m.tri[f].begin(), m.tri[f].end(), static_cast<int>(v)), m.tri[f].end());
    }
}

double total_area(const TriangleMesh& m) {
  double a = 0;
  for (std::size_t f = 0; f < m.tri.size(); ++f)
    if (m.face_alive[f]) a += m.face_area(static_cast<int>(f));
  return a;
}

bool all_faces_up(const TriangleMesh& m) {
  for (std::size_t f = 0; f < m.tri.size(); ++f)
    if (m.face_alive[f] && !(m.face_normal(static_cast<int>(f)).z() > 0.99)) return false;
  return true;
}

TEST(KernelTriangleMesh, QuadIsOrientedFromVToW) {
  const TriangleMesh m = unit_square();
  const auto q = m.quad(2, 0);
  ASSERT_TRUE(q);
  EXPECT_EQ(q->v, 2);
  EXPECT_EQ(q->w, 0);
  // f1 runs 2 -> 0: that is (0, 1, 2), whose third corner is 1.
  EXPECT_EQ(q->f1, 0);
  EXPECT_EQ(q->a, 1);
  EXPECT_EQ(q->f2, 1);
  EXPECT_EQ(q->b, 3);
  EXPECT_FALSE(m.quad(0, 1));  // a border edge has no quad
  EXPECT_TRUE(m.traverses(0, 2, 0));
  EXPECT_FALSE(m.traverses(0, 0, 2));
  EXPECT_TRUE(m.oriented_quad(2, 0));
  // The second face turned over: both still hold 0-2, but not as one oriented surface.
  const std::vector<std::array<int, 3>> turned{{0, 1, 2}, {0, 3, 2}};
  const TriangleMesh t({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, turned);
  EXPECT_TRUE(t.quad(2, 0));
  EXPECT_FALSE(t.oriented_quad(2, 0));
}

TEST(KernelTriangleMesh, FlipTurnsTheDiagonalAndUndoRestoresIt) {
  TriangleMesh m = unit_square();
  const auto before = oriented_faces(m);
  const auto flipped = m.flip(0, 2);
  ASSERT_TRUE(flipped);
  EXPECT_EQ(m.edge_face_count(0, 2), 0);
  EXPECT_EQ(m.edge_face_count(1, 3), 2);
  EXPECT_TRUE(all_faces_up(m));
  EXPECT_NEAR(total_area(m), 1.0, 1e-15);
  EXPECT_EQ(m.valence(0), 2);
  EXPECT_EQ(m.valence(1), 3);
  expect_adjacency_consistent(m);
  const auto flipped_faces = oriented_faces(m);
  m.put_first(flipped->f1, flipped->a);  // the same face, started elsewhere
  EXPECT_EQ(m.tri[flipped->f1][0], flipped->a);
  EXPECT_EQ(oriented_faces(m), flipped_faces);
  m.undo(*flipped);
  EXPECT_EQ(oriented_faces(m), before);
  EXPECT_EQ(m.valence(0), 3);
  expect_adjacency_consistent(m);
}

TEST(KernelTriangleMesh, FlipRefusesWhatWouldDuplicateAnEdge) {
  // Every diagonal of a tetrahedron's quads is an edge already.
  const Mesh tet = test::tetrahedron();
  TriangleMesh m(tet);
  const auto before = oriented_faces(m);
  EXPECT_TRUE(m.quad(0, 1));
  EXPECT_FALSE(m.flip(0, 1));
  EXPECT_EQ(oriented_faces(m), before);
}

TEST(KernelTriangleMesh, SplitHalvesEveryFaceOfAnInteriorEdge) {
  TriangleMesh m = unit_square();
  const auto before = oriented_faces(m);
  const int u = m.add_vertex({0.5, 0.5, 0});
  const EdgeSplit s = m.split(0, 2, u);
  EXPECT_EQ(s.changed.size(), 2u);
  EXPECT_EQ(s.added.size(), 2u);
  EXPECT_EQ(m.face_count(), 4);
  EXPECT_EQ(m.valence(u), 4);
  EXPECT_EQ(m.edge_face_count(0, 2), 0);
  EXPECT_EQ(m.edge_face_count(0, u), 2);
  EXPECT_EQ(m.edge_face_count(u, 2), 2);
  EXPECT_TRUE(all_faces_up(m));
  EXPECT_NEAR(total_area(m), 1.0, 1e-15);
  expect_adjacency_consistent(m);
  m.undo(s);
  EXPECT_EQ(oriented_faces(m), before);
  EXPECT_TRUE(m.vfaces[u].empty());
  expect_adjacency_consistent(m);
}

TEST(KernelTriangleMesh, ATrialRolledBackLeavesTheArraysAsBefore) {
  // A trial as the AFT's small-angle repair makes one: split, then flip at the new vertex,
  // both undone; truncate drops what the trial added, sort_faces gives the lists their order.
  TriangleMesh m = hexagon_fan();
  const auto before = oriented_faces(m);
  const std::size_t faces = m.tri.size(), vertices = m.vfaces.size();
  const int u = m.add_vertex({0.5, 0.0, 0});
  const EdgeSplit s = m.split(0, 1, u);
  const auto flipped = m.flip(u, 2);
  ASSERT_TRUE(flipped);
  m.undo(*flipped);
  m.undo(s);
  EXPECT_THROW(m.truncate(faces, vertices - 1), std::logic_error);  // vertex 6 has faces
  m.truncate(faces, vertices);
  EXPECT_EQ(m.tri.size(), faces);
  EXPECT_EQ(m.vfaces.size(), vertices);
  EXPECT_EQ(m.vertex_count(), 7);
  EXPECT_EQ(oriented_faces(m), before);
  for (int v = 0; v < 7; ++v) m.sort_faces(v);
  for (int v = 0; v < 7; ++v) EXPECT_TRUE(std::is_sorted(m.vfaces[v].begin(), m.vfaces[v].end()));
  expect_adjacency_consistent(m);
  // A live face past the mark is refused: the caller has not undone everything.
  const int w = m.add_vertex({0.5, 0.0, 0});
  m.split(0, 1, w);
  EXPECT_THROW(m.truncate(faces, vertices), std::logic_error);
}

TEST(KernelTriangleMesh, SplitOfANonManifoldEdgeHalvesEachPage) {
  // Three pages on the edge 0-1 (a seam of the remesher's inputs).
  const std::vector<std::array<int, 3>> t{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  TriangleMesh m({{0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, -1, 0}, {1, 0, 1}}, t);
  EXPECT_EQ(m.edge_faces(0, 1).size(), 3u);
  EXPECT_FALSE(m.quad(0, 1));  // no flip across a seam
  const int u = m.add_vertex({1, 0, 0});
  const EdgeSplit s = m.split(0, 1, u);
  EXPECT_EQ(s.added.size(), 3u);
  EXPECT_EQ(m.edge_face_count(0, u), 3);
  EXPECT_EQ(m.edge_face_count(u, 1), 3);
  EXPECT_EQ(m.face_count(), 6);
  expect_adjacency_consistent(m);
}

TEST(KernelTriangleMesh, CollapseMergesVIntoWAndUndoRestores) {
  TriangleMesh m = hexagon_fan();
  const auto before = oriented_faces(m);
  const int v = 1, w = 0;  // a rim vertex into the centre
  const auto star = m.edge_faces(v, w);
  EXPECT_TRUE(m.link_condition(v, w, star, m.neighbours(v), m.neighbours(w)));
  const EdgeCollapse c = m.collapse(v, w);
  EXPECT_EQ(c.removed.size(), 2u);
  EXPECT_EQ(m.face_count(), 4);
  EXPECT_TRUE(m.vfaces[v].empty());
  EXPECT_EQ(m.valence(w), 5);
  const Mesh after = m.to_mesh();
  const TopologyStats st = topology_stats(after);
  EXPECT_EQ(st.euler_characteristic, 1);  // still a disc
  EXPECT_EQ(st.nonmanifold_edges, 0u);
  expect_adjacency_consistent(m);
  m.undo(c);
  EXPECT_EQ(oriented_faces(m), before);
  expect_adjacency_consistent(m);
}

TEST(KernelTriangleMesh, LinkConditionSeesACommonNeighbourOffTheEdge) {
  // 0 and 1 share the faces (0, 1, 2) and (1, 0, 3), and also the neighbour 4 through faces
  // that do not contain the edge: collapsing 0-1 would pinch the surface at 4.
  const std::vector<std::array<int, 3>> t{{0, 1, 2}, {1, 0, 3}, {0, 4, 5}, {1, 6, 4}};
  const TriangleMesh m(
      {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 2}, {-1, 0, 2}, {2, 0, 2}}, t);
  EXPECT_FALSE(m.link_condition(0, 1, m.edge_faces(0, 1), m.neighbours(0), m.neighbours(1)));
  EXPECT_TRUE(m.link_condition(0, 2, m.edge_faces(0, 2), m.neighbours(0), m.neighbours(2)));
}

TEST(KernelTriangleMesh, CompactDropsTheDeadAndKeepsTheOrder) {
  TriangleMesh m = hexagon_fan();
  const EdgeCollapse c = m.collapse(1, 0);
  m.remove_vertex(1);
  const auto faces_before = m.to_mesh().triangles;
  const std::vector<int> map = m.compact();
  ASSERT_EQ(map.size(), 7u);
  EXPECT_EQ(map[0], 0);
  EXPECT_EQ(map[1], -1);
  EXPECT_EQ(map[2], 1);
  EXPECT_EQ(m.pos.size(), 6u);
  EXPECT_EQ(m.tri.size(), 4u);
  EXPECT_EQ(m.face_count(), 4);
  EXPECT_EQ(m.vertex_count(), 6);
  EXPECT_EQ(m.to_mesh().triangles, faces_before);  // same faces, same order
  EXPECT_EQ(m.valence(0), 5);
  for (std::size_t v = 0; v < m.vfaces.size(); ++v)
    EXPECT_TRUE(std::is_sorted(m.vfaces[v].begin(), m.vfaces[v].end()));
  expect_adjacency_consistent(m);
  (void)c;
}

TEST(KernelTriangleMesh, ConstructionRefusesBadTriangles) {
  const std::vector<Vector3d> p{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<std::array<int, 3>> repeated{{0, 1, 1}}, out_of_range{{0, 1, 3}};
  EXPECT_THROW(TriangleMesh(p, repeated), InvalidInputError);
  EXPECT_THROW(TriangleMesh(p, out_of_range), InvalidInputError);
  try {
    TriangleMesh(p, repeated, "remesh");
    ADD_FAILURE() << "a repeated corner was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_STREQ(e.what(), "remesh: triangle 0 repeats a corner");  // says who read it
  }
  const std::vector<std::array<int, 3>> one{{0, 1, 2}};
  const TriangleMesh m(std::vector<Vector3d>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}}, one);
  EXPECT_EQ(m.vertex_count(), 3);  // the vertex in no triangle is not live
}

TEST(KernelSmallIndexList, EraseKeepsTheOrderAcrossTheInlineLimit) {
  // Twelve faces spill a seven-place list to the heap; erasing from the front, the middle and
  // the back must give what a std::vector gives, also when the list moves back in place.
  VertexFaceList list;
  std::vector<int> expected;
  for (int f = 0; f < 12; ++f) {
    list.push_back(10 * f);
    expected.push_back(10 * f);
  }
  for (const std::size_t at : {0u, 5u, 9u, 3u, 0u, 6u, 2u, 1u, 0u, 2u, 1u, 0u}) {
    list.erase(list.begin() + at);
    expected.erase(expected.begin() + static_cast<std::ptrdiff_t>(at));
    ASSERT_EQ(std::vector<int>(list), expected) << "after erasing place " << at;
  }
  EXPECT_TRUE(list.empty());
  list.push_back(7);
  EXPECT_EQ(std::vector<int>(list), std::vector<int>{7});
}

TEST(KernelWedges, APinchVertexKeepsItsLargestWedge) {
  // Vertex 0 carries a fan of three faces (ring 1..4) and, touching it only at 0, a fan of two
  // (ring 5..7): the two faces of the smaller wedge are off, in the order given.
  const std::vector<Vector3d> p{{0, 0, 0},  {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                {-1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  const std::vector<std::array<int, 3>> t{{0, 1, 2}, {0, 5, 6}, {0, 2, 3}, {0, 6, 7}, {0, 3, 4}};
  const TriangleMesh m(p, t);
  const std::vector<int> star(m.vfaces[0].begin(), m.vfaces[0].end());
  EXPECT_EQ(faces_off_largest_wedge(m.tri, star, 0), (std::vector<int>{1, 3}));
  // A manifold fan has one wedge: nothing is off.
  const TriangleMesh fan = hexagon_fan();
  EXPECT_TRUE(faces_off_largest_wedge(fan.tri, fan.vfaces[0], 0).empty());
}

}  // namespace
}  // namespace scanmesh::kernel
