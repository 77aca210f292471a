// Point clouds as scanners write them: PLY vertices (Horus/Ciclop and FabScan layouts with
// colours), PCD (ASCII, binary and binary_compressed; organised width x height), XYZ text, and a
// grid's valid cells (.smg). docs/formats.md, "Point clouds".
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "scanmesh/core/color.h"

namespace scanmesh {

//! An unorganised or organised point cloud with optional per-point attributes.
//! Organised clouds (PCD HEIGHT > 1) keep every lattice position, missing ones as NaN, so that
//! positions[row * width + column] is the sample of that pixel; unorganised clouds hold only
//! finite points.
struct PointCloud {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3f> normals;  //!< empty or one per position
  std::vector<Rgb8> colors;              //!< empty or one per position
  int width = 0;                         //!< organised: lattice columns; else positions.size()
  int height = 1;                        //!< organised: lattice rows (> 1); else 1

  bool organised() const { return height > 1; }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
  std::size_t size() const { return positions.size(); }
  //! Number of finite positions (organised clouds hold NaN for missing pixels).
  std::size_t finite_count() const;
  //! The finite points with their attributes, as an unorganised cloud.
  PointCloud finite_points() const;
};

//! Dispatches on the extension (.ply, .pcd, .xyz/.txt/.pts, .smg). Throws FileFormatError
//! (naming the file) for malformed content or a cloud without a finite point, IoError when the
//! file cannot be read, InvalidInputError for an unknown extension.
PointCloud read_point_cloud(const std::filesystem::path& path);

//! XYZ text: one point per line, 3 or more whitespace- or comma-separated numbers; '#' starts
//! a comment; blank lines skipped. 6 columns are x y z nx ny nz; 7 or more: x y z followed by
//! r g b (0..255) and, with 9 or more, nx ny nz (the MeshLab / CloudCompare layouts). A non-
//! finite coordinate is an error naming the line.
PointCloud parse_xyz(const std::string& text, const std::filesystem::path& source);

//! PCD v0.7 / v0.6, DATA ascii, binary or binary_compressed (LZF, fields stored column by
//! column); fields x y z of type F (size 4 or 8), optional normal_x/y/z and rgb / rgba (packed
//! float or uint). HEIGHT > 1 gives an organised cloud (NaN kept); otherwise non-finite points
//! are skipped.
PointCloud parse_pcd(const std::string& bytes, const std::filesystem::path& source);

//! LZF decompression as PCD binary_compressed stores it. Throws FileFormatError (naming
//! `source`) for a malformed stream or when the output would not be exactly `expected_size`.
std::vector<char> lzf_decompress(const char* in, std::size_t in_size, std::size_t expected_size,
                                 const std::filesystem::path& source);

}  // namespace scanmesh
