// Animation lines (seed 000 §5.1): curves the user draws over the scan's texture image. They
// partition the surface into regions, become mandatory edge chains of the mesh, and mark
// openings (eyes, mouth: the region inside stays empty) and seams (borders to another mesh).
//
// Input: an SVG drawn over the upright texture PNG (coordinates = texture pixels: x = phi
// column, y down from the picture's top edge, where the highest h is; core/texture_layout.h) or
// the same lines as JSON (docs/formats.md, "Animation lines"). read_lines brings them into the
// grid pixel frame (y = h rows up from the lowest h), in which everything below works. Bezier
// curves are flattened to 24 pieces per curve segment; a polyline marked smooth becomes the
// centripetal Catmull-Rom spline through its points (line_curve). That curve is the exact geometry
// every later step (intersections, arc length) uses.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::aft {

//! DataBorder: the edge of a partial scan's data, traced by trace_data_border (data_border.h),
//! never read from a file; a region border like Normal, with no region outside it.
enum class LineKind { Normal, Opening, Seam, DataBorder };

const char* to_string(LineKind kind);

struct AnimationLine {
  std::string id;  //!< SVG id / JSON id; "line-N" when absent
  LineKind kind = LineKind::Normal;
  double node_spacing_mm = 0;           //!< seams: the user's node spacing; 0 = derived
  bool closed = false;                  //!< polygon, path ending in Z, JSON "closed"
  std::vector<Eigen::Vector2d> pixels;  //!< drawn points in texture pixels (curves flattened)
  //! SVG class "smooth" / JSON "smooth": the line is the spline through `pixels` (line_curve).
  bool smooth = false;
  std::string source;  //!< "file:line" where the element starts
};

struct LineSet {
  std::string file;
  std::vector<AnimationLine> lines;
  //! > 0: the lines came from a file counting rows down from the top of a picture this many
  //! rows high and were turned into the grid pixel frame (to_grid_rows); messages convert back
  //! to the file's coordinates (file_pixel). 0: the coordinates are the grid pixel frame's.
  int texture_rows = 0;
};

//! How the y coordinates of a line or region-settings file count (docs/animation-meshes.md,
//! "Coordinates").
enum class FileRows {
  FromTop,     //!< rows down from the top of the upright texture.png: the convention
  FromBottom,  //!< h rows up from the lowest h: files written before pictures were upright
};

//! Parses "top" / "bottom" (the CLI's --line-rows); InvalidInputError otherwise.
FileRows parse_file_rows(const std::string& text);

//! Parses SVG text: <path d="..."> (M L H V C S Q T Z, absolute and relative), <polyline>,
//! <polygon>, <line>. A path with several subpaths gives one line per subpath. id or class
//! containing "opening" / "seam" sets the kind; data-spacing-mm="2.5" the seam node spacing.
//! Throws FileFormatError(file, "line N: ...") for anything it cannot read (arcs, transforms,
//! malformed numbers, fewer than 2 points).
LineSet parse_lines_svg(std::string_view text, const std::string& file);

//! JSON form: {"lines": [{"id": "...", "kind": "line|opening|seam", "spacing_mm": 2,
//! "closed": false, "smooth": true, "points": [[x, y], ...]}]}; "smooth" draws a centripetal
//! Catmull-Rom spline through the points (flattened like the SVG curves).
LineSet parse_lines_json(std::string_view text, const std::string& file);

//! The line as every later step sees it, in pixels: consecutive points less than half the
//! texture's width apart are joined across the phi seam (x unwrapped along the line: 500 then
//! 10 is 500 then 522 on a 512 wide texture), then a smooth line becomes the centripetal
//! Catmull-Rom spline through the joined points (24 pieces per span; a closed line that goes
//! round the axis continues one turn on).
std::vector<Eigen::Vector2d> line_curve(const AnimationLine& line, double width_px);

//! Reads .svg or .json by extension (IoError if unreadable) drawn over a texture `n_h` rows high
//! (the grid's n_h), and brings the coordinates into the grid pixel frame (to_grid_rows) unless
//! the file counts rows from the bottom.
LineSet read_lines(const std::filesystem::path& path, int n_h, FileRows rows = FileRows::FromTop);

//! Texture-pixel coordinates counted down from the top of a picture `n_h` rows high -> the grid
//! pixel frame (y up from the lowest h), for every point of every line. The parse_* functions
//! return the file's coordinates as they are.
void to_grid_rows(LineSet& lines, int n_h);

//! A point of the set in the coordinates its file gave (for messages).
Eigen::Vector2d file_pixel(const LineSet& lines, const Eigen::Vector2d& grid_pixel);

//! Grid pixel (x, y) -> (phi, h): pixel i covers [i, i + 1), cell i sits at its centre.
Eigen::Vector2d pixel_to_param(const ScanSurface& surface, const Eigen::Vector2d& pixel);
Eigen::Vector2d param_to_pixel(const ScanSurface& surface, const Eigen::Vector2d& param);

//! The checks that need the surface: every line lies on the defined scan surface (sampled at
//! a quarter cell) and is at least 2 cells long. Throws FileFormatError naming the file, the
//! line's id and its source line.
void validate_lines(const LineSet& lines, const ScanSurface& surface);

}  // namespace scanmesh::aft
