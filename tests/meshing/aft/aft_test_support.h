// Shared fixtures of the animation-mesh tests: analytic range grids whose surface is known.
#pragma once

#include <cmath>
#include <string>

#include "scanmesh/core/range_grid.h"
#include "scanmesh/meshing/aft/animation_lines.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/reconstruction/scan_surface.h"
#include "scanmesh/sim/range_scanner.h"

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
  LineSet lines = read_lines(std::string(SCANMESH_SOURCE_DIR) + "/configs/sim/head-lines.svg");
  RegionSettings settings =
      read_region_settings(std::string(SCANMESH_SOURCE_DIR) + "/configs/sim/head-regions.yaml");
};

}  // namespace scanmesh::aft::test
