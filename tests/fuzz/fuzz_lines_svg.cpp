// libFuzzer entry point: the animation-mesh lines svg parser and, for small line sets, the
// surface checks and region analysis behind it (docs/animation-meshes.md).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_region_analysis.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/animation_lines.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    scanmesh::fuzz::analyse_lines(scanmesh::aft::parse_lines_svg(text, "fuzz.svg"));
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
