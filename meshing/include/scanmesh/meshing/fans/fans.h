// Point-cloud fans: triangulating an unorganised point cloud by building a triangle fan around
// every point (seed 002: S. Preuss, "Von Punktwolken zu Dreiecksnetzen", 2002, §3.4-3.7).
//
// Pipeline (docs/fans.md has every decision taken where the seed leaves a gap):
//   uniform cell grid (§3.4, cell edge l = sqrt(2(dx dy + dy dz + dx dz) k / n))
//   -> 3-nearest-neighbour plane normals, PCA fallback (§3.4), oriented by propagation
//   -> one fan per point (§3.6 steps 1-6): nearest-first candidate insertion, distance-preserving
//      rotation into the tangent plane, checks 4a-4c (Satz 3.3.3 in-circle test), completeness
//      angle alpha with radius growth up to d_max, spoke flips (7c, Satz 3.3.6)
//   -> assembly (4a, 7a radar sweep, 7b rim closing, step 9) as a surface growth: the fan
//      triangles are voted candidates, the mesh grows across its boundary edges, best-voted
//      first, with no duplicate triangle, no edge with more than two faces, no overlapping
//      triangles and every vertex one fan of faces (vertex-manifold output)
//   -> closing of the small holes left where neighbouring fans disagree, flips towards the
//      Delaunay condition between nearly coplanar faces.
// The input points are the output vertices, in input order.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/core/point_cloud_io.h"

namespace scanmesh {

struct FanOptions {
  int k = 8;                     //!< expected points per grid cell (cell size formula, seed [Gap])
  double alpha_deg = 90.0;       //!< completeness angle: largest accepted gap between spokes
  double dmax_factor = 4.5;      //!< d_max = dmax_factor x cell edge l
  double max_edge = 0.0;         //!< absolute edge-length limit (input units); 0: off
  double max_edge_factor = 0.0;  //!< limit = factor x local spacing (nearest-neighbour
                                 //!< distance of the fan centre), like GP3's mu; 0: off
  double max_normal_angle_deg = 0.0;  //!< reject neighbours whose normal deviates more; 0: off
  int max_hole_edges = 24;   //!< close holes left by disagreeing fans up to this length; 0: off
  bool pca_normals = false;  //!< PCA normals for every point instead of the 3-NN plane
  //! Orient every normal away from the z axis instead of propagating one orientation over the
  //! neighbour graph: right for clouds from a turntable scan (a RangeGrid's cells), whose
  //! outside is known, and robust where noise splits the neighbour graph (hair).
  bool orient_away_from_axis = false;
  std::uint64_t seed = 1;  //!< picks the start point of the normal orientation (determinism)
  int threads = 0;         //!< OpenMP threads; 0: default. Output does not depend on it.
  //! The surface growth runs in parallel blocks of about this many points (slabs of space, grown
  //! again as one across their cuts) on clouds of at least twice as many; kept only where the
  //! fronts closed at every cut, else the growth runs again as one (docs/fans.md, "Growth in
  //! blocks"). 0: one growth for every cloud.
  std::size_t growth_block_points = 250000;
  //! More threads than this are refused: each costs a stack and per-thread buffers, and no
  //! machine this runs on has more cores.
  static constexpr int kMaxThreads = 256;

  //! Throws InvalidInputError for impossible values.
  void validate() const;
};

struct FanStats {
  std::size_t points = 0;
  //! Points at exactly the position of an earlier point: meshed once (the first of them);
  //! the others stay as vertices in no triangle.
  std::size_t duplicate_points = 0;
  double cell_edge = 0.0;              //!< l
  std::size_t pca_fallbacks = 0;       //!< fans rebuilt with a PCA normal
  std::size_t open_fans = 0;           //!< fans with a gap >= 180 deg at d_max (boundary)
  std::size_t proposed_triangles = 0;  //!< distinct fan triangles before assembly
  std::size_t rejected_triangles = 0;  //!< candidates the surface growth never used
  std::size_t seeds = 0;               //!< fronts the surface growth started
  std::size_t growth_blocks = 1;       //!< blocks of the surface growth the mesh came from
  //! Blocks whose growth was discarded, and the growth run again as one: the fronts met at a
  //! cut without closing (FanOptions::growth_block_points).
  std::size_t growth_blocks_discarded = 0;
  std::size_t glued_triangles = 0;     //!< joined two fronts at a vertex (then zipped)
  std::size_t unzipped_glues = 0;      //!< glues taken back: the fronts did not zip from them
  std::size_t bowtie_faces_removed = 0;  //!< faces taken off a vertex whose faces formed
                                         //!< several wedges that nothing could join
  std::size_t hole_triangles = 0;      //!< added by hole closing
  std::size_t inserted_points = 0;     //!< unused points inserted by a 1-to-3 split or
                                       //!< attached to the boundary
  std::size_t delaunay_flips = 0;      //!< edges flipped towards the Delaunay condition
  std::size_t unused_points = 0;       //!< points in no triangle at the end
  double seconds_normals = 0, seconds_fans = 0, seconds_assembly = 0;
};

struct FanResult {
  Mesh mesh;  //!< positions = input points; normals = the oriented estimated normals
  FanStats stats;
};

//! Triangulates the cloud. Throws InvalidInputError for fewer than 3 points, non-finite
//! coordinates or invalid options. Deterministic for any thread count.
FanResult build_fans(const std::vector<Eigen::Vector3d>& points, const FanOptions& options = {});

//! Meshes a cloud with its attributes: its colours become the vertex colours; its normals, when
//! given, become the vertex normals and decide the outside (each estimated normal is turned to
//! agree with the given one, and the faces follow) instead of propagation over the neighbour
//! graph. Non-finite points (an organised cloud's missing pixels) are dropped first; the
//! mesh's vertices are the finite points, in order.
FanResult build_fans(const PointCloud& cloud, const FanOptions& options = {});

//! Normals as the fan stage estimates them (3-NN plane, PCA fallback, oriented by
//! propagation over the k-NN graph); exposed so baselines can be given the same normals.
std::vector<Eigen::Vector3d> estimate_fan_normals(const std::vector<Eigen::Vector3d>& points,
                                                  const FanOptions& options = {});

}  // namespace scanmesh
