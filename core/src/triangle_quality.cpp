#include "scanmesh/core/triangle_quality.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace scanmesh {

using Eigen::Vector3d;

double triangle_min_angle(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  auto at = [](const Vector3d& p, const Vector3d& q, const Vector3d& r) {
    const Vector3d e1 = q - p, e2 = r - p;
    return std::atan2(e1.cross(e2).norm(), e1.dot(e2));
  };
  return std::min({at(a, b, c), at(b, c, a), at(c, a, b)});
}

double radius_ratio(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  // r_in = A / s and R_circ = l1 l2 l3 / (4 A), so 2 r_in / R_circ = 8 A^2 / (s l1 l2 l3).
  const double la = (b - a).norm(), lb = (c - b).norm(), lc = (a - c).norm();
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const double s = 0.5 * (la + lb + lc);
  return s > 0 && la * lb * lc > 0 ? 8 * area * area / (s * la * lb * lc) : 0;
}

double aspect_ratio(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const double la = (b - c).norm(), lb = (c - a).norm(), lc = (a - b).norm();
  const double area = 0.5 * (b - a).cross(c - a).norm();
  if (!(area > 0)) return std::numeric_limits<double>::infinity();
  const double s = 0.5 * (la + lb + lc);
  const double circumradius = la * lb * lc / (4 * area), inradius = area / s;
  return circumradius / (2 * inradius);
}

double mean_ratio(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const double s = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  const double area = 0.5 * (b - a).cross(c - a).norm();
  return s > 0 ? 4.0 * std::sqrt(3.0) * area / s : 0.0;
}

}  // namespace scanmesh
