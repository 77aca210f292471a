// Animation lines (seed 000 §5.1): curves the user draws over the scan's texture image. They
// partition the surface into regions, become mandatory edge chains of the mesh, and mark
// openings (eyes, mouth: the region inside stays empty) and seams (borders to another mesh).
//
// Input: an SVG drawn over the texture PNG (coordinates = texture pixels: x = phi column,
// y = h row, row 0 at the image top = the lowest h) or the same lines as JSON
// (docs/formats.md, "Animation lines"). Bezier curves are flattened to 24 pieces per curve
// segment; a polyline marked smooth becomes the centripetal Catmull-Rom spline through its
// points (line_curve). That curve is the exact geometry every later step (intersections, arc
// length) uses.
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
};

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

//! Reads .svg or .json by extension (IoError if unreadable).
LineSet read_lines(const std::filesystem::path& path);

//! Texture pixel (x, y) -> (phi, h): pixel i covers [i, i + 1), cell i sits at its centre.
Eigen::Vector2d pixel_to_param(const ScanSurface& surface, const Eigen::Vector2d& pixel);
Eigen::Vector2d param_to_pixel(const ScanSurface& surface, const Eigen::Vector2d& param);

//! The checks that need the surface: every line lies on the defined scan surface (sampled at
//! a quarter cell) and is at least 2 cells long. Throws FileFormatError naming the file, the
//! line's id and its source line.
void validate_lines(const LineSet& lines, const ScanSurface& surface);

}  // namespace scanmesh::aft
