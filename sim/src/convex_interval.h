// Ray-interval helpers for convex shapes: the part of a line inside a convex solid is one
// interval [t_in, t_out]; the first surface crossing at or after t_min is t_in, or t_out when the
// ray starts inside.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

namespace scanmesh::sim::detail {

using Interval = std::pair<double, double>;

//! Roots of A t^2 + 2 B t + C (A >= 0): the interval where the quadratic is <= 0, if any.
//! A == 0 (ray parallel to a cylinder axis) gives the whole line when C <= 0.
inline std::optional<Interval> quadratic_interval(double a, double b, double c) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (a <= 1e-300) {
    if (c <= 0.0) return Interval{-kInf, kInf};
    return std::nullopt;
  }
  const double disc = b * b - a * c;
  if (disc < 0.0) return std::nullopt;
  // Numerically stable pair of roots.
  const double sq = std::sqrt(disc);
  const double qq = b >= 0.0 ? -(b + sq) : -(b - sq);
  double t0, t1;
  if (qq == 0.0) {
    t0 = t1 = 0.0;
  } else {
    t0 = qq / a;
    t1 = c / qq;
  }
  if (t0 > t1) std::swap(t0, t1);
  return Interval{t0, t1};
}

//! The t where lo <= p + t v <= hi.
inline std::optional<Interval> slab_interval(double p, double v, double lo, double hi) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (std::abs(v) < 1e-300) {
    if (p >= lo && p <= hi) return Interval{-kInf, kInf};
    return std::nullopt;
  }
  double t0 = (lo - p) / v, t1 = (hi - p) / v;
  if (t0 > t1) std::swap(t0, t1);
  return Interval{t0, t1};
}

inline std::optional<Interval> intersect_intervals(const Interval& a, const Interval& b) {
  const Interval r{std::max(a.first, b.first), std::min(a.second, b.second)};
  if (r.first > r.second) return std::nullopt;
  return r;
}

inline std::optional<double> first_crossing(const Interval& iv, double t_min, double t_max) {
  if (iv.first >= t_min && iv.first <= t_max && std::isfinite(iv.first)) return iv.first;
  if (iv.first < t_min && iv.second >= t_min && iv.second <= t_max && std::isfinite(iv.second))
    return iv.second;
  return std::nullopt;
}

}  // namespace scanmesh::sim::detail
