// libFuzzer entry point: the calibration YAML reader (docs/formats.md, "Calibration files").
#include <cstddef>
#include <cstdint>
#include <string>

#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/core/errors.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const scanmesh::Calibration c = scanmesh::Calibration::from_yaml_text(text, "fuzz.yaml");
    (void)c.to_yaml();
    (void)c.rig_from_camera();
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
