#include "scanmesh/core/surface_curvature.h"

#include <Eigen/Eigenvalues>

namespace scanmesh {

SurfaceCurvature curvature_from_fundamental_forms(const Eigen::Vector3d& du,
                                                  const Eigen::Vector3d& dv,
                                                  const Eigen::Vector3d& normal,
                                                  const Eigen::Matrix2d& first,
                                                  const Eigen::Matrix2d& second) {
  // Generalised symmetric eigenproblem: eigenvalues ascending, eigenvectors in (du, dv).
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d> solver(second, first);
  SurfaceCurvature out;
  out.normal = normal;
  out.k2 = solver.eigenvalues()(0);
  out.k1 = solver.eigenvalues()(1);
  const Eigen::Vector2d a1 = solver.eigenvectors().col(1), a2 = solver.eigenvectors().col(0);
  out.dir1 = (a1(0) * du + a1(1) * dv).normalized();
  out.dir2 = (a2(0) * du + a2(1) * dv).normalized();
  return out;
}

}  // namespace scanmesh
