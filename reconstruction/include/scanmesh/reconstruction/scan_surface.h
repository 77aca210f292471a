// The continuous scan surface over a RangeGrid: a C1 piecewise-bicubic Hermite interpolant of
// r(phi, h) (Catmull-Rom: node slopes and twist from central differences) that wraps in phi.
// A patch is defined only where its four corner cells are valid, and node slopes next to a hole
// are one-sided, so the surface never reads or bridges an invalid cell.
//
// Why: seed 000 §6.1.2 found pixel-based curvature unusable (staircase values 40-80x too high) and
// asked for a continuous surface with float coordinates. docs/reconstruction.md has the details.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "scanmesh/core/range_grid.h"
#include "scanmesh/core/surface_curvature.h"

namespace scanmesh {

//! r and its partial derivatives in (phi [rad], h [mm]) at one parameter point.
struct RadiusJet {
  double r = 0, r_phi = 0, r_h = 0, r_phiphi = 0, r_phih = 0, r_hh = 0;
};

//! Position and first/second derivatives of X(phi, h) = (r cos phi, r sin phi, h).
struct SurfaceJet {
  Eigen::Vector3d position, d_phi, d_h, d_phiphi, d_phih, d_hh;
  //! Curvature from the first and second fundamental forms (Weingarten map).
  SurfaceCurvature curvature() const;
  Eigen::Vector3d normal() const;
};

SurfaceJet lift(double phi, double h, const RadiusJet& r);

//! Position, unit outward normal and the first derivatives dX/dphi, dX/dh (the same values as
//! evaluate()'s position, normal() and d_phi, d_h).
struct SurfacePoint {
  Eigen::Vector3d position, normal, d_phi, d_h;
};

//! One root of a ray or segment with the surface.
struct SurfaceHit {
  double t = 0;  //!< parameter along origin + t * direction
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double phi = 0, h = 0;
};

//! Closest surface point to a query point.
struct SurfaceProjection {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double phi = 0, h = 0;
  double distance = 0;
};

//! F(x) = r(phi(x), h(x)) - rho(x), rho = distance from the axis: > 0 inside the scanned
//! surface (between axis and surface), < 0 outside, 0 on it.
struct ImplicitSample {
  double value = 0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
};

class ScanSurface {
 public:
  //! Keeps a copy of the radius and validity planes (the grid may be destroyed afterwards).
  explicit ScanSurface(const RangeGrid& grid);

  int n_phi() const { return n_phi_; }
  int n_h() const { return n_h_; }
  double dphi() const { return dphi_; }
  double dh() const { return dh_; }
  double phi0() const { return phi0_; }
  double h0() const { return h0_; }

  //! True where the interpolant is defined: the four corners of the patch are valid.
  bool defined(double phi, double h) const;

  //! Bicubic r and its derivatives at any (phi, h); nullopt where not defined.
  std::optional<RadiusJet> radius(double phi, double h) const;
  //! r alone (the same value as radius()->r, bit for bit), for root searches.
  std::optional<double> radius_value(double phi, double h) const;
  std::optional<SurfaceJet> evaluate(double phi, double h) const;
  //! Position and normal only: first derivatives, about half the work of evaluate().
  std::optional<SurfacePoint> point_normal(double phi, double h) const;
  std::optional<Eigen::Vector3d> position(double phi, double h) const;

  //! Derivatives at grid node (i, j) from central differences (exact for quadratics; the
  //! symmetric node value of the interpolant's one-sided second derivatives). nullopt unless
  //! the 3 x 3 neighbourhood is valid (rows at the grid's top/bottom have none).
  std::optional<RadiusJet> node_jet(int i, int j) const;

  //! Every root t in [t_min, t_max] of the segment origin + t * direction with the surface,
  //! in increasing order. The segment is sampled at steps below `max_step_mm` (default: a
  //! quarter of the finest cell) and each sign change of F is refined by bisection to
  //! `tolerance_mm`; a tangential touch that changes no sign between samples is not reported.
  std::vector<SurfaceHit> intersect_segment(const Eigen::Vector3d& origin,
                                            const Eigen::Vector3d& direction, double t_min,
                                            double t_max, double max_step_mm = 0,
                                            double tolerance_mm = 1e-6) const;

  //! Every intersection of the circle (centre, radius, plane spanned by unit u, v) with the
  //! surface, as angles in [0, 2 pi) (the AFT's rotation construction, seed 000 §4.3).
  std::vector<double> intersect_circle(const Eigen::Vector3d& centre, double radius,
                                       const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                                       double tolerance_mm = 1e-6) const;

  //! Closest point by Gauss-Newton on (phi, h) from the radial projection of x; nullopt if
  //! the surface is not defined around x.
  std::optional<SurfaceProjection> project(const Eigen::Vector3d& x) const;
  //! The same from a given start (phi, h) near the answer, e.g. the parameters of a surface
  //! point next to x: fewer iterations, and no angle of x to compute. The returned phi is
  //! unwrapped next to the start's, not reduced to [0, 2 pi).
  std::optional<SurfaceProjection> project(const Eigen::Vector3d& x,
                                           const Eigen::Vector2d& start) const;

  //! The implicit view F(x) = r(phi(x), h(x)) - rho(x) and its gradient.
  std::optional<ImplicitSample> implicit(const Eigen::Vector3d& x) const;

  //! The root-search step of intersect_segment / intersect_circle (a quarter of the finest
  //! cell), for callers that search a part of a curve themselves.
  double sampling_step_mm() const { return sampling_step_mm_; }

  //! Cylindrical coordinates of a point: phi in [phi0, phi0 + 2 pi), h, rho.
  static Eigen::Vector3d to_cylindrical(const Eigen::Vector3d& x);

 private:
  bool cell_valid(int i, int j) const;
  float r_at(int i, int j) const;                  // i wrapped, j in range
  std::size_t index_wrapped(int i, int j) const {  // i wrapped, j in range
    return static_cast<std::size_t>(j) * n_phi_ + ((i % n_phi_) + n_phi_) % n_phi_;
  }
  bool support_valid(int i, int j) const;
  // Grid coordinates: u in [0, n_phi), v in [0, n_h - 1].
  bool to_grid(double phi, double h, double& u, double& v) const;
  std::optional<double> implicit_value(const Eigen::Vector3d& x) const;
  // radius() with or without the second derivatives (left 0 without).
  std::optional<RadiusJet> radius_jet(double phi, double h, bool second_order) const;
  // The patch of (phi, h): corner (i, j) and the local coordinates; false where undefined.
  bool patch_at(double phi, double h, int& i, int& j, double& s, double& t) const;
  struct HermiteNode {
    double r, r_u, r_v, r_uv;  // value and slopes in grid units (per index step)
  };
  HermiteNode hermite_node(int i, int j) const;

  int n_phi_, n_h_;
  double phi0_, h0_, dphi_, dh_;
  std::vector<float> r_;
  std::vector<std::uint8_t> valid_;
  // support_ok_[index(i, j)]: the 4 x 4 support of the patch [i, i+1] x [j, j+1] is valid.
  std::vector<std::uint8_t> support_ok_;
  // hermite_[index(i, j)]: the interpolant's node data, computed once (valid cells only);
  // building it per evaluation was the largest cost of the AFT at fine unit sizes.
  std::vector<HermiteNode> hermite_;
  double sampling_step_mm_ = 0;  // root-search step: a quarter of the finest cell
};

}  // namespace scanmesh
