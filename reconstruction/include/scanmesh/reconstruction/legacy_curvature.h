// Seed 000's discrete curvature operators, kept faithfully for comparison (seed 000 §5.1.2,
// Abb. 5.6 / 5.7, §6.1.2). Legacy: not the default anywhere; docs/reconstruction.md compares
// them with the continuous-surface curvature.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "scanmesh/core/range_grid.h"

namespace scanmesh {

//! Discrete curve curvature at P_i: (pi - angle(P_{i+s}, P_i, P_{i-s})) / (|P_{i+s} - P_i| +
//! |P_i - P_{i-s}|), s = stencil (seed 000 Abb. 5.6 uses s = 1, §6.1.2 uses s = 2). Entries
//! closer than s to an open curve's ends are 0; `closed` wraps around.
std::vector<double> discrete_curve_curvature(const std::vector<Eigen::Vector3d>& points,
                                             int stencil = 2, bool closed = false);

//! Seed 000's maximum surface curvature at every valid cell: in the 7 x 7 (phi, h)
//! neighbourhood of B, the 12 directions A_i - B - C_i through the 24 border cells (A_i and
//! C_i opposite), value = max_i (pi - angle A_i B C_i) / (|A_i B| + |B C_i|) with 3D points.
//! The printed formula has the angle itself in the numerator; pi - angle is the deviation
//! from a straight line, which the curve operator uses (gap decided in
//! docs/reconstruction.md). Directions with an invalid end are skipped; cells with no complete
//! direction get 0 and defined = false.
struct MaxCurvatureMap {
  std::vector<float> value;            //!< 1/mm, RangeGrid::index order
  std::vector<std::uint8_t> defined;
};
MaxCurvatureMap seed000_max_curvature(const RangeGrid& grid);

}  // namespace scanmesh
