// A full simulated scan through the real drivers: the libusb board transport against an emulated
// CDC-ACM board and the V4L2 camera against an emulated capture node (umockdev), both answered
// by the simulated devices. Frames must match the renderer bit for bit (RGB24 + PNG: lossless);
// injected faults must name the device and the step and leave a session that resumes to the
// same result as an uninterrupted scan.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "scanmesh/acquisition/capture.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/board.h"
#include "scanmesh/drivers/usb_transport.h"
#include "scanmesh/sim/emulated_devices.h"
#include "scanmesh/sim/sim_camera.h"
#include "session_compare.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 48, kHeight = 32;
constexpr std::size_t kSteps = 100;

// Sessions go to /dev/shm when there is one: the fsync calls still run but cost nothing there
// (about 60 ms per step on this machine's ext4); durability against power loss is not what
// these tests can check (docs/testing.md).
fs::path scratch(const std::string& name) {
  const fs::path base =
      fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
  const fs::path d = base / ("scanmesh_test_capture_" + std::to_string(getpid())) / name;
  fs::remove_all(d);
  return d;
}

// One set of emulated devices; the table starts where a previous run left it.
struct Rig {
  explicit Rig(double table_angle, sim::BoardFaults board_faults = {},
               sim::CameraFaults camera_faults = {}) {
    sim::SimBoardOptions bo;
    bo.time_scale = 0.002;
    bo.initial_angle_rad = table_angle;
    bo.faults = board_faults;
    firmware = std::make_shared<sim::SimBoardFirmware>(bo);
    sim::SimCameraOptions co;
    co.width = kWidth;
    co.height = kHeight;
    co.time_scale = 0.02;
    co.faults = camera_faults;
    auto fw = firmware;
    camera = std::make_shared<sim::SimCamera>(
        sim::synthetic_turntable_renderer(kWidth, kHeight), [fw] { return fw->angle_rad(); },
        [fw] { return fw->laser_mask(); }, co);
    devices.add_usb_board(firmware);
    devices.add_camera(camera);
  }

  // Runs the capture loop with the real drivers into `dir` (created or resumed).
  CaptureReport scan(const fs::path& dir, double table_angle) {
    drivers::BoardOptions bo;
    bo.command_timeout = std::chrono::milliseconds(200);
    bo.move_timeout_floor = std::chrono::milliseconds(400);
    drivers::Board board(drivers::open_usb_transport({.vendor_id = 0x2341, .product_id = 0x0043}),
                         drivers::make_horus_dialect(), bo);
    board.connect();
    board.set_origin(table_angle);
    drivers::CameraSettings cs;
    cs.width = kWidth;
    cs.height = kHeight;
    cs.format = drivers::PixelFormat::Rgb24;
    cs.io = drivers::IoMethod::UserPtr;
    cs.buffer_count = 3;
    cs.timeout = std::chrono::milliseconds(1000);
    drivers::V4l2Camera cam("/dev/video0", cs);
    std::optional<SessionWriter> session;
    if (fs::exists(dir / "session.json")) {
      session.emplace(SessionWriter::resume(dir));
    } else {
      SessionHeader h;
      h.step_count = kSteps;
      h.laser_count = 2;
      h.camera = cam.descriptor();
      h.board_device = board.device_name();
      h.board_dialect = board.dialect().name();
      h.board_firmware = board.firmware_banner();
      h.simulated = true;
      session.emplace(SessionWriter::create(dir, h));
    }
    CaptureOptions o;
    o.settle_s = 0;
    o.discard_frames = 1;
    return capture_steps(*session, board, cam, o);
  }

  std::shared_ptr<sim::SimBoardFirmware> firmware;
  std::shared_ptr<sim::SimCamera> camera;
  sim::EmulatedDevices devices;
};

// Where the simulated table stands for step i: whole microsteps (3200 per turn).
double table_angle_of_step(std::size_t i) {
  const double steps = std::round(static_cast<double>(i) * 3200.0 / kSteps);
  return steps * 2 * std::numbers::pi / 3200.0;
}

double last_step_angle(const fs::path& dir) {
  const SessionManifest m = read_session_manifest(dir);
  return m.steps.empty() ? 0.0 : m.steps.back().angle_rad;
}

class EmulatedScan : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    reference_ = new fs::path(scratch("reference"));
    Rig rig(0);
    report_ = new CaptureReport(rig.scan(*reference_, 0));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*reference_);
    delete reference_;
    delete report_;
  }
  // Runs a scan with a fault, expects a DeviceError naming `device` and a step, then resumes
  // with healthy devices and compares with the uninterrupted reference.
  void fault_then_resume(const std::string& name, sim::BoardFaults bf, sim::CameraFaults cf,
                         const std::string& device, const std::string& problem) {
    const fs::path dir = scratch(name);
    std::size_t failed_at = 0;
    {
      Rig rig(0, bf, cf);
      try {
        rig.scan(dir, 0);
        ADD_FAILURE() << name << ": no error";
      } catch (const DeviceError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.device(), device) << what;
        EXPECT_NE(what.find(problem), std::string::npos) << what;
        EXPECT_NE(what.find("step "), std::string::npos) << what;
        failed_at = read_session_manifest(dir).steps.size();
        EXPECT_NE(what.find("step " + std::to_string(failed_at) + " of 100"), std::string::npos)
            << what;
      }
    }
    EXPECT_GT(failed_at, 0u);
    EXPECT_LT(failed_at, kSteps);
    const double angle = last_step_angle(dir);
    Rig rig(angle);
    const CaptureReport r = rig.scan(dir, angle);
    EXPECT_EQ(r.first_step, failed_at);
    EXPECT_EQ(r.steps_done, kSteps);
    EXPECT_TRUE(test::sessions_identical(dir, *reference_));
    fs::remove_all(dir);
  }
  static fs::path* reference_;
  static CaptureReport* report_;
};
fs::path* EmulatedScan::reference_ = nullptr;
CaptureReport* EmulatedScan::report_ = nullptr;

TEST_F(EmulatedScan, HundredStepsTwoLasersMatchTheRendererBitForBit) {
  ASSERT_EQ(report_->steps_done, kSteps);
  const SessionReader reader(*reference_);
  ASSERT_EQ(reader.step_count(), kSteps);
  ASSERT_TRUE(reader.complete());
  EXPECT_EQ(reader.manifest().header.camera.card, "Simulated UVC Camera");
  EXPECT_EQ(reader.manifest().header.board_device, "usb 001:002 (2341:0043)");
  const auto render = sim::synthetic_turntable_renderer(kWidth, kHeight);
  for (std::size_t i = 0; i < kSteps; ++i) {
    const ScanStep s = reader.step(i);
    EXPECT_NEAR(s.angle_rad, 2 * std::numbers::pi * i / kSteps, 1e-12);
    const double table = table_angle_of_step(i);
    ASSERT_EQ(s.laser_off.pixels, render(table, 0).pixels) << "step " << i << " laser off";
    ASSERT_EQ(s.laser_on.size(), 2u);
    ASSERT_EQ(s.laser_on[0].pixels, render(table, 1).pixels) << "step " << i << " laser 0";
    ASSERT_EQ(s.laser_on[1].pixels, render(table, 2).pixels) << "step " << i << " laser 1";
  }
}

// Board command numbers: 3 at connect (feed, G90, M17); each step sends 2 lasers off, the
// move, and on/off per laser: 7 commands. Command 3 + 7 * 40 + 3 is step 40's move.
constexpr int kStep40Move = 3 + 7 * 40 + 3;

TEST_F(EmulatedScan, BoardUnplugMidScanResumesToTheSameSession) {
  fault_then_resume("unplug", {.unplug_at_command = kStep40Move}, {}, "usb 001:002 (2341:0043)",
                    "unplugged");
}

TEST_F(EmulatedScan, StalledEndpointResumesToTheSameSession) {
  fault_then_resume("stall", {.stall_at_command = kStep40Move + 2}, {}, "usb 001:002 (2341:0043)",
                    "endpoint stalled");
}

TEST_F(EmulatedScan, MoveThatNeverCompletesResumesToTheSameSession) {
  fault_then_resume("hang", {.hang_move_at_command = kStep40Move}, {}, "usb 001:002 (2341:0043)",
                    "no 'ok' for 'G1 X");
}

TEST_F(EmulatedScan, CameraEioResumesToTheSameSession) {
  fault_then_resume("eio", {}, {.eio_at_sequence = 150}, "/dev/video0", "I/O error (EIO)");
}

TEST_F(EmulatedScan, CameraUnplugResumesToTheSameSession) {
  fault_then_resume("camunplug", {}, {.unplug_at_sequence = 300}, "/dev/video0", "unplugged");
}

TEST_F(EmulatedScan, LostAndGarbledOksAndDroppedFramesAreAbsorbed) {
  const fs::path dir = scratch("absorbed");
  Rig rig(0, {.drop_ok_at_command = kStep40Move + 1, .garble_ok_at_command = kStep40Move},
          {.drop_sequences = {10, 11, 200}, .corrupt_sequences = {}});
  const CaptureReport r = rig.scan(dir, 0);
  EXPECT_EQ(r.steps_done, kSteps);
  EXPECT_EQ(r.dropped_frames, 3u);
  EXPECT_TRUE(test::sessions_identical(dir, *reference_));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace scanmesh
