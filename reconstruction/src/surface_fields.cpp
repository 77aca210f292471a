// Per-cell normals and curvatures: analytic (continuous surface) and quadric fit
// (docs/reconstruction.md). The seed 000 operator lives in legacy_curvature.cpp.
#include "scanmesh/reconstruction/surface_fields.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/legacy_curvature.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh {

namespace {

void store(SurfaceFields& f, std::size_t k, const SurfaceCurvature& c) {
  f.defined[k] = 1;
  f.normal[k] = c.normal.cast<float>();
  f.k1[k] = static_cast<float>(c.k1);
  f.k2[k] = static_cast<float>(c.k2);
  f.dir1[k] = c.dir1.cast<float>();
  f.dir2[k] = c.dir2.cast<float>();
}

// ---- quadric fit ------------------------------------------------------------------------

// Cartesian positions of all cells, computed once: the neighbour gathering below reads each
// cell hundreds of times, and recomputing cos/sin there dominated the run time.
std::vector<Eigen::Vector3d> cell_positions(const RangeGrid& grid) {
  std::vector<Eigen::Vector3d> p(grid.cell_count());
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i) p[grid.index(i, j)] = grid.cartesian(i, j);
  return p;
}

// Cells within radius_mm (3D) of cell (i, j), found through the organised grid: the index
// window is the radius divided by the local cell spacing, so no kd-tree is needed.
void gather_neighbours(const RangeGrid& grid, const std::vector<Eigen::Vector3d>& positions, int i,
                       int j, double radius_mm, std::vector<Eigen::Vector3d>& out) {
  out.clear();
  const Eigen::Vector3d& centre = positions[grid.index(i, j)];
  const double r = grid.radius(i, j);
  const int dj_max = static_cast<int>(std::ceil(radius_mm / grid.dh()));
  // Columns: arc length r * dphi per column; cap at a quarter turn for cells near the axis.
  const int di_max =
      std::min(grid.n_phi() / 4,
               static_cast<int>(std::ceil(radius_mm / (std::max(r, 1e-6) * grid.dphi()))) + 1);
  const double r2 = radius_mm * radius_mm;
  const auto& valid = grid.validity();
  for (int dj = -dj_max; dj <= dj_max; ++dj) {
    const int jj = j + dj;
    if (jj < 0 || jj >= grid.n_h()) continue;
    for (int di = -di_max; di <= di_max; ++di) {
      const std::size_t k = grid.index(grid.wrap_phi(i + di), jj);
      if (valid[k] && (positions[k] - centre).squaredNorm() <= r2) out.push_back(positions[k]);
    }
  }
}

// Fits w = a x^2 + b xy + c y^2 + d x + e y + f in the frame (t1, t2, n) at `origin` and
// returns the curvature of the fitted graph at (0, 0).
std::optional<SurfaceCurvature> fit_quadric(const std::vector<Eigen::Vector3d>& pts,
                                            const Eigen::Vector3d& origin, const Eigen::Vector3d& n,
                                            double radius_mm) {
  Eigen::Vector3d t1 = n.unitOrthogonal();
  Eigen::Vector3d t2 = n.cross(t1);
  // Scale coordinates by the radius so the normal equations are well conditioned.
  const double s = 1.0 / radius_mm;
  // The normal equations of the monomial basis only hold the moments sum x^a y^b (a + b <= 4)
  // and sum w x^a y^b (a + b <= 2): accumulate those instead of 6 x 6 outer products.
  double m[5][5] = {};   // m[a][b] = sum x^a y^b
  double mw[3][3] = {};  // mw[a][b] = sum w x^a y^b
  for (const auto& p : pts) {
    const Eigen::Vector3d q = (p - origin) * s;
    const double x = q.dot(t1), y = q.dot(t2), w = q.dot(n);
    const double xp[5] = {1, x, x * x, x * x * x, x * x * x * x};
    const double yp[5] = {1, y, y * y, y * y * y, y * y * y * y};
    for (int a = 0; a <= 4; ++a)
      for (int b = 0; a + b <= 4; ++b) m[a][b] += xp[a] * yp[b];
    for (int a = 0; a <= 2; ++a)
      for (int b = 0; a + b <= 2; ++b) mw[a][b] += w * xp[a] * yp[b];
  }
  // Basis order: x^2, xy, y^2, x, y, 1 as exponent pairs.
  static constexpr int kExp[6][2] = {{2, 0}, {1, 1}, {0, 2}, {1, 0}, {0, 1}, {0, 0}};
  Eigen::Matrix<double, 6, 6> ata;
  Eigen::Matrix<double, 6, 1> atb;
  for (int r = 0; r < 6; ++r) {
    atb(r) = mw[kExp[r][0]][kExp[r][1]];
    for (int c = 0; c < 6; ++c) ata(r, c) = m[kExp[r][0] + kExp[c][0]][kExp[r][1] + kExp[c][1]];
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(ata);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-10) return std::nullopt;
  const Eigen::Matrix<double, 6, 1> c = ldlt.solve(atb);
  // Back to millimetres: second-order terms scale by s, first-order terms are unitless.
  const double a = c(0) * s, b = c(1) * s, cc = c(2) * s, d = c(3), e = c(4);
  const double g = std::sqrt(1.0 + d * d + e * e);
  Eigen::Matrix2d first, second;
  first << 1 + d * d, d * e, d * e, 1 + e * e;
  // Graph over the tangent plane with n pointing outward: w'' < 0 is convex (k > 0).
  second << -2 * a / g, -b / g, -b / g, -2 * cc / g;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d> solver(second, first);
  SurfaceCurvature out;
  const Eigen::Vector3d du = t1 + d * n, dv = t2 + e * n;
  out.normal = du.cross(dv).normalized();
  out.k2 = solver.eigenvalues()(0);
  out.k1 = solver.eigenvalues()(1);
  const Eigen::Vector2d a1 = solver.eigenvectors().col(1), a2 = solver.eigenvectors().col(0);
  out.dir1 = (a1(0) * du + a1(1) * dv).normalized();
  out.dir2 = (a2(0) * du + a2(1) * dv).normalized();
  return out;
}

Eigen::Vector3d pca_normal(const std::vector<Eigen::Vector3d>& pts,
                           const Eigen::Vector3d& outward) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  Eigen::Vector3d n = solver.eigenvectors().col(0);
  return n.dot(outward) < 0 ? Eigen::Vector3d(-n) : n;
}

}  // namespace

SurfaceFields compute_fields_analytic(const RangeGrid& grid) {
  SurfaceFields f;
  f.resize(grid.n_phi(), grid.n_h());
  f.method = CurvatureMethod::Analytic;
  const ScanSurface surface(grid);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i) {
      const auto jet = surface.node_jet(i, j);
      if (jet) store(f, grid.index(i, j), lift(grid.phi(i), grid.h(j), *jet).curvature());
    }
  return f;
}

SurfaceFields compute_fields_quadric(const RangeGrid& grid, const QuadricOptions& options) {
  if (!(options.radius_mm > 0) || !std::isfinite(options.radius_mm))
    throw InvalidInputError("quadric curvature: neighbourhood radius must be positive, got " +
                            std::to_string(options.radius_mm) + " mm");
  if (options.min_points < 6)
    throw InvalidInputError(
        "quadric curvature: min_points must be >= 6 (a quadric has 6 "
        "coefficients), got " +
        std::to_string(options.min_points));
  SurfaceFields f;
  f.resize(grid.n_phi(), grid.n_h());
  f.method = CurvatureMethod::Quadric;
  f.radius_mm = options.radius_mm;
  const std::vector<Eigen::Vector3d> positions = cell_positions(grid);
#pragma omp parallel
  {
    std::vector<Eigen::Vector3d> pts;
#pragma omp for schedule(dynamic, 4)
    for (int j = 0; j < grid.n_h(); ++j)
      for (int i = 0; i < grid.n_phi(); ++i) {
        if (!grid.valid(i, j)) continue;
        gather_neighbours(grid, positions, i, j, options.radius_mm, pts);
        if (static_cast<int>(pts.size()) < options.min_points) continue;
        const Eigen::Vector3d& origin = positions[grid.index(i, j)];
        const Eigen::Vector3d outward(std::cos(grid.phi(i)), std::sin(grid.phi(i)), 0.0);
        // Two passes: the second fits in the frame of the first fit's normal, which makes the
        // height function flatter and the fit less biased on steep parts.
        auto c = fit_quadric(pts, origin, pca_normal(pts, outward), options.radius_mm);
        if (c) c = fit_quadric(pts, origin, c->normal, options.radius_mm);
        if (c) store(f, grid.index(i, j), *c);
      }
  }
  return f;
}

SurfaceFields compute_fields(const RangeGrid& grid, CurvatureMethod method, double radius_mm) {
  switch (method) {
    case CurvatureMethod::Analytic:
      return compute_fields_analytic(grid);
    case CurvatureMethod::Quadric: {
      QuadricOptions o;
      if (radius_mm > 0) o.radius_mm = radius_mm;
      return compute_fields_quadric(grid, o);
    }
    case CurvatureMethod::Seed000: {
      const MaxCurvatureMap m = seed000_max_curvature(grid);
      SurfaceFields f;
      f.resize(grid.n_phi(), grid.n_h());
      f.method = CurvatureMethod::Seed000;
      f.defined = m.defined;
      // The operator as printed gives half the curvature of a circle ((pi - angle) over the sum
      // of both chords); doubled here so all methods report 1/mm on the same scale. The raw
      // legacy value stays available from seed000_max_curvature (docs/reconstruction.md).
      f.k1.resize(m.value.size());
      std::transform(m.value.begin(), m.value.end(), f.k1.begin(),
                     [](float v) { return 2.0f * v; });
      return f;
    }
  }
  throw InvalidInputError("unknown curvature method");
}

}  // namespace scanmesh
