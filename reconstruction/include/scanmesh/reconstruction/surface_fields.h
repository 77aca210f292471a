// Per-cell normals and curvatures of a scan, by one of three methods (docs/reconstruction.md):
//   analytic     - from the continuous surface's derivatives at each node (default, exact data)
//   grid-quadric - least-squares quadratic of r(phi, h) over a window of cells, computed with
//                  separable running sums (noisy data, fast); 3D quadric next to holes
//   quadric      - least-squares quadric fit in 3D over a neighbourhood radius (noisy data)
//   seed000      - seed 000's 7x7 / 12-direction maximum-curvature operator (legacy; k1 only)
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "scanmesh/core/range_grid.h"

namespace scanmesh {

enum class CurvatureMethod { Analytic, Quadric, Seed000, GridQuadric };

//! Parses "analytic" | "grid-quadric" | "quadric" | "seed"/"seed000"; throws InvalidInputError
//! otherwise.
CurvatureMethod parse_curvature_method(const std::string& name);
std::string to_string(CurvatureMethod m);

//! Per-cell fields in RangeGrid::index order. `defined[k]` is 0 where the method had no
//! estimate (invalid cell, or neighbourhood incomplete); other fields are 0 there.
struct SurfaceFields {
  int n_phi = 0, n_h = 0;
  CurvatureMethod method = CurvatureMethod::Analytic;
  double radius_mm = 0;  //!< neighbourhood radius (quadric), 0 otherwise
  std::vector<std::uint8_t> defined;
  std::vector<Eigen::Vector3f> normal;
  std::vector<float> k1, k2;  //!< k1 >= k2; seed000 fills k1 (max curvature) and sets k2 = 0
  std::vector<Eigen::Vector3f> dir1, dir2;

  std::size_t size() const { return defined.size(); }
  float mean(std::size_t k) const { return 0.5f * (k1[k] + k2[k]); }
  float gauss(std::size_t k) const { return k1[k] * k2[k]; }
  std::size_t defined_count() const;
  void resize(int n_phi, int n_h);
};

struct QuadricOptions {
  double radius_mm = 6.0;   //!< neighbourhood radius around each cell (3D distance)
  int min_points = 12;      //!< fewer valid neighbours than this: undefined
};

SurfaceFields compute_fields_analytic(const RangeGrid& grid);
SurfaceFields compute_fields_quadric(const RangeGrid& grid, const QuadricOptions& options = {});

//! Least-squares quadratic r(u, v) = c0 + cu u + cv v + cuu u^2 + cuv uv + cvv v^2 over the
//! (2 Wu + 1) x (2 Wv + 1) cells around each node, Wv = radius / dh and Wu = radius / (r_median
//! dphi). On a full window the normal equations decouple into six separable running sums, so
//! the cost per cell is independent of the neighbourhood size's square. Cells whose window
//! touches a hole or the grid's top or bottom fall back to compute_fields_quadric's 3D fit.
SurfaceFields compute_fields_grid_quadric(const RangeGrid& grid, const QuadricOptions& options = {});

//! Dispatches on the method; `radius_mm` is used by the quadric methods only (<= 0: default).
SurfaceFields compute_fields(const RangeGrid& grid, CurvatureMethod method, double radius_mm = 0);

}  // namespace scanmesh
