// Fuzz target: the PCD point-cloud reader of the fan mesher, parse_pcd
// (meshing/fans/point_cloud_io.h), ASCII and binary. Accepted points must be finite.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/fans/point_cloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto points = scanmesh::parse_pcd(scanmesh::fuzz::as_text(data, size), "fuzz.pcd");
    for (const auto& p : points)
      if (!p.allFinite()) scanmesh::fuzz::broken_promise();
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
