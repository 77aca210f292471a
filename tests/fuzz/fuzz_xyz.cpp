// Fuzz target: the XYZ text point-cloud reader, parse_xyz (core/point_cloud_io.h).
// Accepted points must be finite.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/point_cloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto points = scanmesh::parse_xyz(scanmesh::fuzz::as_text(data, size), "fuzz.xyz");
    for (const auto& p : points.positions)
      if (!p.allFinite()) scanmesh::fuzz::broken_promise();
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
