// Shared by the animation-line fuzz entry points: what a parsed line set goes through next in
// `scanmesh regions` / `animesh` — the surface checks and the region analysis (intersections,
// the planar graph on the cylinder, faces, holes). A parser that accepts lines which then crash
// or hang the analysis is as much a finding as a crash in the parser.
#pragma once

#include <cmath>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/range_grid.h"
#include "scanmesh/meshing/aft/animation_lines.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::fuzz {

//! A 64 x 64 cylinder of radius 50 mm (texture pixels 0..64 in x and y), a hole in one corner.
inline const ScanSurface& fuzz_cylinder() {
  static const RangeGrid grid = [] {
    RangeGrid g(64, 64, 0.0, 0.0, 1.0);
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) g.set_sample(i, j, 50.0f);
    for (int j = 50; j < 60; ++j)
      for (int i = 50; i < 60; ++i) g.invalidate(i, j);
    return g;
  }();
  static const ScanSurface surface(grid);
  return surface;
}

//! Validates and analyses small line sets (the analysis is polynomial in the points; the cap
//! keeps each input well under the fuzzer's time limit). Clean rejections are fine.
inline void analyse_lines(const aft::LineSet& lines) {
  std::size_t points = 0;
  for (const auto& line : lines.lines) points += line.pixels.size();
  if (lines.lines.size() > 8 || points > 64) return;
  try {
    aft::validate_lines(lines, fuzz_cylinder());
    const aft::RegionGraph g = aft::analyze_regions(lines, fuzz_cylinder());
    for (const aft::Region& r : g.regions)
      if (!std::isfinite(r.area)) std::abort();  // a region must have a real area
  } catch (const Error&) {
  }
}

}  // namespace scanmesh::fuzz
