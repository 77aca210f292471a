// Shared fixtures of the animation-mesh tests: analytic range grids whose surface is known.
#pragma once

#include <cmath>

#include "scanmesh/core/range_grid.h"

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

}  // namespace scanmesh::aft::test
