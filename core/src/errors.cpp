// Shared helpers of scanmesh's error messages.
#include "scanmesh/core/errors.h"

#include <cstdio>

namespace scanmesh {

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

}  // namespace scanmesh
