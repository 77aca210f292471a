// Fuzz target: the PNG reader, decode_png (core/image.h, libpng's simplified API).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const scanmesh::Image8 image = scanmesh::decode_png({data, size}, "fuzz.png");
    if (image.pixels.size() != static_cast<std::size_t>(image.width) *
                                   static_cast<std::size_t>(image.height) *
                                   static_cast<std::size_t>(image.channels))
      scanmesh::fuzz::broken_promise();
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
