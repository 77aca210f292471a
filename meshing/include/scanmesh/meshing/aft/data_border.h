// The data border (issue 25 item 2, "partial scans downstream"): a RangeGrid spans the full turn
// in phi, but an imported scan may cover only part of it. The outer boundary of the defined scan
// surface then becomes an animation line of its own kind (LineKind::DataBorder), so that the
// region analysis finds the regions bounded by the user's lines and the data's edge, and user
// lines that run off the data are clipped at that edge (a T-junction there).
//
// How the border is traced (docs/animation-meshes.md, "Partial scans: the data border"): the
// distance from the defined patches to the nearest undefined one, sampled at half a pixel, is
// contoured at `margin_px` (marching squares: an inward offset of the defined area, so the line
// keeps that margin and the cell staircase becomes arcs), then simplified by Douglas-Peucker to
// `tolerance_px` (the stairs' remaining bumps are far below a cell), then checked as
// validate_lines checks a line; a failing contour is traced again with a wider margin.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "scanmesh/meshing/aft/animation_lines.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::aft {

//! auto: on when the data do not cover the full turn (some phi column has no defined patch),
//! off otherwise, so that a full scan's regions stay as they were.
enum class DataBorderMode { Auto, On, Off };

//! "auto" | "on" | "off"; InvalidInputError for anything else.
DataBorderMode parse_data_border_mode(std::string_view name);
const char* to_string(DataBorderMode mode);

struct DataBorderOptions {
  double margin_px = 1.5;     //!< distance kept inside the defined area (texture pixels)
  double tolerance_px = 0.6;  //!< Douglas-Peucker tolerance of the traced contour
  double min_area_px = 100;   //!< components enclosing less (pixels^2) are specks: no border
};

//! True if some phi column of the surface has no defined patch (the data stop short of a turn).
bool misses_part_of_the_turn(const ScanSurface& surface);

//! The outer boundary of each component of the defined surface that encloses at least
//! min_area_px, as closed lines of kind DataBorder with ids "data-border-N", in texture pixels,
//! counter-clockwise (a component that goes all the way round gives two lines, towards its top
//! and its bottom). Holes inside the data get no border. Every line passes validate_lines.
std::vector<AnimationLine> trace_data_border(const ScanSurface& surface,
                                             const DataBorderOptions& options = {});

//! The user's lines clipped to the inside of the border lines: a line that leaves the data
//! loses its parts outside (each part inside becomes a line of its own, the first keeping the
//! id, the others "<id>.2", "<id>.3", ..., flattened and no longer smooth), and its cut ends
//! lie on the border (the region analysis joins them there as T-junctions). Lines wholly inside
//! are kept as they are; parts shorter than 2 pixels are dropped.
LineSet clip_lines_to_border(const LineSet& lines, const std::vector<AnimationLine>& border,
                             const ScanSurface& surface);

struct DataBorderResult {
  LineSet lines;           //!< clipped user lines, then the border lines
  bool border_on = false;  //!< whether the mode (auto resolved) added a border
  int border_lines = 0;    //!< border lines added
  int clipped_lines = 0;   //!< user lines that were cut at the border
  int dropped_lines = 0;   //!< user lines wholly outside the border
};

//! The lines the region analysis gets: `lines` unchanged when the mode resolves to off, else
//! clip_lines_to_border(lines, trace_data_border(surface)) followed by the border lines.
DataBorderResult with_data_border(const LineSet& lines, const ScanSurface& surface,
                                  DataBorderMode mode, const DataBorderOptions& options = {});

}  // namespace scanmesh::aft
