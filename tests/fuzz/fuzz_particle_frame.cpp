// Fuzz target: the particle frame reader read_ply_ids (meshing/particles/particles.h), which
// reads the vertex ids of a `scanmesh particles` frame PLY. It takes a path, so the bytes go
// through a scratch file.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <system_error>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/particles/particles.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = scanmesh::fuzz::scratch_file(data, size, ".ply");
  try {
    (void)scanmesh::particles::read_ply_ids(path);
  } catch (const scanmesh::Error&) {
  }
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
  return 0;
}
