// Seed 000's discrete curvature operators (seed 000 §5.1.2, Abb. 5.6 / 5.7, §6.1.2), kept as
// printed except for the numerator of the surface operator (pi - angle, see the header and
// docs/reconstruction.md, "Seed 000 legacy operators").
//
// Both operators measure the turning angle at the middle point over the two chord lengths. On a
// circle of radius R that is (s dtheta) / (2 * 2R sin(s dtheta / 2)) -> 1 / (2R): the operators
// estimate HALF the curvature. That is the seed's formula, kept; docs/reconstruction.md says so.
#include "scanmesh/reconstruction/legacy_curvature.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

// (pi - angle A B C) / (|AB| + |BC|); nullopt-like -1 when a chord is degenerate.
double turning_over_length(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c) {
  const Eigen::Vector3d ba = a - b, bc = c - b;
  const double la = ba.norm(), lc = bc.norm();
  if (!(la > 0.0) || !(lc > 0.0)) return -1.0;
  // atan2 of |cross| and dot: accurate for angles near 0 and pi, where acos is not.
  const double angle = std::atan2(ba.cross(bc).norm(), ba.dot(bc));
  return (std::numbers::pi - angle) / (la + lc);
}

// The 12 directions of Abb. 5.7: one cell of each opposite pair on the border of the 7 x 7
// ring (24 cells). (3, -3..3) covers the right column, (-2..2, 3) the top row without the
// corners; the partners are the negated offsets.
struct Offset {
  int di, dj;
};
constexpr std::array<Offset, 12> kDirections = {Offset{3, -3}, {3, -2}, {3, -1}, {3, 0},
                                                {3, 1},        {3, 2},  {3, 3},  {-2, 3},
                                                {-1, 3},       {0, 3},  {1, 3},  {2, 3}};

}  // namespace

std::vector<double> discrete_curve_curvature(const std::vector<Eigen::Vector3d>& points,
                                             int stencil, bool closed) {
  if (stencil < 1)
    throw InvalidInputError("discrete curve curvature: stencil must be >= 1, got " +
                            std::to_string(stencil));
  const int n = static_cast<int>(points.size());
  std::vector<double> k(points.size(), 0.0);
  if (closed && n < 3) return k;
  for (int i = 0; i < n; ++i) {
    int prev = i - stencil, next = i + stencil;
    if (closed) {
      prev = ((prev % n) + n) % n;
      next = next % n;
    } else if (prev < 0 || next >= n) {
      continue;
    }
    k[i] = std::max(0.0, turning_over_length(points[next], points[i], points[prev]));
  }
  return k;
}

MaxCurvatureMap seed000_max_curvature(const RangeGrid& grid) {
  const int n_phi = grid.n_phi(), n_h = grid.n_h();
  MaxCurvatureMap out;
  out.value.assign(grid.cell_count(), 0.0f);
  out.defined.assign(grid.cell_count(), 0);

  // cos / sin per column once, instead of 25 trig pairs per cell.
  std::vector<double> cos_phi(n_phi), sin_phi(n_phi);
  for (int i = 0; i < n_phi; ++i) {
    cos_phi[i] = std::cos(grid.phi(i));
    sin_phi[i] = std::sin(grid.phi(i));
  }
  const auto point = [&](int i, int j) {
    const double r = grid.radius(i, j);
    return Eigen::Vector3d(r * cos_phi[i], r * sin_phi[i], grid.h(j));
  };

#pragma omp parallel for schedule(static)
  for (int j = 0; j < n_h; ++j) {
    for (int i = 0; i < n_phi; ++i) {
      if (!grid.valid(i, j)) continue;
      const Eigen::Vector3d b = point(i, j);
      double best = -1.0;
      for (const auto& d : kDirections) {
        const int ja = j + d.dj, jc = j - d.dj;
        if (ja < 0 || ja >= n_h || jc < 0 || jc >= n_h) continue;  // h does not wrap
        const int ia = grid.wrap_phi(i + d.di), ic = grid.wrap_phi(i - d.di);
        if (!grid.valid(ia, ja) || !grid.valid(ic, jc)) continue;
        best = std::max(best, turning_over_length(point(ia, ja), b, point(ic, jc)));
      }
      if (best < 0.0) continue;  // no complete direction
      const std::size_t k = grid.index(i, j);
      out.value[k] = static_cast<float>(best);
      out.defined[k] = 1;
    }
  }
  return out;
}

}  // namespace scanmesh
