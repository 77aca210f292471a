// Fuzz target: the PCD point-cloud reader, parse_pcd (core/point_cloud_io.h): ASCII, binary and
// binary_compressed (LZF). An accepted unorganised cloud holds only finite points; an organised
// one holds WIDTH x HEIGHT positions with at least one finite; attributes match in length.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/point_cloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto cloud = scanmesh::parse_pcd(scanmesh::fuzz::as_text(data, size), "fuzz.pcd");
    if (cloud.has_colors() && cloud.colors.size() != cloud.size())
      scanmesh::fuzz::broken_promise();
    if (cloud.has_normals() && cloud.normals.size() != cloud.size())
      scanmesh::fuzz::broken_promise();
    if (cloud.organised()) {
      if (cloud.size() != static_cast<std::size_t>(cloud.width) * cloud.height ||
          cloud.finite_count() == 0)
        scanmesh::fuzz::broken_promise();
    } else {
      if (cloud.positions.empty()) scanmesh::fuzz::broken_promise();
      for (const auto& p : cloud.positions)
        if (!p.allFinite()) scanmesh::fuzz::broken_promise();
    }
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
