// Fuzz target: the OBJ mesh reader, parse_obj (core/mesh_io.h), with the input split at the
// first 0 byte into the OBJ text and an MTL text. A mesh it accepts must be valid.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = scanmesh::fuzz::as_text(data, size);
  const std::size_t split = text.find('\0');
  const std::string obj = text.substr(0, split);
  const std::string mtl = split == std::string::npos ? std::string() : text.substr(split + 1);
  scanmesh::ObjMesh out;
  try {
    out = scanmesh::parse_obj(obj, "fuzz.obj", mtl);
  } catch (const scanmesh::Error&) {
    return 0;
  }
  try {
    out.mesh.validate();
  } catch (const scanmesh::Error&) {
    scanmesh::fuzz::broken_promise();
  }
  return 0;
}
