// Little-endian byte encoding and CRC-32 shared by scanmesh's binary file formats (the grid file
// .smg, the surface fields file .smf; docs/formats.md).
//
// Numbers are assembled byte by byte, so the code is correct on any host byte order without a
// byte-swap branch. Readers take raw pointers: callers check lengths against the buffer first.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace scanmesh {

//! Appends little-endian numbers and raw bytes to a byte vector it does not own.
class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}
  void u8(std::uint8_t v) { out_.push_back(v); }
  void u32(std::uint32_t v) {
    for (int k = 0; k < 4; ++k) out_.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void u64(std::uint64_t v) {
    for (int k = 0; k < 8; ++k) out_.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out_.insert(out_.end(), b, b + n);
  }

 private:
  std::vector<std::uint8_t>& out_;
};

//! Little-endian reads of 4 / 8 bytes at p (p must point at enough bytes).
inline std::uint32_t read_le_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
inline std::uint64_t read_le_u64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(read_le_u32(p)) | static_cast<std::uint64_t>(read_le_u32(p + 4))
                                                          << 32;
}
inline float read_le_f32(const std::uint8_t* p) { return std::bit_cast<float>(read_le_u32(p)); }
inline double read_le_f64(const std::uint8_t* p) { return std::bit_cast<double>(read_le_u64(p)); }

//! CRC-32 (zlib `crc32`, the PNG / zip polynomial) of n bytes. Not inline: zlib is linked
//! privately into scanmesh_core only.
std::uint32_t crc32_of(const std::uint8_t* p, std::size_t n);

//! Checks a file's size and trailing CRC-32, the steps every scanmesh binary reader shares.
//! Throw FileFormatError naming `source`: "truncated: expected N bytes, file has M",
//! "trailing garbage: ...", "checksum mismatch (stored 0x..., computed 0x...): the file is
//! corrupt".
void require_file_size(std::uint64_t expected, std::size_t actual,
                       const std::filesystem::path& source);
void require_trailing_crc32(std::span<const std::uint8_t> bytes,
                            const std::filesystem::path& source);
//! Rejects n_phi x n_h grids above kMaxGridCells ("grid size A x B exceeds the limit ...").
void require_cell_limit(std::uint32_t n_phi, std::uint32_t n_h, std::uint64_t max_cells,
                        const std::filesystem::path& source);

}  // namespace scanmesh
