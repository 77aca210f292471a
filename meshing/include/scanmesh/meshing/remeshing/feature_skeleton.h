// The feature skeleton of seed 001 §4.1 on the input mesh M0: non-manifold edges (seams),
// boundary edges, label borders, user feature lines, sharp edges (dihedral threshold) and fixed
// vertices; skeleton vs branch vertices (>= 60 deg kink rule, one branch vertex per closed loop);
// segments with their number of sides k and an arc-length parametrisation (4.1)/(4.2); patches
// (face components bounded by the skeleton). docs/remeshing.md, "Feature skeleton".
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "scanmesh/meshing/kernel/triangle_mesh.h"

namespace scanmesh::remeshing {

// The remesher works on the kernel's mesh throughout.
using kernel::EdgeFaceList;
using kernel::NeighbourList;
using kernel::TriangleMesh;

//! User constraints: feature lines as chains of input vertex indices joined by input edges, and
//! fixed vertices (docs/formats.md, "Feature lines").
struct FeatureLines {
  std::vector<std::vector<int>> lines;
  std::vector<int> fixed;
};

//! Parses the feature-lines text format; `name` is used in error messages. Throws
//! FileFormatError for syntax errors, non-integer or negative indices and lines with fewer than
//! two vertices. Index ranges and edge existence are checked by build_feature_skeleton.
FeatureLines parse_feature_lines(const std::string& text, const std::string& name);
FeatureLines read_feature_lines(const std::filesystem::path& path);
std::string format_feature_lines(const FeatureLines& lines);

struct SkeletonOptions {
  //! Edges whose face normals differ by more than this are sharp feature edges; <= 0: off.
  double sharp_angle_deg = 0.0;
  double kink_angle_deg = 60.0;  //!< a turn of at least this makes a branch vertex (§4.4)
  //! The turn is measured between chords reaching this many mean input edge lengths back and
  //! forward along the chain (0: the two adjacent edges, as in the thesis), and only at the
  //! vertex of largest turn within that reach, so staircase boundaries of scans are not cut
  //! into one-edge segments.
  double kink_window = 3.0;
  //! Absolute reach in mm; when > 0 it replaces kink_window. remesh() sets it to the mean
  //! target edge length when it is 0, so kinks are judged at the scale of the output.
  double kink_reach_mm = 0.0;
  bool label_borders = true;  //!< edges between faces of different labels are skeleton
};

enum class VertexKind : std::uint8_t { Free, Skeleton, Branch };

struct SkeletonSegment {
  std::vector<int> vertices;  //!< input vertex chain from branch vertex to branch vertex
  std::vector<double> arc;    //!< arc length at each vertex, arc[0] = 0 (4.1)/(4.2)
  int sides = 0;              //!< k: faces per edge (1 boundary, 2 feature line, >= 3 seam)
  double length() const { return arc.back(); }
};

struct FeatureSkeleton {
  std::unordered_map<std::uint64_t, int> edge_segment;  //!< skeleton edge -> segment
  std::vector<VertexKind> kind;                         //!< per input vertex
  std::vector<int> vertex_segment;  //!< per input vertex: its segment (skeleton vertices)
  std::vector<double> vertex_arc;   //!< per input vertex: arc length on its segment
  std::vector<SkeletonSegment> segments;
  std::vector<int> face_patch;  //!< per input face: component bounded by the skeleton
  int patch_count = 0;
  std::size_t sharp_edges = 0, user_edges = 0, nonmanifold_edges = 0, boundary_edges = 0,
              label_edges = 0;

  std::size_t branch_vertex_count() const;
  //! Point on segment `seg` at arc length s (clamped to [0, length]); `edge`/`t` receive the
  //! input edge index within the segment and the 1D barycentric coordinate on it.
  Eigen::Vector3d point(const std::vector<Eigen::Vector3d>& positions, int seg, double s,
                        int* edge = nullptr, double* t = nullptr) const;
};

//! Throws InvalidInputError when a feature line names a vertex out of range or two consecutive
//! vertices that are not joined by an edge.
FeatureSkeleton build_feature_skeleton(const TriangleMesh& m0, const FeatureLines& lines = {},
                                       const SkeletonOptions& options = {});

}  // namespace scanmesh::remeshing
