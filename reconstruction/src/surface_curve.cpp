// Curves in (phi, h) lifted onto the continuous scan surface (docs/reconstruction.md, "Curves").
#include "scanmesh/reconstruction/surface_curve.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// 5-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr std::array<double, 5> kGaussX = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                           0.5384693101056831, 0.9061798459386640};
constexpr std::array<double, 5> kGaussW = {0.2369268850561891, 0.4786286704993665,
                                           0.5688888888888889, 0.4786286704993665,
                                           0.2369268850561891};

template <typename F>
double gauss_legendre(const F& f, double a, double b) {
  const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
  double sum = 0;
  for (int k = 0; k < 5; ++k) sum += kGaussW[k] * f(mid + half * kGaussX[k]);
  return half * sum;
}

// Integrates f over [a, b] by doubling the number of Gauss-Legendre pieces until two
// successive estimates agree within the tolerance.
template <typename F>
double integrate(const F& f, double a, double b, double tolerance) {
  double previous = gauss_legendre(f, a, b);
  for (int pieces = 2; pieces <= 4096; pieces *= 2) {
    double sum = 0;
    const double h = (b - a) / pieces;
    for (int k = 0; k < pieces; ++k) sum += gauss_legendre(f, a + k * h, a + (k + 1) * h);
    if (std::abs(sum - previous) <= tolerance) return sum;
    previous = sum;
  }
  return previous;
}

}  // namespace

SurfaceCurve::SurfaceCurve(const ScanSurface& surface, std::vector<Eigen::Vector2d> control_points,
                           CurveKind kind, bool closed)
    : surface_(surface), points_(std::move(control_points)), kind_(kind), closed_(closed) {
  const std::size_t min_points = closed ? 3 : 2;
  if (points_.size() < min_points)
    throw InvalidInputError("surface curve needs at least " + std::to_string(min_points) +
                            " control points, got " + std::to_string(points_.size()));
  for (std::size_t k = 0; k < points_.size(); ++k)
    if (!points_[k].allFinite())
      throw InvalidInputError("surface curve: control point " + std::to_string(k) +
                              " is not finite");
  if (closed_) {
    // The closing span goes the short way round in phi; a curve around the axis closes after
    // one full turn.
    const double gap = points_.back().x() - points_.front().x();
    period_shift_ = kTwoPi * std::round(gap / kTwoPi);
  }
  // Centripetal knots from 3D chord lengths of the lifted control points (phi and h have
  // different units, so parameter-space distances would be meaningless).
  const int n = static_cast<int>(points_.size()) + (closed_ ? 1 : 0);
  knots_.assign(1, 0.0);
  for (int k = 0; k + 1 < n; ++k) {
    const auto a = surface_.position(control(k).x(), control(k).y());
    const auto b = surface_.position(control(k + 1).x(), control(k + 1).y());
    if (!a || !b)
      throw InvalidInputError("surface curve: control point " + std::to_string(a ? k + 1 : k) +
                              " lies outside the scanned surface");
    knots_.push_back(knots_.back() + std::max(std::sqrt((*b - *a).norm()), 1e-9));
  }
}

double SurfaceCurve::t_max() const {
  return static_cast<double>(points_.size()) - (closed_ ? 0.0 : 1.0);
}

Eigen::Vector2d SurfaceCurve::control(int k) const {
  const int n = static_cast<int>(points_.size());
  if (closed_) {
    const int wraps = (k >= 0 ? k / n : -((-k + n - 1) / n));
    return points_[k - wraps * n] + Eigen::Vector2d(wraps * period_shift_, 0.0);
  }
  // Open curves extend linearly past their ends (phantom points for the end tangents).
  if (k < 0) return points_[0] + k * (points_[1] - points_[0]);
  if (k >= n) return points_[n - 1] + (k - n + 1) * (points_[n - 1] - points_[n - 2]);
  return points_[k];
}

double SurfaceCurve::knot(int k) const {
  const int m = static_cast<int>(knots_.size());
  if (k < 0) return knots_[0] - (knots_[1] - knots_[0]) * (-k);
  if (k >= m) return knots_[m - 1] + (knots_[m - 1] - knots_[m - 2]) * (k - m + 1);
  return knots_[k];
}

SurfaceCurve::Derivs SurfaceCurve::parameter_derivatives(double t) const {
  t = std::clamp(t, 0.0, t_max());
  const int k = std::min(static_cast<int>(t), static_cast<int>(t_max()) - 1);
  const double s = t - k;
  const Eigen::Vector2d p0 = control(k - 1), p1 = control(k), p2 = control(k + 1),
                        p3 = control(k + 2);
  if (kind_ == CurveKind::Polyline) return {p1 + s * (p2 - p1), p2 - p1, Eigen::Vector2d::Zero()};
  // Centripetal Catmull-Rom as a cubic Hermite span with tangents from the non-uniform knots.
  const double t0 = knot(k - 1), t1 = knot(k), t2 = knot(k + 1), t3 = knot(k + 2);
  const Eigen::Vector2d m1 =
      ((p1 - p0) / (t1 - t0) - (p2 - p0) / (t2 - t0) + (p2 - p1) / (t2 - t1)) * (t2 - t1);
  const Eigen::Vector2d m2 =
      ((p2 - p1) / (t2 - t1) - (p3 - p1) / (t3 - t1) + (p3 - p2) / (t3 - t2)) * (t2 - t1);
  const double s2 = s * s, s3 = s2 * s;
  Derivs d;
  d.p = (2 * s3 - 3 * s2 + 1) * p1 + (s3 - 2 * s2 + s) * m1 + (-2 * s3 + 3 * s2) * p2 +
        (s3 - s2) * m2;
  d.dp = (6 * s2 - 6 * s) * p1 + (3 * s2 - 4 * s + 1) * m1 + (-6 * s2 + 6 * s) * p2 +
         (3 * s2 - 2 * s) * m2;
  d.ddp = (12 * s - 6) * p1 + (6 * s - 4) * m1 + (-12 * s + 6) * p2 + (6 * s - 2) * m2;
  return d;
}

Eigen::Vector2d SurfaceCurve::parameter_point(double t) const { return parameter_derivatives(t).p; }

std::optional<Eigen::Vector3d> SurfaceCurve::point(double t) const {
  const Eigen::Vector2d p = parameter_point(t);
  return surface_.position(p.x(), p.y());
}

std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> SurfaceCurve::lifted_derivatives(
    double t) const {
  const Derivs d = parameter_derivatives(t);
  const auto jet = surface_.evaluate(d.p.x(), d.p.y());
  if (!jet) return std::nullopt;
  const double a = d.dp.x(), b = d.dp.y();
  const Eigen::Vector3d first = jet->d_phi * a + jet->d_h * b;
  const Eigen::Vector3d second = jet->d_phiphi * a * a + 2.0 * jet->d_phih * a * b +
                                 jet->d_hh * b * b + jet->d_phi * d.ddp.x() + jet->d_h * d.ddp.y();
  return std::make_pair(first, second);
}

double SurfaceCurve::speed(double t) const {
  const auto d = lifted_derivatives(t);
  if (!d)
    throw InvalidInputError("surface curve leaves the scanned surface near parameter t = " +
                            std::to_string(t));
  return d->first.norm();
}

double SurfaceCurve::arc_length_to(double t, double tolerance_mm) const {
  t = std::clamp(t, 0.0, t_max());
  double length = 0;
  const auto f = [&](double x) { return speed(x); };
  // Integrate span by span: the curve is smooth inside a span, only C1 (or C0) across.
  for (int k = 0; k < static_cast<int>(std::ceil(t)); ++k)
    length += integrate(f, k, std::min<double>(k + 1, t), tolerance_mm / (t_max() + 1));
  return length;
}

double SurfaceCurve::arc_length(double tolerance_mm) const {
  return arc_length_to(t_max(), tolerance_mm);
}

std::optional<double> SurfaceCurve::curvature(double t) const {
  const auto d = lifted_derivatives(t);
  if (!d) return std::nullopt;
  const double speed3 = std::pow(d->first.norm(), 3);
  if (speed3 < 1e-300) return std::nullopt;
  return d->first.cross(d->second).norm() / speed3;
}

double SurfaceCurve::curvature_integral() const {
  // integral of k ds = integral of |X' x X''| / |X'|^2 dt
  const auto f = [&](double t) {
    const auto d = lifted_derivatives(t);
    if (!d)
      throw InvalidInputError("surface curve leaves the scanned surface near t = " +
                              std::to_string(t));
    const double s2 = d->first.squaredNorm();
    return s2 > 0 ? d->first.cross(d->second).norm() / s2 : 0.0;
  };
  double total = 0;
  const int spans = static_cast<int>(t_max());
  for (int k = 0; k < spans; ++k) total += integrate(f, k, k + 1, 1e-9);
  // A polyline also turns at its interior vertices (and at every vertex when closed): add the
  // angle between the lifted tangents on either side.
  if (kind_ == CurveKind::Polyline) {
    for (int k = closed_ ? 0 : 1; k < spans; ++k) {
      const double before = k == 0 ? t_max() - 1e-9 : k - 1e-9;
      const auto a = lifted_derivatives(before), b = lifted_derivatives(k + 1e-9);
      if (!a || !b) continue;
      const double c = a->first.normalized().dot(b->first.normalized());
      total += std::acos(std::clamp(c, -1.0, 1.0));
    }
  }
  return total;
}

std::vector<double> SurfaceCurve::equal_arc_length_parameters(int n) const {
  if (n < 2)
    throw InvalidInputError("need at least 2 points along a curve, got " + std::to_string(n));
  // Tabulate arc length on a fine parameter grid, then invert by linear interpolation and
  // one bisection refinement per point.
  const int samples_per_span = 64;
  const int total = static_cast<int>(t_max()) * samples_per_span;
  std::vector<double> ts(total + 1), lengths(total + 1, 0.0);
  for (int k = 0; k <= total; ++k) ts[k] = t_max() * k / total;
  const auto f = [&](double x) { return speed(x); };
  for (int k = 1; k <= total; ++k)
    lengths[k] = lengths[k - 1] + gauss_legendre(f, ts[k - 1], ts[k]);
  std::vector<double> out;
  for (int m = 0; m < n; ++m) {
    const double target = lengths.back() * m / (n - 1);
    const auto it = std::lower_bound(lengths.begin(), lengths.end(), target);
    const std::size_t hi =
        std::min<std::size_t>(std::max<std::ptrdiff_t>(it - lengths.begin(), 1), total);
    const std::size_t lo = hi - 1;
    const double span = lengths[hi] - lengths[lo];
    const double frac = span > 0 ? (target - lengths[lo]) / span : 0.0;
    out.push_back(ts[lo] + frac * (ts[hi] - ts[lo]));
  }
  out.front() = 0.0;
  out.back() = t_max();
  return out;
}

}  // namespace scanmesh
