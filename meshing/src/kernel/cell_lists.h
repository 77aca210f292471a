// The meshing kernel's sparse 3D grid: cell keys and lists of indices by key. The AFT's front,
// node and triangle cells and the scan clean-up's neck search file their entries here (the
// dense, static grids are point_grid.h and triangle_grid.h).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

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

//! Lists of indices by cell key (keys >= 0): open addressing with linear probing in a
//! power-of-two table. The advancing front looks up ~65 cells around every front edge, most of
//! them empty; with std::unordered_map (a modulo by a prime and a node per entry) these
//! look-ups were ~8 % of the mesher's time at a quarter of the sample units. Entries are
//! removed only all at once (clear(), which keeps the memory for the next round).
class CellLists {
 public:
  CellLists() : keys_(64, kEmpty), slot_(64, -1) {}
  //! The list of `key`, created empty if absent.
  std::vector<int>& operator[](std::int64_t key) {
    std::size_t i = home(key);
    for (; keys_[i] != kEmpty; i = (i + 1) & mask())
      if (keys_[i] == key) return lists_[slot_[i]];
    if (2 * (used_ + 1) > keys_.size()) {
      grow();
      return (*this)[key];
    }
    keys_[i] = key;
    slot_[i] = static_cast<int>(used_);
    if (used_ == lists_.size()) lists_.emplace_back();
    return lists_[used_++];
  }
  //! The list of `key`, or nullptr.
  std::vector<int>* find(std::int64_t key) {
    return const_cast<std::vector<int>*>(std::as_const(*this).find(key));
  }
  const std::vector<int>* find(std::int64_t key) const {
    for (std::size_t i = home(key); keys_[i] != kEmpty; i = (i + 1) & mask())
      if (keys_[i] == key) return &lists_[slot_[i]];
    return nullptr;
  }
  //! Every list in the order of creation (a list may be empty).
  std::span<const std::vector<int>> lists() const { return {lists_.data(), used_}; }
  //! Removes every key; the lists' memory is reused.
  void clear() {
    std::fill(keys_.begin(), keys_.end(), kEmpty);
    for (std::size_t k = 0; k < used_; ++k) lists_[k].clear();
    used_ = 0;
  }

 private:
  static constexpr std::int64_t kEmpty = -1;
  std::size_t mask() const { return keys_.size() - 1; }
  // Fibonacci hashing: the top bits of the product depend on every bit of the key. (Bits from
  // 32 up, masked, ignored the x coordinate packed at bit 42 in tables under 1024 slots: cells
  // differing only in x collided, and probe runs were most of the front search's time.)
  std::size_t home(std::int64_t key) const {
    return static_cast<std::size_t>((static_cast<std::uint64_t>(key) * 0x9E3779B97F4A7C15ull) >>
                                    shift_);
  }
  void grow() {
    std::vector<std::int64_t> keys(2 * keys_.size(), kEmpty);
    std::vector<int> slot(keys.size(), -1);
    --shift_;
    keys_.swap(keys);
    slot_.swap(slot);
    for (std::size_t j = 0; j < keys.size(); ++j) {
      if (keys[j] == kEmpty) continue;
      std::size_t i = home(keys[j]);
      while (keys_[i] != kEmpty) i = (i + 1) & mask();
      keys_[i] = keys[j];
      slot_[i] = slot[j];
    }
  }
  std::vector<std::int64_t> keys_;
  std::vector<int> slot_;  // index into lists_
  int shift_ = 64 - 6;     // 64 - log2(keys_.size())
  std::vector<std::vector<int>> lists_;
  std::size_t used_ = 0;  // lists_[0, used_) are in use
};

}  // namespace scanmesh::kernel
