// Mesh files: PLY (binary little-endian and ASCII), OBJ + MTL, binary STL writers and a PLY
// reader. All writers are atomic (docs/formats.md, "Mesh files").
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "scanmesh/core/mesh.h"

namespace scanmesh {

enum class PlyEncoding { Binary, Ascii };

//! Writes positions (float), and when present normals, colours and per-face labels.
void write_ply(const std::filesystem::path& path, const Mesh& mesh,
               PlyEncoding encoding = PlyEncoding::Binary);
//! Reads ASCII or binary (little/big endian) PLY with vertex x/y/z (float or double), optional
//! nx/ny/nz, red/green/blue, and faces as vertex_indices or vertex_index lists (polygons are
//! fan-triangulated); a face `label` property is read when present. Unknown properties are
//! skipped. Throws FileFormatError naming the file and the problem.
Mesh read_ply(const std::filesystem::path& path);
//! The same reader on bytes already in memory; `source` names them in errors.
Mesh parse_ply(std::span<const std::uint8_t> bytes, const std::filesystem::path& source);

//! Writes OBJ with v / vn / vt / f. When `texture_png` is non-empty, writes `<stem>.mtl`
//! beside it referencing the texture (map_Kd) and the OBJ uses that material.
void write_obj(const std::filesystem::path& path, const Mesh& mesh,
               const std::string& texture_png = "");

//! Binary STL with facet normals from the triangle geometry.
void write_stl(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace scanmesh
