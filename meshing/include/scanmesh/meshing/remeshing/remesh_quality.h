// Quality report of a remeshing result (seed 001 §5.3): aspect ratio Q = R / (2r), min angle,
// irregular valence (6 inside, 2p + 2 on a seam with p sides), symmetric sampled Hausdorff
// distance to the input, label / seam checks; pictures (mesh coloured by Q with irregular
// vertices marked, histograms). docs/remeshing.md, "Quality report".
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh.h"
#include "scanmesh/meshing/remeshing/remesh.h"

namespace scanmesh::remeshing {

struct RemeshQuality {
  std::size_t vertices = 0, faces = 0;
  double min_angle_deg = 0, mean_min_angle_deg = 0, fraction_min_angle_ge_30 = 0;
  //! Aspect ratio Q = R / (2 r) (triangle_quality.h; 1 = equilateral): mean, largest, and
  //! faces per bin [1, 1.1), [1.1, 1.2) ... [1.9, inf).
  double aspect_ratio_mean = 0, aspect_ratio_max = 0;
  std::array<std::size_t, 10> aspect_ratio_histogram{};
  std::array<std::size_t, 12> angle_histogram{};         //!< min angle, 5 deg bins over [0, 60]
  std::size_t valence_counted = 0, valence_optimal = 0;  //!< free + skeleton vertices
  double fraction_irregular = 0;
  //! Where the triangles with min angle < 30 deg are, by their most constrained corner: a branch
  //! vertex, else a boundary skeleton vertex (1 side), else another skeleton vertex (feature
  //! line or seam), else only free corners.
  std::size_t bad_at_branch = 0, bad_at_boundary = 0, bad_at_skeleton = 0, bad_interior = 0;
  double hausdorff_out_to_in = 0, hausdorff_in_to_out = 0, hausdorff = 0, mean_distance = 0;
  double bbox_diagonal = 0;
  bool self_intersections_checked = false;
  std::size_t self_intersections = 0;
  std::string to_json() const;
};

//! One-sided sampled distance from `a` to `b`: vertices, edge midpoints and centroids of `a`
//! projected exactly onto the triangles of `b` (uniform cell grid). Returns {max, mean}.
std::array<double, 2> sampled_distance(const Mesh& a, const Mesh& b);

//! Optimal valence of an output vertex (0 = undefined: branch vertex).
int optimal_valence(VertexKind kind, int sides);

RemeshQuality evaluate_remesh(const Mesh& input, const RemeshResult& result,
                              bool check_self_intersections = true);

//! Mesh coloured by Q (blue 1 -> red >= 2), irregular vertices marked (white: too many
//! neighbours, black: too few), two views side by side.
Image8 render_quality(const RemeshResult& result, int view_size = 560);
//! The input coloured by the density's target edge length sqrt(Psi) on a log scale (blue:
//! shortest, red: longest; the output is densest where blue), two views side by side.
Image8 render_density(const Mesh& input, const std::vector<double>& density, int view_size = 560);
//! Histograms of the aspect ratio Q and of the min angle, side by side (1280 x 400).
Image8 quality_histograms(const RemeshQuality& q);

}  // namespace scanmesh::remeshing
