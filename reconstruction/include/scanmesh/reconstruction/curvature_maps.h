// Pictures of curvature and normals: what people would rather look at than read. Values are
// per cell (k = j * width + i); the pictures are upright (core/texture_layout.h: the highest h
// at the top).
#pragma once

#include <string>
#include <vector>

#include "scanmesh/core/image.h"
#include "scanmesh/core/image_text.h"  // draw_text, used with these maps
#include "scanmesh/reconstruction/surface_fields.h"

namespace scanmesh {

//! Grey map like seed 000 Abb. 5.9: value / scale mapped to 0..255 (clamped), undefined black.
//! scale <= 0: the 99th percentile of the defined values.
Image8 grey_map(const std::vector<float>& values, const std::vector<std::uint8_t>& defined,
                int width, int height, double scale = 0);

//! Diverging blue-white-red map of a signed field, symmetric around 0 with +-scale at the ends
//! (scale <= 0: the 98th percentile of |value|), undefined cells dark grey, and a legend strip
//! on the right with the scale's numbers and `title` (e.g. "H [1/mm]").
Image8 diverging_map(const std::vector<float>& values, const std::vector<std::uint8_t>& defined,
                     int width, int height, const std::string& title, double scale = 0);

//! Normal map: RGB = (n + 1) / 2 in the turntable frame, undefined cells black.
Image8 normal_map(const SurfaceFields& fields);

}  // namespace scanmesh
