// libFuzzer entry point: the simulated turntable rig YAML reader (docs/formats.md,
// "Turntable rig files").
#include <cstddef>
#include <cstdint>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/sim/turntable_camera.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const scanmesh::sim::RigConfig r = scanmesh::sim::RigConfig::from_yaml_text(text, "fuzz.yaml");
    (void)r.to_yaml();
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
