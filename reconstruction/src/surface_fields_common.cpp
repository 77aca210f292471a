// The parts of surface_fields.h shared by every method: the method names and the field planes.
#include <algorithm>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/surface_fields.h"

namespace scanmesh {

CurvatureMethod parse_curvature_method(const std::string& name) {
  if (name == "analytic") return CurvatureMethod::Analytic;
  if (name == "quadric") return CurvatureMethod::Quadric;
  if (name == "grid-quadric") return CurvatureMethod::GridQuadric;
  if (name == "seed" || name == "seed000") return CurvatureMethod::Seed000;
  throw InvalidInputError("unknown curvature method '" + name +
                          "' (expected analytic, grid-quadric, quadric or seed)");
}

std::string to_string(CurvatureMethod m) {
  switch (m) {
    case CurvatureMethod::Analytic:
      return "analytic";
    case CurvatureMethod::Quadric:
      return "quadric";
    case CurvatureMethod::Seed000:
      return "seed000";
    case CurvatureMethod::GridQuadric:
      return "grid-quadric";
  }
  return "unknown";
}

std::size_t SurfaceFields::defined_count() const {
  return static_cast<std::size_t>(
      std::count_if(defined.begin(), defined.end(), [](std::uint8_t d) { return d != 0; }));
}

void SurfaceFields::resize(int new_n_phi, int new_n_h) {
  if (new_n_phi < 0 || new_n_h < 0)
    throw InvalidInputError("surface fields size " + std::to_string(new_n_phi) + " x " +
                            std::to_string(new_n_h) + " is impossible");
  n_phi = new_n_phi;
  n_h = new_n_h;
  const std::size_t n = static_cast<std::size_t>(n_phi) * static_cast<std::size_t>(n_h);
  // Every plane starts over at "no estimate": defined 0 and all values 0 (the header's rule).
  defined.assign(n, 0);
  normal.assign(n, Eigen::Vector3f::Zero());
  k1.assign(n, 0.0f);
  k2.assign(n, 0.0f);
  dir1.assign(n, Eigen::Vector3f::Zero());
  dir2.assign(n, Eigen::Vector3f::Zero());
}

}  // namespace scanmesh
