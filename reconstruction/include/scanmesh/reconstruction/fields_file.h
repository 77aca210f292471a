// The surface fields file (.smf): per-cell normals and curvatures of a grid, versioned and
// CRC-32 checked like the grid file (docs/formats.md, "Surface fields file (.smf)").
#pragma once

#include <filesystem>

#include "scanmesh/reconstruction/surface_fields.h"

namespace scanmesh {

void write_fields(const std::filesystem::path& path, const SurfaceFields& fields);  // atomic
//! Throws FileFormatError (naming the file and the problem) for truncated, corrupt or
//! inconsistent files; sizes are checked against the file length before allocating.
SurfaceFields read_fields(const std::filesystem::path& path);

}  // namespace scanmesh
