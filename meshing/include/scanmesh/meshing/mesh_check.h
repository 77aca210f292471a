// Mesh-correctness checker shared by all meshers: the failure modes of seed 002 §3.1 (duplicate
// triangles, edges with more than two faces, overlapping/penetrating triangles, holes) plus
// vertex manifoldness, completeness and triangle quality. docs/fans.md, "Checker".
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "scanmesh/core/histogram_picture.h"
#include "scanmesh/core/mesh.h"
#include "scanmesh/core/triangle_quality.h"
#include "scanmesh/meshing/mesh_topology.h"

namespace scanmesh {

struct MeshCheckOptions {
  bool self_intersections = true;  //!< the most expensive test; O(F) expected with a cell grid
};

struct MeshCheckReport {
  std::size_t vertices = 0, faces = 0;
  TopologyStats topology;                //!< edges, boundary loops and lengths, Euler, unreferenced
  std::size_t duplicate_faces = 0;       //!< faces whose vertex set repeats an earlier face
  std::size_t degenerate_faces = 0;      //!< repeated corner or zero area
  std::size_t nonmanifold_vertices = 0;  //!< faces around the vertex form more than one fan
  std::size_t self_intersections = 0;    //!< intersecting face pairs (touching along shared
                                         //!< corners/edges is not counted)
  bool self_intersections_checked = false;
  //! Why the test did not run although asked for (empty otherwise): faces crowding one place so
  //! that the pair tests would grow quadratically (intersecting_face_pairs' budget).
  std::string self_intersections_not_checked_reason;
  // Quality: min angle per face, and the radius ratio 2 r_in / R_circ (triangle_quality.h;
  // 1 = equilateral, 0 = degenerate).
  double min_angle_deg = 0, mean_min_angle_deg = 0;
  double min_radius_ratio = 0, mean_radius_ratio = 0;
  double fraction_min_angle_ge_30 = 0;  //!< share of faces whose smallest angle is >= 30 deg
  std::array<std::size_t, 12> min_angle_histogram{};  //!< bins of 5 deg over [0, 60]

  //! No edge has more than two faces.
  bool edge_manifold() const { return topology.nonmanifold_edges == 0; }
  //! Edge- and vertex-manifold, no duplicate, degenerate or intersecting faces.
  bool defect_free() const;
  //! Multi-line human-readable report.
  std::string to_text() const;
};

MeshCheckReport check_mesh(const Mesh& mesh, const MeshCheckOptions& options = {});

//! A property `scanmesh check --require` can demand of a mesh.
enum class MeshProperty {
  NonEmpty,          //!< at least one face
  Closed,            //!< non-empty, no boundary edge and edge-manifold (watertight)
  EdgeManifold,      //!< no edge with more than two faces
  VertexManifold,    //!< the faces around every vertex form one fan
  Oriented,          //!< every interior edge is traversed once in each direction
  IntersectionFree,  //!< no two faces cross (needs the self-intersection test)
  NoDegenerate,      //!< no repeated corner or zero-area face
  NoDuplicates,      //!< no two faces with the same vertex set
};

struct PropertyVerdict {
  MeshProperty property;
  bool known = true;  //!< false: not tested (self-intersections skipped)
  bool holds = false;
  std::string evidence;  //!< what decided it, e.g. "2 boundary loops (14 edges)"
};

//! The names used on the command line and in reports ("closed", "vertex-manifold", ...).
const char* property_name(MeshProperty p);
//! All properties, in report order.
std::span<const MeshProperty> all_mesh_properties();
//! Parses a comma-separated list of property names; throws InvalidInputError naming the
//! unknown one and listing the valid names.
std::vector<MeshProperty> parse_mesh_properties(const std::string& list);
//! One verdict per property, in report order.
std::vector<PropertyVerdict> mesh_verdicts(const MeshCheckReport& report);

//! Intersecting face pairs, as check_mesh counts them; with `labels` (one per face) only the
//! pairs of faces with different labels (e.g. crossings between the regions of a mesh); with
//! `involved` (one flag per face) only the pairs with at least one flagged face.
std::size_t count_intersecting_faces(const Mesh& mesh, const std::vector<int>* labels = nullptr,
                                     const std::vector<char>* involved = nullptr);
//! The same pairs themselves (f < g, sorted). Faces repeating an earlier face's corner positions
//! take no part (check_mesh counts them as duplicates), so n copies of one triangle cost O(n).
//! `max_candidate_pairs` bounds the work: when the cells of the broad phase would hold more
//! face pairs than that (faces crowding one place, e.g. a fan of 100,000 triangles), nothing is
//! tested and `*complete` (if given) is set to false.
//! The work bound check_mesh gives intersecting_face_pairs: ~100 candidate pairs per face is
//! far above any real mesh (about 10); 2e7 pairs take about a second.
inline std::size_t default_candidate_pair_budget(std::size_t faces) {
  return std::max<std::size_t>(20'000'000, 100 * faces);
}

std::vector<std::array<int, 2>> intersecting_face_pairs(
    const Mesh& mesh, const std::vector<int>* labels = nullptr,
    const std::vector<char>* involved = nullptr,
    std::size_t max_candidate_pairs = static_cast<std::size_t>(-1), bool* complete = nullptr);

//! Faces f and g (indices into P) intersect improperly: more than touching at shared corners or
//! along a shared edge (the self-intersection predicate of check_mesh; double precision).
bool triangles_intersect(const std::vector<Eigen::Vector3d>& P, const std::array<int, 3>& f,
                         const std::array<int, 3>& g);

//! Squared distance from p to the closest point of the triangle (a, b, c) (Ericson, Real-Time
//! Collision Detection, 5.1.5).
double point_triangle_squared_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c);

//! Bar chart of the checker's min-angle histogram (PNG, written atomically); bins from 30 deg
//! on are drawn green.
void write_min_angle_histogram_png(const std::filesystem::path& path, const MeshCheckReport& report,
                                   const std::string& title = "MIN ANGLE PER TRIANGLE [DEG]");

}  // namespace scanmesh
