// Analytic scene objects: sphere, cylinder, ellipsoid, torus, box (docs/simulator.md).
#include "scanmesh/sim/shapes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "convex_interval.h"
#include "scanmesh/core/errors.h"

namespace scanmesh::sim {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kInf = std::numeric_limits<double>::infinity();

void require_positive(double v, const char* what) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw InvalidInputError(std::string(what) + " must be positive and finite, got " +
                            std::to_string(v));
}

void require_finite(const Vector3d& v, const char* what) {
  if (!v.allFinite()) throw InvalidInputError(std::string(what) + " must be finite");
}

Vector3d unit_axis(const Vector3d& axis) {
  require_finite(axis, "axis");
  const double n = axis.norm();
  if (!(n > 1e-12)) throw InvalidInputError("axis must be a non-zero vector");
  return axis / n;
}

//! A point seen from an axis through `center` with unit direction `axis`: its height `z` along
//! the axis, its offset `radial` perpendicular to it and that offset's length `rho`.
struct AxialCoordinates {
  double z;
  Vector3d radial;
  double rho;
};

AxialCoordinates axial_coordinates(const Vector3d& x, const Vector3d& center,
                                   const Vector3d& axis) {
  const Vector3d q = x - center;
  const double z = q.dot(axis);
  const Vector3d radial = q - z * axis;
  return {z, radial, radial.norm()};
}

class Sphere final : public SceneObject {
 public:
  Sphere(const Vector3d& c, double r) : c_(c), r_(r) {}
  FieldSample field(const Vector3d& x) const override {
    const Vector3d q = x - c_;
    return {(q.squaredNorm() - r_ * r_) / (2.0 * r_), q / r_, Matrix3d::Identity() / r_};
  }
  std::optional<double> intersect(const Vector3d& o, const Vector3d& d, double t_min,
                                  double t_max) const override {
    const Vector3d q = o - c_;
    const auto iv = detail::quadratic_interval(1.0, q.dot(d), q.squaredNorm() - r_ * r_);
    if (!iv) return std::nullopt;
    return detail::first_crossing(*iv, t_min, t_max);
  }

  Eigen::AlignedBox3d bounds() const override {
    return {c_ - Vector3d::Constant(r_), c_ + Vector3d::Constant(r_)};
  }

 private:
  Vector3d c_;
  double r_;
};

class Cylinder final : public SceneObject {
 public:
  Cylinder(const Vector3d& c, const Vector3d& axis, double r, std::optional<double> hl)
      : c_(c), a_(axis), r_(r), hl_(hl) {}
  FieldSample field(const Vector3d& x) const override {
    const auto [z, radial, rho] = axial_coordinates(x, c_, a_);
    FieldSample f;
    const double d_rad = rho - r_;
    const double d_cap = hl_ ? std::abs(z) - *hl_ : -kInf;
    if (d_cap > d_rad) {  // a flat cap is the nearer surface: plane, Hessian 0
      f.value = d_cap;
      f.gradient = z >= 0 ? a_ : Vector3d(-a_);
      return f;
    }
    f.value = d_rad;
    if (rho > 1e-300) {
      const Vector3d e = radial / rho;
      f.gradient = e;
      f.hessian = (Matrix3d::Identity() - a_ * a_.transpose() - e * e.transpose()) / rho;
    }
    return f;
  }
  std::optional<double> intersect(const Vector3d& o, const Vector3d& d, double t_min,
                                  double t_max) const override {
    const Vector3d q = o - c_;
    const Vector3d qp = q - q.dot(a_) * a_, dp = d - d.dot(a_) * a_;
    auto iv = detail::quadratic_interval(dp.squaredNorm(), qp.dot(dp), qp.squaredNorm() - r_ * r_);
    if (!iv) return std::nullopt;
    if (hl_) {
      const auto slab = detail::slab_interval(q.dot(a_), d.dot(a_), -*hl_, *hl_);
      if (!slab) return std::nullopt;
      iv = detail::intersect_intervals(*iv, *slab);
      if (!iv) return std::nullopt;
    }
    return detail::first_crossing(*iv, t_min, t_max);
  }

  Eigen::AlignedBox3d bounds() const override {
    if (!hl_) return {Vector3d::Constant(-1e12), Vector3d::Constant(1e12)};
    // Per axis: the caps' centres reach hl |a_i|, the rims a further r sqrt(1 - a_i^2).
    Vector3d extent;
    for (int k = 0; k < 3; ++k)
      extent(k) = *hl_ * std::abs(a_(k)) + r_ * std::sqrt(std::max(0.0, 1.0 - a_(k) * a_(k)));
    return {c_ - extent, c_ + extent};
  }

 private:
  Vector3d c_, a_;
  double r_;
  std::optional<double> hl_;
};

class Ellipsoid final : public SceneObject {
 public:
  Ellipsoid(const Vector3d& c, const Vector3d& radii)
      : c_(c), inv2_(radii.cwiseProduct(radii).cwiseInverse()), scale_(radii.minCoeff() / 2.0) {}
  FieldSample field(const Vector3d& x) const override {
    const Vector3d q = x - c_;
    FieldSample f;
    f.value = scale_ * (q.cwiseProduct(q).dot(inv2_) - 1.0);
    f.gradient = 2.0 * scale_ * q.cwiseProduct(inv2_);
    f.hessian = (2.0 * scale_ * inv2_).asDiagonal();
    return f;
  }
  std::optional<double> intersect(const Vector3d& o, const Vector3d& d, double t_min,
                                  double t_max) const override {
    const Vector3d q = o - c_;
    const Vector3d qs = q.cwiseProduct(inv2_), ds = d.cwiseProduct(inv2_);
    const auto iv = detail::quadratic_interval(d.dot(ds), q.dot(ds), q.dot(qs) - 1.0);
    if (!iv) return std::nullopt;
    return detail::first_crossing(*iv, t_min, t_max);
  }

  Eigen::AlignedBox3d bounds() const override {
    const Vector3d radii = inv2_.cwiseInverse().cwiseSqrt();
    return {c_ - radii, c_ + radii};
  }

 private:
  Vector3d c_, inv2_;
  double scale_;
};

class Torus final : public SceneObject {
 public:
  Torus(const Vector3d& c, const Vector3d& axis, double big_r, double small_r)
      : c_(c), a_(axis), big_r_(big_r), small_r_(small_r) {}

  FieldSample field(const Vector3d& x) const override {
    const auto [z, radial, rho] = axial_coordinates(x, c_, a_);
    FieldSample f;
    // On the axis every direction is radial; pick one so the field stays defined.
    const Vector3d e = rho > 1e-300 ? Vector3d(radial / rho) : any_perpendicular();
    const double w = rho - big_r_;
    const double d = std::hypot(w, z);
    f.value = d - small_r_;
    if (d < 1e-300) return f;  // on the core circle: distance not differentiable
    const Vector3d n = (w * e + z * a_) / d;
    f.gradient = n;
    // Hessian of the distance to the core circle: (m m^T + (w / rho) t t^T) / d, with m the
    // unit vector normal to n in the (e, a) plane and t the azimuthal direction.
    const Vector3d m = (z * e - w * a_) / d;
    Matrix3d h = m * m.transpose();
    if (rho > 1e-300) {
      const Vector3d t = a_.cross(e);
      h += (w / rho) * t * t.transpose();
    }
    f.hessian = h / d;
    return f;
  }

  std::optional<double> intersect(const Vector3d& o, const Vector3d& d, double t_min,
                                  double t_max) const override {
    // Restrict to the bounding sphere, then sphere-trace the exact (1-Lipschitz) distance.
    const Vector3d q = o - c_;
    const double bound = big_r_ + small_r_;
    const auto iv = detail::quadratic_interval(1.0, q.dot(d), q.squaredNorm() - bound * bound);
    if (!iv) return std::nullopt;
    double t = std::max(t_min, iv->first), t_end = std::min(t_max, iv->second);
    if (t > t_end) return std::nullopt;
    auto sdf = [&](double s) { return field(o + s * d).value; };
    double f = sdf(t);
    const bool inside = f < 0.0;
    for (int it = 0; it < 100000 && t <= t_end; ++it) {
      if (std::abs(f) < 1e-11) return t;
      const double step = std::max(std::abs(f), 1e-7);
      const double tn = std::min(t + step, t_end);
      const double fn = sdf(tn);
      if ((fn < 0.0) != inside) {  // crossed within a minimum step: bisect
        double lo = t, hi = tn;
        for (int k = 0; k < 80 && hi - lo > 1e-12; ++k) {
          const double mid = 0.5 * (lo + hi);
          ((sdf(mid) < 0.0) == inside ? lo : hi) = mid;
        }
        return 0.5 * (lo + hi);
      }
      if (tn >= t_end) break;
      t = tn;
      f = fn;
    }
    return std::nullopt;
  }

  Eigen::AlignedBox3d bounds() const override {
    const double reach = big_r_ + small_r_;
    return {c_ - Vector3d::Constant(reach), c_ + Vector3d::Constant(reach)};
  }

 private:
  Vector3d any_perpendicular() const {
    const Vector3d helper = std::abs(a_.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
    return a_.cross(helper).normalized();
  }
  Vector3d c_, a_;
  double big_r_, small_r_;
};

class Box final : public SceneObject {
 public:
  Box(const Vector3d& c, const Vector3d& half) : c_(c), half_(half) {}

  FieldSample field(const Vector3d& x) const override {
    const Vector3d p = x - c_;
    const Vector3d q = p.cwiseAbs() - half_;
    FieldSample f;
    Vector3d sign;
    for (int k = 0; k < 3; ++k) sign[k] = p[k] >= 0.0 ? 1.0 : -1.0;
    if (q.maxCoeff() <= 0.0) {  // inside: distance to the nearest face plane
      int k = 0;
      q.maxCoeff(&k);
      f.value = q[k];
      f.gradient[k] = sign[k];
      return f;
    }
    // Outside: distance to the nearest face (plane), edge (line) or corner (point).
    const Vector3d pos = q.cwiseMax(0.0);
    const double d = pos.norm();
    f.value = d;
    const Vector3d n = pos.cwiseProduct(sign) / d;
    f.gradient = n;
    Matrix3d proj = Matrix3d::Zero();  // projector onto the directions the distance varies in
    int active = 0;
    for (int k = 0; k < 3; ++k)
      if (q[k] > 0.0) {
        proj(k, k) = 1.0;
        ++active;
      }
    if (active >= 2) f.hessian = (proj - n * n.transpose()) / d;
    return f;
  }

  std::optional<double> intersect(const Vector3d& o, const Vector3d& d, double t_min,
                                  double t_max) const override {
    detail::Interval iv{-kInf, kInf};
    for (int k = 0; k < 3; ++k) {
      const auto slab = detail::slab_interval(o[k] - c_[k], d[k], -half_[k], half_[k]);
      if (!slab) return std::nullopt;
      const auto both = detail::intersect_intervals(iv, *slab);
      if (!both) return std::nullopt;
      iv = *both;
    }
    return detail::first_crossing(iv, t_min, t_max);
  }

  Eigen::AlignedBox3d bounds() const override { return {c_ - half_, c_ + half_}; }

 private:
  Vector3d c_, half_;
};

}  // namespace

std::shared_ptr<const SceneObject> make_sphere(const Vector3d& center, double radius) {
  require_finite(center, "sphere center");
  require_positive(radius, "sphere radius");
  return std::make_shared<Sphere>(center, radius);
}

std::shared_ptr<const SceneObject> make_cylinder(const Vector3d& center, const Vector3d& axis,
                                                 double radius, std::optional<double> half_length) {
  require_finite(center, "cylinder center");
  require_positive(radius, "cylinder radius");
  if (half_length) require_positive(*half_length, "cylinder half_length");
  return std::make_shared<Cylinder>(center, unit_axis(axis), radius, half_length);
}

std::shared_ptr<const SceneObject> make_ellipsoid(const Vector3d& center, const Vector3d& radii) {
  require_finite(center, "ellipsoid center");
  for (int k = 0; k < 3; ++k) require_positive(radii[k], "ellipsoid radii");
  return std::make_shared<Ellipsoid>(center, radii);
}

std::shared_ptr<const SceneObject> make_torus(const Vector3d& center, const Vector3d& axis,
                                              double major_radius, double minor_radius) {
  require_finite(center, "torus center");
  require_positive(major_radius, "torus major_radius");
  require_positive(minor_radius, "torus minor_radius");
  return std::make_shared<Torus>(center, unit_axis(axis), major_radius, minor_radius);
}

std::shared_ptr<const SceneObject> make_box(const Vector3d& center, const Vector3d& half_extents) {
  require_finite(center, "box center");
  for (int k = 0; k < 3; ++k) require_positive(half_extents[k], "box half_extents");
  return std::make_shared<Box>(center, half_extents);
}

}  // namespace scanmesh::sim
