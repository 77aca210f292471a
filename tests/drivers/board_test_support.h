// Shared checks of the board driver against the simulated firmware, run once over a pty
// (termios transport) and once over an emulated USB device (libusb transport).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <numbers>

#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/board.h"
#include "scanmesh/sim/board_firmware.h"

namespace scanmesh::test {

// Time scale of the simulated board in tests: a 1 s move takes 5 ms.
constexpr double kTimeScale = 0.005;
// The simulated table stands on whole microsteps (3200 per turn): half a microstep.
constexpr double kAngleTolerance = std::numbers::pi / 3200;

inline sim::SimBoardOptions fast_board() {
  sim::SimBoardOptions o;
  o.time_scale = kTimeScale;
  return o;
}

// Timeouts far above any round trip a loaded machine needs (ctest -j, sanitizers): a test that
// expects a timeout waits it out (a few tests, 3 s each), and no other test can see one fire
// because the machine is busy (issue 31: 150 ms fired under load).
inline constexpr auto kPatientTimeout = std::chrono::milliseconds(3000);

inline drivers::BoardOptions fast_driver() {
  drivers::BoardOptions o;
  o.command_timeout = kPatientTimeout;
  o.move_timeout_floor = kPatientTimeout;
  o.banner_timeout = std::chrono::milliseconds(5000);
  o.feed_rate_deg_per_s = 120;
  return o;
}

// Expects a DeviceError whose message contains `fragment`; returns the message.
inline std::string expect_device_error(const std::function<void()>& f, const std::string& device,
                                       const std::string& fragment) {
  try {
    f();
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device(), device) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no DeviceError (expected '" << fragment << "')";
  return {};
}

}  // namespace scanmesh::test
