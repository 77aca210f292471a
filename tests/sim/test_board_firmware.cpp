// The simulated board firmware on its own, without a transport: what it answers and when it
// says it has output (the pty pump and the emulated USB endpoint poll has_output_ready()), and
// G92, which declares a position without moving the table (a resumed scan's first command).
#include <gtest/gtest.h>

#include <numbers>
#include <string>

#include "scanmesh/sim/board_firmware.h"

namespace scanmesh::sim {
namespace {

constexpr double kPi = std::numbers::pi;

SimBoardOptions instant_board() {
  SimBoardOptions o;
  o.boot_time_s = 0.0;  // the banner is due at power-on
  o.time_scale = 0.0;   // moves end as they start: nothing here waits for a clock
  return o;
}

TEST(SimBoardFirmware, OutputIsReadyExactlyWhileRepliesAreQueued) {
  SimBoardFirmware fw(instant_board());
  ASSERT_TRUE(fw.has_output_ready());  // the banner
  EXPECT_NE(fw.transmit().find("Horus"), std::string::npos);
  EXPECT_FALSE(fw.has_output_ready());
  fw.receive("M17\n");
  ASSERT_TRUE(fw.has_output_ready());
  EXPECT_EQ(fw.transmit(), "ok\r\n");
  EXPECT_FALSE(fw.has_output_ready());
  fw.receive("M1");  // half a line: no command yet, no answer
  EXPECT_FALSE(fw.has_output_ready());
  fw.receive("8\n");
  EXPECT_TRUE(fw.has_output_ready());
  EXPECT_FALSE(fw.motor_enabled());
}

TEST(SimBoardFirmware, AStalledBoardHasNothingToSend) {
  SimBoardOptions o = instant_board();
  o.faults.stall_at_command = 2;
  SimBoardFirmware fw(o);
  (void)fw.transmit();
  fw.receive("M17\n");
  EXPECT_TRUE(fw.has_output_ready());
  fw.receive("G91\n");  // command 2: the endpoint stalls
  EXPECT_TRUE(fw.stalled());
  EXPECT_FALSE(fw.has_output_ready());
  EXPECT_EQ(fw.transmit(), "");
}

TEST(SimBoardFirmware, PositionDeclarationsRenameTheCoordinateWithoutMovingTheTable) {
  SimBoardOptions o = instant_board();
  o.initial_angle_rad = 0.25 * kPi;
  SimBoardFirmware fw(o);
  (void)fw.transmit();
  EXPECT_EQ(fw.position_declarations(), 0);
  fw.receive("M17\nG92 X90\n");
  EXPECT_EQ(fw.position_declarations(), 1);
  EXPECT_NEAR(fw.angle_rad(), 0.25 * kPi, 1e-12);  // the table did not turn
  EXPECT_EQ(fw.transmit(), "ok\r\nok\r\n");
  // Absolute X100 from the declared X90 is a 10 degree turn, to the nearest microstep.
  fw.receive("G90\nG1 X100 F100\n");
  EXPECT_NEAR(fw.angle_rad(), 0.25 * kPi + 10.0 * kPi / 180.0, kPi / 3200.0);
  fw.receive("G92 X\n");  // no number: an error, not a declaration
  EXPECT_EQ(fw.position_declarations(), 1);
  EXPECT_NE(fw.transmit().find("error: bad number"), std::string::npos);
  fw.reset();
  EXPECT_EQ(fw.position_declarations(), 1);  // counted since the object was made
}

}  // namespace
}  // namespace scanmesh::sim
