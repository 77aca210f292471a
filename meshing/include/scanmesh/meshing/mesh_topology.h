// Edge-based topology statistics of a triangle mesh: what a watertightness or hole check needs.
#pragma once

#include <cstddef>
#include <vector>

#include "scanmesh/core/mesh.h"

namespace scanmesh {

struct TopologyStats {
  std::size_t edges = 0;
  std::size_t boundary_edges = 0;      //!< edges with exactly one face
  std::size_t manifold_edges = 0;      //!< edges with exactly two faces
  std::size_t nonmanifold_edges = 0;   //!< edges with more than two faces
  std::size_t inconsistent_edges = 0;  //!< two faces traversing the edge in the same direction
  std::size_t boundary_loops = 0;
  std::vector<std::size_t> boundary_loop_lengths;  //!< in edges, longest first
  std::size_t border_ears = 0;  //!< faces with two or three boundary edges
  std::size_t unreferenced_vertices = 0;
  long long euler_characteristic = 0;  //!< V - E + F over referenced vertices
  std::size_t components = 0;          //!< groups of faces joined through shared vertices
  //! Handles, from chi = 2 components - 2 genus - loops; meaningful for a manifold, oriented
  //! mesh (the checker prints it only then).
  long long genus() const {
    return (2 * static_cast<long long>(components) - euler_characteristic -
            static_cast<long long>(boundary_loops)) /
           2;
  }
};

TopologyStats topology_stats(const Mesh& mesh);

}  // namespace scanmesh
