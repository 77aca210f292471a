// A consumer of the installed scanmesh package (core + meshing only): meshes a point cloud of a
// sphere with the seed 002 fans, writes it with core's PLY writer, reads it back with read_mesh
// and checks it with the mesh checker. Exit code 0 when every check holds, 1 otherwise.
// Usage: scanmesh_consumer WORK_DIR
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <vector>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/meshing/fans/fans.h"
#include "scanmesh/meshing/mesh_check.h"

namespace {

constexpr double kPi = 3.14159265358979323846;

//! n points uniformly distributed on the sphere of the given radius (deterministic: a fixed
//! splitmix64 sequence, the same cloud on every machine).
std::vector<Eigen::Vector3d> sphere_cloud(std::size_t n, double radius) {
  std::uint64_t state = 29;
  auto uniform = [&state]() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * (1.0 / 9007199254740992.0);
  };
  std::vector<Eigen::Vector3d> points;
  points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    // Archimedes: z uniform in [-1, 1] and an azimuth uniform in [0, 2 pi) are uniform on the
    // sphere.
    const double z = 2.0 * uniform() - 1.0, phi = 2.0 * kPi * uniform();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    points.emplace_back(radius * r * std::cos(phi), radius * r * std::sin(phi), radius * z);
  }
  return points;
}

int failures = 0;

void check(bool ok, const char* what) {
  std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what);
  if (!ok) ++failures;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: scanmesh_consumer WORK_DIR\n");
    return 2;
  }
  try {
    const std::filesystem::path work = argv[1];
    std::filesystem::create_directories(work);
    constexpr std::size_t kPoints = 3000;
    constexpr double kRadius = 50.0;

    const scanmesh::FanResult fans = scanmesh::build_fans(sphere_cloud(kPoints, kRadius));
    const std::filesystem::path ply = work / "sphere.ply";
    scanmesh::write_ply(ply, fans.mesh);
    const scanmesh::Mesh mesh = scanmesh::read_mesh(ply);
    const scanmesh::MeshCheckReport report = scanmesh::check_mesh(mesh);
    std::printf("%s", report.to_text().c_str());

    check(mesh.vertex_count() == kPoints, "every point is a vertex after the PLY round trip");
    // A closed genus-0 triangulation of V vertices has F = 2V - 4 faces and Euler number 2.
    check(mesh.face_count() == 2 * kPoints - 4, "F = 2V - 4");
    check(report.topology.euler_characteristic == 2, "Euler characteristic 2");
    check(report.topology.boundary_loops == 0, "no boundary loop");
    check(report.self_intersections_checked && report.defect_free(),
          "manifold, no duplicate, degenerate or intersecting face");
    check(report.topology.inconsistent_edges == 0, "consistently oriented");
    for (const scanmesh::PropertyVerdict& v : scanmesh::mesh_verdicts(report)) {
      if (v.property == scanmesh::MeshProperty::Closed)
        check(v.known && v.holds, "the checker's verdict: closed");
    }

    double area = 0.0, max_radius_error = 0.0;
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector3d& a = mesh.positions[t[0]];
      area += 0.5 * (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).norm();
    }
    for (const Eigen::Vector3d& p : mesh.positions)
      max_radius_error = std::max(max_radius_error, std::abs(p.norm() - kRadius));
    const double sphere_area = 4.0 * kPi * kRadius * kRadius;
    std::printf("area %.1f (sphere %.1f), max |r - R| %.2g\n", area, sphere_area, max_radius_error);
    // Inscribed triangles lose area: 0.2 % with these ~6000 faces on R = 50; 1 % allows for
    // the random spacing.
    check(area < sphere_area && area > 0.99 * sphere_area, "area within 1 % below 4 pi R^2");
    check(max_radius_error < 1e-4, "vertices on the sphere (float PLY)");
  } catch (const scanmesh::Error& e) {
    std::fprintf(stderr, "scanmesh error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  std::printf("%s\n", failures == 0 ? "consumer: all checks passed" : "consumer: FAILED");
  return failures == 0 ? 0 : 1;
}
