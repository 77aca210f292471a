// Per-cell normals and curvatures: analytic (continuous surface) and quadric fit
// (docs/reconstruction.md). The seed 000 operator lives in legacy_curvature.cpp.
#include "scanmesh/reconstruction/surface_fields.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
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
  // A window wider than 2 * kMaxHalfWindow + 1 cells is sampled every `step`-th row and column:
  // a quadric through ~2,400 evenly spread cells is as good as through all of them, and a large
  // --radius (40 mm on a 0.45 mm grid: 30,000 cells per fit, 262,144 fits) ran for minutes.
  constexpr int kMaxHalfWindow = 24;
  const int step = std::max(1, (std::max(dj_max, di_max) + kMaxHalfWindow - 1) / kMaxHalfWindow);
  // Multiples of the step: the sampled window stays centred on the cell.
  for (int dj = -(dj_max / step) * step; dj <= dj_max; dj += step) {
    const int jj = j + dj;
    if (jj < 0 || jj >= grid.n_h()) continue;
    for (int di = -(di_max / step) * step; di <= di_max; di += step) {
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
  const Eigen::Vector3d du = t1 + d * n, dv = t2 + e * n;
  return curvature_from_fundamental_forms(du, dv, du.cross(dv).normalized(), first, second);
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

// The 3D quadric estimate at one cell, or nullopt if it has too few neighbours.
std::optional<SurfaceCurvature> quadric_at(const RangeGrid& grid,
                                           const std::vector<Eigen::Vector3d>& positions, int i,
                                           int j, const QuadricOptions& options,
                                           std::vector<Eigen::Vector3d>& pts) {
  gather_neighbours(grid, positions, i, j, options.radius_mm, pts);
  if (static_cast<int>(pts.size()) < options.min_points) return std::nullopt;
  const Eigen::Vector3d& origin = positions[grid.index(i, j)];
  const Eigen::Vector3d outward(std::cos(grid.phi(i)), std::sin(grid.phi(i)), 0.0);
  // Two passes: the second fits in the frame of the first fit's normal, which makes the height
  // function flatter and the fit less biased on steep parts.
  auto c = fit_quadric(pts, origin, pca_normal(pts, outward), options.radius_mm);
  if (c) c = fit_quadric(pts, origin, c->normal, options.radius_mm);
  return c;
}

void check_quadric_options(const QuadricOptions& options) {
  if (!(options.radius_mm > 0) || !std::isfinite(options.radius_mm))
    throw InvalidInputError("quadric curvature: neighbourhood radius must be positive, got " +
                            std::to_string(options.radius_mm) + " mm");
  if (options.min_points < 6)
    throw InvalidInputError(
        "quadric curvature: min_points must be >= 6 (a quadric has 6 "
        "coefficients), got " +
        std::to_string(options.min_points));
}

// ---- grid quadric: separable least squares in (u, v) = (column, row) offsets ----------------

// Running sums along phi (wrapping) of k_a(u) * x(i + u, j) for the kernels u^0, u^1, u^2.
void sum_along_phi(const std::vector<double>& x, int n_phi, int n_h, int w,
                   std::array<std::vector<double>, 3>& out) {
  for (auto& o : out) o.assign(x.size(), 0.0);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      double s0 = 0, s1 = 0, s2 = 0;
      for (int u = -w; u <= w; ++u) {
        const int ii = ((i + u) % n_phi + n_phi) % n_phi;
        const double v = x[static_cast<std::size_t>(j) * n_phi + ii];
        s0 += v;
        s1 += u * v;
        s2 += u * u * v;
      }
      const std::size_t k = static_cast<std::size_t>(j) * n_phi + i;
      out[0][k] = s0;
      out[1][k] = s1;
      out[2][k] = s2;
    }
}

// Sum along h of v^b * x(i, j + v) for |v| <= w; rows whose window leaves the grid get NaN.
std::vector<double> sum_along_h(const std::vector<double>& x, int n_phi, int n_h, int w, int b) {
  std::vector<double> out(x.size(), std::numeric_limits<double>::quiet_NaN());
  for (int j = w; j + w < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      double s = 0;
      for (int v = -w; v <= w; ++v)
        s += (b == 0 ? 1.0 : b == 1 ? v : v * v) * x[static_cast<std::size_t>(j + v) * n_phi + i];
      out[static_cast<std::size_t>(j) * n_phi + i] = s;
    }
  return out;
}

// Fields of the grid's size with no cell defined yet, labelled with the method that fills them.
SurfaceFields unfilled_fields(const RangeGrid& grid, CurvatureMethod method) {
  SurfaceFields f;
  f.resize(grid.n_phi(), grid.n_h());
  f.method = method;
  return f;
}

// The same for a quadric method, with its radius; the options are checked first, so that bad
// ones fail before the planes are allocated.
SurfaceFields unfilled_quadric_fields(const RangeGrid& grid, CurvatureMethod method,
                                      const QuadricOptions& options) {
  check_quadric_options(options);
  SurfaceFields f = unfilled_fields(grid, method);
  f.radius_mm = options.radius_mm;
  return f;
}

double median_radius(const RangeGrid& grid) {
  std::vector<float> r;
  for (std::size_t k = 0; k < grid.cell_count(); ++k)
    if (grid.validity()[k]) r.push_back(grid.radii()[k]);
  if (r.empty()) return 0.0;
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  return r[r.size() / 2];
}

}  // namespace

SurfaceFields compute_fields_analytic(const RangeGrid& grid) {
  SurfaceFields f = unfilled_fields(grid, CurvatureMethod::Analytic);
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
  SurfaceFields f = unfilled_quadric_fields(grid, CurvatureMethod::Quadric, options);
  const std::vector<Eigen::Vector3d> positions = cell_positions(grid);
#pragma omp parallel
  {
    std::vector<Eigen::Vector3d> pts;
#pragma omp for schedule(dynamic, 4)
    for (int j = 0; j < grid.n_h(); ++j)
      for (int i = 0; i < grid.n_phi(); ++i)
        if (grid.valid(i, j))
          if (const auto c = quadric_at(grid, positions, i, j, options, pts))
            store(f, grid.index(i, j), *c);
  }
  return f;
}

SurfaceFields compute_fields_grid_quadric(const RangeGrid& grid, const QuadricOptions& options) {
  SurfaceFields f = unfilled_quadric_fields(grid, CurvatureMethod::GridQuadric, options);
  const int n_phi = grid.n_phi(), n_h = grid.n_h();
  const double r_med = median_radius(grid);
  if (r_med <= 0) return f;
  const int wv = std::max(1, static_cast<int>(std::lround(options.radius_mm / grid.dh())));
  const int wu = std::clamp(
      static_cast<int>(std::lround(options.radius_mm / (r_med * grid.dphi()))), 1, n_phi / 4);

  // Radius plane with holes as 0 and an "invalid" plane: a window is usable where the box sum
  // of the invalid plane is 0.
  std::vector<double> r(grid.cell_count()), invalid(grid.cell_count());
  for (std::size_t k = 0; k < r.size(); ++k) {
    r[k] = grid.validity()[k] ? grid.radii()[k] : 0.0;
    invalid[k] = grid.validity()[k] ? 0.0 : 1.0;
  }
  std::array<std::vector<double>, 3> ru, iu;
  sum_along_phi(r, n_phi, n_h, wu, ru);
  sum_along_phi(invalid, n_phi, n_h, wu, iu);
  const std::vector<double> holes = sum_along_h(iu[0], n_phi, n_h, wv, 0);
  const std::vector<double> s00 = sum_along_h(ru[0], n_phi, n_h, wv, 0);
  const std::vector<double> s01 = sum_along_h(ru[0], n_phi, n_h, wv, 1);
  const std::vector<double> s02 = sum_along_h(ru[0], n_phi, n_h, wv, 2);
  const std::vector<double> s10 = sum_along_h(ru[1], n_phi, n_h, wv, 0);
  const std::vector<double> s11 = sum_along_h(ru[1], n_phi, n_h, wv, 1);
  const std::vector<double> s20 = sum_along_h(ru[2], n_phi, n_h, wv, 0);

  // Full-window moments: the odd terms decouple, (c0, cuu, cvv) solve one fixed 3 x 3 system.
  const double nu = 2.0 * wu + 1, nv = 2.0 * wv + 1;
  const double u2 = wu * (wu + 1.0) * (2.0 * wu + 1) / 3.0,
               v2 = wv * (wv + 1.0) * (2.0 * wv + 1) / 3.0;
  auto fourth = [](double w) { return w * (w + 1) * (2 * w + 1) * (3 * w * w + 3 * w - 1) / 15.0; };
  const double u4 = fourth(wu), v4 = fourth(wv);
  Eigen::Matrix3d even;
  even << nu * nv, u2 * nv, v2 * nu, u2 * nv, u4 * nv, u2 * v2, v2 * nu, u2 * v2, v4 * nu;
  const Eigen::Matrix3d even_inverse = even.inverse();

  const std::vector<Eigen::Vector3d> positions = cell_positions(grid);
#pragma omp parallel
  {
    std::vector<Eigen::Vector3d> pts;
#pragma omp for schedule(dynamic, 4)
    for (int j = 0; j < n_h; ++j)
      for (int i = 0; i < n_phi; ++i) {
        const std::size_t k = grid.index(i, j);
        if (!grid.validity()[k]) continue;
        if (!(holes[k] == 0.0)) {  // NaN (window leaves the rows) or a hole inside
          if (const auto c = quadric_at(grid, positions, i, j, options, pts)) store(f, k, *c);
          continue;
        }
        const Eigen::Vector3d c_even = even_inverse * Eigen::Vector3d(s00[k], s20[k], s02[k]);
        const double du = grid.dphi(), dv = grid.dh();
        RadiusJet jet;
        jet.r = c_even(0);
        jet.r_phi = s10[k] / (u2 * nv) / du;
        jet.r_h = s01[k] / (v2 * nu) / dv;
        jet.r_phiphi = 2.0 * c_even(1) / (du * du);
        jet.r_phih = s11[k] / (u2 * v2) / (du * dv);
        jet.r_hh = 2.0 * c_even(2) / (dv * dv);
        store(f, k, lift(grid.phi(i), grid.h(j), jet).curvature());
      }
  }
  return f;
}

SurfaceFields compute_fields(const RangeGrid& grid, CurvatureMethod method, double radius_mm) {
  switch (method) {
    case CurvatureMethod::Analytic:
      return compute_fields_analytic(grid);
    case CurvatureMethod::Quadric:
    case CurvatureMethod::GridQuadric: {
      QuadricOptions o;
      if (radius_mm > 0) o.radius_mm = radius_mm;
      return method == CurvatureMethod::Quadric ? compute_fields_quadric(grid, o)
                                                : compute_fields_grid_quadric(grid, o);
    }
    case CurvatureMethod::Seed000: {
      const MaxCurvatureMap m = seed000_max_curvature(grid);
      SurfaceFields f = unfilled_fields(grid, CurvatureMethod::Seed000);
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
