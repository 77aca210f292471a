// libusb-1.0 transport: the board's USB interface spoken to directly with bulk transfers, after
// detaching the kernel driver (cdc_acm, ch341, ftdi_sio). For CDC-ACM devices the line coding is
// set with the class request SET_LINE_CODING (USB CDC PSTN 1.2 §6.3.10) and DTR/RTS raised with
// SET_CONTROL_LINE_STATE; the USB-serial bridges CH340/CH341 and FTDI FT232 are set up with
// their vendor requests (baud divisor, 8N1, DTR/RTS), chosen by VID:PID (docs/hardware.md).
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

//! How the line is set up: CDC-ACM class requests or a bridge's vendor requests.
enum class UsbBridge { CdcAcm, Ch34x, Ftdi };
//! 1a86:7523/7522/5523 -> Ch34x; 0403:6001/6014/6015 -> Ftdi; anything else CdcAcm.
UsbBridge usb_bridge_of(std::uint16_t vid, std::uint16_t pid);

//! CH34x baud register pair value (WRITE_REG 0x1312): divisor byte (0x100 - div) << 8, bit 2 the
//! clock factor, bits 0-1 the prescaler; the closest rate to `baud` of 48 MHz /
//! (2^(12 - 3 ps - fact) * div). Throws InvalidInputError outside 50..2000000.
std::uint16_t ch34x_baud_register(int baud);
//! FT232 (BM/R/X) SET_BAUD_RATE divisor of 3 MHz in eighths: bits 0-13 whole part, bits 14-16
//! the eighths code; the low 16 bits go to wValue, the rest to wIndex. Throws InvalidInputError
//! outside 183..3000000.
std::uint32_t ftdi_baud_divisor(int baud);

//! USB devices that look like boards. Empty (not an error) without USB access.
std::vector<UsbBoardInfo> list_usb_boards();

//! Parses "VID:PID" or "usb:BUS:ADDR" (as printed by `scanmesh devices`). Throws
//! InvalidInputError for anything else.
UsbSerialOptions parse_usb_board_spec(const std::string& spec);

//! Opens the first matching device. Throws DeviceError: not found, access denied (udev rule),
//! busy (another program claimed it), unplugged (LIBUSB_ERROR_NO_DEVICE).
std::unique_ptr<Transport> open_usb_transport(const UsbSerialOptions& options);

}  // namespace scanmesh::drivers
