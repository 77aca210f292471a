// libFuzzer entry point: the session manifest parser. The input is session.json, a NUL byte,
// then steps.jsonl (no NUL: everything is session.json and steps.jsonl is empty).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scanmesh/acquisition/session.h"
#include "scanmesh/core/errors.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto nul = bytes.find('\0');
  const std::string_view header = bytes.substr(0, nul);
  const std::string_view steps =
      nul == std::string_view::npos ? std::string_view() : bytes.substr(nul + 1);
  try {
    (void)scanmesh::parse_session_manifest(header, steps, "fuzz");
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
