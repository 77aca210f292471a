// Curves drawn in (phi, h) and lifted onto the continuous scan surface: arc length, curvature
// and curvature integral (needed by segment initialisation, seed 000 §5.1.3).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh {

enum class CurveKind {
  Polyline,    //!< straight in (phi, h) between control points
  CatmullRom,  //!< centripetal Catmull-Rom spline through the control points (C1)
};

//! A curve given by control points (phi, h) — phi may run past 2 pi (it is unwrapped, so a
//! curve can cross the seam) — lifted onto the surface. Parameter t runs over [0, n - 1]
//! (n control points; n for a closed curve).
class SurfaceCurve {
 public:
  //! Throws InvalidInputError for fewer than 2 points (3 when closed) or non-finite values.
  SurfaceCurve(const ScanSurface& surface, std::vector<Eigen::Vector2d> control_points,
               CurveKind kind = CurveKind::CatmullRom, bool closed = false);

  double t_max() const;
  //! (phi, h) at parameter t.
  Eigen::Vector2d parameter_point(double t) const;
  //! The lifted 3D point; nullopt where the surface is undefined.
  std::optional<Eigen::Vector3d> point(double t) const;

  //! 3D arc length along the lifted curve (adaptive Gauss-Legendre per span, tolerance_mm).
  //! Throws InvalidInputError if the curve leaves the defined surface.
  double arc_length(double tolerance_mm = 1e-6) const;
  //! Arc length from t = 0 to t.
  double arc_length_to(double t, double tolerance_mm = 1e-6) const;
  //! Curvature |X' x X''| / |X'|^3 of the lifted curve at t (1/mm).
  std::optional<double> curvature(double t) const;
  //! Integral of curvature over arc length (rad), by Gauss-Legendre per span.
  double curvature_integral() const;
  //! Parameters t of n points equally spaced in 3D arc length, first and last included.
  std::vector<double> equal_arc_length_parameters(int n) const;

 private:
  struct Derivs {
    Eigen::Vector2d p, dp, ddp;
  };
  Derivs parameter_derivatives(double t) const;
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> lifted_derivatives(double t) const;
  double speed(double t) const;
  //! Control point k for any integer k: wraps (with the period shift) when closed, extends
  //! linearly past the ends when open.
  Eigen::Vector2d control(int k) const;
  double knot(int k) const;

  const ScanSurface& surface_;
  std::vector<Eigen::Vector2d> points_;
  CurveKind kind_;
  bool closed_;
  double period_shift_ = 0;    //!< phi added per trip round a closed curve (0 or +-2 pi)
  std::vector<double> knots_;  //!< centripetal knots of control(0) .. control(last)
};

}  // namespace scanmesh
