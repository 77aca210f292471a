// Animation meshes (seed 000): segment initialisation on the continuous surface (§5.1.2, with
// the "on rails" relaxation of §7.1), the advancing-front region mesher built in 3D on the scan
// surface (§4.3.4, §5.1.1), final 3D Delaunay flips and smoothing, stitching of all regions into
// one mesh, and the quality report. docs/animation-meshes.md explains every decision.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::aft {

//! Nodes placed on the segments: shared junction nodes first, then each segment's interior.
struct SegmentNodes {
  std::vector<Eigen::Vector2d> params;   //!< (phi, h) of every boundary node
  std::vector<std::vector<int>> chains;  //!< per segment: node indices from node0 to node1
  std::vector<double> spacing_mm;        //!< per segment: the interval d_I' used
};

//! §5.1.2: N_nodes = floor(s / d_I) + 2 and d_I' = s / (floor(s / d_I) + 1), s the 3D arc length
//! (equidistant) or arc + weight * turning angle (curvature); d_I = mean unit of the regions on
//! both sides (seams: the line's spacing); then `relax_iterations` sweeps on rails.
SegmentNodes initialise_segments(const RegionGraph& graph, const LineSet& lines,
                                 const ScanSurface& surface, const RegionSettings& settings);

struct RegionMeshStats {
  int region = -1;
  int triangles = 0, steiner_points = 0;
  int chose_new = 0, chose_existing = 0, chose_circumcentre = 0;
  int unmeshed_front_edges = 0;  //!< > 0: the front could not be closed (a failure)
  //! "aft" or "delaunay" (surface Delaunay refinement); "aft" also when a region asked for
  //! delaunay but has no planar parameter domain (it winds around the axis).
  std::string mesher = "aft";
  //! Delaunay: triangles left non-ideal because their circumcentre was outside the region,
  //! behind a segment edge or crowding a node (segments are shared and never split).
  int rejected_circumcentres = 0;
};

struct AnimationMesh {
  Mesh mesh;                                      //!< face_labels = region index
  std::vector<Eigen::Vector2d> params;            //!< (phi, h) per vertex
  std::vector<std::uint8_t> steiner;              //!< 1 for nodes the mesher added
  std::vector<std::array<int, 2>> line_edges;     //!< mesh edges lying on animation lines
  std::vector<int> line_edge_line;                //!< the line of each line edge
  std::vector<std::vector<int>> segment_chains;   //!< per segment: its vertex chain
  std::map<std::string, std::vector<int>> seams;  //!< seam line id -> ordered vertex list
  std::vector<RegionMeshStats> region_stats;
  int flips = 0;
  //! Regions post-processed a second time without valence flips because they crossed with
  //! them (docs/animation-meshes.md, "Valence flips").
  int valence_flip_retries = 0;
  //! Small-angle repair: accepted operations (optimise, flip, collapse into one end, into the
  //! other, split), triangles left below 20 deg, of which at a sharp input corner.
  std::array<int, 5> repair_operations{};
  int repair_left_below_20 = 0, repair_forced_below_20 = 0;
  //! Triangles still further from the surface than RegionSettings::deviation_goal_mm (sampled).
  int repair_left_above_deviation_goal = 0;
  //! Regions meshed again with another front order because their own triangles crossed or
  //! their front did not close.
  std::vector<int> regions_remeshed;
  //! True if the flips, smoothing and repair ran on the stitched mesh: because the settings ask
  //! for it, or because the regions' own ones made an edge with more than two triangles or a
  //! crossing between regions (the fallback).
  bool serial_postprocessing = false;
  //! Seconds, for reports and benchmarks (not part of the result). `seconds`: wall clock of
  //! the segment nodes, of the regions (meshed, flipped, smoothed and repaired in parallel),
  //! of the check for crossings (including re-meshing regions whose own triangles crossed and
  //! a serial post-processing), and of
  //! the serial flips, smoothing and repair if they ran. `thread_seconds`: the regions' stages
  //! summed over the threads (regions = the meshers).
  struct StageSeconds {
    double segments = 0, regions = 0, flips = 0, smoothing = 0, repair = 0, check = 0;
  } seconds, thread_seconds;
};

//! Meshes every region (openings stay empty) and stitches them: segment nodes appear once.
AnimationMesh build_animation_mesh(const RegionGraph& graph, const LineSet& lines,
                                   const ScanSurface& surface, const RegionSettings& settings);

struct AnimationMeshQuality {
  double min_angle_deg = 0, max_angle_deg = 0;
  double mean_radius_ratio = 0, min_radius_ratio = 0;  //!< 2 r_in / R_circ (triangle_quality.h)
  double fraction_min_angle_ge_30 = 0, fraction_min_angle_ge_20 = 0;
  //! Triangles below 20 deg that have a corner where two constraint lines meet at < 20 deg.
  int small_angle_exempt = 0;
  double min_angle_non_exempt_deg = 0;
  std::array<int, 12> min_angle_histogram{};     //!< 5 deg bins over [0, 60]
  std::array<int, 10> radius_ratio_histogram{};  //!< 0.1 bins over [0, 1]
  std::map<int, int> valence_histogram;
  std::vector<int> triangles_per_region;
  double hausdorff_mesh_to_surface_mm = 0, hausdorff_surface_to_mesh_mm = 0;
  double max_vertex_offset_mm = 0;  //!< largest vertex distance to the scan surface
  int vertices_off_surface = 0;     //!< vertices with no surface around them to project onto

  std::string to_text() const;
};

//! The quality report. The Hausdorff distances are sampled (`samples_per_triangle` subdivisions
//! per edge); surface -> mesh samples the surface under the mesh's own triangles and, given
//! `regions`, also over its meshed regions (every second grid cell in phi and in h), so that a
//! gap in the mesh counts.
AnimationMeshQuality evaluate_quality(const AnimationMesh& am, const ScanSurface& surface,
                                      int samples_per_triangle = 6,
                                      const RegionGraph* regions = nullptr);

}  // namespace scanmesh::aft
