// Start triangulation (gap in seed 003 §4.2): marching tetrahedra over a cubic grid, each cube
// cut into the six Kuhn tetrahedra around its main diagonal. Neighbouring cubes then share
// consistent face triangulations, so the extracted surface is a manifold without cracks.
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/particles/particles.h"

namespace scanmesh::particles {

using Eigen::Vector3d;

Mesh marching_tetrahedra(const ImplicitSurface& surface, double spacing) {
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw InvalidInputError("marching_tetrahedra: spacing must be positive");
  const Eigen::AlignedBox3d box = surface.bounds();
  const Vector3d lo = box.min() - Vector3d::Constant(spacing);
  const Vector3d extent = box.max() - box.min() + Vector3d::Constant(2 * spacing);
  // The node count in double first: a tiny spacing overflows any integer product.
  double nodes = 1.0;
  for (int a = 0; a < 3; ++a) nodes *= std::ceil(extent[a] / spacing) + 1.0;
  if (!(nodes <= 60'000'000.0))
    throw InvalidInputError("marching_tetrahedra: grid too fine for the bounds (> 6e7 nodes; "
                            "edge length too small for the scene)");
  std::array<long long, 3> n{};
  for (int a = 0; a < 3; ++a) n[a] = static_cast<long long>(std::ceil(extent[a] / spacing)) + 1;
  auto node_index = [&](long long i, long long j, long long k) {
    return (k * n[1] + j) * n[0] + i;
  };
  auto node_pos = [&](long long i, long long j, long long k) {
    return Vector3d(lo.x() + i * spacing, lo.y() + j * spacing, lo.z() + k * spacing);
  };
  std::vector<double> value(static_cast<std::size_t>(n[0] * n[1] * n[2]));
  const double nan = std::numeric_limits<double>::quiet_NaN();
#pragma omp parallel for schedule(static)
  for (long long k = 0; k < n[2]; ++k)
    for (long long j = 0; j < n[1]; ++j)
      for (long long i = 0; i < n[0]; ++i) {
        const auto f = surface.evaluate(node_pos(i, j, k));
        value[node_index(i, j, k)] = f ? f->value : nan;
      }

  Mesh mesh;
  std::unordered_map<std::uint64_t, int> edge_vertex;
  auto vertex_on = [&](long long na, long long nb) {
    if (na > nb) std::swap(na, nb);
    const std::uint64_t k2 =
        (static_cast<std::uint64_t>(na) << 32) ^ static_cast<std::uint64_t>(nb);
    const auto it = edge_vertex.find(k2);
    if (it != edge_vertex.end()) return it->second;
    auto pos = [&](long long id) {
      const long long i = id % n[0], j = (id / n[0]) % n[1], k = id / (n[0] * n[1]);
      return node_pos(i, j, k);
    };
    const double va = value[na], vb = value[nb];
    const double t = std::clamp(va / (va - vb), 0.0, 1.0);
    mesh.positions.push_back((1 - t) * pos(na) + t * pos(nb));
    const int v = static_cast<int>(mesh.positions.size()) - 1;
    edge_vertex.emplace(k2, v);
    return v;
  };
  // Cube corner c has offsets (c & 1, c >> 1 & 1, c >> 2 & 1); tetrahedra 0 - a - a|b - 7.
  static constexpr std::array<std::array<int, 3>, 6> kPerm{
      {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}}};
  for (long long k = 0; k + 1 < n[2]; ++k)
    for (long long j = 0; j + 1 < n[1]; ++j)
      for (long long i = 0; i + 1 < n[0]; ++i) {
        std::array<long long, 8> corner{};
        for (int c = 0; c < 8; ++c)
          corner[c] = node_index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        int inside_count = 0;
        bool undefined = false;
        for (int c = 0; c < 8; ++c) {
          const double v = value[corner[c]];
          if (std::isnan(v)) undefined = true;
          inside_count += v < 0.0 ? 1 : 0;
        }
        if (undefined || inside_count == 0 || inside_count == 8) continue;
        for (const auto& p : kPerm) {
          const std::array<long long, 4> tet{corner[0], corner[p[0]], corner[p[0] | p[1]],
                                             corner[7]};
          std::array<long long, 4> in{}, out{};
          int ni = 0, no = 0;
          for (long long t : tet) (value[t] < 0.0 ? in[ni++] : out[no++]) = t;
          if (ni == 0 || no == 0) continue;
          // Each output vertex lies on a tetrahedron edge (inside node, outside node).
          std::vector<std::pair<long long, long long>> on;
          if (ni == 1) {
            for (int q = 0; q < 3; ++q) on.emplace_back(in[0], out[q]);
          } else if (no == 1) {
            for (int q = 0; q < 3; ++q) on.emplace_back(in[q], out[0]);
          } else {
            on = {{in[0], out[0]}, {in[0], out[1]}, {in[1], out[1]}, {in[1], out[0]}};
          }
          std::vector<int> poly;
          for (const auto& [x, y] : on) poly.push_back(vertex_on(x, y));
          // Orient outward from the edge midpoints, which never degenerate (the interpolated
          // points can coincide when a node value is exactly zero): the normal must point from
          // the inside corners to the outside ones.
          auto node = [&](long long id) {
            return node_pos(id % n[0], (id / n[0]) % n[1], id / (n[0] * n[1]));
          };
          std::vector<Vector3d> mid;
          Vector3d dir = Vector3d::Zero();
          for (const auto& [x, y] : on) {
            mid.push_back(0.5 * (node(x) + node(y)));
            dir += node(y) - node(x);
          }
          const Vector3d normal = mid.size() == 3
                                      ? Vector3d((mid[1] - mid[0]).cross(mid[2] - mid[0]))
                                      : Vector3d((mid[2] - mid[0]).cross(mid[3] - mid[1]));
          const bool flip = normal.dot(dir) < 0.0;
          auto emit = [&](int x, int y, int z) {
            if (flip)
              mesh.triangles.push_back({x, z, y});
            else
              mesh.triangles.push_back({x, y, z});
          };
          emit(poly[0], poly[1], poly[2]);
          if (poly.size() == 4) emit(poly[0], poly[2], poly[3]);
        }
      }
  return mesh;
}

}  // namespace scanmesh::particles
