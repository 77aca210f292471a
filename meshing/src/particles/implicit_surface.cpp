// Newton projection (eq. 8 with P = 0) and the scan surface adapter.
#include "scanmesh/meshing/particles/implicit_surface.h"

#include <cmath>

namespace scanmesh::particles {

using Eigen::Vector3d;

std::optional<Vector3d> project_to_surface(const ImplicitSurface& surface, const Vector3d& x,
                                           int iterations, double tolerance) {
  Vector3d p = x;
  for (int k = 0; k < iterations; ++k) {
    const auto f = surface.evaluate(p);
    if (!f) return std::nullopt;
    const double g2 = f->gradient.squaredNorm();
    if (!(g2 > 1e-24)) return std::nullopt;
    const Vector3d delta = f->value / g2 * f->gradient;
    p -= delta;
    if (delta.norm() < tolerance) break;
  }
  return p;
}

ScanImplicitSurface::ScanImplicitSurface(const ScanSurface& surface) : surface_(surface) {
  // Bounds from the interpolant at the grid nodes (plus one cell of margin in h and 5% in r).
  double r_max = 0.0, h_min = 1e300, h_max = -1e300;
  for (int j = 0; j < surface.n_h(); ++j)
    for (int i = 0; i < surface.n_phi(); ++i) {
      const double phi = surface.phi0() + (i + 0.5) * surface.dphi();
      const double h = surface.h0() + j * surface.dh();
      if (const auto p = surface.position(phi, h)) {
        r_max = std::max(r_max, std::hypot(p->x(), p->y()));
        h_min = std::min(h_min, h);
        h_max = std::max(h_max, h);
      }
    }
  if (h_min > h_max) {
    bounds_ = Eigen::AlignedBox3d(Vector3d::Zero(), Vector3d::Zero());
    return;
  }
  const double r = 1.05 * r_max + surface.dh();
  bounds_ = Eigen::AlignedBox3d(Vector3d(-r, -r, h_min - surface.dh()),
                                Vector3d(r, r, h_max + surface.dh()));
}

std::optional<ImplicitValue> ScanImplicitSurface::evaluate(const Vector3d& x) const {
  const auto s = surface_.implicit(x);
  if (!s) return std::nullopt;
  // ScanSurface: F = r - rho > 0 inside; this interface wants < 0 inside.
  return ImplicitValue{.value = -s->value, .gradient = -s->gradient, .dvalue_dt = 0.0};
}

}  // namespace scanmesh::particles
