// The meshing kernel's cell keys for sparse 3D grids (hash maps of cells): the AFT's front and
// triangle cells and the scan clean-up's neck search file their entries under these keys.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>

namespace scanmesh::kernel {

//! The cell (of side `cell`) holding p: floor(p / cell) per axis.
inline std::array<std::int64_t, 3> cell_of(const Eigen::Vector3d& p, double cell) {
  return {static_cast<std::int64_t>(std::floor(p.x() / cell)),
          static_cast<std::int64_t>(std::floor(p.y() / cell)),
          static_cast<std::int64_t>(std::floor(p.z() / cell))};
}

//! The key of cell (x, y, z): each coordinate's low 21 bits (two's complement). Cells 2^21
//! apart share a key, which only adds candidates to a query.
inline std::int64_t pack_cell(std::int64_t x, std::int64_t y, std::int64_t z) {
  return ((x & 0x1fffff) << 42) | ((y & 0x1fffff) << 21) | (z & 0x1fffff);
}

//! The key of the cell (of side `cell`) that holds p.
inline std::int64_t cell_key(const Eigen::Vector3d& p, double cell) {
  const auto c = cell_of(p, cell);
  return pack_cell(c[0], c[1], c[2]);
}

}  // namespace scanmesh::kernel
