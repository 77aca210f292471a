// Fuzz target: the surface fields file (.smf) reader, decode_fields
// (reconstruction/fields_file.h).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/fields_file.h"

namespace {

void decode(std::span<const std::uint8_t> bytes) {
  try {
    const scanmesh::SurfaceFields f = scanmesh::decode_fields(bytes, "fuzz.smf");
    if (static_cast<std::size_t>(f.n_phi) * static_cast<std::size_t>(f.n_h) != f.size())
      scanmesh::fuzz::broken_promise();
  } catch (const scanmesh::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  decode({data, size});
  decode(scanmesh::fuzz::with_valid_crc({data, size}));
  return 0;
}
