// Emulated device nodes (umockdev) answered by the simulated devices, so the real libusb and
// V4L2 backends in drivers/ run unmodified in tests. Only works in a process started under
// `umockdev-wrapper` (LD_PRELOAD of libumockdev-preload); see docs/testing.md for what is and is
// not emulated. Linked by tests and benchmarks only (target scanmesh_sim_emulated), never by the
// scanmesh binary.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "scanmesh/sim/board_firmware.h"

namespace scanmesh::sim {

class SimCamera;

//! True when this process runs under umockdev-wrapper (libumockdev-preload is active).
bool in_umockdev_environment();

//! What the emulated USB board looked like to the host (for assertions in tests).
struct EmulatedUsbBoardState {
  std::string kernel_driver;  //!< "cdc_acm", "ch341" or "ftdi_sio" (by VID:PID)
  bool kernel_driver_detached = false;
  //! The baud rate the host set: SET_LINE_CODING, or the CH34x / FTDI baud divisor decoded
  //! (the rate the bridge's UART really runs at); 0 if never set.
  double line_coding_baud = 0;
  int vendor_requests = 0;  //!< CH34x / FTDI vendor control requests accepted
  int data_bits = 0;
  bool dtr = false;
  int claimed_interfaces = 0;
  int stalls_cleared = 0;  //!< CLEAR_HALT requests seen
};

//! One umockdev testbed with the devices added to it. Create at most one per process.
class EmulatedDevices {
 public:
  EmulatedDevices();
  ~EmulatedDevices();
  EmulatedDevices(const EmulatedDevices&) = delete;
  EmulatedDevices& operator=(const EmulatedDevices&) = delete;

  //! Adds a board at bus 1, address `address`, whose usbdevfs URBs are answered by `firmware`.
  //! What it looks like follows the VID:PID: 1a86:7523/7522/5523 a WCH CH340 bridge (vendor
  //! interface, bulk OUT 0x02 / IN 0x82, driver ch341), 0403:6001/6014/6015 an FTDI FT232R
  //! (vendor interface, bulk OUT 0x02 / IN 0x81, two status bytes heading every IN packet,
  //! driver ftdi_sio), anything else CDC-ACM (interface 0: communication, interrupt EP 0x82;
  //! interface 1: data, bulk OUT 0x04 / IN 0x83, driver cdc_acm). The kernel driver is "bound"
  //! until the host detaches it. A bridge's UART talks to the firmware at 115200 baud: until
  //! the host sets the bridge's baud within 3 % of that, every byte either way arrives garbled,
  //! as on a real wire; unknown vendor requests stall (EPIPE).
  void add_usb_board(std::shared_ptr<SimBoardFirmware> firmware, std::uint16_t vendor_id = 0x2341,
                     std::uint16_t product_id = 0x0043, int address = 2);
  EmulatedUsbBoardState usb_board_state() const;

  //! Adds /dev/videoN (a UVC-like capture node) whose V4L2 ioctls are answered by `camera`.
  //! Returns the device path.
  std::string add_camera(std::shared_ptr<SimCamera> camera, int index = 0);
  //! The value the host last set for V4L2 control `id` on the first camera, if it set one.
  std::optional<int> camera_control(std::uint32_t id) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace scanmesh::sim
