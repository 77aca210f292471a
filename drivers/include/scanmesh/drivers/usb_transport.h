// libusb-1.0 transport: the board's USB interface spoken to directly with bulk transfers, after
// detaching the kernel driver (cdc_acm, ch341, ftdi_sio). For CDC-ACM devices the line coding is
// set with the class request SET_LINE_CODING (USB CDC PSTN 1.2 §6.3.10) and DTR/RTS raised with
// SET_CONTROL_LINE_STATE; bridges with vendor protocols (CH340, FTDI) are opened with their data
// endpoints only (see docs/hardware.md).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/drivers/transport.h"

namespace scanmesh::drivers {

struct UsbSerialOptions {
  std::uint16_t vendor_id = 0;  //!< 0: any known board
  std::uint16_t product_id = 0;
  int bus = -1, address = -1;  //!< -1: any
  int baud = 115200;
};

//! A USB device that looks like a scanner board (known VID:PID or CDC-ACM class).
struct UsbBoardInfo {
  int bus = 0, address = 0;
  std::uint16_t vendor_id = 0, product_id = 0;
  std::string kind;  //!< "CDC-ACM", "CH340", "FTDI", "Arduino"
};

//! What a VID:PID/class pair is known as, or nullopt for an unrelated device.
std::optional<std::string> known_board_kind(std::uint16_t vid, std::uint16_t pid,
                                            std::uint8_t device_class, bool has_cdc_interface);

//! USB devices that look like boards. Empty (not an error) without USB access.
std::vector<UsbBoardInfo> list_usb_boards();

//! Parses "VID:PID" or "usb:BUS:ADDR" (as printed by `scanmesh devices`). Throws
//! InvalidInputError for anything else.
UsbSerialOptions parse_usb_board_spec(const std::string& spec);

//! Opens the first matching device. Throws DeviceError: not found, access denied (udev rule),
//! busy (another program claimed it), unplugged (LIBUSB_ERROR_NO_DEVICE).
std::unique_ptr<Transport> open_usb_transport(const UsbSerialOptions& options);

}  // namespace scanmesh::drivers
