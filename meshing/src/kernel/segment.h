// The meshing kernel's point-segment queries, for any Eigen vector (2D or 3D). Shared by the
// AFT (regions, data border, front) and the scan clean-up's neck search.
#pragma once

#include <algorithm>

namespace scanmesh::kernel {

//! The place t in [0, 1] of the point of segment a-b closest to p (0 if a = b).
template <typename Vector>
double closest_segment_parameter(const Vector& p, const Vector& a, const Vector& b) {
  const Vector ab = b - a;
  return ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
}

//! Distance from p to the segment a-b.
template <typename Vector>
double point_segment_distance(const Vector& p, const Vector& a, const Vector& b) {
  const double t = closest_segment_parameter(p, a, b);
  return (a + t * (b - a) - p).norm();
}

}  // namespace scanmesh::kernel
