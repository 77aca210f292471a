// Shared fixtures of the animation-mesh tests: analytic range grids whose surface is known.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>

#include "scanmesh/core/range_grid.h"
#include "scanmesh/meshing/aft/animation_lines.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/reconstruction/scan_surface.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh_test_paths.h"

namespace scanmesh::aft::test {

//! A 512 x 400 grid of r(phi, h) = radius + bump * sin(3 phi) * sin(h / 20), all cells valid.
inline RangeGrid cylinder_grid(double radius = 100.0, double bump = 0.0, int n_phi = 512,
                               int n_h = 400, double dh = 0.5) {
  RangeGrid g(n_phi, n_h, 0.0, 0.0, dh);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      const double r = radius + bump * std::sin(3 * g.phi(i)) * std::sin(g.h(j) / 20.0);
      g.set_sample(i, j, static_cast<float>(r));
    }
  return g;
}

//! The sample input of issue 4: the ideal head scan, configs/sim/head-lines.svg and
//! head-regions.yaml (settings read, not yet applied).
struct SampleHead {
  sim::SimulatedScan scan = sim::simulate_scan(
      sim::builtin_head_scene(),
      sim::ScannerConfig::from_yaml_file(std::string(SCANMESH_SOURCE_DIR) +
                                         "/configs/sim/head-scanner-ideal.yaml"));
  ScanSurface surface{scan.grid};
  LineSet lines =
      read_lines(std::string(SCANMESH_SOURCE_DIR) + "/configs/sim/head-lines.svg", scan.grid.n_h());
  RegionSettings settings = read_region_settings(
      std::string(SCANMESH_SOURCE_DIR) + "/configs/sim/head-regions.yaml", scan.grid.n_h());
};

//! What every stitched animation mesh must be, checked from the region graph, independently
//! of the mesh's own line-edge list: every segment with a meshed side is a complete chain of
//! mesh edges (no node dropped), with two faces along it where both sides are meshed (an
//! internal line: both sides of it), one where the other side is an opening or outside; the
//! faces are consistently oriented; every seam's node list is a chain of mesh edges.
inline void expect_lines_are_edge_chains(const RegionGraph& graph, const AnimationMesh& am) {
  const Mesh& m = am.mesh;
  std::map<std::uint64_t, int> faces_of_edge;
  const auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
           static_cast<std::uint32_t>(std::max(a, b));
  };
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) ++faces_of_edge[key(t[k], t[(k + 1) % 3])];
  const auto faces = [&](int a, int b) {
    const auto it = faces_of_edge.find(key(a, b));
    return it == faces_of_edge.end() ? 0 : it->second;
  };
  const auto meshed = [&](int r) { return r >= 0 && !graph.regions[r].opening; };
  ASSERT_EQ(am.segment_chains.size(), graph.segments.size());
  for (std::size_t s = 0; s < graph.segments.size(); ++s) {
    const Segment& seg = graph.segments[s];
    const int sides = meshed(seg.left_region) + meshed(seg.right_region);
    if (sides == 0) continue;
    const std::vector<int>& chain = am.segment_chains[s];
    ASSERT_GE(chain.size(), 2u) << "segment " << s;
    for (std::size_t k = 0; k < chain.size(); ++k) {
      ASSERT_GE(chain[k], 0) << "segment " << s << " lost node " << k;
      if (k == 0) continue;
      EXPECT_EQ(faces(chain[k - 1], chain[k]), sides)
          << "segment " << s << " edge " << k << " (regions " << seg.left_region << ", "
          << seg.right_region << ")";
    }
  }
  EXPECT_EQ(check_mesh(m).topology.inconsistent_edges, 0u);
  for (const auto& [id, list] : am.seams) {
    ASSERT_GE(list.size(), 2u) << id;
    for (std::size_t k = 1; k < list.size(); ++k) {
      ASSERT_GE(list[k - 1], 0) << id;
      ASSERT_GE(list[k], 0) << id;
      EXPECT_GT(faces(list[k - 1], list[k]), 0) << "seam " << id << " node " << k;
    }
  }
}

}  // namespace scanmesh::aft::test
