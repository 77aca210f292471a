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

// USB-serial bridges: the same board behind a CH340 and behind an FT232R. The emulated bridge
// decodes the vendor requests the transport sends into the rate its UART would run at, and only
// passes bytes intact when that rate is within 3 % of the firmware's 115200 baud.
struct BridgeCase {
  std::uint16_t vid, pid;
  const char* kernel_driver;
  const char* name;
};

class UsbBridgeBoard : public ::testing::TestWithParam<BridgeCase> {};

TEST_P(UsbBridgeBoard, VendorRequestsSetTheBaudRateAndTheBoardScans) {
  const BridgeCase c = GetParam();
  auto firmware = std::make_shared<sim::SimBoardFirmware>(test::fast_board());
  sim::EmulatedDevices devices;
  devices.add_usb_board(firmware, c.vid, c.pid);
  const auto boards = list_usb_boards();
  ASSERT_EQ(boards.size(), 1u);
  EXPECT_EQ(boards[0].kind, c.name);
  Board board(open_usb_transport({.vendor_id = c.vid, .product_id = c.pid}), make_horus_dialect(),
              test::fast_driver());
  const auto state = devices.usb_board_state();
  EXPECT_EQ(state.kernel_driver, c.kernel_driver);
  EXPECT_TRUE(state.kernel_driver_detached);
  EXPECT_NEAR(state.line_coding_baud, 115200, 0.01 * 115200);
  EXPECT_EQ(state.data_bits, 8);
  EXPECT_TRUE(state.dtr);
  EXPECT_GE(state.vendor_requests, 4);
  board.connect();
  for (int i = 1; i <= 3; ++i) {
    board.move_to(i * 0.3);
    EXPECT_NEAR(firmware->angle_rad(), i * 0.3, test::kAngleTolerance);
    board.set_laser(1, true);
    EXPECT_EQ(firmware->laser_mask(), 2u);
    board.set_laser(1, false);
  }
}

TEST_P(UsbBridgeBoard, WrongBaudRateGarblesTheBanner) {
  const BridgeCase c = GetParam();
  auto firmware = std::make_shared<sim::SimBoardFirmware>(test::fast_board());
  sim::EmulatedDevices devices;
  devices.add_usb_board(firmware, c.vid, c.pid);
  Board board(open_usb_transport({.vendor_id = c.vid, .product_id = c.pid, .baud = 9600}),
              make_horus_dialect(), test::fast_driver());
  EXPECT_NEAR(devices.usb_board_state().line_coding_baud, 9600, 0.01 * 9600);
  EXPECT_THROW(board.connect(), DeviceError);
}

INSTANTIATE_TEST_SUITE_P(Bridges, UsbBridgeBoard,
                         ::testing::Values(BridgeCase{0x1a86, 0x7523, "ch341", "CH340"},
                                           BridgeCase{0x0403, 0x6001, "ftdi_sio", "FTDI"}),
                         [](const auto& p) { return std::string(p.param.kernel_driver); });

// The divisor encodings against the chips' rate formulas, over the usual rates.
TEST(UsbBridgeDivisors, EncodeRatesWithinOnePercent) {
  for (int baud : {300, 1200, 9600, 19200, 57600, 115200, 230400, 250000, 500000, 1000000}) {
    const unsigned reg = ch34x_baud_register(baud);
    const unsigned ps = reg & 3, fact = (reg >> 2) & 1, div = 0x100 - (reg >> 8);
    const double ch = 48e6 / ((1u << (12 - 3 * ps - fact)) * static_cast<double>(div));
    EXPECT_NEAR(ch, baud, 0.01 * baud) << baud;
    const std::uint32_t d = ftdi_baud_divisor(baud);
    static constexpr double kEighths[8] = {0, 4, 2, 1, 3, 5, 6, 7};
    const double divisor = (d & 0x3fff) + kEighths[(d >> 14) & 7] / 8.0;
    EXPECT_NEAR(3e6 / divisor, baud, 0.01 * baud) << baud;
  }
  EXPECT_EQ(ftdi_baud_divisor(115200), 26u);  // 3 MHz / 26 = 115385 baud
  EXPECT_EQ(ftdi_baud_divisor(3000000), 0u);
  EXPECT_THROW(ch34x_baud_register(10), InvalidInputError);
  EXPECT_THROW(ftdi_baud_divisor(5000000), InvalidInputError);
}

}  // namespace
}  // namespace scanmesh::drivers
