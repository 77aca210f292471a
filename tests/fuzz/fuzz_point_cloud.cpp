// Fuzz target: read_point_cloud (core/point_cloud_io.h), the fan mesher's way in, which
// dispatches on the extension to the PLY, PCD, XYZ and grid (.smg valid cells) readers. The
// first byte picks the extension; the rest is the file (through a scratch file, as the reader
// takes a path). Accepted clouds must have a finite point, and unorganised ones only finite points.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <system_error>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/point_cloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[] = {".ply", ".pcd", ".xyz", ".smg", ".txt", ".pts"};
  const std::string extension = kExtensions[data[0] % 6];
  const std::filesystem::path path = scanmesh::fuzz::scratch_file(data + 1, size - 1, extension);
  try {
    const auto points = scanmesh::read_point_cloud(path);
    if (points.finite_count() == 0) scanmesh::fuzz::broken_promise();
    if (!points.organised())
      for (const auto& p : points.positions)
        if (!p.allFinite()) scanmesh::fuzz::broken_promise();
  } catch (const scanmesh::Error&) {
  }
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
  return 0;
}
