// Texture layout: how pictures of a grid's planes (texture, depth, curvature, normals, regions,
// the 2D mesh) and the texture-pixel coordinates in user files (animation lines, region points)
// relate to grid cells (docs/formats.md, "Texture layout").
//
// Pictures are n_phi pixels wide and n_h high and upright: column x is phi index x, and the TOP
// row shows the HIGHEST h, so a scanned head stands the right way up in any image viewer and in a
// drawing program. Texture-pixel coordinates in files follow the picture: x to the right, y down
// from the top edge, pixel (x, y) covering [x, x+1) x [y, y+1).
//
// Inside the library, line geometry is kept in the *grid pixel* frame: x the same, y counted up
// from the lowest h (cell row j covers [j, j+1)); that frame maps to (phi, h) with a positive
// diagonal, so counter-clockwise stays counter-clockwise seen from outside.
#pragma once

#include <Eigen/Core>

namespace scanmesh {

//! The picture row that shows grid row `h_index` of a grid with `n_h` rows.
inline int texture_row(int h_index, int n_h) { return n_h - 1 - h_index; }

//! A texture-pixel position (y down from the top) in the grid pixel frame (y up from the lowest
//! h), for a picture `n_h` rows high; the map is its own inverse.
inline Eigen::Vector2d texture_to_grid_pixel(const Eigen::Vector2d& p, int n_h) {
  return {p.x(), static_cast<double>(n_h) - p.y()};
}

}  // namespace scanmesh
