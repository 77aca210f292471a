// libFuzzer entry point: the feature-lines text parser of `scanmesh remesh --features`.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/remeshing/feature_skeleton.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto lines = scanmesh::remeshing::parse_feature_lines(text, "fuzz");
    (void)scanmesh::remeshing::format_feature_lines(lines);
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
