// Mesh files: PLY (binary little-endian and ASCII), OBJ + MTL, binary STL writers; PLY, OFF,
// OBJ and STL readers. All writers are atomic (docs/formats.md, "Mesh files").
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

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

//! OFF / COFF / NOFF (ASCII): vertices with optional colours (0..255 integers or 0..1 floats),
//! polygons fan-triangulated; '#' comments. Throws FileFormatError naming the file and line.
Mesh parse_off(std::string_view text, const std::filesystem::path& source);

//! A mesh read from an OBJ file and the texture image its material names (map_Kd), if any.
struct ObjMesh {
  Mesh mesh;
  std::filesystem::path texture;  //!< resolved against the OBJ's folder; empty if none
};
//! OBJ: v (optionally followed by r g b), vt, vn, f with v, v/t, v//n, v/t/n and negative
//! indices, polygons fan-triangulated; mtllib / usemtl for the texture of the first textured
//! material used (`mtl_text` is the MTL file's text, or empty). Other statements are ignored.
ObjMesh parse_obj(std::string_view text, const std::filesystem::path& source,
                  std::string_view mtl_text = {});
//! Reads the OBJ and its MTL file (a missing MTL file means no texture, not an error).
ObjMesh read_obj(const std::filesystem::path& path);

//! Binary or ASCII STL; coincident corners are welded into shared vertices (exact match).
Mesh parse_stl(std::span<const std::uint8_t> bytes, const std::filesystem::path& source);

//! Any mesh file by extension: .ply, .off, .obj, .stl. Throws InvalidInputError for another
//! extension, FileFormatError for malformed content.
Mesh read_mesh(const std::filesystem::path& path);

//! Writes OBJ with v / vn / vt / f. When `texture_png` is non-empty, writes `<stem>.mtl`
//! beside it referencing the texture (map_Kd) and the OBJ uses that material.
void write_obj(const std::filesystem::path& path, const Mesh& mesh,
               const std::string& texture_png = "");

//! Binary STL with facet normals from the triangle geometry.
void write_stl(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace scanmesh
