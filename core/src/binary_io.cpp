// CRC-32 and the shared size/checksum checks of the binary file formats; the only use of zlib
// outside PNG.
#include "scanmesh/core/binary_io.h"

#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

std::uint32_t crc32_of(const std::uint8_t* p, std::size_t n) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes uInt lengths; feed in chunks so files over 4 GiB would still be right.
  while (n > 0) {
    const auto chunk = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    crc = crc32(crc, p, chunk);
    p += chunk;
    n -= chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

namespace {
std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}
}  // namespace

void require_file_size(std::uint64_t expected, std::size_t actual,
                       const std::filesystem::path& source) {
  if (actual < expected)
    throw FileFormatError(source, "truncated: expected " + std::to_string(expected) +
                                      " bytes, file has " + std::to_string(actual));
  if (actual > expected)
    throw FileFormatError(source, "trailing garbage: expected " + std::to_string(expected) +
                                      " bytes, file has " + std::to_string(actual));
}

void require_trailing_crc32(std::span<const std::uint8_t> bytes,
                            const std::filesystem::path& source) {
  if (bytes.size() < 4) throw FileFormatError(source, "truncated: no room for the checksum");
  const std::size_t body = bytes.size() - 4;
  const std::uint32_t stored = read_le_u32(bytes.data() + body);
  const std::uint32_t actual = crc32_of(bytes.data(), body);
  if (stored != actual)
    throw FileFormatError(source, "checksum mismatch (stored " + hex32(stored) + ", computed " +
                                      hex32(actual) + "): the file is corrupt");
}

void require_cell_limit(std::uint32_t n_phi, std::uint32_t n_h, std::uint64_t max_cells,
                        const std::filesystem::path& source) {
  if (static_cast<std::uint64_t>(n_phi) * n_h > max_cells)
    throw FileFormatError(source, "grid size " + std::to_string(n_phi) + " x " +
                                      std::to_string(n_h) + " exceeds the limit of " +
                                      std::to_string(max_cells) + " cells");
}

}  // namespace scanmesh
