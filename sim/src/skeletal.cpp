// Skeleton-based implicit surface, seed 003 §2.1-2.2: F(x) = sum_i w_i e(d_i(x)^2), surface
// F = I, Wyvill kernel, Euclidean distance to points and segments.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "convex_interval.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/shapes.h"

namespace scanmesh::sim {

using Eigen::Matrix3d;
using Eigen::Vector3d;

KernelValue wyvill_kernel(double s, double radius) {
  const double r2 = radius * radius;
  if (s >= r2) return {};
  const double u = s / r2;
  KernelValue k;
  k.e = 1.0 + u * (-22.0 / 9.0 + u * (17.0 / 9.0 - 4.0 / 9.0 * u));
  k.de_ds = (-22.0 / 9.0 + u * (34.0 / 9.0 - 4.0 / 3.0 * u)) / r2;
  k.d2e_ds2 = (34.0 / 9.0 - 8.0 / 3.0 * u) / (r2 * r2);
  return k;
}

double wyvill_max_slope() {
  // e(rho) = 1 - 4/9 rho^6 + 17/9 rho^4 - 22/9 rho^2; |e'| peaks where e'' = 0, i.e. where
  // 120 x^2 - 204 x + 44 = 0 with x = rho^2 (the root in [0, 1]).
  static const double slope = [] {
    const double x = (204.0 - std::sqrt(204.0 * 204.0 - 4.0 * 120.0 * 44.0)) / 240.0;
    const double rho = std::sqrt(x);
    const double de =
        -24.0 / 9.0 * std::pow(rho, 5) + 68.0 / 9.0 * std::pow(rho, 3) - 44.0 / 9.0 * rho;
    return std::abs(de);
  }();
  return slope;
}

namespace {

// w e(u(t)), u = dist^2 / R^2 along a unit ray: u'' <= 2 / R^2 (for a segment too: the squared
// distance is piecewise quadratic with a continuous first derivative) and |u'| <= 2 sqrt(u) / R,
// so |d^2/dt^2| <= |w| / R^2 max_u (4 u |e''(u)| + 2 |e'(u)|) = |w| / R^2 (44 + 68 u - 72 u^2) / 9
// at its peak u = 17/36: 60.0556 / 9.
constexpr double kKernelBendBound = 6.673;

constexpr double kMinStepMm = 1e-3;  // smallest march step: features thinner are ignored
constexpr double kRootTolMm = 1e-9;  // crossing refinement tolerance

struct Element {
  SkeletonElement::Type type;
  Vector3d a, b, u;  // u = unit segment direction
  double len = 0.0, radius = 1.0, r2 = 1.0, weight = 1.0, slope = 0.0;
  double bend = 0.0;  // bound of |d^2 F_i / dt^2| along any ray (kKernelBendBound)
  Vector3d centre;    // a ball holding the support, for a cheap miss test
  double reach2 = 0.0;
};

class Skeletal final : public SceneObject {
  //! Where an element's support (its sphere or capsule of influence) meets a ray.
  struct Support {
    double t0, t1;
    int element;
  };

 public:
  Skeletal(std::vector<Element> elements, double iso) : el_(std::move(elements)), iso_(iso) {}

  FieldSample field(const Vector3d& x) const override {
    FieldSample f;
    double sum = 0.0;
    Vector3d grad = Vector3d::Zero();
    Matrix3d hess = Matrix3d::Zero();
    for (const Element& e : el_) {
      Vector3d diff;
      bool interior = false;
      if (e.type == SkeletonElement::Type::Point) {
        diff = x - e.a;
      } else {
        const double t = (x - e.a).dot(e.u);
        if (t <= 0.0) {
          diff = x - e.a;
        } else if (t >= e.len) {
          diff = x - e.b;
        } else {
          diff = x - e.a - t * e.u;
          interior = true;
        }
      }
      const double s = diff.squaredNorm();
      if (s >= e.r2) continue;
      const KernelValue k = wyvill_kernel(s, e.radius);
      const Vector3d ds = 2.0 * diff;  // grad of s = d^2
      sum += e.weight * k.e;
      grad += e.weight * k.de_ds * ds;
      // Hessian of s: 2 I for points and clamped segment ends, 2 (I - u u^T) inside a segment.
      Matrix3d hs = 2.0 * Matrix3d::Identity();
      if (interior) hs -= 2.0 * e.u * e.u.transpose();
      hess += e.weight * (k.d2e_ds2 * ds * ds.transpose() + k.de_ds * hs);
    }
    // Exposed as iso - F: negative inside (F > iso), gradient outward.
    f.value = iso_ - sum;
    f.gradient = -grad;
    f.hessian = -hess;
    return f;
  }

  std::optional<double> intersect(const Vector3d& o, const Vector3d& d, double t_min,
                                  double t_max) const override {
    // 1. Support intervals of the elements along the ray (sphere / capsule of radius R_i).
    Support buf[64];
    std::vector<Support> heap;
    Support* supports = buf;
    int count = 0;
    if (el_.size() > 64) {
      heap.resize(el_.size());
      supports = heap.data();
    }
    for (int k = 0; k < static_cast<int>(el_.size()); ++k) {
      // Most elements lie off a given ray: a ray that misses the ball misses the support.
      const Vector3d q = o - el_[k].centre;
      const double along = q.dot(d);
      if (q.squaredNorm() - along * along > el_[k].reach2) continue;
      const auto iv = support_interval(el_[k], o, d);
      if (!iv) continue;
      const double t0 = std::max(iv->first, t_min), t1 = std::min(iv->second, t_max);
      if (t0 > t1) continue;
      supports[count++] = {t0, t1, k};
    }
    if (count == 0) return std::nullopt;
    std::sort(supports, supports + count,
              [](const Support& p, const Support& q) { return p.t0 < q.t0; });
    // 2. March each connected group of supports; F = 0 between groups, so a crossing can
    //    only lie inside a group.
    for (int g = 0; g < count;) {
      double g0 = supports[g].t0, g1 = supports[g].t1;
      int h = g;
      for (; h < count && supports[h].t0 <= g1; ++h) g1 = std::max(g1, supports[h].t1);
      if (auto t = march(o, d, g0, g1, supports + g, h - g)) return t;
      g = h;
    }
    return std::nullopt;
  }

  // The support of every element (a sphere or capsule of its radius of influence).
  Eigen::AlignedBox3d bounds() const override {
    Eigen::AlignedBox3d box;
    for (const Element& e : el_) {
      const Vector3d reach = Vector3d::Constant(e.radius);
      box.extend(e.a - reach).extend(e.a + reach);
      if (e.type == SkeletonElement::Type::Segment) box.extend(e.b - reach).extend(e.b + reach);
    }
    return box;
  }

 private:
  // Value of F - iso at o + t d and its derivative d/dt, from the elements whose support holds
  // t (the others add nothing there: the kernel is zero outside its radius).
  double eval(const Vector3d& o, const Vector3d& d, double t, const Support* supports, int n,
              double* slope) const {
    const Vector3d x = o + t * d;
    double sum = 0.0, deriv = 0.0;
    for (int k = 0; k < n; ++k) {
      if (t < supports[k].t0 || t > supports[k].t1) continue;
      const Element& e = el_[supports[k].element];
      Vector3d diff;
      if (e.type == SkeletonElement::Type::Point) {
        diff = x - e.a;
      } else {
        const double along = std::clamp((x - e.a).dot(e.u), 0.0, e.len);
        diff = x - e.a - along * e.u;
      }
      const double s = diff.squaredNorm();
      if (s >= e.r2) continue;
      const double u = s / e.r2;
      sum += e.weight * (1.0 + u * (-22.0 / 9.0 + u * (17.0 / 9.0 - 4.0 / 9.0 * u)));
      if (slope)
        deriv +=
            e.weight * (-22.0 / 9.0 + u * (34.0 / 9.0 - 4.0 / 3.0 * u)) / e.r2 * 2.0 * diff.dot(d);
    }
    if (slope) *slope = deriv;
    return sum - iso_;
  }

  // The longest step from t over which F - iso = g cannot reach zero. An element changes F only
  // inside its support, by at most its slope per mm, so over [t, t + s] F changes by at most s
  // times the summed slopes of the supports that window meets. That sum grows with s at each
  // support's start (`supports` sorted by t0): the step is |g| / (the sum up to the start it
  // stops short of). The summed slope of the whole group, used before, shortened every step of
  // a group that chains several supports (30 % more CPU time on the head's renders).
  double safe_step(double t, double g, const Support* supports, int n) const {
    double lipschitz = 0.0;
    int k = 0;
    for (; k < n && supports[k].t0 <= t; ++k)
      if (supports[k].t1 >= t) lipschitz += el_[supports[k].element].slope;
    for (;; ++k) {
      const double step = lipschitz > 0.0 ? std::abs(g) / lipschitz
                                           : std::numeric_limits<double>::infinity();
      if (k == n || t + step <= supports[k].t0) return step;
      lipschitz += el_[supports[k].element].slope;
    }
  }

  // The step over which g cannot reach zero by its Taylor bound: |g(t + s)| >= |g| - b s -
  // bend s^2 / 2, b the rate toward zero. Close to a crossing this is nearly Newton's step, where
  // the slope bound alone only shrinks the distance by a fixed factor each time (22 steps per
  // group of supports on the head, most of them crawling up to the surface; 8 with this step).
  static double taylor_step(double g, double slope, double bend) {
    const double a = std::abs(g), b = g > 0.0 ? -slope : slope;
    const double root = std::sqrt(b * b + 2.0 * bend * a);
    return b + root > 0.0 ? 2.0 * a / (b + root) : 0.0;
  }

  std::optional<double> march(const Vector3d& o, const Vector3d& d, double t0, double t1,
                              const Support* supports, int n) const {
    double bend = 0.0;
    for (int k = 0; k < n; ++k) bend += el_[supports[k].element].bend;
    double t = t0, slope = 0.0;
    double g = eval(o, d, t, supports, n, &slope);
    if (g == 0.0) return t;
    const bool inside0 = g > 0.0;
    while (t < t1) {
      const double step =
          std::max({safe_step(t, g, supports, n), taylor_step(g, slope, bend), kMinStepMm});
      const double tn = std::min(t + step, t1);
      const double gn = eval(o, d, tn, supports, n, &slope);
      if (gn == 0.0) return tn;
      if ((gn > 0.0) != inside0) return refine(o, d, t, tn, inside0, supports, n);
      t = tn;
      g = gn;
    }
    return std::nullopt;
  }

  // Safeguarded Newton on a bracket [lo, hi] with the sign change; ends within 1e-9 mm.
  double refine(const Vector3d& o, const Vector3d& d, double lo, double hi, bool inside_lo,
                const Support* supports, int n) const {
    double x = 0.5 * (lo + hi);
    for (int it = 0; it < 100 && hi - lo > kRootTolMm; ++it) {
      double slope = 0.0;
      const double g = eval(o, d, x, supports, n, &slope);
      if (g == 0.0) return x;
      ((g > 0.0) == inside_lo ? lo : hi) = x;
      double next = slope != 0.0 ? x - g / slope : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      // A Newton step converging from one side never shrinks the bracket; probe the other side.
      if (std::abs(next - x) < 0.25 * kRootTolMm) {
        const double probe = next + (((g > 0.0) == inside_lo) ? 0.5 : -0.5) * kRootTolMm;
        if (probe > lo && probe < hi) next = probe;
      }
      x = next;
    }
    return std::clamp(x, lo, hi);
  }

  static std::optional<detail::Interval> support_interval(const Element& e, const Vector3d& o,
                                                          const Vector3d& d) {
    auto sphere = [&](const Vector3d& c) {
      const Vector3d q = o - c;
      return detail::quadratic_interval(1.0, q.dot(d), q.squaredNorm() - e.r2);
    };
    if (e.type == SkeletonElement::Type::Point) return sphere(e.a);
    // The capsule is convex: its line interval is the hull of the cylinder part (clipped to
    // the slab between the end planes) and the two end spheres.
    std::optional<detail::Interval> hull;
    auto add = [&](const std::optional<detail::Interval>& iv) {
      if (!iv) return;
      hull = hull ? detail::Interval{std::min(hull->first, iv->first),
                                     std::max(hull->second, iv->second)}
                  : *iv;
    };
    add(sphere(e.a));
    add(sphere(e.b));
    const Vector3d q = o - e.a;
    const Vector3d qp = q - q.dot(e.u) * e.u, dp = d - d.dot(e.u) * e.u;
    auto cyl = detail::quadratic_interval(dp.squaredNorm(), qp.dot(dp), qp.squaredNorm() - e.r2);
    const auto slab = detail::slab_interval(q.dot(e.u), d.dot(e.u), 0.0, e.len);
    if (cyl && slab) add(detail::intersect_intervals(*cyl, *slab));
    return hull;
  }

  std::vector<Element> el_;
  double iso_;
};

}  // namespace

std::shared_ptr<const SceneObject> make_skeletal(std::vector<SkeletonElement> elements,
                                                 double iso) {
  if (elements.empty()) throw InvalidInputError("skeletal surface needs at least one element");
  if (!(iso > 0.0) || !std::isfinite(iso))
    throw InvalidInputError("skeletal iso value must be positive, got " + std::to_string(iso));
  std::vector<Element> el;
  el.reserve(elements.size());
  for (const SkeletonElement& s : elements) {
    const std::string who = "skeleton element '" + s.name + "'";
    if (!(s.radius > 0.0) || !std::isfinite(s.radius))
      throw InvalidInputError(who + ": radius must be positive, got " + std::to_string(s.radius));
    if (!std::isfinite(s.weight)) throw InvalidInputError(who + ": weight must be finite");
    if (!s.a.allFinite() || !s.b.allFinite())
      throw InvalidInputError(who + ": coordinates must be finite");
    Element e;
    e.type = s.type;
    e.a = s.a;
    e.b = s.b;
    e.radius = s.radius;
    e.r2 = s.radius * s.radius;
    e.weight = s.weight;
    e.slope = std::abs(s.weight) * wyvill_max_slope() / s.radius;
    e.bend = std::abs(s.weight) * kKernelBendBound / e.r2;
    e.centre = s.a;
    if (s.type == SkeletonElement::Type::Segment) {
      e.len = (s.b - s.a).norm();
      if (!(e.len > 1e-9)) throw InvalidInputError(who + ": segment has zero length");
      e.u = (s.b - s.a) / e.len;
      e.centre = 0.5 * (s.a + s.b);
    }
    // Widened by a part in 10^6: the miss test must never drop an element the exact
    // interval would keep.
    const double reach = e.radius + 0.5 * e.len;
    e.reach2 = reach * reach * (1.0 + 1e-6) + 1e-9;
    el.push_back(e);
  }
  return std::make_shared<Skeletal>(std::move(el), iso);
}

}  // namespace scanmesh::sim
