// Internal interfaces of the animation-mesh stage (not installed).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "../kernel/cell_lists.h"
#include "../kernel/segment.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/edge_key.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::aft::detail {

//! std::remainder(d, 2 pi), the angle difference d wrapped into [-pi, pi], bit for bit, with the
//! common case |d| <= pi (where the answer is d) first: remainder's rounding-mode bookkeeping
//! made it ~7 % of the advancing front's time.
inline double wrap_angle(double d) {
  return std::fabs(d) <= M_PI ? d : std::remainder(d, 2 * M_PI);
}

//! The midpoint of two (phi, h) parameters across the phi seam: phi next to a's.
inline Eigen::Vector2d param_midpoint(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return {a.x() + 0.5 * wrap_angle(b.x() - a.x()), 0.5 * (a.y() + b.y())};
}

//! The signed area of the polygon p (shoelace formula), positive if it runs counter-clockwise.
inline double signed_area(const std::vector<Eigen::Vector2d>& p) {
  double a = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& u = p[i];
    const Eigen::Vector2d& v = p[(i + 1) % p.size()];
    a += u.x() * v.y() - v.x() * u.y();
  }
  return 0.5 * a;
}

//! The periodic copy of the piece q (end points a, b in texture pixels, x unwrapped with period
//! W) whose midpoint is nearest p's, moved k more periods along x. Crossing tests try
//! k = -1, 0, 1: the nearest copy by midpoint need not be the one that crosses a long piece.
template <typename Piece>
Piece periodic_copy_near(const Piece& p, const Piece& q, double W, int k) {
  Piece copy = q;
  const double shift =
      W * (std::round((0.5 * (p.a.x() + p.b.x()) - 0.5 * (copy.a.x() + copy.b.x())) / W) + k);
  copy.a.x() += shift;
  copy.b.x() += shift;
  return copy;
}

//! The angle at p of the triangle (p, q, r), in radians.
inline double angle_at(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                       const Eigen::Vector3d& r) {
  const Eigen::Vector3d u = q - p, v = r - p;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

//! The angles of triangle f (corners in P) at f[0], f[1] and f[2], in radians.
inline std::array<double, 3> corner_angles(std::span<const Eigen::Vector3d> P,
                                           const std::array<int, 3>& f) {
  std::array<double, 3> a;
  for (int k = 0; k < 3; ++k) a[k] = angle_at(P[f[k]], P[f[(k + 1) % 3]], P[f[(k + 2) % 3]]);
  return a;
}

//! The corner (0, 1 or 2) with the smallest of a triangle's angles, the first of equals.
inline int smallest_corner(const std::array<double, 3>& angles) {
  return static_cast<int>(std::min_element(angles.begin(), angles.end()) - angles.begin());
}
//! True if both edges of f at corner k are in `edges` (edge_key keys): the angle there lies
//! between two constraint (line) edges, so the input fixes it.
inline bool corner_between(const std::array<int, 3>& f, int k,
                           const std::unordered_set<std::uint64_t>& edges) {
  return edges.count(edge_key(f[k], f[(k + 1) % 3])) && edges.count(edge_key(f[k], f[(k + 2) % 3]));
}

//! The smallest angle of the triangle (a, b, c), in radians: the angle opposite the shortest
//! side, so one atan2 instead of three (angle evaluations are a large share of the meshers' and
//! the repair's work).
inline double min_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c) {
  const double la = (b - c).squaredNorm(), lb = (c - a).squaredNorm(), lc = (a - b).squaredNorm();
  if (la <= lb && la <= lc) return angle_at(a, b, c);
  return lb <= lc ? angle_at(b, c, a) : angle_at(c, a, b);
}

using kernel::closest_segment_parameter;
using kernel::point_segment_distance;

using kernel::cell_key;
using kernel::cell_of;
using kernel::pack_cell;

//! The map from a tangent displacement at a surface point to the (phi, h) step that makes it,
//! to first order: the pseudo-inverse of [dX/dphi, dX/dh]. Lifting param + M d lands on the
//! surface within |d|^2 x curvature of the point + d, for the cost of one evaluation, where a
//! projection of the point + d iterates.
inline Eigen::Matrix<double, 2, 3> tangent_to_parameters(const SurfacePoint& at) {
  Eigen::Matrix<double, 3, 2> jac;
  jac << at.d_phi, at.d_h;
  return (jac.transpose() * jac).inverse() * jac.transpose();
}

using kernel::CellLists;

//! Triangles filed under the cells of a uniform 3D grid that their bounding boxes overlap, for
//! local 3D crossing tests while a mesh changes (the post-processing's moves and flips, the
//! small-angle repair's candidates). Entries are only ever added: a triangle that moved or was
//! replaced is filed again where it lies now, and a query meets the triangles as they are now,
//! so stale entries cost time, never answers. An insert can be recorded and taken back
//! (undo), for a caller that rolls a trial change back.
class TriangleCells {
 public:
  using CellBox = Eigen::AlignedBox<std::int64_t, 3>;
  //! What inserts added, newest last.
  struct Undo {
    std::vector<std::int64_t> keys;              // cells that got an entry
    std::vector<std::pair<int, CellBox>> filed;  // (t, its filing's cells before)
    // Emptied, keeping the arrays' memory (one undo serves every candidate of a pass).
    void clear() {
      keys.clear();
      filed.clear();
    }
  };

  explicit TriangleCells(double cell) : cell_(cell) {}
  //! The cell size for the triangles T: 1.5 x their mean edge (one per triangle), >= 0.5 mm.
  static double cell_size_for(std::span<const std::array<int, 3>> T,
                              std::span<const Eigen::Vector3d> P);
  //! Files triangle t (its corners f) under every cell its box overlaps, unless it already is
  //! (the cells of its last filing contain them); with `undo`, records what it added.
  void insert(int t, const std::array<int, 3>& f, std::span<const Eigen::Vector3d> P,
              Undo* undo = nullptr);
  //! Takes back what the recorded inserts added, newest first, and clears `undo`.
  void take_back(Undo& undo);
  //! Calls visit(u) once for every triangle index u < n_triangles other than `self` filed in a
  //! cell that f's box overlaps, until visit returns true (then true).
  template <typename Visit>
  bool any_near(const std::array<int, 3>& f, int self, std::size_t n_triangles,
                std::span<const Eigen::Vector3d> P, Visit&& visit) const {
    if (stamp_.size() < n_triangles) stamp_.resize(n_triangles, 0);
    if (++epoch_ == 0) {  // wrapped: forget every stamp
      std::fill(stamp_.begin(), stamp_.end(), 0);
      epoch_ = 1;
    }
    const CellBox cells = cells_of(f, P);
    for (std::int64_t x = cells.min().x(); x <= cells.max().x(); ++x)
      for (std::int64_t y = cells.min().y(); y <= cells.max().y(); ++y)
        for (std::int64_t z = cells.min().z(); z <= cells.max().z(); ++z) {
          const std::vector<int>* list = lists_.find(pack_cell(x, y, z));
          if (!list) continue;
          for (int u : *list) {
            if (u == self || u >= static_cast<int>(n_triangles) || stamp_[u] == epoch_) continue;
            stamp_[u] = epoch_;
            if (visit(u)) return true;
          }
        }
    return false;
  }
  //! True if the triangle f intersects a live triangle of T (f[0] >= 0) filed near it, more than
  //! at shared corners or along a shared edge; T's triangles `self` and `also_self` (f's own
  //! index, the one it replaces, or -1) are not tested.
  bool crosses_any(const std::array<int, 3>& f, int self, std::span<const std::array<int, 3>> T,
                   const std::vector<Eigen::Vector3d>& P, int also_self = -1) const;

 private:
  CellBox cells_of(const std::array<int, 3>& f, std::span<const Eigen::Vector3d> P) const;
  double cell_;
  CellLists lists_;
  std::vector<CellBox> filed_;                // per triangle: its last filing's cells
  mutable std::vector<std::uint32_t> stamp_;  // any_near: the last query that met a triangle
  mutable std::uint32_t epoch_ = 0;
};

//! Every node of the animation mesh: (phi, h) and its point and normal on the surface.
struct NodeStore {
  std::vector<Eigen::Vector2d> params;
  std::vector<Eigen::Vector3d> pos, normal;
  //! Lifts (phi, h) onto the surface; -1 if the surface is undefined there.
  int add(const Eigen::Vector2d& param, const ScanSurface& surface);
  //! Moves node i to (phi, h); false (node unchanged) if the surface is undefined there.
  bool move(int i, const Eigen::Vector2d& param, const ScanSurface& surface);
  //! A node's (phi, h), point and normal, for putting it back after a trial move.
  struct Saved {
    Eigen::Vector2d param;
    Eigen::Vector3d pos, normal;
  };
  Saved save(int i) const { return {params[i], pos[i], normal[i]}; }
  void restore(int i, const Saved& s) {
    params[i] = s.param;
    pos[i] = s.pos;
    normal[i] = s.normal;
  }
};

//! (phi, h) of a 3D point near the surface: the cylindrical angle unwrapped next to `near_phi`.
Eigen::Vector2d param_of(const Eigen::Vector3d& x, double near_phi);

struct RegionMeshInput {
  std::vector<std::array<int, 2>> front;  //!< directed boundary edges, region on the left
  double unit_mm = 6;
  EdgeStrategy strategy = EdgeStrategy::Shortest;
  double chordal_tolerance_mm = 0.15;
  double min_unit_mm = 0.3;
  std::uint64_t seed = 1;
  std::size_t max_steps = 0;  //!< 0: derived from the front size
  //! The region in (phi, h): outer boundary and holes (even-odd); every new node and triangle
  //! centroid must lie inside (a safety net behind the front tests).
  std::vector<std::vector<Eigen::Vector2d>> polygons;
};

//! The advancing-front mesher of one region; triangles counter-clockwise seen from outside.
std::vector<std::array<int, 3>> aft_mesh_region(NodeStore& nodes, const ScanSurface& surface,
                                                const RegionMeshInput& input,
                                                RegionMeshStats& stats);

//! The surface Delaunay refinement mesher of one region (Chew, seed 000 §4.3.4); same
//! conventions as aft_mesh_region. nullopt: the region has no planar (phi, h) domain.
std::optional<std::vector<std::array<int, 3>>> delaunay_mesh_region(NodeStore& nodes,
                                                                    const ScanSurface& surface,
                                                                    const RegionMeshInput& input,
                                                                    RegionMeshStats& stats);

//! Two-way sampled Hausdorff distance between the mesh and the scan surface, `samples`
//! subdivisions per triangle edge. Surface -> mesh samples the surface over the mesh's own
//! (phi, h) footprint at the same density and, given `regions`, also over the meshed regions
//! (the centre of every second grid cell in phi and in h inside a region that is not an
//! opening), independently of the mesh, so that a gap in it counts.
struct TwoWayDistance {
  double mesh_to_surface_mm = 0, surface_to_mesh_mm = 0;
};
TwoWayDistance sampled_hausdorff(const AnimationMesh& am, const ScanSurface& surface, int samples,
                                 const RegionGraph* regions = nullptr);

//! Distances from points to the same grid triangulation of the surface that sampled_hausdorff
//! measures against: exact where ScanSurface::project (a local search) can stop in a far local
//! minimum, e.g. at an ear's rim. The grid nodes it lifts are kept for later queries nearby
//! (one object per thread).
class GridSurfaceDistance {
 public:
  explicit GridSurfaceDistance(const ScanSurface& surface) : surface_(surface) {}
  //! min(distance from x to the triangulation, radius), searching only within `radius`.
  double operator()(const Eigen::Vector3d& x, double radius) const;

 private:
  const std::optional<Eigen::Vector3d>& node(int i, int j) const;
  const ScanSurface& surface_;
  mutable std::unordered_map<std::int64_t, std::optional<Eigen::Vector3d>> nodes_;
};

struct RepairStats {
  //! Accepted composite operations: 0 optimise, 1 flip, 2/3 collapse, 4 split (each followed by
  //! optimising the Steiner points it touched).
  std::array<int, 5> operations{};
  int left_below_goal = 0;    //!< triangles left below report_rad (a failure)
  int forced_below_goal = 0;  //!< below report_rad at a corner of two constraint edges (input)
  int left_above_deviation_goal = 0;  //!< triangles still further from the surface than asked
};

//! The local small-angle repair after the front (quality_pass.cpp): triangles (with their
//! labels) below `goal_rad` are improved by local operations that keep constraint edges and
//! segment nodes (indices < boundary_nodes) fixed and Steiner points on the surface.
RepairStats repair_small_angles(std::vector<std::array<int, 3>>& triangles,
                                std::vector<int>& labels, NodeStore& nodes,
                                const ScanSurface& surface,
                                const std::unordered_set<std::uint64_t>& constraint,
                                std::size_t boundary_nodes, double goal_rad, double report_rad,
                                int rounds = 8, double deviation_goal_mm = 0);

}  // namespace scanmesh::aft::detail
