#include "scanmesh/core/mesh.h"

#include <Eigen/Geometry>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {
void require(bool ok, const std::string& what) {
  if (!ok) throw InvalidInputError("invalid mesh: " + what);
}
}  // namespace

void Mesh::validate() const {
  const auto nv = static_cast<long long>(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v)
    require(positions[v].allFinite(),
            "vertex " + std::to_string(v) + " has a non-finite coordinate");
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int k : triangles[f])
      require(k >= 0 && k < nv, "face " + std::to_string(f) + " refers to vertex " +
                                    std::to_string(k) + " of " + std::to_string(nv));
  require(normals.empty() || normals.size() == positions.size(), "normals count != vertex count");
  require(colors.empty() || colors.size() == positions.size(), "colours count != vertex count");
  require(face_labels.empty() || face_labels.size() == triangles.size(),
          "face label count != face count");
  require(face_texcoords.empty() || face_texcoords.size() == triangles.size(),
          "face texcoord count != face count");
  const auto nt = static_cast<long long>(texcoords.size());
  for (std::size_t f = 0; f < face_texcoords.size(); ++f)
    for (int k : face_texcoords[f])
      require(k >= 0 && k < nt, "face " + std::to_string(f) + " refers to texcoord " +
                                    std::to_string(k) + " of " + std::to_string(nt));
}

void Mesh::compute_vertex_normals() {
  std::vector<Eigen::Vector3d> sum(positions.size(), Eigen::Vector3d::Zero());
  for (const auto& t : triangles) {
    // The unnormalised cross product weights each face by twice its area.
    const Eigen::Vector3d n =
        (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    for (int k : t) sum[k] += n;
  }
  normals.resize(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const double len = sum[v].norm();
    normals[v] = len > 0 ? Eigen::Vector3f((sum[v] / len).cast<float>()) : Eigen::Vector3f::UnitZ();
  }
}

}  // namespace scanmesh
