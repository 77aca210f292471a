// Indexed triangle mesh shared by all meshers and writers (docs/formats.md, "Mesh").
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "scanmesh/core/color.h"

namespace scanmesh {

//! A triangle mesh with optional attributes. An optional attribute is either empty or has one
//! entry per vertex (normals, colors) or per face (face_labels, face_texcoords).
//! Texture coordinates are indexed separately from positions, as in OBJ, so a vertex on a
//! texture seam keeps one position but gets a different (u, v) in each face.
struct Mesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<int, 3>> triangles;  //!< counter-clockwise seen from outside

  std::vector<Eigen::Vector3f> normals;  //!< per vertex, unit length
  std::vector<Rgb8> colors;              //!< per vertex
  std::vector<int> face_labels;          //!< per face (region, material, ...)

  std::vector<Eigen::Vector2f> texcoords;          //!< (u, v), v = 0 at the image bottom
  std::vector<std::array<int, 3>> face_texcoords;  //!< per face, indices into texcoords

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t face_count() const { return triangles.size(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_face_labels() const { return !face_labels.empty(); }
  bool has_texcoords() const { return !face_texcoords.empty(); }

  //! Throws InvalidInputError if an index is out of range, an attribute has the wrong length,
  //! or a coordinate is not finite.
  void validate() const;

  //! Area-weighted vertex normals from the faces (overwrites normals).
  void compute_vertex_normals();
};

//! Sum of the triangles' areas (degenerate ones add 0).
double surface_area(const Mesh& mesh);

//! One flag per face: its three corner positions (as a set) repeat an earlier face's. Lets
//! drawing and intersection tests treat n copies of one triangle as one (O(F log F)).
std::vector<char> faces_repeating_earlier_geometry(const Mesh& mesh);

}  // namespace scanmesh
