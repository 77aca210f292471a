// The meshing kernel's union-find over vertex indices, joined triangle by triangle: the
// connected components of a triangle mesh through shared vertices (two pieces touching at one
// vertex are one component, as the Euler formula of a pinched surface needs). Shared by the
// topology statistics, the scan clean-up, the spring network and the fans' orientation.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace scanmesh::kernel {

class VertexComponents {
 public:
  explicit VertexComponents(std::size_t vertices) : parent_(vertices) {
    for (std::size_t i = 0; i < vertices; ++i) parent_[i] = static_cast<int>(i);
  }
  void join(const std::array<int, 3>& t) {
    parent_[root(t[1])] = root(t[0]);
    parent_[root(t[2])] = root(t[0]);
  }
  //! The representative of x's component (path halving: later look-ups are shorter).
  int root(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace scanmesh::kernel
