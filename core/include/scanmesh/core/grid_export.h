// Exports of a RangeGrid to the formats other tools read (docs/formats.md, "Exports").
#pragma once

#include <filesystem>

#include "scanmesh/core/image.h"
#include "scanmesh/core/range_grid.h"

namespace scanmesh {

//! Organised PCL point cloud (PointXYZRGB, width = n_phi, height = n_h, invalid cells NaN,
//! is_dense = false), binary PCD, written atomically.
void export_pcd(const std::filesystem::path& path, const RangeGrid& grid);
//! Binary PLY point cloud of the valid cells: x y z (float), red green blue (uchar),
//! confidence (float), phi_index/h_index (int).
void export_ply_points(const std::filesystem::path& path, const RangeGrid& grid);

//! The RGB plane as an upright picture (texture_layout.h): pixel (x, y) = cell (phi index x,
//! h index n_h - 1 - y), the highest h at the top. Invalid cells keep their colour (the camera
//! saw them even where the laser did not).
Image8 texture_image(const RangeGrid& grid);
//! A picture of the radius in the same layout: grey, near the axis dark, far bright; invalid
//! cells pure black.
Image8 depth_image(const RangeGrid& grid);
//! depth_image with a legend strip on the right: the grey scale with the smallest and largest
//! radius in mm (what export_depth_png writes).
Image8 depth_picture(const RangeGrid& grid);

void export_texture_png(const std::filesystem::path& path, const RangeGrid& grid);
void export_depth_png(const std::filesystem::path& path, const RangeGrid& grid);

}  // namespace scanmesh
