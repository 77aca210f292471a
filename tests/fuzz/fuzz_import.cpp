// Fuzz target: import_scan (acquisition/scan_import.h), the whole way from another scanner's
// file to a grid: the first byte picks the format (.xyz .ply .pcd .off .obj .stl), the rest is the
// file. An accepted import gives a grid with at least one valid cell, finite positive radii and
// confidences in (0, 1], and a coverage that counts at most every column. (VTK files go through
// VTK's own readers, which are not scanmesh's to fuzz.)
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <system_error>

#include "fuzz_support.h"
#include "scanmesh/acquisition/scan_import.h"
#include "scanmesh/core/errors.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[] = {".xyz", ".ply", ".pcd", ".off", ".obj", ".stl"};
  const std::filesystem::path path =
      scanmesh::fuzz::scratch_file(data + 1, size - 1, kExtensions[data[0] % 6]);
  try {
    scanmesh::ImportOptions options;
    options.n_phi = 64;  // bounded work per input; the automatic resolution is tested elsewhere
    options.n_h = 64;
    const scanmesh::ImportResult r = scanmesh::import_scan(path, options);
    const scanmesh::RangeGrid& g = r.grid;
    if (g.valid_count() == 0) scanmesh::fuzz::broken_promise();
    for (int j = 0; j < g.n_h(); ++j)
      for (int i = 0; i < g.n_phi(); ++i)
        if (g.valid(i, j) && (!std::isfinite(g.radius(i, j)) || !(g.radius(i, j) > 0) ||
                              !(g.confidence(i, j) > 0) || g.confidence(i, j) > 1))
          scanmesh::fuzz::broken_promise();
    if (r.report.coverage.covered_columns > g.n_phi()) scanmesh::fuzz::broken_promise();
  } catch (const scanmesh::Error&) {
  }
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
  return 0;
}
