// Reading unorganised point clouds for the fan mesher: PLY (vertices), PCD (ASCII or binary,
// x y z fields), XYZ text (docs/formats.md, "XYZ point clouds") and a grid's valid cells (.smg).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace scanmesh {

//! Dispatches on the extension (.ply, .pcd, .xyz/.txt/.pts, .smg). Throws FileFormatError
//! (naming the file) for malformed content, IoError when the file cannot be read,
//! InvalidInputError for an unknown extension.
std::vector<Eigen::Vector3d> read_point_cloud(const std::filesystem::path& path);

//! XYZ text: one point per line, 3 or more whitespace- or comma-separated numbers (extra
//! columns such as normals or colours are ignored); '#' starts a comment; blank lines skipped.
std::vector<Eigen::Vector3d> parse_xyz(const std::string& text,
                                       const std::filesystem::path& source);

//! PCD v0.7 / v0.6 with DATA ascii or binary (binary_compressed is rejected); needs fields x y z
//! of type F (size 4 or 8). Non-finite points (NaN in organised clouds) are skipped.
std::vector<Eigen::Vector3d> parse_pcd(const std::string& bytes,
                                       const std::filesystem::path& source);

}  // namespace scanmesh
