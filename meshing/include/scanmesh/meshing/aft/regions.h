// Region analysis (seed 000 §5.1 and §7.1 item 1): exact intersections of the animation lines
// in (phi, h) with phi wrapping round, segments between intersections and end points, the
// planar graph on the cylinder, its faces (regions), holes (components inside a region) and
// dangling internal constraint lines. Region settings (unit size, mesher) per region.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scanmesh/meshing/aft/animation_lines.h"
#include "scanmesh/meshing/aft/data_border.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::aft {

//! Part of one animation line between two junctions (intersections or end points).
struct Segment {
  int line = -1;                     //!< index into LineSet::lines
  int node0 = -1, node1 = -1;        //!< graph nodes at the ends (equal for a lone loop)
  std::vector<Eigen::Vector2d> pts;  //!< (phi, h), phi unwrapped (continuous along the segment)
  int left_region = -1, right_region = -1;  //!< meshed region on each side, -1 none
};

//! One segment traversed in a direction.
struct HalfEdgeRef {
  int segment = -1;
  bool forward = true;
};

//! A closed walk along segments with the face on its left: an outer boundary (counter-
//! clockwise in (phi, h), area > 0), or the outside of a component (area <= 0). A dangling line
//! appears in it twice, once in each direction.
struct BoundaryCycle {
  std::vector<HalfEdgeRef> edges;
  double area = 0;  //!< signed, rad * mm
  int winding = 0;  //!< turns round the axis (non-zero: a cap towards the grid's top/bottom)
  int component = -1;
};

struct Region {
  int outer = -1;               //!< index into RegionGraph::cycles
  std::vector<int> inner;       //!< holes and free-standing internal lines inside it
  bool opening = false;         //!< bounded only by opening lines: left empty
  double area = 0;              //!< outer area minus the holes' (rad * mm)
  Eigen::Vector2d label_point;  //!< a (phi, h) point inside, for labels
  std::string name;             //!< from the settings, or "region-N"
  double unit_mm = 0;           //!< standard edge length (settings)
  std::string mesher = "aft";   //!< aft | delaunay
};

struct RegionGraph {
  std::vector<Eigen::Vector2d> nodes;  //!< (phi, h), phi in [phi0, phi0 + 2 pi)
  std::vector<Segment> segments;
  std::vector<BoundaryCycle> cycles;
  std::vector<Region> regions;     //!< includes openings (opening = true)
  std::vector<int> dangling_ends;  //!< nodes where a line ends without meeting another

  //! The region containing (phi, h), or nullopt (outside all regions).
  std::optional<int> region_at(const Eigen::Vector2d& param) const;
  //! Polygon of a cycle in (phi, h), phi unwrapped along it.
  std::vector<Eigen::Vector2d> cycle_polygon(int cycle) const;
  //! Human-readable summary.
  std::string to_text() const;
};

//! RegionGraph::region_at for many points (pictures, sampled distances): the regions'
//! polygons are traced once and tested inside their boxes only. The same answers.
class RegionLocator {
 public:
  explicit RegionLocator(const RegionGraph& graph);
  std::optional<int> region_at(const Eigen::Vector2d& param) const;

 private:
  struct Polygon {
    std::vector<Eigen::Vector2d> pts;  // phi unwrapped along the cycle
    double xmin = 0, xmax = 0, ymin = 0, ymax = 0;
  };
  static Polygon make(std::vector<Eigen::Vector2d> pts);
  static bool contains(const Polygon& poly, Eigen::Vector2d q);
  std::vector<Polygon> outer_;
  std::vector<std::vector<Polygon>> holes_;
  std::vector<double> area_;  // |outer cycle area|: the smallest containing region wins
};

//! Builds the graph. End points within `snap_px` texture pixels of another line are moved onto
//! it (a T junction); end points within snap_px of each other are joined. Throws
//! FileFormatError naming the file and line for a self-intersecting line or lines that overlap.
RegionGraph analyze_regions(const LineSet& lines, const ScanSurface& surface, double snap_px = 1.5);

// ---------------------------------------------------------------------------------------------

struct RegionRule {
  std::string name;
  std::optional<Eigen::Vector2d> point_px;  //!< pixel inside the region (see texture_rows)
  std::optional<double> unit_mm;
  std::optional<std::string> mesher;
};

enum class EdgeStrategy { Random, Shortest, Longest };
enum class SegmentInit { Equidistant, Curvature };
//! d_I of a segment between two meshed regions: the mean of both regions' unit sizes, or the
//! finer one (docs/animation-meshes.md, "Segment spacing").
enum class SegmentSpacing { Finer, Mean };

struct RegionSettings {
  double default_unit_mm = 6.0;
  std::string default_mesher = "aft";
  EdgeStrategy strategy = EdgeStrategy::Shortest;
  SegmentInit segment_init = SegmentInit::Equidistant;
  SegmentSpacing segment_spacing = SegmentSpacing::Mean;
  double curvature_weight_mm = 10.0;  //!< curvature init: measure = arc + weight * turning
  double chordal_tolerance_mm = 0.5;  //!< curvature-adaptive size: sagitta bound
  double min_unit_mm = 0.3;           //!< lower bound of the adaptive size
  int relax_iterations = 30;          //!< segment nodes "on rails"
  int smooth_iterations = 3;          //!< tangential smoothing of Steiner points
  //! Edge flips towards valence 6 (4 on a straight region border) before the smoothing
  //! (docs/animation-meshes.md, "Valence flips"); false: max-min-angle flips only.
  bool valence_flips = true;
  int repair_rounds = 8;  //!< small-angle repair sweeps (0: off)
  //! The advancing front's step budget per region (a bound on its time; 0: automatic, enough
  //! for any front that closes). A region over budget is meshed again with the other front
  //! orders and, if none closes, left with a hole that the report names.
  long max_front_steps = 0;
  //! The repair attacks every triangle whose smallest angle is below this (deg): 20.5 keeps
  //! the 20 deg guarantee at the least cost; 30.5 also lifts the triangles between 20 and 30
  //! deg, ~3-4 times the post-processing time (docs/animation-meshes.md, "Repair goal").
  double repair_goal_deg = 20.5;
  //! The repair also attacks every triangle further than this from the surface (mm, sampled;
  //! 0: off), with the same operations, never lowering the smallest angle below the angle
  //! goal (docs/animation-meshes.md, "Deviation goal"). Off by default: a distance in mm
  //! depends on the scale of the object.
  double deviation_goal_mm = 0;
  //! Flips, smoothing and repair per region in the parallel jobs (false: on the stitched mesh,
  //! serially, as the fallback does; docs/animation-meshes.md).
  bool parallel_postprocessing = true;
  std::uint64_t seed = 1;
  //! When the edge of the scan's data becomes a region border (data_border.h); nullopt: not
  //! set here (the CLI's --data-border, else auto).
  std::optional<DataBorderMode> data_border;
  std::vector<RegionRule> regions;
  //! As LineSet::texture_rows: > 0 when the rules' points were turned from a file's
  //! top-down rows into the grid pixel frame (to_grid_rows); messages give the file's values.
  int texture_rows = 0;

  //! The same settings with every unit size (the default and each rule's) times `factor`, e.g.
  //! 0.25 for a mesh four times finer; the adaptive lower bound min_unit_mm is kept.
  RegionSettings with_units_scaled(double factor) const;
};

//! YAML (or JSON, a subset of YAML) region settings (docs/formats.md, "Region settings").
//! Throws FileFormatError naming the file for unknown keys, wrong types or impossible values.
//! parse_region_settings keeps the points as written; read_region_settings brings them into the
//! grid pixel frame for a texture `n_h` rows high unless the file counts rows from the bottom.
RegionSettings parse_region_settings(std::string_view text, const std::string& file);
RegionSettings read_region_settings(const std::filesystem::path& path, int n_h,
                                    FileRows rows = FileRows::FromTop);
//! The rules' points from top-down texture rows into the grid pixel frame (as for lines).
void to_grid_rows(RegionSettings& settings, int n_h);

//! Applies the settings' rules to the graph's regions (names, unit sizes, meshers). A rule whose
//! point lies in no region throws InvalidInputError naming the rule.
void apply_region_settings(RegionGraph& graph, const RegionSettings& settings,
                           const ScanSurface& surface);

}  // namespace scanmesh::aft
