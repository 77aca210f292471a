// The surface fields file (.smf): per-cell normals and curvatures of a grid, versioned and
// CRC-32 checked like the grid file (docs/formats.md, "Surface fields file (.smf)").
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "scanmesh/reconstruction/surface_fields.h"

namespace scanmesh {

void write_fields(const std::filesystem::path& path, const SurfaceFields& fields);  // atomic
//! Throws FileFormatError (naming the file and the problem) for truncated, corrupt or
//! inconsistent files; sizes are checked against the file length before allocating.
SurfaceFields read_fields(const std::filesystem::path& path);
//! The same reader on bytes already in memory; `source` names them in errors.
SurfaceFields decode_fields(std::span<const std::uint8_t> bytes,
                            const std::filesystem::path& source);

}  // namespace scanmesh
