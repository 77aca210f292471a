// The two-way sampled Hausdorff distance between an animation mesh and the continuous scan
// surface, with exact point-to-triangle-set distances (CGAL AABB trees).
//
// Why not closest-point projection: ScanSurface::project is a local Gauss-Newton search from the
// radial foot point; under the chin or behind an ear it stops in a far local minimum and the
// earlier estimate (the minimum of three such upper bounds) reported 20-35 mm on meshes that lie
// on the surface. Here the surface is represented by its grid-resolution triangulation (the
// bicubic patch deviates from it by (cell size)^2 / (8 rho), about 0.002 mm on the head), and
// every distance is the true distance to a triangle set.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <cmath>
#include <optional>

#include "aft_internal.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::aft::detail {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Triangle = Kernel::Triangle_3;
using Point = Kernel::Point_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point point(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

// The grid triangulation of the surface, the reference of both the quality report and the
// repair's deviation goal (GridSurfaceDistance), so both come from these two functions:
// grid node (i, j) lifted onto the surface, and the two triangles of the cell with corners
// a = (i, j), b = (i + 1, j), c = (i + 1, j + 1), d = (i, j + 1) (i wrapping in phi), each
// present where its three nodes are on the surface.
std::optional<Eigen::Vector3d> grid_node(const ScanSurface& s, int i, int j) {
  return s.position(s.phi0() + i * s.dphi(), s.h0() + j * s.dh());
}
template <class Emit>
void cell_triangles(const std::optional<Eigen::Vector3d>& a,
                    const std::optional<Eigen::Vector3d>& b,
                    const std::optional<Eigen::Vector3d>& c,
                    const std::optional<Eigen::Vector3d>& d, Emit&& emit) {
  if (!a || !c) return;
  if (b) emit(*a, *b, *c);
  if (d) emit(*a, *c, *d);
}

std::vector<Triangle> surface_triangles(const ScanSurface& s) {
  const int n_phi = s.n_phi(), n_h = s.n_h();
  std::vector<std::optional<Eigen::Vector3d>> node(static_cast<std::size_t>(n_phi) * n_h);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i)
      node[static_cast<std::size_t>(j) * n_phi + i] = grid_node(s, i, j);
  std::vector<Triangle> out;
  for (int j = 0; j + 1 < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      const int i1 = (i + 1) % n_phi;
      cell_triangles(node[static_cast<std::size_t>(j) * n_phi + i],
                     node[static_cast<std::size_t>(j) * n_phi + i1],
                     node[static_cast<std::size_t>(j + 1) * n_phi + i1],
                     node[static_cast<std::size_t>(j + 1) * n_phi + i],
                     [&](const auto& a, const auto& b, const auto& c) {
                       out.emplace_back(point(a), point(b), point(c));
                     });
    }
  return out;
}

}  // namespace

const std::optional<Eigen::Vector3d>& GridSurfaceDistance::node(int i, int j) const {
  const std::int64_t key = static_cast<std::int64_t>(j) * surface_.n_phi() + i;
  auto it = nodes_.find(key);
  if (it == nodes_.end()) it = nodes_.emplace(key, grid_node(surface_, i, j)).first;
  return it->second;
}

double GridSurfaceDistance::operator()(const Eigen::Vector3d& x, double radius) const {
  const ScanSurface& s = surface_;
  const Eigen::Vector3d cyl = ScanSurface::to_cylindrical(x);  // phi, h, rho
  const int n_phi = s.n_phi(), n_h = s.n_h();
  // Every triangle of a cell lies in the cell's sector and height band (a chord of the sector
  // stays in it), so the cells whose sector meets the ball's angular shadow asin(radius / rho)
  // and whose band meets [h - radius, h + radius] hold every point within `radius`.
  const double u = (cyl.x() - s.phi0()) / s.dphi();
  int i_lo = 0, n_cols = n_phi;
  if (radius < cyl.z()) {
    const double half = std::asin(radius / cyl.z()) / s.dphi();
    i_lo = static_cast<int>(std::floor(u - half));
    n_cols = std::min(n_phi, static_cast<int>(std::floor(u + half)) - i_lo + 1);
  }
  const int j_lo = std::max(0, static_cast<int>(std::floor((cyl.y() - radius - s.h0()) / s.dh())));
  const int j_hi =
      std::min(n_h - 2, static_cast<int>(std::floor((cyl.y() + radius - s.h0()) / s.dh())));
  double best = radius * radius;
  for (int j = j_lo; j <= j_hi; ++j)
    for (int c = 0; c < n_cols; ++c) {
      const int i = (((i_lo + c) % n_phi) + n_phi) % n_phi, i1 = (i + 1) % n_phi;
      cell_triangles(node(i, j), node(i1, j), node(i1, j + 1), node(i, j + 1),
                     [&](const auto& a, const auto& b, const auto& cc) {
                       best = std::min(best, point_triangle_squared_distance(x, a, b, cc));
                     });
    }
  return std::sqrt(best);
}

TwoWayDistance sampled_hausdorff(const AnimationMesh& am, const ScanSurface& surface, int samples,
                                 const RegionGraph* regions) {
  TwoWayDistance out;
  const auto& P = am.mesh.positions;
  const auto& T = am.mesh.triangles;
  if (T.empty()) return out;
  const std::vector<Triangle> reference = surface_triangles(surface);
  std::vector<Triangle> mesh;
  mesh.reserve(T.size());
  for (const auto& f : T) mesh.emplace_back(point(P[f[0]]), point(P[f[1]]), point(P[f[2]]));
  if (reference.empty()) return out;
  Tree surface_tree(reference.begin(), reference.end());
  Tree mesh_tree(mesh.begin(), mesh.end());
  surface_tree.accelerate_distance_queries();
  mesh_tree.accelerate_distance_queries();
  const int n = std::max(2, samples);
  for (std::size_t t = 0; t < T.size(); ++t) {
    const auto& f = T[t];
    // (phi, h) of the corners, unwrapped next to the first: the triangle's footprint.
    Eigen::Vector2d pa = am.params[f[0]], pb = am.params[f[1]], pc = am.params[f[2]];
    pb.x() = pa.x() + wrap_angle(pb.x() - pa.x());
    pc.x() = pa.x() + wrap_angle(pc.x() - pa.x());
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double u = double(i) / n, v = double(j) / n, w = 1 - u - v;
        const Eigen::Vector3d x = w * P[f[0]] + u * P[f[1]] + v * P[f[2]];
        out.mesh_to_surface_mm =
            std::max(out.mesh_to_surface_mm, std::sqrt(surface_tree.squared_distance(point(x))));
        // The surface over the triangle's footprint, at the mesh's own sample density.
        const Eigen::Vector2d pp = w * pa + u * pb + v * pc;
        if (const auto y = surface.position(pp.x(), pp.y()))
          out.surface_to_mesh_mm =
              std::max(out.surface_to_mesh_mm, std::sqrt(mesh_tree.squared_distance(point(*y))));
      }
  }
  if (!regions) return out;
  // And the surface over the meshed regions, whatever the mesh covers of it (a gap counts).
  const RegionLocator locate(*regions);
  for (int j = 0; j < surface.n_h(); j += 2)
    for (int i = 0; i < surface.n_phi(); i += 2) {
      const double phi = surface.phi0() + (i + 0.5) * surface.dphi();
      const double h = surface.h0() + (j + 0.5) * surface.dh();
      const auto r = locate.region_at({phi, h});
      if (!r || regions->regions[*r].opening) continue;
      if (const auto y = surface.position(phi, h))
        out.surface_to_mesh_mm =
            std::max(out.surface_to_mesh_mm, std::sqrt(mesh_tree.squared_distance(point(*y))));
    }
  return out;
}

}  // namespace scanmesh::aft::detail
