// CRC-32 for the binary file formats; the only use of zlib outside PNG.
#include "scanmesh/core/binary_io.h"

#include <zlib.h>

#include <algorithm>

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

}  // namespace scanmesh
