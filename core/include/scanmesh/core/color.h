#pragma once

#include <cstdint>

namespace scanmesh {

//! 8-bit sRGB colour, as stored in range grids, meshes and PNGs.
struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb8&, const Rgb8&) = default;
};

}  // namespace scanmesh
