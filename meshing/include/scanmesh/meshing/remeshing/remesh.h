// Adaptive remeshing of non-manifold triangle meshes with feature lines (seed 001, Zilske 2007,
// after Surazhsky-Gotsman / Surazhsky-Alliez-Gotsman): a prescribed vertex count, curvature-
// adapted density Psi = kappa_max^-2 (clipped, n_filter smoothed, gamma contrast), validity-
// checked local operations (move, collapse, split, flip) against E_dist / E_glatt, the feature
// skeleton kept exactly, connectivity regularisation and angle-based smoothing (or weighted
// centroidal relaxation). Vertices stay on the input by local closest-point projection (walking
// over the input patch) instead of PN triangles with local parametrisations (docs/remeshing.md).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/meshing/remeshing/feature_skeleton.h"

namespace scanmesh::remeshing {

enum class RemeshScheme {
  Regularize,  //!< §3.8 connectivity regularisation + §3.5 angle-based smoothing
  Lloyd,       //!< §3.6-like weighted centroidal relaxation with Delaunay flips
};
RemeshScheme parse_remesh_scheme(const std::string& name);  //!< "regularize" | "lloyd"
std::string to_string(RemeshScheme s);

struct DensityOptions {
  double gamma = 3.0;  //!< Psi <- Psi^gamma on the normalised field; 0: uniform
  int n_filter = 10;   //!< neighbour-mean passes (3.3), across the skeleton too
  double clip = 4.0;   //!< Psi^(1/2) (target edge length) clipped to [m/clip, m*clip], m = median
  std::vector<double> user;  //!< per input vertex Psi (replaces the curvature field when set)
};

//! Psi per input vertex: kappa_max^-2 from a per-vertex quadric fit over the 2-ring, clipped,
//! filtered, raised to gamma, normalised to median 1. Throws InvalidInputError for a user field of
//! the wrong length or with non-positive / non-finite values.
std::vector<double> compute_density(const NmMesh& m0, const DensityOptions& options);

//! Per input vertex kappa_max = max(|k1|, |k2|) of a least-squares quadric over the 2-ring.
std::vector<double> estimate_kappa_max(const NmMesh& m0);

//! Optional clean-up of scan meshes before remeshing (not part of seed 001): every boundary loop
//! is a skeleton curve the remesher must keep, so the pin-holes and crumbs of a raw scan would
//! hold thousands of vertices. Both default to off.
struct PrepareOptions {
  int min_component_faces = 0;  //!< drop connected components with fewer faces
  int max_hole_edges = 0;       //!< close simple boundary loops with at most this many edges
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
  double tip_reach_mm = 0;
  double tip_angle_deg = 120;
};
struct PrepareStats {
  std::size_t components_removed = 0, faces_removed = 0, holes_filled = 0, faces_added = 0;
  std::size_t degenerate_removed = 0, needles_welded = 0, caps_flipped = 0, caps_removed = 0;
  std::size_t spike_faces_removed = 0, pinch_faces_removed = 0, tip_faces_removed = 0;
};
//! Returns the cleaned mesh (labels kept; a hole's fan takes the label of its rim faces).
Mesh prepare_input(const Mesh& input, const PrepareOptions& options, PrepareStats* stats = nullptr);

struct RemeshOptions {
  int target_vertices = 20000;
  RemeshScheme scheme = RemeshScheme::Regularize;
  DensityOptions density;
  SkeletonOptions skeleton;
  FeatureLines features;
  double theta_dist_deg = 90.0;   //!< E_dist (3.4): max angle between corner surface normals
  double theta_glatt_deg = 60.0;  //!< E_glatt (3.5): max angle face normal vs corner normals
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

}  // namespace scanmesh::remeshing
