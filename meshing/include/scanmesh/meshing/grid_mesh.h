// Grid mesh: the organised triangulation of a range grid, two triangles per fully valid cell
// quad (the classic rotary-scanner mesh; compare PCL OrganizedFastMesh).
#pragma once

#include <cstddef>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/core/range_grid.h"

namespace scanmesh {

struct GridMeshOptions {
  //! A quad whose corner radii differ by more than this is a depth jump (silhouette, occlusion
  //! edge) and gets no triangles.
  double max_depth_jump_mm = 8.0;
  //! Connect column n_phi-1 to column 0 (the grid covers the full turn).
  bool close_seam = true;
  bool with_colors = true;
  //! Per-corner texture coordinates into the texture image (docs/formats.md, "Mesh files").
  bool with_texcoords = true;
};

struct GridMesh {
  Mesh mesh;
  //! For each mesh vertex, the RangeGrid::index of the cell it came from.
  std::vector<std::size_t> vertex_cell;
  std::size_t quads_meshed = 0;
  std::size_t quads_skipped_for_holes = 0;
  std::size_t quads_skipped_for_depth_jumps = 0;
};

//! Triangulates the valid cells. A quad is meshed only if its four cells are valid and its
//! depth jump is within the limit, so no triangle ever spans a hole. Each quad is split along
//! its shorter 3D diagonal; triangles face outward (away from the axis). Vertex normals are
//! area-weighted from the faces. Throws InvalidInputError for a non-positive depth limit.
GridMesh grid_mesh(const RangeGrid& grid, const GridMeshOptions& options = {});

}  // namespace scanmesh
