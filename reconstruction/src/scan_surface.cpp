// Continuous scan surface: bicubic Hermite patches over the grid nodes (docs/reconstruction.md).
#include "scanmesh/reconstruction/scan_surface.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "scanmesh/reconstruction/bisection.h"

namespace scanmesh {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Cubic Hermite basis on [0, 1] and its first two derivatives: value weights for the end
// points (v0, v1) and slope weights (d0, d1).
struct HermiteBasis {
  std::array<double, 3> v0, v1, d0, d1;  // [value, first derivative, second derivative]
  explicit HermiteBasis(double t) {
    const double t2 = t * t, t3 = t2 * t;
    v0 = {2 * t3 - 3 * t2 + 1, 6 * t2 - 6 * t, 12 * t - 6};
    v1 = {-2 * t3 + 3 * t2, -6 * t2 + 6 * t, -12 * t + 6};
    d0 = {t3 - 2 * t2 + t, 3 * t2 - 4 * t + 1, 6 * t - 4};
    d1 = {t3 - t2, 3 * t2 - 2 * t, 6 * t - 2};
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Differential geometry of X(phi, h) = (r cos phi, r sin phi, h)

SurfaceJet lift(double phi, double h, const RadiusJet& j) {
  const double c = std::cos(phi), s = std::sin(phi);
  const Eigen::Vector3d radial(c, s, 0), tangential(-s, c, 0);
  SurfaceJet out;
  out.position = j.r * radial + Eigen::Vector3d(0, 0, h);
  out.d_phi = j.r_phi * radial + j.r * tangential;
  out.d_h = j.r_h * radial + Eigen::Vector3d::UnitZ();
  out.d_phiphi = (j.r_phiphi - j.r) * radial + 2.0 * j.r_phi * tangential;
  out.d_phih = j.r_phih * radial + j.r_h * tangential;
  out.d_hh = j.r_hh * radial;
  return out;
}

Eigen::Vector3d SurfaceJet::normal() const {
  // d_phi x d_h points away from the axis for any r > 0.
  return d_phi.cross(d_h).normalized();
}

SurfaceCurvature SurfaceJet::curvature() const {
  const Eigen::Vector3d n = normal();
  Eigen::Matrix2d first, second;
  first << d_phi.dot(d_phi), d_phi.dot(d_h), d_phi.dot(d_h), d_h.dot(d_h);
  // Minus sign: with the outward normal a convex surface has X_uu . n < 0, and the project's
  // convention is k > 0 for convex.
  second << -d_phiphi.dot(n), -d_phih.dot(n), -d_phih.dot(n), -d_hh.dot(n);
  return curvature_from_fundamental_forms(d_phi, d_h, n, first, second);
}

// ---------------------------------------------------------------------------------------------
// ScanSurface

ScanSurface::ScanSurface(const RangeGrid& grid)
    : n_phi_(grid.n_phi()),
      n_h_(grid.n_h()),
      phi0_(grid.phi0()),
      h0_(grid.h0()),
      dphi_(grid.dphi()),
      dh_(grid.dh()),
      r_(grid.radii()),
      valid_(grid.validity()),
      support_ok_(grid.cell_count(), 0) {
  for (int j = 0; j + 1 < n_h_; ++j)
    for (int i = 0; i < n_phi_; ++i)
      support_ok_[j * static_cast<std::size_t>(n_phi_) + i] = support_valid(i, j);
  hermite_.resize(r_.size());
  for (int j = 0; j < n_h_; ++j)
    for (int i = 0; i < n_phi_; ++i)
      if (cell_valid(i, j)) hermite_[j * static_cast<std::size_t>(n_phi_) + i] = hermite_node(i, j);
  // Root search samples finer than the finest cell: phi spacing at the smallest radius.
  double min_r = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < r_.size(); ++k)
    if (valid_[k]) min_r = std::min(min_r, static_cast<double>(r_[k]));
  if (std::isfinite(min_r)) sampling_step_mm_ = 0.25 * std::min(dh_, min_r * dphi_);
}

bool ScanSurface::cell_valid(int i, int j) const {
  if (j < 0 || j >= n_h_) return false;
  const int w = ((i % n_phi_) + n_phi_) % n_phi_;
  return valid_[static_cast<std::size_t>(j) * n_phi_ + w] != 0;
}

float ScanSurface::r_at(int i, int j) const {
  const int w = ((i % n_phi_) + n_phi_) % n_phi_;
  return r_[static_cast<std::size_t>(j) * n_phi_ + w];
}

// A patch is defined where its four corners are valid; its tangents then use central
// differences where both neighbours are valid and one-sided ones otherwise, so it never
// reads an invalid cell.
bool ScanSurface::support_valid(int i, int j) const {
  return cell_valid(i, j) && cell_valid(i + 1, j) && cell_valid(i, j + 1) &&
         cell_valid(i + 1, j + 1);
}

bool ScanSurface::to_grid(double phi, double h, double& u, double& v) const {
  if (!std::isfinite(phi) || !std::isfinite(h)) return false;
  v = (h - h0_) / dh_;
  if (v < 0.0 || v > n_h_ - 1) return false;
  // fmod(x, n) is x itself for x in [0, n), the common case; fmod is exact, so this is the
  // same value without the call.
  const double x = (phi - phi0_) / dphi_, n = static_cast<double>(n_phi_);
  u = x >= 0.0 && x < n ? x : std::fmod(x, n);
  if (u < 0.0) u += n_phi_;
  if (u >= n_phi_) u = 0.0;
  return true;
}

bool ScanSurface::defined(double phi, double h) const {
  double u, v;
  if (!to_grid(phi, h, u, v)) return false;
  const int i = std::min(static_cast<int>(u), n_phi_ - 1);
  const int j = std::min(static_cast<int>(v), n_h_ - 2);
  return support_ok_[static_cast<std::size_t>(j) * n_phi_ + i] != 0;
}

namespace {

// Slope of a 1D sequence at the middle sample from its valid neighbours.
double slope(bool has_prev, double prev, double here, bool has_next, double next) {
  if (has_prev && has_next) return 0.5 * (next - prev);
  if (has_next) return next - here;
  if (has_prev) return here - prev;
  return 0.0;
}

}  // namespace

ScanSurface::HermiteNode ScanSurface::hermite_node(int ni, int nj) const {
  const double r = r_at(ni, nj);
  const bool left = cell_valid(ni - 1, nj), right = cell_valid(ni + 1, nj);
  const bool down = cell_valid(ni, nj - 1), up = cell_valid(ni, nj + 1);
  HermiteNode d{r, slope(left, left ? r_at(ni - 1, nj) : 0, r, right, right ? r_at(ni + 1, nj) : 0),
                slope(down, down ? r_at(ni, nj - 1) : 0, r, up, up ? r_at(ni, nj + 1) : 0), 0.0};
  if (cell_valid(ni - 1, nj - 1) && cell_valid(ni + 1, nj - 1) && cell_valid(ni - 1, nj + 1) &&
      cell_valid(ni + 1, nj + 1))
    d.r_uv = 0.25 * (r_at(ni + 1, nj + 1) - r_at(ni + 1, nj - 1) - r_at(ni - 1, nj + 1) +
                     r_at(ni - 1, nj - 1));
  return d;
}

bool ScanSurface::patch_at(double phi, double h, int& i, int& j, double& s, double& t) const {
  double u, v;
  if (!to_grid(phi, h, u, v)) return false;
  i = std::min(static_cast<int>(u), n_phi_ - 1);
  j = std::min(static_cast<int>(v), n_h_ - 2);
  if (!support_ok_[static_cast<std::size_t>(j) * n_phi_ + i]) return false;
  s = u - i;
  t = v - j;
  return true;
}

std::optional<double> ScanSurface::radius_value(double phi, double h) const {
  int i, j;
  double s, t;
  if (!patch_at(phi, h, i, j, s, t)) return std::nullopt;
  const HermiteNode* n[2][2] = {
      {&hermite_[index_wrapped(i, j)], &hermite_[index_wrapped(i, j + 1)]},
      {&hermite_[index_wrapped(i + 1, j)], &hermite_[index_wrapped(i + 1, j + 1)]}};
  // The value terms of radius() below, in the same order, so the result is the same bit for bit.
  const double s2 = s * s, s3 = s2 * s, t2 = t * t, t3 = t2 * t;
  const double vs[2] = {2 * s3 - 3 * s2 + 1, -2 * s3 + 3 * s2}, ds[2] = {s3 - 2 * s2 + s, s3 - s2};
  const double vt[2] = {2 * t3 - 3 * t2 + 1, -2 * t3 + 3 * t2}, dt[2] = {t3 - 2 * t2 + t, t3 - t2};
  double r = 0;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      const HermiteNode& c = *n[a][b];
      r += c.r * vs[a] * vt[b] + c.r_u * ds[a] * vt[b] + c.r_v * vs[a] * dt[b] +
           c.r_uv * ds[a] * dt[b];
    }
  return r;
}

std::optional<RadiusJet> ScanSurface::radius(double phi, double h) const {
  return radius_jet(phi, h, true);
}

std::optional<RadiusJet> ScanSurface::radius_jet(double phi, double h, bool second_order) const {
  double u, v;
  if (!to_grid(phi, h, u, v)) return std::nullopt;
  const int i = std::min(static_cast<int>(u), n_phi_ - 1);
  const int j = std::min(static_cast<int>(v), n_h_ - 2);
  if (!support_ok_[static_cast<std::size_t>(j) * n_phi_ + i]) return std::nullopt;
  auto node = [&](int ni, int nj) -> const HermiteNode& { return hermite_[index_wrapped(ni, nj)]; };
  const std::array<std::array<HermiteNode, 2>, 2> n = {
      {{node(i, j), node(i, j + 1)}, {node(i + 1, j), node(i + 1, j + 1)}}};
  const HermiteBasis bs(u - i), bt(v - j);

  // Sum over the four corners: value, u-slope, v-slope and twist, each with its basis.
  std::array<double, 6> acc{};  // r, r_u, r_v, r_uu, r_uv, r_vv
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      const auto& vs = a == 0 ? bs.v0 : bs.v1;
      const auto& ds = a == 0 ? bs.d0 : bs.d1;
      const auto& vt = b == 0 ? bt.v0 : bt.v1;
      const auto& dt = b == 0 ? bt.d0 : bt.d1;
      const HermiteNode& c = n[a][b];
      auto term = [&](int ks, int kt) {
        return c.r * vs[ks] * vt[kt] + c.r_u * ds[ks] * vt[kt] + c.r_v * vs[ks] * dt[kt] +
               c.r_uv * ds[ks] * dt[kt];
      };
      acc[0] += term(0, 0);
      acc[1] += term(1, 0);
      acc[2] += term(0, 1);
      if (!second_order) continue;
      acc[3] += term(2, 0);
      acc[4] += term(1, 1);
      acc[5] += term(0, 2);
    }
  RadiusJet jet;
  jet.r = acc[0];
  jet.r_phi = acc[1] / dphi_;
  jet.r_h = acc[2] / dh_;
  jet.r_phiphi = acc[3] / (dphi_ * dphi_);
  jet.r_phih = acc[4] / (dphi_ * dh_);
  jet.r_hh = acc[5] / (dh_ * dh_);
  return jet;
}

std::optional<SurfaceJet> ScanSurface::evaluate(double phi, double h) const {
  const auto r = radius(phi, h);
  if (!r) return std::nullopt;
  return lift(phi, h, *r);
}

std::optional<SurfacePoint> ScanSurface::point_normal(double phi, double h) const {
  const auto r = radius_jet(phi, h, false);
  if (!r) return std::nullopt;
  // lift() without the second-order terms.
  const double c = std::cos(phi), s = std::sin(phi);
  const Eigen::Vector3d radial(c, s, 0), tangential(-s, c, 0);
  const Eigen::Vector3d d_phi = r->r_phi * radial + r->r * tangential;
  const Eigen::Vector3d d_h = r->r_h * radial + Eigen::Vector3d::UnitZ();
  return SurfacePoint{r->r * radial + Eigen::Vector3d(0, 0, h), d_phi.cross(d_h).normalized(),
                      d_phi, d_h};
}

std::optional<Eigen::Vector3d> ScanSurface::position(double phi, double h) const {
  const auto r = radius_value(phi, h);
  if (!r) return std::nullopt;
  return Eigen::Vector3d(*r * std::cos(phi), *r * std::sin(phi), h);
}

std::optional<RadiusJet> ScanSurface::node_jet(int i, int j) const {
  if (j < 1 || j + 1 >= n_h_) return std::nullopt;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di)
      if (!cell_valid(i + di, j + dj)) return std::nullopt;
  const double r = r_at(i, j);
  RadiusJet jet;
  jet.r = r;
  jet.r_phi = 0.5 * (r_at(i + 1, j) - r_at(i - 1, j)) / dphi_;
  jet.r_h = 0.5 * (r_at(i, j + 1) - r_at(i, j - 1)) / dh_;
  jet.r_phiphi = (r_at(i + 1, j) - 2.0 * r + r_at(i - 1, j)) / (dphi_ * dphi_);
  jet.r_hh = (r_at(i, j + 1) - 2.0 * r + r_at(i, j - 1)) / (dh_ * dh_);
  jet.r_phih = 0.25 *
               (r_at(i + 1, j + 1) - r_at(i + 1, j - 1) - r_at(i - 1, j + 1) + r_at(i - 1, j - 1)) /
               (dphi_ * dh_);
  return jet;
}

Eigen::Vector3d ScanSurface::to_cylindrical(const Eigen::Vector3d& x) {
  double phi = std::atan2(x.y(), x.x());
  if (phi < 0) phi += kTwoPi;
  return {phi, x.z(), std::hypot(x.x(), x.y())};
}

std::optional<double> ScanSurface::implicit_value(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d c = to_cylindrical(x);
  const auto r = radius_value(c.x(), c.y());
  if (!r) return std::nullopt;
  return *r - c.z();
}

std::optional<ImplicitSample> ScanSurface::implicit(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d c = to_cylindrical(x);
  const double rho = c.z();
  if (rho < 1e-9) return std::nullopt;  // phi is undefined on the axis
  const auto r = radius(c.x(), c.y());
  if (!r) return std::nullopt;
  const Eigen::Vector3d grad_phi(-x.y() / (rho * rho), x.x() / (rho * rho), 0.0);
  const Eigen::Vector3d grad_rho(x.x() / rho, x.y() / rho, 0.0);
  return ImplicitSample{r->r - rho,
                        r->r_phi * grad_phi + r->r_h * Eigen::Vector3d::UnitZ() - grad_rho};
}

namespace {

// The Gauss-Newton step d of the normal equations (J^T J) d = J^T res, J = [ju jv]: the result of
// Eigen's (J^T J).ldlt().solve(J^T res) bit for bit (the same pivot choice — the larger diagonal
// entry first —, the same operations in the same order; checked on 2e7 random systems), without
// its generic machinery, which was ~20 % of a projection. false where that pivot is 0.
bool gauss_newton_step(const Eigen::Vector3d& ju, const Eigen::Vector3d& jv,
                       const Eigen::Vector3d& res, Eigen::Vector2d& d) {
  const double a = ju.dot(ju), b = jv.dot(ju), c = jv.dot(jv);
  const double r0 = ju.dot(res), r1 = jv.dot(res);
  const bool swap = std::abs(c) > std::abs(a);
  const double d0 = swap ? c : a, a11 = swap ? a : c;
  if (!(std::abs(d0) > 0)) return false;
  const double l = b / d0;  // L = [1 0; l 1], D = diag(d0, d1)
  const double d1 = a11 - l * (d0 * l);
  double y0 = swap ? r1 : r0, y1 = swap ? r0 : r1;
  y1 -= l * y0;
  const double tiny = std::numeric_limits<double>::min();  // Eigen's pseudo-inverse of D
  y0 = std::abs(d0) > tiny ? y0 / d0 : 0.0;
  y1 = std::abs(d1) > tiny ? y1 / d1 : 0.0;
  y0 -= l * y1;
  d = swap ? Eigen::Vector2d(y1, y0) : Eigen::Vector2d(y0, y1);
  return true;
}

// All sign changes of f over [t0, t1] sampled with `steps` intervals.
template <typename F>
std::vector<double> sampled_roots(const F& f, double t0, double t1, long steps, double tolerance) {
  std::vector<double> roots;
  const double dt = (t1 - t0) / static_cast<double>(steps);
  std::optional<double> prev = f(t0);
  double prev_t = t0;
  if (prev && *prev == 0.0) roots.push_back(t0);
  for (long k = 1; k <= steps; ++k) {
    const double t = k == steps ? t1 : t0 + k * dt;
    const std::optional<double> cur = f(t);
    if (prev && cur) {
      if (*cur == 0.0)
        roots.push_back(t);
      else if (*prev != 0.0 && ((*prev < 0) != (*cur < 0)))
        // f is defined on the whole bracket by construction (both ends defined and the step
        // below the cell size); an undefined sample inside still ends the refinement.
        roots.push_back(bisect_sign_change(f, prev_t, *prev, t, tolerance));
    }
    prev = cur;
    prev_t = t;
  }
  return roots;
}

}  // namespace

std::vector<SurfaceHit> ScanSurface::intersect_segment(const Eigen::Vector3d& origin,
                                                       const Eigen::Vector3d& direction,
                                                       double t_min, double t_max,
                                                       double max_step_mm,
                                                       double tolerance_mm) const {
  std::vector<SurfaceHit> hits;
  const double speed = direction.norm();
  if (!(speed > 0) || !(t_max > t_min)) return hits;
  if (!(sampling_step_mm_ > 0)) return hits;  // no valid cell at all
  double step = sampling_step_mm_;
  if (max_step_mm > 0) step = std::min(step, max_step_mm);
  const long steps =
      std::max<long>(1, static_cast<long>(std::ceil((t_max - t_min) * speed / step)));
  const auto f = [&](double t) { return implicit_value(origin + t * direction); };
  for (double t : sampled_roots(f, t_min, t_max, steps, tolerance_mm / speed)) {
    SurfaceHit hit;
    hit.t = t;
    hit.point = origin + t * direction;
    const Eigen::Vector3d c = to_cylindrical(hit.point);
    hit.phi = c.x();
    hit.h = c.y();
    hits.push_back(hit);
  }
  return hits;
}

std::vector<double> ScanSurface::intersect_circle(const Eigen::Vector3d& centre, double radius,
                                                  const Eigen::Vector3d& u,
                                                  const Eigen::Vector3d& v,
                                                  double tolerance_mm) const {
  if (!(radius > 0) || !(sampling_step_mm_ > 0)) return {};
  const double step = sampling_step_mm_;
  const long steps = std::max<long>(64, static_cast<long>(std::ceil(kTwoPi * radius / step)));
  const auto f = [&](double theta) {
    return implicit_value(centre + radius * (std::cos(theta) * u + std::sin(theta) * v));
  };
  std::vector<double> roots = sampled_roots(f, 0.0, kTwoPi, steps, tolerance_mm / radius);
  // theta = 0 and 2 pi are the same point.
  if (roots.size() >= 2 && roots.front() == 0.0 && roots.back() >= kTwoPi) roots.pop_back();
  for (double& t : roots)
    if (t >= kTwoPi) t -= kTwoPi;
  std::sort(roots.begin(), roots.end());
  return roots;
}

std::optional<SurfaceProjection> ScanSurface::project(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d c = to_cylindrical(x);
  auto p = project(x, Eigen::Vector2d(c.x(), c.y()));
  if (!p) return std::nullopt;
  p->phi = std::fmod(p->phi, kTwoPi);
  if (p->phi < 0) p->phi += kTwoPi;
  return p;
}

std::optional<SurfaceProjection> ScanSurface::project(const Eigen::Vector3d& x,
                                                      const Eigen::Vector2d& start) const {
  double phi = start.x(), h = start.y();
  const double rho = std::hypot(x.x(), x.y());
  for (int it = 0; it < 50; ++it) {
    // Gauss-Newton needs the position and the first derivatives only (lift() without the
    // second-order terms: the same values).
    const auto r = radius_jet(phi, h, false);
    if (!r) return std::nullopt;
    const double cs = std::cos(phi), sn = std::sin(phi);
    const Eigen::Vector3d radial(cs, sn, 0), tangential(-sn, cs, 0);
    const Eigen::Vector3d position = r->r * radial + Eigen::Vector3d(0, 0, h);
    const Eigen::Vector3d d_phi = r->r_phi * radial + r->r * tangential;
    const Eigen::Vector3d d_h = r->r_h * radial + Eigen::Vector3d::UnitZ();
    Eigen::Vector2d delta;
    if (!gauss_newton_step(d_phi, d_h, x - position, delta)) {
      Eigen::Matrix<double, 3, 2> jac;
      jac << d_phi, d_h;
      delta = (jac.transpose() * jac).ldlt().solve(jac.transpose() * (x - position));
    }
    // Damp steps larger than a few cells: the Gauss-Newton model is local.
    const double limit = 4.0;
    const double scale =
        std::min(1.0, limit / std::max(std::abs(delta(0)) / dphi_, std::abs(delta(1)) / dh_));
    phi += scale * delta(0);
    h += scale * delta(1);
    if (std::abs(delta(0)) * rho < 1e-9 && std::abs(delta(1)) < 1e-9) break;
  }
  const auto p = position(phi, h);
  if (!p) return std::nullopt;
  return SurfaceProjection{*p, phi, h, (*p - x).norm()};
}

}  // namespace scanmesh
