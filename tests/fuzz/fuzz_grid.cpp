// Fuzz target: the native range grid file (.smg) reader, decode_grid (core/grid_file.h).
// Also checks that any grid it accepts survives encode -> decode unchanged.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"

namespace {

void decode_and_round_trip(std::span<const std::uint8_t> bytes) {
  using namespace scanmesh;
  try {
    const RangeGrid grid = decode_grid(bytes, "fuzz.smg");
    const std::vector<std::uint8_t> encoded = encode_grid(grid);
    const RangeGrid again = decode_grid(encoded, "fuzz re-encoded.smg");
    if (encode_grid(again) != encoded) fuzz::broken_promise();
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  decode_and_round_trip({data, size});
  decode_and_round_trip(scanmesh::fuzz::with_valid_crc({data, size}));
  return 0;
}
