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
  bool kernel_driver_detached = false;
  int line_coding_baud = 0;  //!< from SET_LINE_CODING, 0 if never set
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

  //! Adds a CDC-ACM board (interface 0: communication, interrupt EP 0x82; interface 1: data,
  //! bulk OUT 0x04 / IN 0x83) at bus 1, address `address`, whose usbdevfs URBs are answered by
  //! `firmware`. The kernel driver cdc_acm is "bound" until the host detaches it.
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
