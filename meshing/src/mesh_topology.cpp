#include "scanmesh/meshing/mesh_topology.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <unordered_map>

#include "scanmesh/meshing/edge_key.h"

#include "kernel/vertex_components.h"

namespace scanmesh {

namespace {

struct EdgeUse {
  int faces = 0;
  int forward = 0;  // uses in the direction lo -> hi
};

// Boundary loops: follow boundary half-edges head to tail. At a vertex where several boundary
// loops touch, any continuation is taken; the loop count is still exact per traversal.
void count_loops(const std::vector<std::pair<int, int>>& boundary, TopologyStats& stats) {
  std::unordered_multimap<int, std::size_t> by_start;
  for (std::size_t k = 0; k < boundary.size(); ++k) by_start.emplace(boundary[k].first, k);
  std::vector<bool> used(boundary.size(), false);
  for (std::size_t start = 0; start < boundary.size(); ++start) {
    if (used[start]) continue;
    std::size_t length = 0, k = start;
    while (true) {
      used[k] = true;
      ++length;
      auto [it, end] = by_start.equal_range(boundary[k].second);
      std::size_t next = boundary.size();
      for (; it != end; ++it)
        if (!used[it->second]) {
          next = it->second;
          break;
        }
      if (next == boundary.size()) break;
      k = next;
    }
    ++stats.boundary_loops;
    stats.boundary_loop_lengths.push_back(length);
  }
  std::sort(stats.boundary_loop_lengths.begin(), stats.boundary_loop_lengths.end(),
            std::greater<>());
}

// Faces joined through shared vertices (union-find over the vertices); a component touching
// another only at a vertex counts once, as the Euler formula of a pinched surface needs.
std::size_t count_components(const Mesh& mesh, const std::vector<bool>& referenced) {
  kernel::VertexComponents components(mesh.positions.size());
  for (const auto& t : mesh.triangles) components.join(t);
  std::size_t roots = 0;
  for (std::size_t i = 0; i < referenced.size(); ++i)
    if (referenced[i] && components.root(static_cast<int>(i)) == static_cast<int>(i)) ++roots;
  return roots;
}

}  // namespace

TopologyStats topology_stats(const Mesh& mesh) {
  TopologyStats stats;
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(mesh.triangles.size() * 2);
  std::vector<bool> referenced(mesh.positions.size(), false);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      referenced[a] = true;
      EdgeUse& use = edges[edge_key(a, b)];
      ++use.faces;
      use.forward += a < b;
    }
  std::vector<std::pair<int, int>> boundary;  // as half-edges, in face orientation
  for (const auto& t : mesh.triangles) {
    int border_sides = 0;
    for (int k = 0; k < 3; ++k)
      if (edges[edge_key(t[k], t[(k + 1) % 3])].faces == 1) {
        boundary.emplace_back(t[k], t[(k + 1) % 3]);
        ++border_sides;
      }
    stats.border_ears += border_sides >= 2;
  }
  for (const auto& [key, use] : edges) {
    if (use.faces == 1) ++stats.boundary_edges;
    if (use.faces == 2) {
      ++stats.manifold_edges;
      if (use.forward != 1) ++stats.inconsistent_edges;
    }
    if (use.faces > 2) ++stats.nonmanifold_edges;
  }
  stats.edges = edges.size();
  const auto used_vertices =
      static_cast<long long>(std::count(referenced.begin(), referenced.end(), true));
  stats.unreferenced_vertices = mesh.positions.size() - static_cast<std::size_t>(used_vertices);
  stats.euler_characteristic = used_vertices - static_cast<long long>(stats.edges) +
                               static_cast<long long>(mesh.triangles.size());
  count_loops(boundary, stats);
  stats.components = count_components(mesh, referenced);
  return stats;
}

}  // namespace scanmesh
