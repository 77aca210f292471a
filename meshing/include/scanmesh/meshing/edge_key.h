// 64-bit keys of mesh edges for hash sets and sorted lists, shared by every mesher.
#pragma once

#include <cstdint>

namespace scanmesh {

//! Key of the undirected edge {a, b}: the smaller index in the high 32 bits, so sorting the
//! keys sorts the edges by their smaller, then their larger end. Indices must be >= 0.
inline std::uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<std::uint64_t>(a < b ? a : b);
  const auto hi = static_cast<std::uint64_t>(a < b ? b : a);
  return (lo << 32) | hi;
}

//! Key of the directed edge a -> b (a in the high 32 bits): a front edge, a half-edge.
inline std::uint64_t directed_edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

//! The high (first) and low (second) index of a key.
inline int edge_key_first(std::uint64_t k) { return static_cast<int>(k >> 32); }
inline int edge_key_second(std::uint64_t k) { return static_cast<int>(k & 0xffffffffu); }

}  // namespace scanmesh
