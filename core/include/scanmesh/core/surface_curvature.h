// Principal curvatures of a surface point: the one type the simulator's ground truth and the
// reconstruction's estimates share, so they compare directly.
#pragma once

#include <Eigen/Core>

namespace scanmesh {

//! Normal and principal curvatures at a surface point. The normal points outward (away from the
//! turntable axis for a scan); k > 0 where the surface bends away from the normal (a sphere of
//! radius R has k1 = k2 = 1/R); k1 >= k2; dir1, dir2 are unit principal directions.
struct SurfaceCurvature {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double k1 = 0.0, k2 = 0.0;
  Eigen::Vector3d dir1 = Eigen::Vector3d::Zero(), dir2 = Eigen::Vector3d::Zero();
  double mean() const { return 0.5 * (k1 + k2); }
  double gauss() const { return k1 * k2; }
};

//! Curvature of a parametrised surface patch from its tangent vectors du, dv, unit normal, first
//! fundamental form I (Gram matrix of du, dv) and second fundamental form II taken with the sign
//! that makes convex surfaces positive (II_ij = -X_ij . n): solves II a = k I a.
SurfaceCurvature curvature_from_fundamental_forms(const Eigen::Vector3d& du,
                                                  const Eigen::Vector3d& dv,
                                                  const Eigen::Vector3d& normal,
                                                  const Eigen::Matrix2d& first,
                                                  const Eigen::Matrix2d& second);

}  // namespace scanmesh
