// A small software renderer (z-buffer rasteriser, orthographic camera, Lambert + Blinn-Phong
// shading) so every stage can write a picture of its mesh without a GPU or a display.
#pragma once

#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh.h"

namespace scanmesh {

struct RenderOptions {
  int width = 640, height = 640;
  //! Camera direction (from the object toward the camera): azimuth around z from +x, and
  //! elevation above the xy-plane. 180 deg looks at the face of the built-in head.
  double azimuth_deg = 180.0;
  double elevation_deg = 10.0;
  bool use_vertex_colors = true;  //!< otherwise a neutral clay colour
  bool draw_wireframe = false;
  Rgb8 background{40, 44, 52};
  double margin = 0.06;  //!< fraction of the image kept free around the object
};

//! Renders the mesh. Back faces are drawn in one dark slate blue whatever their colour, so holes
//! and flipped triangles show as such and never as a tint of the surface. A mesh without
//! triangles (a point cloud) is drawn as round splats. Throws InvalidInputError for sizes
//! outside 16..8192.
Image8 render_mesh(const Mesh& mesh, const RenderOptions& options = {});

//! Places images side by side (same height expected; shorter ones are padded).
Image8 hconcat(const std::vector<Image8>& images, Rgb8 background = {40, 44, 52});

}  // namespace scanmesh
