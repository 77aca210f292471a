// `scanmesh scan --sim --calibration` records a calibration session through the device path (the
// simulated board behind a pty, the simulated camera rendering the chessboard in each pose) and
// `scanmesh calibrate SESSION` computes the calibration from the recorded frames; the result is
// compared with the simulated rig. Bad or missing sessions are bad files (exit 4) named in the
// message. 640 x 480 frames keep the run short (docs/acquisition.md, "Calibration sessions").
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "../acquisition/session_compare.h"
#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/acquisition/session.h"
#include "scanmesh/sim/turntable_camera.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr int kWidth = 640, kHeight = 480;

const fs::path kBinary = fs::path(SCANMESH_BINARY_DIR) / "apps" / "scanmesh";

struct RunResult {
  int exit_code = -1;
  std::string output;
};

RunResult run(const std::string& args) {
  RunResult result;
  FILE* pipe = popen((kBinary.string() + " " + args + " 2>&1 </dev/null").c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

fs::path scratch(const std::string& name) {
  const fs::path base =
      fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
  const fs::path d = base / ("scanmesh_test_calcli_" + std::to_string(getpid())) / name;
  fs::remove_all(d);
  fs::create_directories(d.parent_path());
  return d;
}

// The simulated rig of `scan --sim` at 640 x 480: the built-in rig, intrinsics scaled with the
// sensor (sim::rig_at_size, which scan --sim renders with).
sim::RigConfig truth_rig() { return sim::rig_at_size(sim::builtin_ciclop_rig(), kWidth, kHeight); }

class CalibrationCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    session_ = new fs::path(scratch("calib_session"));
    yaml_ = new fs::path(session_->parent_path() / "calib.yaml");
    const RunResult scan =
        run("scan --sim --calibration --poses 3 --handheld 8 --pose-angle-step 14 --size 640x480 "
            "--time-scale 0.01 --settle 0.02 --out " +
            session_->string());
    ASSERT_EQ(scan.exit_code, 0) << scan.output;
    calibrate_ =
        new RunResult(run("calibrate " + session_->string() + " --out " + yaml_->string()));
  }
  static void TearDownTestSuite() {
    fs::remove_all(session_->parent_path());
    delete session_;
    delete yaml_;
    delete calibrate_;
  }
  static fs::path* session_;
  static fs::path* yaml_;
  static RunResult* calibrate_;
};
fs::path* CalibrationCli::session_ = nullptr;
fs::path* CalibrationCli::yaml_ = nullptr;
RunResult* CalibrationCli::calibrate_ = nullptr;

// One test for the expensive scan + calibrate set-up: ctest runs each test in its own process, so
// three tests paid for it three times (~80 s each).
TEST_F(CalibrationCli, RecordedSessionCalibratesAndBadSessionsAreNamed) {
  {
    SCOPED_TRACE("SessionIsMarkedAndCarriesThePattern");
    const SessionReader reader(*session_);
    ASSERT_TRUE(reader.complete());
    const auto& h = reader.manifest().header;
    ASSERT_TRUE(h.calibration.has_value());
    EXPECT_EQ(h.calibration->pattern.corner_cols, 11);
    EXPECT_EQ(h.calibration->pattern.corner_rows, 6);
    EXPECT_EQ(h.calibration->pattern.square_mm, 13.0);
    EXPECT_EQ(h.calibration->poses.size(), 3u + 8u);
    EXPECT_EQ(h.step_count, 3u * 11u + 8u);
    // Every step was recorded at its planned angle.
    for (std::size_t i = 0; i < reader.step_count(); ++i)
      EXPECT_NEAR(reader.manifest().steps[i].angle_rad, h.step_angle(i), 0.2 / kDeg) << i;
    // reconstruct refuses a calibration session.
    const RunResult r = run("reconstruct " + session_->string() + " --calib " + yaml_->string() +
                            " --out " + (session_->parent_path() / "x.smg").string());
    EXPECT_EQ(r.exit_code, 4) << r.output;
    EXPECT_NE(r.output.find("calibration session"), std::string::npos) << r.output;
  }
  {
    SCOPED_TRACE("CalibrationFromTheRecordedSessionMatchesTheRig");
    ASSERT_EQ(calibrate_->exit_code, 0) << calibrate_->output;
    std::printf("%s", calibrate_->output.c_str());
    const Calibration c = Calibration::read_yaml(*yaml_);
    const sim::RigConfig rig = truth_rig();
    const sim::Scene unused = sim::Scene::from_yaml_text(
        "objects:\n  - {type: sphere, name: unused, center: [0, 0, -1000], radius: 1}\n", "unused");
    const sim::TurntableCamera camera(unused, rig);
    const auto& t = rig.intrinsics;
    std::printf("  fx %.3f (true %.3f)  fy %.3f (%.3f)  cx %.3f (%.3f)  cy %.3f (%.3f)\n",
                c.camera.fx, t.fx, c.camera.fy, t.fy, c.camera.cx, t.cx, c.camera.cy, t.cy);
    EXPECT_LT(std::abs(c.camera.fx / t.fx - 1.0), 0.002);
    EXPECT_LT(std::abs(c.camera.fy / t.fy - 1.0), 0.002);
    EXPECT_LT(std::abs(c.camera.cx - t.cx), 1.0);
    EXPECT_LT(std::abs(c.camera.cy - t.cy), 1.0);
    const Eigen::Isometry3d cam_from_rig = camera.camera_from_rig();
    ASSERT_EQ(c.lasers.size(), 2u);
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d n_true = cam_from_rig.linear() * rig.lasers[k].normal;
      const double angle =
          std::acos(std::min(1.0, std::abs(n_true.dot(c.lasers[k].normal)))) * kDeg;
      std::printf("  laser %d: normal off by %.4f deg (sigma %.4f)\n", k, angle,
                  c.uncertainty.laser_normal_deg[k]);
      EXPECT_LT(angle, 0.1);
    }
    const Eigen::Vector3d a_true = cam_from_rig.linear() * Eigen::Vector3d::UnitZ();
    const double axis_angle = std::acos(std::min(1.0, a_true.dot(c.axis_direction))) * kDeg;
    double axis_off = 0;
    for (double z : {0.0, 100.0, 200.0}) {
      const Eigen::Vector3d q = cam_from_rig * Eigen::Vector3d(0, 0, z);
      const Eigen::Vector3d d = q - c.axis_origin_mm;
      axis_off = std::max(axis_off, (d - d.dot(c.axis_direction) * c.axis_direction).norm());
    }
    std::printf(
        "  axis: direction off by %.4f deg (sigma %.4f), line off by %.4f mm (sigma %.4f)\n",
        axis_angle, c.uncertainty.axis_direction_deg, axis_off, c.uncertainty.axis_point_mm);
    // Half the built-in resolution: one pixel is 0.56 mm at the axis, twice the 1280 x 960 rig's,
    // and the leaning boards at +-70 degrees are too small to detect, so the fit's own sigma of the
    // axis line is ~0.28 mm here (0.08 mm at full resolution, where test_calibration checks the
    // issue's 0.1 mm). Asserted: the axis within 0.5 mm and within 3 sigma of its own uncertainty
    // (the reported uncertainty is honest), the normals and axis direction within 0.1 degrees.
    EXPECT_LT(axis_angle, 0.1);
    EXPECT_LT(axis_off, 0.5);
    EXPECT_LT(axis_off, 3.0 * c.uncertainty.axis_point_mm);
  }
  {
    SCOPED_TRACE("BadOrMissingSessionsAreBadFilesNamed");
    const fs::path dir = session_->parent_path();
    const std::string out = " --out " + (dir / "bad.yaml").string();
    // No such folder.
    RunResult r = run("calibrate " + (dir / "missing").string() + out);
    EXPECT_EQ(r.exit_code, 4) << r.output;
    EXPECT_NE(r.output.find("missing"), std::string::npos) << r.output;
    // A scan session is not a calibration session.
    const fs::path scan = dir / "scan";
    ASSERT_EQ(run("scan --sim --steps 2 --size 32x24 --time-scale 0.01 --settle 0.01 --out " +
                  scan.string())
                  .exit_code,
              0);
    r = run("calibrate " + scan.string() + out);
    EXPECT_EQ(r.exit_code, 4) << r.output;
    EXPECT_NE(r.output.find("session.json"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("not a calibration session"), std::string::npos) << r.output;
    // A damaged pattern block.
    const fs::path broken = dir / "broken";
    fs::create_directories(broken);
    for (const auto& e : fs::directory_iterator(*session_))
      if (e.is_regular_file()) fs::copy_file(e.path(), broken / e.path().filename());
    fs::create_directory_symlink(fs::absolute(*session_ / "frames"), broken / "frames");
    {
      std::ifstream in(broken / "session.json");
      std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const auto pos = text.find("\"square_mm\"");
      ASSERT_NE(pos, std::string::npos);
      text.replace(pos, 11, "\"square_cm\"");
      std::ofstream(broken / "session.json", std::ios::trunc) << text;  // non-atomic: test input
    }
    r = run("calibrate " + broken.string() + out);
    EXPECT_EQ(r.exit_code, 4) << r.output;
    EXPECT_NE(r.output.find("session.json"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("square_mm"), std::string::npos) << r.output;
    // A damaged frame names the frame file.
    const fs::path damaged = dir / "damaged";
    fs::copy(*session_, damaged, fs::copy_options::recursive);
    const fs::path frame = damaged / "frames" / "000005_off.png";
    fs::resize_file(frame, fs::file_size(frame) / 2);
    r = run("calibrate " + damaged.string() + out);
    EXPECT_EQ(r.exit_code, 4) << r.output;
    EXPECT_NE(r.output.find("000005_off.png"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad.yaml"));
  }
}

TEST(CalibrationCliResume, InterruptedPoseStartsOverAndGivesTheSameSession) {
  // Two placements, 5 angles each (steps 0..4, 5..9). Board commands: 3 at connect, then 7 per
  // step; command 3 + 7 * 6 + 3 = 48 is the move of step 6, inside pose 2.
  const std::string cal =
      "scan --sim --calibration --poses 2 --pose-angle-step 35 --size 64x48 --time-scale 0.01 "
      "--settle 0.01";
  const fs::path reference = scratch("resume_reference");
  ASSERT_EQ(run(cal + " --out " + reference.string()).exit_code, 0);
  const fs::path dir = scratch("resume");
  const RunResult failed = run(cal + " --out " + dir.string() + " --sim-fault board-unplug@48");
  EXPECT_EQ(failed.exit_code, 7) << failed.output;
  EXPECT_NE(failed.output.find("step 6 of 10"), std::string::npos) << failed.output;
  EXPECT_EQ(read_session_manifest(dir).steps.size(), 6u);
  // Resuming needs only --calibration: the plan is the session's own.
  const RunResult resumed =
      run("scan --sim --calibration --size 64x48 --time-scale 0.01 --settle 0.01 --resume --out " +
          dir.string());
  EXPECT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resumed at step 5"), std::string::npos) << resumed.output;
  EXPECT_TRUE(test::sessions_identical(dir, reference));
  // A scan session cannot be resumed as a calibration session.
  const RunResult wrong =
      run("scan --sim --size 64x48 --time-scale 0.01 --resume --out " + dir.string());
  EXPECT_EQ(wrong.exit_code, 3) << wrong.output;
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace scanmesh
