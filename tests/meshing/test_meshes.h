// Small hand-made meshes shared by the meshing tests.
#pragma once

#include "scanmesh/core/mesh.h"

namespace scanmesh::test {

//! The closed unit tetrahedron, faces counter-clockwise seen from outside (chi = 2).
inline Mesh tetrahedron() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  return m;
}

}  // namespace scanmesh::test
