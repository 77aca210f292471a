// Byte transports to the turntable board: the protocol layer (board.h) speaks lines of text over
// any of them. Two real backends: termios for boards the kernel already exposes as
// /dev/ttyUSB* or /dev/ttyACM* (serial_transport.h), and libusb-1.0 for CDC-ACM boards and
// USB-serial bridges spoken to directly (usb_transport.h).
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace scanmesh::drivers {

class Transport {
 public:
  virtual ~Transport() = default;
  //! Writes all bytes. Throws DeviceError naming the device if it vanished or stalls.
  virtual void write(std::string_view bytes) = 0;
  //! Next line without its "\r\n"/"\n", or nullopt if none completed within `timeout`.
  //! Throws DeviceError if the device vanished ("unplugged") or the endpoint stalled.
  virtual std::optional<std::string> read_line(std::chrono::milliseconds timeout) = 0;
  //! Discards bytes already received but not yet read (before a retry).
  virtual void discard_input() = 0;
  virtual void close() = 0;
  //! The device as the user would name it: "/dev/ttyACM0" or "usb 001:004 (2341:0043)".
  virtual std::string name() const = 0;
};

//! Splits a byte stream into lines; shared by the transports that read raw chunks.
class LineBuffer {
 public:
  void append(std::string_view bytes) { pending_.append(bytes); }
  //! Pops one complete line (without "\r\n"), if there is one.
  std::optional<std::string> pop_line();
  void clear() { pending_.clear(); }
  std::size_t size() const { return pending_.size(); }

 private:
  std::string pending_;
};

}  // namespace scanmesh::drivers
