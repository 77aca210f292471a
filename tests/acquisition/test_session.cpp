// The session folder: manifest round trip, torn lines, resume, CRC checks, replay.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <numbers>

#include "core/test_util.h"
#include "scanmesh/acquisition/session.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"
#include "scanmesh/sim/sim_camera.h"
#include "session_compare.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

// A folder in this test process's own temporary directory, which goes when the process ends
// (it used to stay behind in /tmp, one per test run).
fs::path scratch(const std::string& name) {
  static const test::TempDir root;
  const fs::path d = root / name;
  fs::remove_all(d);
  return d;
}

SessionHeader small_header(std::size_t steps = 4) {
  SessionHeader h;
  h.step_count = steps;
  h.laser_count = 2;
  h.camera = {"/dev/video9", "Cam", "uvcvideo", "usb-1", 32, 24, drivers::PixelFormat::Rgb24, 30};
  h.board_device = "/dev/ttyACM0";
  h.board_dialect = "horus";
  h.board_firmware = "Horus 0.2 ['$' for help]";
  return h;
}

std::vector<drivers::Frame> frames_for(std::size_t step, const sim::FrameRenderer& render,
                                       double angle) {
  std::vector<drivers::Frame> frames;
  for (unsigned mask : {0u, 1u, 2u}) {
    drivers::Frame f;
    f.rgb = render(angle, mask);
    f.sequence = static_cast<std::uint32_t>(step * 3 + mask);
    f.timestamp_s = 100.0 + step;
    frames.push_back(f);
  }
  return frames;
}

TEST(Session, RecordsAndReplaysStepsExactly) {
  const fs::path dir = scratch("roundtrip");
  const auto render = sim::synthetic_turntable_renderer(32, 24);
  SessionWriter w = SessionWriter::create(dir, small_header());
  for (std::size_t i = 0; i < 4; ++i)
    w.append_step(w.header().step_angle(i), frames_for(i, render, w.header().step_angle(i)));
  EXPECT_TRUE(w.complete());
  const SessionReader r(dir);
  ASSERT_EQ(r.step_count(), 4u);
  EXPECT_EQ(r.laser_count(), 2);
  EXPECT_EQ(r.manifest().header.camera.card, "Cam");
  for (std::size_t i = 0; i < 4; ++i) {
    const ScanStep s = r.step(i);
    EXPECT_DOUBLE_EQ(s.angle_rad, i * std::numbers::pi / 2);
    EXPECT_EQ(s.laser_off.pixels, render(s.angle_rad, 0).pixels);
    ASSERT_EQ(s.laser_on.size(), 2u);
    EXPECT_EQ(s.laser_on[0].pixels, render(s.angle_rad, 1).pixels);
    EXPECT_EQ(s.laser_on[1].pixels, render(s.angle_rad, 2).pixels);
    EXPECT_DOUBLE_EQ(s.timestamp_s, 100.0 + i);
  }
  // Replay is deterministic: a second reader yields the same pixels.
  EXPECT_EQ(SessionReader(dir).step(2).laser_on[1].pixels, r.step(2).laser_on[1].pixels);
  fs::remove_all(dir);
}

TEST(Session, TornLastLineIsDroppedOnResume) {
  const fs::path dir = scratch("torn");
  const auto render = sim::synthetic_turntable_renderer(32, 24);
  {
    SessionWriter w = SessionWriter::create(dir, small_header());
    for (std::size_t i = 0; i < 2; ++i)
      w.append_step(w.header().step_angle(i), frames_for(i, render, w.header().step_angle(i)));
  }
  const auto complete_size = fs::file_size(dir / "steps.jsonl");
  { std::ofstream(dir / "steps.jsonl", std::ios::app) << "{\"step\":2,\"angle_rad\":3.1"; }
  { std::ofstream(dir / "frames" / "000002_off.png") << "half a png"; }
  EXPECT_EQ(read_session_manifest(dir).steps.size(), 2u);
  SessionWriter w = SessionWriter::resume(dir);
  EXPECT_EQ(w.steps_done(), 2u);
  EXPECT_EQ(fs::file_size(dir / "steps.jsonl"), complete_size);
  EXPECT_FALSE(fs::exists(dir / "frames" / "000002_off.png"));
  for (std::size_t i = 2; i < 4; ++i)
    w.append_step(w.header().step_angle(i), frames_for(i, render, w.header().step_angle(i)));
  // The same as a session written without interruption.
  const fs::path ref = scratch("torn_ref");
  SessionWriter rw = SessionWriter::create(ref, small_header());
  for (std::size_t i = 0; i < 4; ++i)
    rw.append_step(rw.header().step_angle(i), frames_for(i, render, rw.header().step_angle(i)));
  EXPECT_TRUE(test::sessions_identical(dir, ref));
  fs::remove_all(dir);
  fs::remove_all(ref);
}

TEST(Session, DamagedFrameIsAFileFormatError) {
  const fs::path dir = scratch("damaged");
  const auto render = sim::synthetic_turntable_renderer(32, 24);
  SessionWriter w = SessionWriter::create(dir, small_header());
  w.append_step(0, frames_for(0, render, 0));
  Image8 other = render(1.0, 1);
  write_png(dir / "frames" / "000000_laser0.png", other);
  const SessionReader r(dir);
  EXPECT_THROW(r.step(0), FileFormatError);
  fs::remove_all(dir);
}

TEST(Session, MjpegStorageKeepsTheCameraBytesUnchanged) {
  const fs::path dir = scratch("mjpeg");
  SessionHeader h = small_header(1);
  h.storage = FrameStorage::Mjpeg;
  h.camera.format = drivers::PixelFormat::Mjpeg;
  const auto render = sim::synthetic_turntable_renderer(32, 24);
  std::vector<drivers::Frame> frames;
  for (unsigned mask : {0u, 1u, 2u}) {
    drivers::Frame f;
    f.original = encode_jpeg(render(0.5, mask), 85);
    f.rgb = drivers::decode_frame(drivers::PixelFormat::Mjpeg, f.original, 32, 24);
    frames.push_back(f);
  }
  SessionWriter w = SessionWriter::create(dir, h);
  w.append_step(0, frames);
  EXPECT_EQ(read_file_bytes(dir / "frames" / "000000_laser1.jpg"), frames[2].original);
  const ScanStep s = SessionReader(dir).step(0);
  EXPECT_EQ(s.laser_on[1].pixels, frames[2].rgb.pixels);
  EXPECT_EQ(s.laser_off.pixels, frames[0].rgb.pixels);
  fs::remove_all(dir);
}

TEST(Session, RefusesToOverwriteAnExistingSession) {
  const fs::path dir = scratch("exists");
  SessionWriter::create(dir, small_header());
  EXPECT_THROW(SessionWriter::create(dir, small_header()), InvalidInputError);
  fs::remove_all(dir);
}

TEST(SessionManifest, RejectsMalformedInput) {
  const std::string header = header_to_json(small_header());
  EXPECT_NO_THROW(parse_session_manifest(header, ""));
  EXPECT_THROW(parse_session_manifest("{", ""), FileFormatError);
  EXPECT_THROW(parse_session_manifest("[]", ""), FileFormatError);
  std::string bad = header;
  bad.replace(bad.find("\"step_count\": 4"), 15, "\"step_count\": -4");
  EXPECT_THROW(parse_session_manifest(bad, ""), FileFormatError);
  // A step out of order, a complete line that is not JSON, a wrong frame count.
  EXPECT_THROW(parse_session_manifest(header, "{\"step\":1,\"angle_rad\":0,\"frames\":[]}\n"),
               FileFormatError);
  EXPECT_THROW(parse_session_manifest(header, "garbage\n"), FileFormatError);
  EXPECT_THROW(parse_session_manifest(header, "{\"step\":0,\"angle_rad\":0,\"frames\":[]}\n"),
               FileFormatError);
  // A torn line (no newline) is not an error: it is a step that never completed.
  EXPECT_EQ(parse_session_manifest(header, "{\"step\":0,\"ang").steps.size(), 0u);
}

TEST(Session, CalibrationSessionRoundTripAndRewind) {
  const fs::path dir = scratch("calibration");
  SessionHeader h = small_header(5);
  CalibrationSessionInfo info;
  info.pattern = {9, 7, 20.0, 30.0};
  info.poses.push_back({true, "upright", {-0.5, 0.0, 0.5}});
  info.poses.push_back({false, "held", {0.0}});
  info.poses.push_back({true, "leaning", {0.25}});
  h.calibration = info;
  const auto render = sim::synthetic_turntable_renderer(32, 24);
  {
    SessionWriter w = SessionWriter::create(dir, h);
    for (std::size_t i = 0; i < 5; ++i)
      w.append_step(w.header().step_angle(i), frames_for(i, render, w.header().step_angle(i)));
    // A resumed capture of pose 1 (step 3) starts the pose over: steps 3 and 4 go.
    w.rewind(3);
    EXPECT_EQ(w.steps_done(), 3u);
  }
  EXPECT_FALSE(fs::exists(dir / "frames" / "000003_off.png"));
  EXPECT_TRUE(fs::exists(dir / "frames" / "000002_off.png"));
  SessionWriter w = SessionWriter::resume(dir);
  EXPECT_EQ(w.steps_done(), 3u);
  w.append_step(w.header().step_angle(3), frames_for(3, render, 0.0));
  const SessionReader r(dir);
  ASSERT_TRUE(r.manifest().header.calibration.has_value());
  const CalibrationSessionInfo& c = *r.manifest().header.calibration;
  EXPECT_EQ(c.pattern.corner_cols, 9);
  EXPECT_EQ(c.pattern.corner_rows, 7);
  EXPECT_EQ(c.pattern.square_mm, 20.0);
  EXPECT_EQ(c.pattern.bottom_mm, 30.0);
  ASSERT_EQ(c.poses.size(), 3u);
  EXPECT_FALSE(c.poses[1].on_platter);
  EXPECT_EQ(c.poses[2].description, "leaning");
  EXPECT_EQ(c.step(4).first, 2u);
  EXPECT_EQ(c.first_step(2), 4u);
  EXPECT_DOUBLE_EQ(r.manifest().header.step_angle(4), 0.25);
  EXPECT_DOUBLE_EQ(r.manifest().steps[1].angle_rad, 0.0);
  EXPECT_EQ(r.step_count(), 4u);
  // A scan session has no "kind" (as every session written before calibration sessions).
  EXPECT_EQ(header_to_json(small_header()).find("\"kind\""), std::string::npos);
  const std::string text = header_to_json(h);
  auto bad = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto pos = t.find(from);
    ASSERT_NE(pos, std::string::npos) << from;
    t.replace(pos, from.size(), to);
    EXPECT_THROW(parse_session_manifest(t, "", dir), FileFormatError) << to;
  };
  bad("\"kind\": \"calibration\"", "\"kind\": \"other\"");
  bad("\"step_count\": 5", "\"step_count\": 6");
  bad("\"placement\": \"handheld\"", "\"placement\": \"floor\"");
  bad("\"corner_cols\": 9", "\"corner_cols\": 2");
  bad("\"square_mm\": 20.0", "\"square_mm\": -1.0");
  bad("\"type\": \"chessboard\"", "\"type\": \"charuco\"");
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace scanmesh
