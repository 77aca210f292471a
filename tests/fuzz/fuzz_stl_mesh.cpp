// Fuzz target: the STL mesh reader, parse_stl (core/mesh_io.h), binary and ASCII. A mesh it
// accepts must be valid and have no face with a repeated corner.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  scanmesh::Mesh mesh;
  try {
    mesh = scanmesh::parse_stl({data, size}, "fuzz.stl");
  } catch (const scanmesh::Error&) {
    return 0;
  }
  try {
    mesh.validate();
  } catch (const scanmesh::Error&) {
    scanmesh::fuzz::broken_promise();
  }
  for (const auto& t : mesh.triangles)
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) scanmesh::fuzz::broken_promise();
  return 0;
}
