// Fuzz target: the simulator's scene YAML reader, Scene::from_yaml_text (sim/scene.h).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const scanmesh::sim::Scene scene =
        scanmesh::sim::Scene::from_yaml_text(scanmesh::fuzz::as_text(data, size), "fuzz.yaml");
    (void)scene.bounds();
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
