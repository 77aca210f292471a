// The meshing kernel's static triangle index (issue 28): each triangle filed under every cell
// of a uniform grid that its bounding box overlaps, the cells dense and filled by one counting
// sort (a hash map of vectors was 40 % of the self-intersection check at a quarter of the
// sample units). The self-intersection broad phase (mesh_check.cpp) and the remesh report's
// nearest-triangle distances (remesh_quality.cpp) use it, each with its own cell size.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

namespace scanmesh::kernel {

class TriangleGrid {
 public:
  //! Where the grid lies: cell (x, y, z) spans origin + cell * [x, x + 1) etc.; points outside
  //! fall into the border cells.
  struct Layout {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    double cell = 1;
    std::array<long long, 3> dims{1, 1, 1};
  };
  using Cell = std::array<long long, 3>;

  //! Files triangle f, with box [lo[f], hi[f]], under every cell the box overlaps, unless
  //! `skip` is given and skip[f] is set. Each cell lists its triangles in increasing order.
  TriangleGrid(const Layout& layout, std::span<const Eigen::Vector3d> lo,
               std::span<const Eigen::Vector3d> hi, const std::vector<char>* skip = nullptr)
      : layout_(layout) {
    const std::size_t n_cells = cells();
    start_.assign(n_cells + 1, 0);
    const auto files = [&](std::size_t f) { return !skip || !(*skip)[f]; };
    for (std::size_t f = 0; f < lo.size(); ++f)
      if (files(f)) for_cells_of_box(lo[f], hi[f], [&](std::size_t k) { ++start_[k + 1]; });
    for (std::size_t k = 0; k < n_cells; ++k) start_[k + 1] += start_[k];
    members_.resize(start_[n_cells]);
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t f = 0; f < lo.size(); ++f)
      if (files(f))
        for_cells_of_box(lo[f], hi[f],
                         [&](std::size_t k) { members_[fill[k]++] = static_cast<int>(f); });
  }

  const Layout& layout() const { return layout_; }
  std::size_t cells() const {
    return static_cast<std::size_t>(layout_.dims[0] * layout_.dims[1] * layout_.dims[2]);
  }
  //! The cell holding p (clamped to the grid).
  Cell cell_of(const Eigen::Vector3d& p) const {
    Cell c{};
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp<long long>(
          static_cast<long long>(std::floor((p[a] - layout_.origin[a]) / layout_.cell)), 0,
          layout_.dims[a] - 1);
    return c;
  }
  std::size_t flat(long long x, long long y, long long z) const {
    return static_cast<std::size_t>((z * layout_.dims[1] + y) * layout_.dims[0] + x);
  }
  std::size_t flat(const Cell& c) const { return flat(c[0], c[1], c[2]); }
  //! The triangles filed under cell k, in increasing order.
  std::span<const int> triangles_in(std::size_t k) const {
    return {members_.data() + start_[k], start_[k + 1] - start_[k]};
  }
  //! Calls visit(k) for every cell the box [lo, hi] overlaps.
  template <class Visit>
  void for_cells_of_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Visit&& visit) const {
    const Cell a = cell_of(lo), b = cell_of(hi);
    for (long long z = a[2]; z <= b[2]; ++z)
      for (long long y = a[1]; y <= b[1]; ++y)
        for (long long x = a[0]; x <= b[0]; ++x) visit(flat(x, y, z));
  }

 private:
  Layout layout_;
  std::vector<std::size_t> start_;
  std::vector<int> members_;
};

}  // namespace scanmesh::kernel
