#include "scanmesh/core/mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <utility>
#include <vector>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {
// The message is built only on failure: validate() runs on every mesh a stage is given, and
// building it for each of 300,000 faces was ~3 % of a remesh of the demo head.
template <typename Message>
void require(bool ok, Message&& what) {
  if (!ok) throw InvalidInputError("invalid mesh: " + std::string(what()));
}
}  // namespace

void Mesh::validate() const {
  const auto nv = static_cast<long long>(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v)
    require(positions[v].allFinite(),
            [&] { return "vertex " + std::to_string(v) + " has a non-finite coordinate"; });
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int k : triangles[f])
      require(k >= 0 && k < nv, [&] {
        return "face " + std::to_string(f) + " refers to vertex " + std::to_string(k) + " of " +
               std::to_string(nv);
      });
  require(normals.empty() || normals.size() == positions.size(),
          [] { return "normals count != vertex count"; });
  require(colors.empty() || colors.size() == positions.size(),
          [] { return "colours count != vertex count"; });
  require(face_labels.empty() || face_labels.size() == triangles.size(),
          [] { return "face label count != face count"; });
  require(face_texcoords.empty() || face_texcoords.size() == triangles.size(),
          [] { return "face texcoord count != face count"; });
  const auto nt = static_cast<long long>(texcoords.size());
  for (std::size_t f = 0; f < face_texcoords.size(); ++f)
    for (int k : face_texcoords[f])
      require(k >= 0 && k < nt, [&] {
        return "face " + std::to_string(f) + " refers to texcoord " + std::to_string(k) + " of " +
               std::to_string(nt);
      });
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

// Flags every face whose three corner positions (as a set) repeat an earlier face's.
double surface_area(const Mesh& mesh) {
  const auto& p = mesh.positions;
  double area = 0.0;
  for (const auto& t : mesh.triangles)
    area += 0.5 * (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).norm();
  return area;
}

std::vector<char> faces_repeating_earlier_geometry(const Mesh& mesh) {
  using Corners = std::array<std::array<double, 3>, 3>;
  const auto& F = mesh.triangles;
  std::vector<std::pair<Corners, int>> keyed(F.size());
  for (std::size_t f = 0; f < F.size(); ++f) {
    Corners c;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = mesh.positions[F[f][k]];
      c[k] = {p.x(), p.y(), p.z()};
    }
    std::sort(c.begin(), c.end());
    keyed[f] = {c, static_cast<int>(f)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<char> repeats(F.size(), 0);
  for (std::size_t i = 1; i < keyed.size(); ++i)
    if (keyed[i].first == keyed[i - 1].first) repeats[keyed[i].second] = 1;
  return repeats;
}

}  // namespace scanmesh
