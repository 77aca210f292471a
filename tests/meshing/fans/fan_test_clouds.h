// Generated clouds of seed 002 §4 (no downloads): random sphere, square and hexagonal planes.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

namespace scanmesh::test {

// Uniform on the unit sphere (normalised Gaussian triples); splitmix64, deterministic.
inline std::vector<Eigen::Vector3d> random_sphere(std::size_t n, std::uint64_t seed,
                                                  double radius = 1.0) {
  std::uint64_t s = seed;
  auto next = [&s]() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * (1.0 / 9007199254740992.0);
  };
  auto gauss = [&]() {
    const double u = std::max(next(), 1e-300), v = next();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * v);
  };
  std::vector<Eigen::Vector3d> pts;
  while (pts.size() < n) {
    Eigen::Vector3d p(gauss(), gauss(), gauss());
    if (p.norm() < 1e-9) continue;
    pts.push_back(radius * p.normalized());
  }
  return pts;
}

inline std::vector<Eigen::Vector3d> square_grid(int nx, int ny, double h = 1.0) {
  std::vector<Eigen::Vector3d> pts;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) pts.emplace_back(i * h, j * h, 0.0);
  return pts;
}

// Rows offset by half a spacing, row distance sqrt(3)/2: 155 rows x 260 = 40,300 points.
inline std::vector<Eigen::Vector3d> hex_grid(int nx = 260, int ny = 155, double h = 1.0) {
  std::vector<Eigen::Vector3d> pts;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      pts.emplace_back((i + 0.5 * (j % 2)) * h, j * h * std::sqrt(3.0) / 2.0, 0.0);
  return pts;
}

}  // namespace scanmesh::test
