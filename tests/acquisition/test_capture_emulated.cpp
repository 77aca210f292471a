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
#include <vector>

#include "scanmesh/acquisition/capture.h"
#include "scanmesh/acquisition/reconstruction.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/drivers/board.h"
#include "scanmesh/drivers/usb_transport.h"
#include "scanmesh/sim/emulated_devices.h"
#include "scanmesh/sim/sim_camera.h"
#include "scanmesh/sim/turntable_camera.h"
#include "session_compare.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 48, kHeight = 32;
constexpr std::size_t kSteps = 100;  // the bit-for-bit scans
// The head scan's frame size: the built-in Ciclop rig scaled to 160 x 120 (docs/testing.md,
// "Why 160 x 120 for the emulated head scan").
constexpr int kHeadWidth = 160, kHeadHeight = 120;
// The head camera runs at 30 fps in real time: a frame period (33 ms) longer than a head render,
// so the flush before each grab finds at most one ready frame. With a period shorter than a
// render every dequeue finds the next frame ready and the flush renders up to 64 frames a grab.
constexpr double kHeadCameraTimeScale = 1.0;
constexpr std::size_t kFaultSteps = 30;  // the fault-and-resume scans

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

// One set of emulated devices; the table starts where a previous run left it. The camera renders
// with `renderer` (the synthetic one unless given) at width x height.
struct Rig {
  explicit Rig(double table_angle, sim::BoardFaults board_faults = {},
               sim::CameraFaults camera_faults = {}, sim::FrameRenderer renderer = {},
               int frame_width = kWidth, int frame_height = kHeight,
               double camera_time_scale = 0.02)
      : width(frame_width), height(frame_height) {
    sim::SimBoardOptions bo;
    bo.time_scale = 0.002;
    bo.initial_angle_rad = table_angle;
    bo.faults = board_faults;
    firmware = std::make_shared<sim::SimBoardFirmware>(bo);
    sim::SimCameraOptions co;
    co.width = width;
    co.height = height;
    co.time_scale = camera_time_scale;
    co.faults = camera_faults;
    auto fw = firmware;
    if (!renderer) renderer = sim::synthetic_turntable_renderer(width, height);
    camera = std::make_shared<sim::SimCamera>(
        std::move(renderer), [fw] { return fw->angle_rad(); }, [fw] { return fw->laser_mask(); },
        co);
    devices.add_usb_board(firmware);
    devices.add_camera(camera);
  }

  // Runs the capture loop with the real drivers into `dir` (created or resumed).
  CaptureReport scan(const fs::path& dir, double table_angle, std::size_t steps = kSteps,
                     int discard_frames = 1) {
    drivers::BoardOptions bo;
    // Patient timeouts: only the hang case waits one out; none fires because of load.
    bo.command_timeout = std::chrono::milliseconds(3000);
    bo.move_timeout_floor = std::chrono::milliseconds(3000);
    drivers::Board board(drivers::open_usb_transport({.vendor_id = 0x2341, .product_id = 0x0043}),
                         drivers::make_horus_dialect(), bo);
    board.connect();
    // As `scanmesh scan --resume` does: a resumed session tells the board where the table stands
    // (G92 in the Horus dialect), since the firmware counts from 0 after its reset.
    if (fs::exists(dir / "session.json") && !read_session_manifest(dir).steps.empty())
      board.declare_position(table_angle);
    drivers::CameraSettings cs;
    cs.width = width;
    cs.height = height;
    cs.format = drivers::PixelFormat::Rgb24;
    cs.io = drivers::IoMethod::UserPtr;
    cs.buffer_count = 3;
    cs.timeout = std::chrono::milliseconds(5000);
    drivers::V4l2Camera cam("/dev/video0", cs);
    std::optional<SessionWriter> session;
    if (fs::exists(dir / "session.json")) {
      session.emplace(SessionWriter::resume(dir));
    } else {
      SessionHeader h;
      h.step_count = steps;
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
    o.discard_frames = discard_frames;
    return capture_steps(*session, board, cam, o);
  }

  int width, height;
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

TEST(EmulatedScan, HundredStepsTwoLasersMatchTheRendererBitForBit) {
  const fs::path dir = scratch("hundred");
  {
    Rig rig(0);
    const CaptureReport r = rig.scan(dir, 0);
    ASSERT_EQ(r.steps_done, kSteps);
  }
  const SessionReader reader(dir);
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
  fs::remove_all(dir);
}

// The calibration a perfect calibration would find: the simulated rig's own camera and lasers.
Calibration exact_calibration(const sim::TurntableCamera& cam) {
  const sim::RigConfig& rig = cam.rig();
  Calibration c;
  const auto& in = rig.intrinsics;
  c.camera = {rig.width, rig.height, in.fx, in.fy, in.cx, in.cy, in.k1, in.k2, in.p1, in.p2, in.k3};
  const Eigen::Isometry3d t = cam.camera_from_rig();
  for (const auto& l : rig.lasers) {
    const Eigen::Vector3d n = t.linear() * l.normal;
    c.lasers.push_back({l.name, n, n.dot(t * l.position_mm)});
  }
  c.axis_direction = t.linear() * Eigen::Vector3d::UnitZ();
  c.axis_origin_mm = t * Eigen::Vector3d(0, 0, rig.platform_height_mm);
  return c;
}

// The acceptance scan: the simulated head on the turntable, 100 steps, two lasers, through the
// real libusb board driver and the real V4L2 backend (USERPTR streaming, RGB24; MMAP cannot be
// emulated, docs/testing.md) under umockdev. The emulated camera renders with a TurntableCamera at
// the angle and laser state the emulated board reports at the moment of capture; the test renders
// every step again with a second, independent TurntableCamera (its own scene and rig) and wants the
// recorded PNG frames equal byte for byte.
TEST(EmulatedScan, HeadHundredStepsTwoLasersMatchTheTurntableCameraBitForBit) {
  const fs::path dir = scratch("head");
  const sim::RigConfig rig = sim::rig_at_size(sim::builtin_ciclop_rig(), kHeadWidth, kHeadHeight);
  ASSERT_EQ(rig.lasers.size(), 2u);
  {
    auto scene = std::make_shared<sim::Scene>(sim::builtin_head_scene());
    auto device_camera = std::make_shared<sim::TurntableCamera>(*scene, rig);
    sim::FrameRenderer renderer = [scene, device_camera](double angle, unsigned mask) {
      return device_camera->render(angle, mask);
    };
    Rig emulated(0, {}, {}, renderer, kHeadWidth, kHeadHeight, kHeadCameraTimeScale);
    // The simulated camera renders each frame at the board's state when it is dequeued, so no
    // frame needs discarding after a laser switch; the head renders are what costs time here.
    const CaptureReport r = emulated.scan(dir, 0, kSteps, /*discard_frames=*/0);
    ASSERT_EQ(r.steps_done, kSteps);
    EXPECT_EQ(r.dropped_frames, 0u);
  }
  const sim::Scene scene = sim::builtin_head_scene();
  const sim::TurntableCamera truth(scene, rig);
  const SessionReader reader(dir);
  ASSERT_EQ(reader.step_count(), kSteps);
  ASSERT_TRUE(reader.complete());
  EXPECT_EQ(reader.manifest().header.camera.width, kHeadWidth);
  EXPECT_EQ(reader.manifest().header.camera.height, kHeadHeight);
  std::size_t laser_pixels_differing = 0;
  for (std::size_t i = 0; i < kSteps; ++i) {
    const ScanStep s = reader.step(i);
    EXPECT_NEAR(s.angle_rad, 2 * std::numbers::pi * i / kSteps, 1e-12);
    const double table = table_angle_of_step(i);
    const Image8 off = truth.render(table, 0);
    ASSERT_EQ(s.laser_off.width, kHeadWidth);
    ASSERT_EQ(s.laser_off.pixels, off.pixels) << "step " << i << " laser off";
    ASSERT_EQ(s.laser_on.size(), 2u);
    for (unsigned k = 0; k < 2; ++k) {
      const Image8 on = truth.render(table, 1u << k);
      ASSERT_EQ(s.laser_on[k].pixels, on.pixels) << "step " << i << " laser " << k;
      for (std::size_t p = 0; p < on.pixels.size(); ++p)
        laser_pixels_differing += on.pixels[p] != off.pixels[p];
    }
  }
  // The lasers do light the head: a frame pair that did not differ would make the test vacuous.
  EXPECT_GT(laser_pixels_differing, kSteps * 2 * kHeadHeight / 4);

  // Replay is deterministic: the session fed twice through reconstruction (line extraction,
  // triangulation with the rig's exact calibration, grid assembly) gives the same grid bytes,
  // and that grid holds the head.
  const Calibration cal = exact_calibration(truth);
  ReconstructionStats stats;
  const RangeGrid first = reconstruct_grid(SessionReader(dir), cal, {}, &stats);
  const RangeGrid second = reconstruct_grid(SessionReader(dir), cal);
  EXPECT_EQ(encode_grid(first), encode_grid(second));
  EXPECT_EQ(stats.steps, kSteps);
  // Both lasers find the head in most rows of every frame (it fills about half the image height).
  EXPECT_GT(stats.peaks, kSteps * 2 * kHeadHeight / 4);
  EXPECT_GT(first.valid_count(), 0u);
  fs::remove_all(dir);
}

struct FaultCase {
  const char* name;
  sim::BoardFaults board;
  sim::CameraFaults camera;
  const char* device;
  const char* problem;
};

// Board command numbers: 3 at connect (feed, G90, M17); each step sends 2 lasers off, the move,
// and on/off per laser: 7 commands, so 3 + 7 * 10 + 3 is step 10's move. Camera frames: 6 per
// step (each kept frame follows a discarded one).
constexpr int kStep10Move = 3 + 7 * 10 + 3;

TEST(EmulatedScan, EveryFaultNamesDeviceAndStepAndResumesToTheSameSession) {
  const fs::path reference = scratch("reference");
  {
    Rig rig(0);
    ASSERT_EQ(rig.scan(reference, 0, kFaultSteps).steps_done, kFaultSteps);
  }
  const char* usb = "usb 001:002 (2341:0043)";
  const std::vector<FaultCase> cases = {
      {"board unplug", {.unplug_at_command = kStep10Move}, {}, usb, "unplugged"},
      {"stalled endpoint", {.stall_at_command = kStep10Move + 2}, {}, usb, "endpoint stalled"},
      {"move never completes", {.hang_move_at_command = kStep10Move}, {}, usb, "no 'ok' for 'G1 X"},
      {"camera EIO", {}, {.eio_at_sequence = 40}, "/dev/video0", "I/O error (EIO)"},
      {"camera unplug", {}, {.unplug_at_sequence = 100}, "/dev/video0", "unplugged"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path dir = scratch("fault");
    std::size_t failed_at = 0;
    {
      Rig rig(0, c.board, c.camera);
      try {
        rig.scan(dir, 0, kFaultSteps);
        ADD_FAILURE() << "no error";
      } catch (const DeviceError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.device(), c.device) << what;
        EXPECT_NE(what.find(c.problem), std::string::npos) << what;
        failed_at = read_session_manifest(dir).steps.size();
        EXPECT_NE(what.find("step " + std::to_string(failed_at) + " of 30: "), std::string::npos)
            << what;
      }
    }
    EXPECT_GT(failed_at, 0u);
    EXPECT_LT(failed_at, kFaultSteps);
    const double angle = last_step_angle(dir);
    Rig rig(angle);
    const CaptureReport r = rig.scan(dir, angle, kFaultSteps);
    EXPECT_EQ(r.first_step, failed_at);
    EXPECT_EQ(r.steps_done, kFaultSteps);
    EXPECT_TRUE(test::sessions_identical(dir, reference));
    fs::remove_all(dir);
  }
  // Lost and garbled acknowledgements are retried, dropped frames counted: same session.
  const fs::path dir = scratch("absorbed");
  {
    Rig rig(0, {.drop_ok_at_command = kStep10Move + 1, .garble_ok_at_command = kStep10Move},
            {.drop_sequences = {10, 11, 50}});
    const CaptureReport r = rig.scan(dir, 0, kFaultSteps);
    EXPECT_EQ(r.steps_done, kFaultSteps);
    EXPECT_EQ(r.dropped_frames, 3u);
  }
  EXPECT_TRUE(test::sessions_identical(dir, reference));
  fs::remove_all(dir);
  fs::remove_all(reference);
}

// Fault and --resume on the head scene: the resumed session (the board told where the table
// stands with one G92) equals the uninterrupted one byte for byte.
TEST(EmulatedScan, HeadScanResumedAfterFaultsEqualsTheUninterruptedOne) {
  constexpr std::size_t kHeadFaultSteps = 12;
  const sim::RigConfig rig = sim::rig_at_size(sim::builtin_ciclop_rig(), kHeadWidth, kHeadHeight);
  auto scene = std::make_shared<sim::Scene>(sim::builtin_head_scene());
  auto camera = std::make_shared<sim::TurntableCamera>(*scene, rig);
  const sim::FrameRenderer head = [scene, camera](double angle, unsigned mask) {
    return camera->render(angle, mask);
  };
  const fs::path reference = scratch("head_reference");
  {
    Rig emulated(0, {}, {}, head, kHeadWidth, kHeadHeight, kHeadCameraTimeScale);
    ASSERT_EQ(emulated.scan(reference, 0, kHeadFaultSteps, 0).steps_done, kHeadFaultSteps);
    EXPECT_EQ(emulated.firmware->position_declarations(), 0);
  }
  // Step 6's move and the command after step 3's move (3 commands at connect, 7 per step, the
  // move third). Board faults, since command numbers are deterministic; frame sequence numbers
  // are not (the camera flushes ready frames before each grab), and camera faults are covered
  // by EveryFaultNamesDeviceAndStepAndResumesToTheSameSession.
  const std::vector<FaultCase> cases = {
      {"board unplug",
       {.unplug_at_command = 3 + 7 * 6 + 3},
       {},
       "usb 001:002 (2341:0043)",
       "unplugged"},
      {"stalled endpoint",
       {.stall_at_command = 3 + 7 * 3 + 4},
       {},
       "usb 001:002 (2341:0043)",
       "endpoint stalled"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path dir = scratch("head_fault");
    {
      Rig emulated(0, c.board, c.camera, head, kHeadWidth, kHeadHeight, kHeadCameraTimeScale);
      try {
        emulated.scan(dir, 0, kHeadFaultSteps, 0);
        ADD_FAILURE() << "no error";
      } catch (const DeviceError& e) {
        EXPECT_EQ(e.device(), c.device) << e.what();
        EXPECT_NE(std::string(e.what()).find(c.problem), std::string::npos) << e.what();
      }
    }
    const std::size_t failed_at = read_session_manifest(dir).steps.size();
    EXPECT_GT(failed_at, 0u);
    EXPECT_LT(failed_at, kHeadFaultSteps);
    const double angle = last_step_angle(dir);
    Rig emulated(angle, {}, {}, head, kHeadWidth, kHeadHeight, kHeadCameraTimeScale);
    const CaptureReport r = emulated.scan(dir, angle, kHeadFaultSteps, 0);
    EXPECT_EQ(r.first_step, failed_at);
    EXPECT_EQ(r.steps_done, kHeadFaultSteps);
    EXPECT_EQ(emulated.firmware->position_declarations(), 1);
    EXPECT_TRUE(test::sessions_identical(dir, reference));
    fs::remove_all(dir);
  }
  fs::remove_all(reference);
}

}  // namespace
}  // namespace scanmesh
