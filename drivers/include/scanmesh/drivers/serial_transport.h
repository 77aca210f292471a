// termios transport: a board the kernel exposes as a tty (/dev/ttyUSB*, /dev/ttyACM*, or a pty
// in tests). Raw mode, 8N1, no flow control, the given baud rate.
#pragma once

#include <memory>
#include <string>

#include "scanmesh/drivers/transport.h"

namespace scanmesh::drivers {

//! Opens `path` in raw 8N1 mode at `baud` (one of the standard rates; 115200 for Horus).
//! Throws DeviceError naming the path: missing node, permission (see docs/hardware.md for the
//! udev rule), busy, or a baud rate termios does not know.
std::unique_ptr<Transport> open_serial_transport(const std::string& path, int baud = 115200);

}  // namespace scanmesh::drivers
