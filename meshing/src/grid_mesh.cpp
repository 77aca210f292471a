#include "scanmesh/meshing/grid_mesh.h"

#include <algorithm>
#include <array>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

constexpr int kNoVertex = -1;

// Texture coordinate of cell column `column` (unwrapped: column n_phi is column 0 seen from the
// seam, u > 1, so the seam triangles do not stretch across the whole texture) and row j. OBJ's
// v runs up from the bottom of the image, and the texture is upright (highest h at the top,
// core/texture_layout.h), so v grows with h.
Eigen::Vector2f texcoord(int column, int j, const RangeGrid& grid) {
  return {static_cast<float>((column + 0.5) / grid.n_phi()),
          static_cast<float>((j + 0.5) / grid.n_h())};
}

bool depth_jump(const RangeGrid& grid, const std::array<std::size_t, 4>& cells, double limit) {
  const auto& r = grid.radii();
  const auto [lo, hi] = std::minmax({r[cells[0]], r[cells[1]], r[cells[2]], r[cells[3]]});
  return hi - lo > limit;
}

class GridMesher {
 public:
  GridMesher(const RangeGrid& grid, const GridMeshOptions& options)
      : grid_(grid), options_(options), vertex_of_cell_(grid.cell_count(), kNoVertex) {
    if (options.with_texcoords)
      texcoord_of_column_.assign(static_cast<std::size_t>(grid.n_phi() + 1) * grid.n_h(),
                                 kNoVertex);
  }

  GridMesh run() {
    const int last_column = options_.close_seam ? grid_.n_phi() : grid_.n_phi() - 1;
    for (int j = 0; j + 1 < grid_.n_h(); ++j)
      for (int i = 0; i < last_column; ++i) mesh_quad(i, j);
    result_.mesh.compute_vertex_normals();
    return std::move(result_);
  }

 private:
  void mesh_quad(int i, int j) {
    const int i1 = grid_.wrap_phi(i + 1);
    // Corners counter-clockwise seen from outside: +phi first, then +h.
    const std::array<std::size_t, 4> cells = {grid_.index(i, j), grid_.index(i1, j),
                                              grid_.index(i1, j + 1), grid_.index(i, j + 1)};
    const auto& valid = grid_.validity();
    if (!valid[cells[0]] || !valid[cells[1]] || !valid[cells[2]] || !valid[cells[3]]) {
      ++result_.quads_skipped_for_holes;
      return;
    }
    if (depth_jump(grid_, cells, options_.max_depth_jump_mm)) {
      ++result_.quads_skipped_for_depth_jumps;
      return;
    }
    const std::array<int, 4> columns = {i, i + 1, i + 1, i};
    const std::array<int, 4> rows = {j, j, j + 1, j + 1};
    std::array<int, 4> v{}, t{};
    for (int k = 0; k < 4; ++k) {
      v[k] = vertex(cells[k]);
      if (options_.with_texcoords) t[k] = texcoord_index(columns[k], rows[k]);
    }
    const auto& p = result_.mesh.positions;
    const bool split_02 = (p[v[0]] - p[v[2]]).squaredNorm() <= (p[v[1]] - p[v[3]]).squaredNorm();
    const std::array<std::array<int, 3>, 2> corners =
        split_02 ? std::array<std::array<int, 3>, 2>{{{0, 1, 2}, {0, 2, 3}}}
                 : std::array<std::array<int, 3>, 2>{{{0, 1, 3}, {1, 2, 3}}};
    for (const auto& c : corners) {
      result_.mesh.triangles.push_back({v[c[0]], v[c[1]], v[c[2]]});
      if (options_.with_texcoords)
        result_.mesh.face_texcoords.push_back({t[c[0]], t[c[1]], t[c[2]]});
    }
    ++result_.quads_meshed;
  }

  int vertex(std::size_t cell) {
    int& v = vertex_of_cell_[cell];
    if (v != kNoVertex) return v;
    v = static_cast<int>(result_.mesh.positions.size());
    const int i = static_cast<int>(cell % grid_.n_phi());
    const int j = static_cast<int>(cell / grid_.n_phi());
    result_.mesh.positions.push_back(grid_.cartesian(i, j));
    if (options_.with_colors) result_.mesh.colors.push_back(grid_.colors()[cell]);
    result_.vertex_cell.push_back(cell);
    return v;
  }

  int texcoord_index(int column, int j) {
    int& t = texcoord_of_column_[static_cast<std::size_t>(j) * (grid_.n_phi() + 1) + column];
    if (t != kNoVertex) return t;
    t = static_cast<int>(result_.mesh.texcoords.size());
    result_.mesh.texcoords.push_back(texcoord(column, j, grid_));
    return t;
  }

  const RangeGrid& grid_;
  const GridMeshOptions& options_;
  std::vector<int> vertex_of_cell_;
  std::vector<int> texcoord_of_column_;
  GridMesh result_;
};

}  // namespace

GridMesh grid_mesh(const RangeGrid& grid, const GridMeshOptions& options) {
  if (!(options.max_depth_jump_mm > 0.0))
    throw InvalidInputError("grid mesh: max depth jump must be positive, got " +
                            std::to_string(options.max_depth_jump_mm) + " mm");
  return GridMesher(grid, options).run();
}

}  // namespace scanmesh
