// The real termios transport and board driver against the simulated firmware behind a pty.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "board_test_support.h"
#include "scanmesh/drivers/serial_transport.h"
#include "scanmesh/sim/pty_board.h"

namespace scanmesh::drivers {
namespace {

using test::expect_device_error;

struct Rig {
  explicit Rig(sim::SimBoardOptions o = test::fast_board()) : pty(o) {}
  Board make_board() {
    return Board(open_serial_transport(pty.slave_path()), make_horus_dialect(),
                 test::fast_driver());
  }
  sim::PtyBoard pty;
};

TEST(SerialBoard, ConnectsMovesAndSwitchesLasers) {
  Rig rig;
  Board board = rig.make_board();
  board.connect();
  EXPECT_EQ(board.firmware_banner(), "Horus 0.2 ['$' for help]");
  EXPECT_TRUE(rig.pty.firmware().motor_enabled());
  board.move_to(std::numbers::pi / 2);
  EXPECT_NEAR(rig.pty.firmware().angle_rad(), std::numbers::pi / 2, test::kAngleTolerance);
  board.move_by(-std::numbers::pi / 4);
  EXPECT_NEAR(rig.pty.firmware().angle_rad(), std::numbers::pi / 4, test::kAngleTolerance);
  board.move_to(std::numbers::pi);  // back to absolute mode
  EXPECT_NEAR(rig.pty.firmware().angle_rad(), std::numbers::pi, test::kAngleTolerance);
  board.set_laser(1, true);
  EXPECT_EQ(rig.pty.firmware().laser_mask(), 2u);
  board.set_laser(0, true);
  EXPECT_EQ(rig.pty.firmware().laser_mask(), 3u);
  board.set_laser(1, false);
  EXPECT_EQ(rig.pty.firmware().laser_mask(), 1u);
  board.shutdown();
  EXPECT_EQ(rig.pty.firmware().laser_mask(), 0u);
  EXPECT_FALSE(rig.pty.firmware().motor_enabled());
}

TEST(SerialBoard, ShutdownReleasesTheMotorEvenIfALaserIsRefused) {
  auto o = test::fast_board();
  o.laser_count = 1;
  Rig rig(o);
  Board board = rig.make_board();
  board.connect();
  board.set_laser(0, true);
  board.shutdown();  // "M70 T2" is answered with an error on a one-laser board
  EXPECT_EQ(rig.pty.firmware().laser_mask(), 0u);
  EXPECT_FALSE(rig.pty.firmware().motor_enabled());
}

// Connects and switches laser 1 on; returns the firmware's command count, to arm a fault at the
// next command.
int connect_with_laser_on(Rig& rig, Board& board) {
  board.connect();
  board.set_laser(0, true);
  return rig.pty.firmware().commands_received();
}

// A board gone mute (a stalled tty) is the usual reason to shut down early: the first command
// waits once, the other two are only sent (each command once, not three attempts of three).
TEST(SerialBoard, ShutdownOfAMuteBoardWaitsForOneCommandOnly) {
  Rig rig;
  Board board = rig.make_board();
  const int n = connect_with_laser_on(rig, board);
  rig.pty.firmware().set_faults({.stall_at_command = n + 1});
  board.shutdown();
  // The last two are only written: the firmware's thread reads them a moment later.
  const auto deadline = std::chrono::steady_clock::now() + test::kPatientTimeout;
  while (rig.pty.firmware().commands_received() < n + 3 &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(rig.pty.firmware().stalled());
  EXPECT_EQ(rig.pty.firmware().commands_received(), n + 3);
}

// A garbled acknowledgement of "laser off" comes from a live board that may not have switched:
// that command is repeated, and the rest of the shutdown waits for its answers as usual.
TEST(SerialBoard, ShutdownRepeatsAGarbledLaserOff) {
  Rig rig;
  Board board = rig.make_board();
  const int n = connect_with_laser_on(rig, board);
  rig.pty.firmware().set_faults({.garble_ok_at_command = n + 1});
  board.shutdown();
  EXPECT_EQ(rig.pty.firmware().commands_received(), n + 4);
  EXPECT_EQ(rig.pty.firmware().laser_mask(), 0u);
  EXPECT_FALSE(rig.pty.firmware().motor_enabled());
}

// 30 steps per turn are 106.67 microsteps each: a resumed scan must round its targets exactly
// as the uninterrupted one, so it declares its position in the firmware's coordinates.
TEST(SerialBoard, DeclaredPositionLandsOnTheSameMicrostepsAsAnUninterruptedRun) {
  const double step = 2 * std::numbers::pi / 30;
  double uninterrupted = 0;
  {
    Rig rig;
    Board board = rig.make_board();
    board.connect();
    for (int i = 1; i <= 20; ++i) board.move_to(i * step);
    uninterrupted = rig.pty.firmware().angle_rad();
  }
  double first_run_end = 0;
  {
    Rig rig;
    Board board = rig.make_board();
    board.connect();
    for (int i = 1; i <= 16; ++i) board.move_to(i * step);
    first_run_end = rig.pty.firmware().angle_rad();
  }
  auto o = test::fast_board();
  o.initial_angle_rad = first_run_end;  // the table stays where the first run left it
  Rig rig(o);
  Board board = rig.make_board();
  board.connect();
  board.declare_position(16 * step);
  for (int i = 17; i <= 20; ++i) board.move_to(i * step);
  EXPECT_EQ(rig.pty.firmware().angle_rad(), uninterrupted);
}

TEST(SerialBoard, RejectsUnknownFirmwareVersion) {
  auto o = test::fast_board();
  o.banner = "Horus 3.0 ['$' for help]";
  Rig rig(o);
  Board board = rig.make_board();
  expect_device_error([&] { board.connect(); }, rig.pty.slave_path(), "unsupported firmware");
}

TEST(SerialBoard, ErrorReplyNamesTheCommand) {
  auto o = test::fast_board();
  o.faults.refuse_lasers = true;
  Rig rig(o);
  Board board = rig.make_board();
  board.connect();
  expect_device_error([&] { board.set_laser(0, true); }, rig.pty.slave_path(),
                      "refused 'M71 T1': error: laser driver fault");
}

TEST(SerialBoard, MissingOkOnASafeCommandIsRetried) {
  Rig rig;
  Board board = rig.make_board();
  board.connect();
  const int n = rig.pty.firmware().commands_received();
  rig.pty.firmware().set_faults({.drop_ok_at_command = n + 1});
  board.set_laser(0, true);  // first "ok" lost, the repeat is acknowledged
  EXPECT_EQ(rig.pty.firmware().commands_received(), n + 2);
  EXPECT_EQ(rig.pty.firmware().laser_mask(), 1u);
}

TEST(SerialBoard, GarbledOkOnARelativeMoveIsNotRetried) {
  Rig rig;
  Board board = rig.make_board();
  board.connect();
  board.move_by(0.1);  // switches to relative mode
  const int n = rig.pty.firmware().commands_received();
  rig.pty.firmware().set_faults({.garble_ok_at_command = n + 1});
  expect_device_error([&] { board.move_by(0.1); }, rig.pty.slave_path(), "garbled reply");
  // A repeat would have turned the table twice: exactly one more command reached the board.
  EXPECT_EQ(rig.pty.firmware().commands_received(), n + 1);
  EXPECT_NEAR(rig.pty.firmware().angle_rad(), 0.2, test::kAngleTolerance);
}

TEST(SerialBoard, MoveThatNeverCompletesTimesOut) {
  Rig rig;
  Board board = rig.make_board();
  board.connect();
  const int n = rig.pty.firmware().commands_received();
  rig.pty.firmware().set_faults({.hang_move_at_command = n + 1});
  expect_device_error([&] { board.move_to(1.0); }, rig.pty.slave_path(), "no 'ok' for 'G1 X");
}

TEST(SerialBoard, UnplugIsReported) {
  Rig rig;
  Board board = rig.make_board();
  board.connect();
  const int n = rig.pty.firmware().commands_received();
  rig.pty.firmware().set_faults({.unplug_at_command = n + 1});
  expect_device_error([&] { board.move_to(1.0); }, rig.pty.slave_path(), "unplugged");
}

TEST(SerialBoard, MissingDeviceNodeIsADeviceError) {
  expect_device_error([] { open_serial_transport("/dev/ttyACM-scanmesh-none"); },
                      "/dev/ttyACM-scanmesh-none", "cannot open");
}

}  // namespace
}  // namespace scanmesh::drivers
