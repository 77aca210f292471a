// libFuzzer entry point: the animation-mesh region settings parser (docs/animation-meshes.md).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/regions.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    scanmesh::aft::parse_region_settings(text, "fuzz.yaml");
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
