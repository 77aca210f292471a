// The real libusb transport and board driver against an emulated CDC-ACM board (umockdev):
// libusb enumerates it from sysfs, opens /dev/bus/usb/001/002, detaches "cdc_acm", claims the
// interfaces, sends SET_LINE_CODING, and exchanges bulk URBs answered by the simulated firmware.
#include <gtest/gtest.h>

#include "board_test_support.h"
#include "scanmesh/drivers/usb_transport.h"
#include "scanmesh/sim/emulated_devices.h"

namespace scanmesh::drivers {
namespace {

using test::expect_device_error;

const char* const kDeviceName = "usb 001:002 (2341:0043)";

struct UsbRig {
  UsbRig() : firmware(std::make_shared<sim::SimBoardFirmware>(test::fast_board())) {
    devices.add_usb_board(firmware);
  }
  Board make_board() {
    return Board(open_usb_transport({.vendor_id = 0x2341, .product_id = 0x0043}),
                 make_horus_dialect(), test::fast_driver());
  }
  std::shared_ptr<sim::SimBoardFirmware> firmware;
  sim::EmulatedDevices devices;
};

TEST(UsbBoard, ListsTheEmulatedBoard) {
  UsbRig rig;
  const auto boards = list_usb_boards();
  ASSERT_EQ(boards.size(), 1u);
  EXPECT_EQ(boards[0].vendor_id, 0x2341);
  EXPECT_EQ(boards[0].product_id, 0x0043);
  EXPECT_EQ(boards[0].bus, 1);
  EXPECT_EQ(boards[0].address, 2);
  EXPECT_EQ(boards[0].kind, "Arduino");
}

TEST(UsbBoard, DetachesKernelDriverSetsLineCodingAndScans) {
  UsbRig rig;
  Board board = rig.make_board();
  const auto state = rig.devices.usb_board_state();
  EXPECT_TRUE(state.kernel_driver_detached);
  EXPECT_EQ(state.line_coding_baud, 115200);
  EXPECT_EQ(state.data_bits, 8);
  EXPECT_TRUE(state.dtr);
  EXPECT_EQ(state.claimed_interfaces, 2);
  board.connect();
  EXPECT_EQ(board.device_name(), kDeviceName);
  for (int i = 1; i <= 4; ++i) {
    board.move_to(i * 0.25);
    EXPECT_NEAR(rig.firmware->angle_rad(), i * 0.25, test::kAngleTolerance);
    board.set_laser(0, true);
    board.set_laser(1, true);
    EXPECT_EQ(rig.firmware->laser_mask(), 3u);
    board.set_laser(0, false);
    board.set_laser(1, false);
    EXPECT_EQ(rig.firmware->laser_mask(), 0u);
  }
}

TEST(UsbBoard, UnplugMidScanIsNoDevice) {
  UsbRig rig;
  Board board = rig.make_board();
  board.connect();
  board.move_to(0.5);
  const int n = rig.firmware->commands_received();
  rig.firmware->set_faults({.unplug_at_command = n + 2});
  board.set_laser(0, true);
  expect_device_error([&] { board.move_to(1.0); }, kDeviceName, "unplugged");
}

TEST(UsbBoard, StalledEndpointIsClearedOnceThenReported) {
  UsbRig rig;
  Board board = rig.make_board();
  board.connect();
  const int n = rig.firmware->commands_received();
  rig.firmware->set_faults({.stall_at_command = n + 1});
  expect_device_error([&] { board.set_laser(0, true); }, kDeviceName, "endpoint stalled");
  EXPECT_GE(rig.devices.usb_board_state().stalls_cleared, 1);
}

TEST(UsbBoard, MissingOkIsRetriedOverUsb) {
  UsbRig rig;
  Board board = rig.make_board();
  board.connect();
  const int n = rig.firmware->commands_received();
  rig.firmware->set_faults({.drop_ok_at_command = n + 1});
  board.set_laser(1, true);
  EXPECT_EQ(rig.firmware->commands_received(), n + 2);
  EXPECT_EQ(rig.firmware->laser_mask(), 2u);
}

TEST(UsbBoard, WrongVidPidIsNotFound) {
  UsbRig rig;
  expect_device_error([] { open_usb_transport({.vendor_id = 0x1a86, .product_id = 0x7523}); },
                      "1a86:7523", "no such USB device");
}

}  // namespace
}  // namespace scanmesh::drivers
