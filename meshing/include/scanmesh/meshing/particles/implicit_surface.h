// The implicit surface the particle and spring methods of seed 003 work on (seed 003 eq. 3-8).
// Meshing must not depend on sim, so this is the abstract interface; adapters wrap sim's scene
// objects and animated skeletons (apps/src/implicit_adapters.h, tests) and the scan surface's
// implicit view (ScanImplicitSurface below).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <optional>

#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::particles {

//! F, grad F and dF/dt at one point. Convention: value < 0 inside, > 0 outside, gradient
//! outward. (Seed 003 has the solid at F >= I; value here is I - F_seed.)
struct ImplicitValue {
  double value = 0.0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  double dvalue_dt = 0.0;  //!< F_q q' of eq. (5): zero for a static surface
};

//! A (possibly time-varying) implicit surface F(x) = 0 frozen at one time, with its time
//! derivative at that time.
class ImplicitSurface {
 public:
  virtual ~ImplicitSurface() = default;
  //! nullopt where the function is not defined (e.g. over a hole of a scan).
  virtual std::optional<ImplicitValue> evaluate(const Eigen::Vector3d& x) const = 0;
  //! Hessian if the surface has one (used only for test/benchmark ground truth).
  virtual std::optional<Eigen::Matrix3d> hessian(const Eigen::Vector3d&) const {
    return std::nullopt;
  }
  //! A box that contains the whole surface (the start triangulation polygonises it).
  virtual Eigen::AlignedBox3d bounds() const = 0;
};

//! Newton projection onto F = 0 (eq. 8 with P = 0, phi dt = 1), at most `iterations` steps,
//! stopping when |F|/|grad F| < tolerance. nullopt if F is undefined or the gradient vanishes.
std::optional<Eigen::Vector3d> project_to_surface(const ImplicitSurface& surface,
                                                  const Eigen::Vector3d& x, int iterations = 20,
                                                  double tolerance = 1e-12);

//! The scan surface's implicit view with the sign flipped to this interface's convention:
//! value = rho(x) - r(phi(x), h(x)) (< 0 between the axis and the surface). Defined only where
//! the bicubic patch is; bounds from the grid's valid radii and heights. Static (dF/dt = 0).
class ScanImplicitSurface final : public ImplicitSurface {
 public:
  //! Keeps a reference: `surface` must outlive this object.
  explicit ScanImplicitSurface(const ScanSurface& surface);
  std::optional<ImplicitValue> evaluate(const Eigen::Vector3d& x) const override;
  Eigen::AlignedBox3d bounds() const override { return bounds_; }

 private:
  const ScanSurface& surface_;
  Eigen::AlignedBox3d bounds_;
};

}  // namespace scanmesh::particles
