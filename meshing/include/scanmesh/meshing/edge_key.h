// 64-bit keys of mesh edges for hash sets and sorted lists, shared by every mesher.
#pragma once

#include <cstdint>

namespace scanmesh {

//! Key of the directed edge a -> b (a in the high 32 bits): a front edge, a half-edge.
inline std::uint64_t directed_edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

//! Key of the undirected edge {a, b}: the smaller index in the high 32 bits, so sorting the
//! keys sorts the edges by their smaller, then their larger end (for indices >= 0).
inline std::uint64_t edge_key(int a, int b) {
  return a < b ? directed_edge_key(a, b) : directed_edge_key(b, a);
}

//! The high (first) and low (second) index of a key.
inline int edge_key_first(std::uint64_t k) { return static_cast<int>(k >> 32); }
inline int edge_key_second(std::uint64_t k) { return static_cast<int>(k & 0xffffffffu); }

}  // namespace scanmesh
