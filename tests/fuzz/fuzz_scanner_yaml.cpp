// Fuzz target: the simulated scanner's YAML reader, ScannerConfig::from_yaml_text
// (sim/range_scanner.h). An accepted configuration must pass its own validation.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/range_scanner.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  scanmesh::sim::ScannerConfig config;
  try {
    config = scanmesh::sim::ScannerConfig::from_yaml_text(scanmesh::fuzz::as_text(data, size),
                                                          "fuzz.yaml");
  } catch (const scanmesh::Error&) {
    return 0;
  }
  try {
    config.validate();
  } catch (const scanmesh::Error&) {
    scanmesh::fuzz::broken_promise();
  }
  return 0;
}
