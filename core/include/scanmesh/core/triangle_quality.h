// Named shape measures of one triangle: the only place a quality report takes them from, so
// that a number called "radius ratio" is the same number in every report (docs/formats.md,
// "Triangle quality measures").
#pragma once

#include <Eigen/Core>

namespace scanmesh {

//! Smallest interior angle in radians (atan2 of |e1 x e2| and e1 . e2, accurate near 0 and pi).
double triangle_min_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& c);

//! Radius ratio rho = 2 r_in / R_circ in [0, 1]: 1 for the equilateral triangle, 0 for a
//! degenerate one. What the checker, the animation meshes and the web UI report.
double radius_ratio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

//! Aspect ratio Q = R_circ / (2 r_in) = 1 / rho in [1, inf): seed 001's measure, what the
//! remesher reports; infinity for a degenerate triangle.
double aspect_ratio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

//! Mean ratio 4 sqrt(3) A / (l1^2 + l2^2 + l3^2) in [0, 1]: 1 for the equilateral triangle.
//! Smooth in the corners (no division by the area), so the AFT's star smoothing compares sums
//! of it; of the reports only bench_particles shows it (its q column).
double mean_ratio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace scanmesh
