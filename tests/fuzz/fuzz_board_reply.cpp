// libFuzzer entry point: the board-reply parser (Horus dialect) and the line splitter the
// transports feed it through.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/board.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    scanmesh::drivers::LineBuffer lines;
    lines.append(bytes);
    const auto dialect = scanmesh::drivers::make_horus_dialect();
    while (auto line = lines.pop_line()) {
      const auto reply = scanmesh::drivers::parse_horus_reply(*line);
      (void)dialect->version_supported(reply);
    }
    (void)scanmesh::drivers::parse_horus_reply(bytes);
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
