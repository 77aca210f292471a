// Fuzz target: the OFF mesh reader, parse_off (core/mesh_io.h). A mesh it accepts must be valid
// (finite positions, face indices in range, matching attribute counts).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  scanmesh::Mesh mesh;
  try {
    mesh = scanmesh::parse_off(scanmesh::fuzz::as_text(data, size), "fuzz.off");
  } catch (const scanmesh::Error&) {
    return 0;
  }
  try {
    mesh.validate();
  } catch (const scanmesh::Error&) {
    scanmesh::fuzz::broken_promise();
  }
  return 0;
}
