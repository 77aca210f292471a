// Scene objects with exact field, gradient and Hessian (docs/simulator.md, "Scene objects"):
// analytic shapes and the skeleton-based implicit surface of seed 003 §2.1-2.2 (eq. 1-2).
// Every field is < 0 inside, > 0 outside, with the gradient pointing outward.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/core/errors.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh::sim {

//! Sphere |x - c| = r. Field (|x-c|^2 - r^2) / (2r): smooth everywhere, |grad| = 1 on the surface.
std::shared_ptr<const SceneObject> make_sphere(const Eigen::Vector3d& center, double radius);

//! Cylinder of `radius` around the line through `center` along `axis` (normalised here).
//! half_length = nullopt gives the infinite cylinder, otherwise it is capped by two flat discs
//! at +-half_length from center. Field: max(rho - r, |z| - half_length).
std::shared_ptr<const SceneObject> make_cylinder(const Eigen::Vector3d& center,
                                                 const Eigen::Vector3d& axis, double radius,
                                                 std::optional<double> half_length);

//! Axis-aligned ellipsoid with semi-axes `radii`. Field min(radii)/2 * (sum x_i^2/a_i^2 - 1).
std::shared_ptr<const SceneObject> make_ellipsoid(const Eigen::Vector3d& center,
                                                  const Eigen::Vector3d& radii);

//! Torus around `axis` through `center`: tube of radius `minor_radius` around the circle of
//! radius `major_radius`. Field: the exact signed distance. Intersection: sphere tracing.
std::shared_ptr<const SceneObject> make_torus(const Eigen::Vector3d& center,
                                              const Eigen::Vector3d& axis, double major_radius,
                                              double minor_radius);

//! Axis-aligned box. Field: the exact signed distance (its Hessian is that of the distance to
//! the nearest face, edge or corner). Intersection: exact slab test.
std::shared_ptr<const SceneObject> make_box(const Eigen::Vector3d& center,
                                            const Eigen::Vector3d& half_extents);

//! One skeleton element of a skeletal implicit surface (seed 003 §2.1: points and segments).
struct SkeletonElement {
  enum class Type { Point, Segment };
  std::string name;
  Type type = Type::Point;
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  //!< the point, or the segment start
  Eigen::Vector3d b = Eigen::Vector3d::Zero();  //!< the segment end (unused for points)
  double radius = 1.0;  //!< radius of influence R_i: the kernel is 0 beyond it
  double weight = 1.0;  //!< w_i; negative weights carve (eye sockets)
};

//! Wyvill "soft objects" kernel of seed 003 §2.2 as a function of s = d^2 (no square root):
//! e = 1 - 4/9 u^3 + 17/9 u^2 - 22/9 u with u = s / R^2 for s < R^2, else 0.
//! Returns e, de/ds and d^2e/ds^2.
struct KernelValue {
  double e = 0.0, de_ds = 0.0, d2e_ds2 = 0.0;
};
KernelValue wyvill_kernel(double s, double radius);
//! max over r of |de/dr| of the Wyvill kernel for R = 1 (about 1.5844); divide by R_i.
double wyvill_max_slope();

//! The skeleton-based implicit surface F(x) = sum_i w_i e(d_i(x)) = iso (seed 003 eq. 1-2) with
//! the Wyvill kernel and the Euclidean distance to each element, exposed with field value
//! iso - F (so < 0 inside, gradient outward; seed 003 has the solid at F >= I). A single point
//! with iso 0.5 is the sphere of radius R/2. Ray intersection marches only inside the union of
//! the elements' support spheres/capsules along the ray, with steps bounded by the Lipschitz
//! constant sum |w_i| * 1.5844 / R_i, then refines the crossing to 1e-9 mm.
//! \throw InvalidInputError for no elements, non-positive radius, iso <= 0, degenerate segment
//!        or non-finite numbers.
std::shared_ptr<const SceneObject> make_skeletal(std::vector<SkeletonElement> elements,
                                                 double iso = 0.5);

}  // namespace scanmesh::sim
