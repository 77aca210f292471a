// Adaptive remeshing of non-manifold triangle meshes with feature lines (seed 001, Zilske 2007,
// after Surazhsky-Gotsman / Surazhsky-Alliez-Gotsman): a prescribed vertex count, curvature-
// adapted density Psi = kappa_max^-2 (clipped, n_filter smoothed, gamma contrast), validity-
// checked local operations (move, collapse, split, flip) against E_dist / E_glatt, the feature
// skeleton kept exactly, connectivity regularisation and angle-based smoothing (or weighted
// centroidal relaxation). Vertices stay on the input by local closest-point projection (walking
// over the input patch) instead of PN triangles with local parametrisations (docs/remeshing.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/remeshing/feature_skeleton.h"

namespace scanmesh::remeshing {

enum class RemeshScheme {
  Regularize,  //!< §3.8 connectivity regularisation + §3.5 angle-based smoothing
  Lloyd,       //!< §3.6 Lloyd: moves to the Voronoi-cell centroids (rho = h^-4), Delaunay flips
};
RemeshScheme parse_remesh_scheme(const std::string& name);  //!< "regularize" | "lloyd"
std::string to_string(RemeshScheme s);

struct DensityOptions {
  //! Psi <- Psi^gamma on the normalised field; 0: uniform. Seed 001 uses 3; 0.5 makes the
  //! target edge h ~ kappa^-1/2, the length at which a chord's height h^2 kappa / 8 is the
  //! same everywhere (docs/remeshing.md, "Density on scans").
  double gamma = 0.5;
  int n_filter = 10;   //!< neighbour-mean passes (3.3), across the skeleton too
  double clip = 4.0;   //!< Psi^(1/2) (target edge length) clipped to [m/clip, m*clip], m = median
  //! Radius (mm) of the surface patches the curvature is fitted over. < 0: the output's uniform
  //! edge length (remesh sets it from the target count), so that scanner noise at the input's
  //! spacing does not read as curvature; 0: the input's 2-ring (seed 001's fit).
  double curvature_radius = -1;
  //! Largest slope |grad h| of the absolute target edge length h over the surface (0: off).
  //! Without it a sharp density step needs vertices of valence 4 and 8 however well the
  //! operations work; 0.3 lets h double over about three edges.
  double gradation = 0.3;
  std::vector<double> user;  //!< per input vertex Psi (replaces the curvature field when set)
};

//! Psi per input vertex: kappa_max^-2 from quadric fits (estimate_kappa_max at
//! options.curvature_radius), clipped, filtered, raised to gamma, normalised to median 1. The
//! gradation limit needs the absolute scale and is applied by remesh (limit_gradation). Throws
//! InvalidInputError for a user field of the wrong length or with non-positive / non-finite
//! values.
std::vector<double> compute_density(const TriangleMesh& m0, const DensityOptions& options);

//! Per input vertex kappa_max = max(|k1|, |k2|) of a least-squares quadric over the 2-ring
//! (radius <= 0, or no more than two median input edges) or, at a larger radius, fitted over
//! the vertices within `radius` reached over mesh edges (another sheet nearer than the radius
//! stays out) around samples about radius / 2 apart, each vertex taking the distance-weighted
//! mean of the fits whose patch holds it.
std::vector<double> estimate_kappa_max(const TriangleMesh& m0, double radius = 0);

//! The scale s of the target edge length h = s sqrt(Psi) that gives `target_vertices`:
//! V ~ (2 / sqrt 3) * integral of 1 / h^2 over the input.
double density_scale(const TriangleMesh& m0, const std::vector<double>& psi, int target_vertices);

//! Lowers Psi where the target edge length h = scale sqrt(Psi) (scale from the vertex count as
//! in remesh) would grow faster than `gradation` per unit length along the input's edges:
//! h(v) <= h(w) + gradation |v w| (a multi-source Dijkstra). Only ever refines.
void limit_gradation(const TriangleMesh& m0, std::vector<double>& psi, int target_vertices,
                     double gradation);

//! Optional clean-up of scan meshes before remeshing (not part of seed 001): every boundary loop
//! is a skeleton curve the remesher must keep, so the pin-holes and crumbs of a raw scan would
//! hold thousands of vertices. Both default to off.
struct PrepareOptions {
  int min_component_faces = 0;  //!< drop connected components with fewer faces
  int max_hole_edges = 0;       //!< close simple boundary loops with at most this many edges
  //! Also drop components whose area is below this (mm^2; 0: off). scan_prepare_options sets it
  //! so that a dropped piece would have held only a handful of output vertices.
  double min_component_area = 0;
  //! Also close simple boundary loops whose perimeter is at most this (mm; 0: off), up to
  //! kMaxHolePatchEdges input edges (the patch is a cubic-time triangulation).
  double max_hole_perimeter = 0;
  //! Triangles with a min angle below this (deg) are repaired first: zero-area faces dropped,
  //! needles (one short edge) welded shut, caps (one angle > 120 deg) flipped across their long
  //! edge or dropped when it is a boundary edge. 0: off.
  double needle_angle_deg = 0;
  //! Strip one-triangle-wide spikes and strands of a ragged scan border (hair): faces with two
  //! boundary edges are removed until none is left, and at a pinch vertex (several face fans
  //! touching at one point) all but the largest fan are removed.
  bool remove_spikes = false;
  //! With remove_spikes: the border is also followed tip_reach_mm back and forward from each
  //! boundary vertex, and where the surface's angle between those chords is below tip_angle_deg
  //! (a sharp convex tip at the scale of the output edges, which no good triangle fits) the
  //! vertex's faces are removed, repeatedly. 0: off. `scanmesh remesh` uses the target edge.
  //! It is also the scale of the thin parts opened (none fits a triangle of the output): at
  //! necks narrower than tip_reach_mm / 4 between two parts of the border (not within
  //! tip_reach_mm of each other along it) the faces at the border vertices are removed, and so
  //! are veils, faces along the border thinner than tip_reach_mm / 4 and four times longer.
  double tip_reach_mm = 0;
  double tip_angle_deg = 120;
};
struct PrepareStats {
  std::size_t components_removed = 0, faces_removed = 0, holes_filled = 0, faces_added = 0;
  std::size_t degenerate_removed = 0, needles_welded = 0, caps_flipped = 0, caps_removed = 0;
  std::size_t spike_faces_removed = 0, pinch_faces_removed = 0, tip_faces_removed = 0;
  std::size_t neck_faces_removed = 0;  //!< at necks and veils (see tip_reach_mm)
  std::size_t repeated_faces_removed = 0;  //!< copies of an earlier face's corners (always)
};
//! Returns the cleaned mesh (labels kept; a hole's fan takes the label of its rim faces).
Mesh prepare_input(const Mesh& input, const PrepareOptions& options, PrepareStats* stats = nullptr);

//! Longest hole (in input edges) that max_hole_perimeter closes.
inline constexpr int kMaxHolePatchEdges = 400;

//! Edge length of a uniform mesh of `vertices` vertices over the input's area (F ~ 2 V
//! equilateral faces): the scale of the output, and so of what the clean-up must remove.
double uniform_edge_length(const Mesh& mesh, int vertices);

//! What makes `scanmesh remesh` run the scan clean-up by default: a mesh as a scanner writes
//! it (more than kScanLoops boundary loops, more than kScanComponents components or more than
//! kScanEars border ears: pin-holes, crumbs, a ragged border). Every boundary loop is a skeleton
//! curve the remesher must keep, so such a mesh holds thousands of fixed vertices and misses any
//! small target. An ear, a face with two or three border edges, is where a grid mesh's border
//! steps from row to row (16-510 on imported grid meshes of the corpus with two to nine loops;
//! 0 or 1 on the corpus meshes themselves).
inline constexpr std::size_t kScanLoops = 8, kScanComponents = 8, kScanEars = 8;
bool looks_like_scan(const Mesh& mesh);
bool looks_like_scan(const TopologyStats& stats);  //!< the same from the mesh's statistics

//! The clean-up for a scan remeshed to `target_vertices`, at the output's scale L
//! (uniform_edge_length): components under 10 L^2 (about a dozen output vertices) dropped, holes
//! with a perimeter up to 10 L (at most ten output edges) closed, needles under 5 deg repaired,
//! spikes, pinches and border tips sharper than 120 deg over L removed.
PrepareOptions scan_prepare_options(const Mesh& mesh, int target_vertices);

struct RemeshOptions {
  int target_vertices = 20000;
  RemeshScheme scheme = RemeshScheme::Regularize;
  DensityOptions density;
  SkeletonOptions skeleton;
  FeatureLines features;
  double theta_dist_deg = 90.0;   //!< E_dist (3.4): max angle between corner surface normals
  double theta_glatt_deg = 75.0;  //!< E_glatt (3.5): max angle face normal vs corner normals
  int adapt_iterations = 6;       //!< split/collapse/flip/relax rounds reaching the density
  int n_area = 3;                 //!< area-based moves per flip sweep (§3.4)
  int n_step = 5;                 //!< outer rounds of area-based remeshing (§3.4)
  int drive_limit = 10;           //!< §3.8
  //! Regularisation's simple-edge flips from a priority queue (worst valence deviation first,
  //! best flip of its star) instead of sweeps over the edges in index order.
  bool regularize_queue = false;
  //! Every operation is refused when a changed face would cut a face at one of its corners
  //! (folds, local self-intersections); off only to measure what it costs and prevents.
  bool prevent_intersections = true;
  int smoothing_passes = 10;  //!< final angle-based (or centroidal) passes (§3.5)
  //! Angle polish after the smoothing (not in the seed): rounds over the faces whose min angle
  //! is below polish_angle_deg; their corners move to the position that maximises the min angle
  //! of their star (pattern search on the surface, skeleton vertices along their segment), and
  //! their edges flip when that raises the quad's min angle at a bounded valence cost. 0: off.
  int polish_rounds = 3;
  double polish_angle_deg = 30.0;
  //! Largest rise of R (3.22) an angle-raising flip may cost; a flip in a regular patch costs 4.
  int polish_flip_cost = 2;
  //! Faces still under this min angle (deg) after the polish get more polish rounds with the
  //! error bounds widened to these angles (deg): where a crease finer than the output makes
  //! E_glatt / E_dist refuse every move, a needle is the worse error. 0: off.
  double polish_floor_deg = 30.0;
  double polish_floor_glatt_deg = 85.0, polish_floor_dist_deg = 120.0;
  //! Faces still under this min angle (deg) after that get polish rounds without the normal
  //! bounds (a needle is worse than any normal error; the intersection test stays). 0: off.
  double polish_needle_deg = 15.0;
  //! Called with (phase name, fraction done in [0, 1]); may be empty.
  std::function<void(const std::string&, double)> progress;
};

struct RemeshStats {
  int input_vertices = 0, input_faces = 0;
  int output_vertices = 0, output_faces = 0;
  std::size_t skeleton_segments = 0, branch_vertices = 0, patches = 0;
  std::size_t collapses = 0, splits = 0, flips = 0, moves = 0;
  std::size_t rejected_error = 0;     //!< operations undone by E_dist / E_glatt
  std::size_t rejected_topology = 0;  //!< link condition / skeleton rules
  std::size_t skeleton_splits = 0, skeleton_collapses = 0;  //!< (4.5) / (4.4)
  //! Faces of the final mesh that cut another face before the repair pass (0 when prevention in
  //! the operators sufficed; the report's self_intersections counts what is left after it).
  std::size_t intersecting_faces_before_repair = 0;
  //! Angle polish: faces below polish_angle_deg before and after it, its moves and flips.
  std::size_t polish_bad_before = 0, polish_bad_after = 0, polish_moves = 0, polish_flips = 0;
  //! Edges split by the repair pass to make faces of two nearby sheets follow the input.
  std::size_t repair_splits = 0;
  //! Input faces that cut another input face, and the input faces within two output edges of
  //! them (the defect zone: operations there are checked for degenerate faces only, and the
  //! repair pass leaves the output's crossings there alone). 0 for an input that is a surface.
  std::size_t input_intersecting_faces = 0, input_defect_zone_faces = 0;
  double seconds_setup = 0, seconds_adapt = 0, seconds_count = 0, seconds_regularize = 0,
         seconds_smooth = 0, seconds_total = 0;
};

struct RemeshResult {
  Mesh mesh;                     //!< face_labels carried from the input faces
  std::vector<VertexKind> kind;  //!< per output vertex
  std::vector<int> segment;      //!< per output vertex: skeleton segment (-1 free / branch)
  std::vector<int> sides;        //!< per output vertex: k of its segment (0 free / branch)
  std::vector<int> face_patch;   //!< per output face: input patch
  FeatureSkeleton skeleton;      //!< on the input
  std::vector<double> density;   //!< Psi per input vertex
  RemeshStats stats;
};

//! Remeshes `input` to options.target_vertices vertices. Throws InvalidInputError for an empty
//! mesh, a target below 4 or above 10 million, or invalid feature lines.
RemeshResult remesh(const Mesh& input, const RemeshOptions& options = {});

//! The vertex count is the one promise of a remesh: throws InvalidInputError saying why (the
//! fixed skeleton vertices of `input_boundary_loops` loops and feature lines, or operations the
//! bounds refused) when `result` misses `target` by more than 1 %. The CLI and the Python
//! module call it after remesh().
void require_vertex_count(const RemeshResult& result, int target,
                          std::size_t input_boundary_loops);

}  // namespace scanmesh::remeshing
