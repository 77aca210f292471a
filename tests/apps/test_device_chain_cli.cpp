// The device path through the command line at a small size: `scan --sim --scene head` (the
// simulated board behind the real termios driver on a pty + the simulated turntable camera) ->
// `calibrate --sim --size` -> `reconstruct SESSION`, checked against the direct range simulator
// of the same scene; and `check-calibration`, which must pass with the calibration `calibrate`
// produced and fail with the same calibration's laser plane tilted.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "cli_runner.h"
#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

// 320 x 240 frames (fx 358 px, 1.1 mm per pixel at the axis): small enough for a test, the
// 11 x 6 chessboard is still found in most calibration views.
const std::string kSize = "320x240";

using test::run;
using test::RunResult;

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

class DeviceChainCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() /
                        ("scanmesh_test_device_chain_" + std::to_string(getpid())));
    fs::remove_all(*dir_);
    fs::create_directories(*dir_);
    // One calibration for every test: calibrate --sim renders the chessboard views of the rig
    // that scan --sim renders the scene with (the built-in rig scaled to the frame size); fewer
    // views than the defaults, to keep the test short.
    const RunResult r =
        run("calibrate --sim --size " + kSize + " --handheld 10 --angle-step 10 --out " +
            (*dir_ / "calib.yaml").string());
    calibrate_output_ = new std::string(r.output);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete calibrate_output_;
  }
  static fs::path* dir_;
  static std::string* calibrate_output_;
};
fs::path* DeviceChainCli::dir_ = nullptr;
std::string* DeviceChainCli::calibrate_output_ = nullptr;

TEST_F(DeviceChainCli, ScanCalibrateReconstructMatchesTheDirectRangeSimulator) {
  const fs::path calib = *dir_ / "calib.yaml";
  ASSERT_TRUE(fs::exists(calib)) << *calibrate_output_;
  const Calibration cal = Calibration::read_yaml(calib);
  EXPECT_EQ(cal.camera.width, 320);
  EXPECT_EQ(cal.camera.height, 240);
  // The scaled rig's focal length (1430 px at 1280 x 960) recovered within 1 %.
  EXPECT_NEAR(cal.camera.fx, 1430.0 / 4, 3.6);

  const fs::path session = *dir_ / "head_session";
  const RunResult scan = run("scan --sim --scene head --steps 24 --size " + kSize +
                             " --time-scale 0.001 --out " + session.string());
  ASSERT_EQ(scan.exit_code, 0) << scan.output;
  ASSERT_TRUE(fs::exists(session / "session.json"));

  // 48 columns (7.5 degrees: both lasers' lines of 24 steps), 1.8 mm rows. (Much coarser
  // grids leave single lines per column, which the hair and fragment filters rightly distrust.)
  const int n_phi = 48, n_h = 128;
  const double dh = 1.8;
  const fs::path grid_file = *dir_ / "head.smg";
  const RunResult rec = run("reconstruct " + session.string() + " --calib " + calib.string() +
                            " --n-phi " + std::to_string(n_phi) + " --n-h " + std::to_string(n_h) +
                            " --dh 1.8 --out " + grid_file.string());
  ASSERT_EQ(rec.exit_code, 0) << rec.output;
  const RangeGrid grid = read_grid(grid_file);
  ASSERT_EQ(grid.n_phi(), n_phi);
  ASSERT_EQ(grid.n_h(), n_h);

  // The direct range simulator of the same scene on the same grid, without noise or defects.
  sim::ScannerConfig sc;
  sc.n_phi = n_phi;
  sc.n_h = n_h;
  sc.h0_mm = 0.0;
  sc.dh_mm = dh;
  sc.grazing_dropout = false;
  sc.hair = false;
  sc.height_band = false;
  const sim::SimulatedScan direct = sim::simulate_scan(sim::builtin_head_scene(), sc);
  double ss = 0;
  std::size_t both = 0, far = 0;
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      if (!grid.valid(i, j) || !direct.grid.valid(i, j)) continue;
      const double d = grid.radius(i, j) - direct.grid.radius(i, j);
      ss += d * d;
      far += std::abs(d) > 3.0;
      ++both;
    }
  const double rms = std::sqrt(ss / static_cast<double>(std::max<std::size_t>(both, 1)));
  std::printf(
      "  device chain at %s: %zu device cells, %zu direct cells, %zu in both, RMS %.3f mm,"
      " %zu cells off by > 3 mm\n",
      kSize.c_str(), grid.valid_count(), direct.grid.valid_count(), both, rms, far);
  // Coverage: the direct simulator measures every cell its (ideal) camera sees, the top of the
  // head included; 24 steps of two lasers at 320 x 240 fill about half the columns' cells, and
  // cleaning drops a third of those at this coarse grid (mostly the hair test). Measured: 34 %.
  EXPECT_GT(static_cast<double>(both), 0.25 * static_cast<double>(direct.grid.valid_count()));
  // Accuracy over the cells valid in both (measured 0.17 mm with the calibration from
  // calibrate --sim at 320 x 240; the 0.2 mm is for full-size frames).
  EXPECT_LT(rms, 0.5);
  EXPECT_LT(static_cast<double>(far), 0.02 * static_cast<double>(both));
}

// Tolerances for 320 x 240 frames and 24 steps (the defaults, 0.05 / 0.1 / 0.1 mm, are the
// issue's for 640 x 480 and 72 steps).
const std::string kCheck = "check-calibration --sim --size " + kSize +
                           " --steps 24 --max-radius-error 0.25 --max-rms 0.4 "
                           "--max-spacing-error 0.5";

TEST_F(DeviceChainCli, CheckCalibrationPassesWithTheCalibration) {
  const fs::path calib = *dir_ / "calib.yaml";
  ASSERT_TRUE(fs::exists(calib)) << *calibrate_output_;
  const fs::path report = *dir_ / "check_good.json";
  const RunResult r = run(kCheck + " --calib " + calib.string() + " --report " + report.string());
  std::printf("%s", r.output.c_str());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = read_json(report);
  EXPECT_TRUE(j["pass"].get<bool>());
  EXPECT_NEAR(j["sphere"]["radius_mm"].get<double>(), 50.0, 0.25);
  EXPECT_LT(j["sphere"]["rms_distance_mm"].get<double>(), 0.4);
  // The sphere stands on the axis at 70 mm: its fitted centre is there too.
  const auto c = j["sphere"]["centre_mm"];
  EXPECT_NEAR(c[0].get<double>(), 0.0, 0.5);
  EXPECT_NEAR(c[1].get<double>(), 0.0, 0.5);
  EXPECT_NEAR(c[2].get<double>(), 70.0, 0.5);
  EXPECT_NEAR(j["dumbbell"]["spacing_mm"].get<double>(), 90.0, 0.5);
  EXPECT_GT(j["dumbbell"]["ball_1"]["points"].get<int>(), 150);
  EXPECT_GT(j["dumbbell"]["ball_2"]["points"].get<int>(), 150);
}

TEST_F(DeviceChainCli, CheckCalibrationFailsWithATiltedLaserPlane) {
  const fs::path calib = *dir_ / "calib.yaml";
  ASSERT_TRUE(fs::exists(calib)) << *calibrate_output_;
  // Tilt the first laser's plane by 2 degrees about a horizontal line through its point nearest
  // the camera: the kind of error a knocked laser module makes.
  Calibration cal = Calibration::read_yaml(calib);
  LaserPlane& l = cal.lasers.at(0);
  const Eigen::Vector3d p0 = l.normal * l.distance_mm;
  const Eigen::Vector3d axis = l.normal.cross(cal.axis_direction).normalized();
  l.normal = Eigen::AngleAxisd(2.0 * std::numbers::pi / 180.0, axis) * l.normal;
  l.distance_mm = l.normal.dot(p0);
  const fs::path bad = *dir_ / "calib_tilted.yaml";
  cal.write_yaml(bad);
  const fs::path report = *dir_ / "check_bad.json";
  const RunResult r = run(kCheck + " --calib " + bad.string() + " --report " + report.string());
  std::printf("%s", r.output.c_str());
  EXPECT_EQ(r.exit_code, 8) << r.output;
  EXPECT_NE(r.output.find("FAIL"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(report);
  EXPECT_FALSE(j["pass"].get<bool>());
  EXPECT_FALSE(j["failures"].empty());
  // The tilted plane's laser disagrees with the other one: the sphere is measured wrong.
  EXPECT_GT(std::abs(j["sphere"]["radius_error_mm"].get<double>()), 0.25);
}

TEST(DeviceDemo, RunsTheDevicePathAndComparesWithTheDirectRangeSimulator) {
  // demo --device-sim at a small size: every stage runs (scan, calibrate, reconstruct, mesh,
  // pictures) and the report compares the grid with the direct range simulator. 16 steps on a
  // 32-column grid (11.25 degrees) interpolate across features: measured RMS 0.63 mm.
  const fs::path out =
      fs::temp_directory_path() / ("scanmesh_test_device_demo_" + std::to_string(getpid()));
  fs::remove_all(out);
  const RunResult r = run("demo --device-sim --steps 16 --size " + kSize +
                          " --n-phi 32 --n-h 128 --dh 1.8 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f :
       {"session/session.json", "calibration.yaml", "scan.smg", "direct.smg", "mesh.ply",
        "mesh.obj", "texture.png", "render.png", "curvature.png", "report.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const nlohmann::json j = read_json(out / "report.json");
  const auto& c = j["comparison_with_direct_range_simulator"];
  EXPECT_GT(c["coverage_of_direct_grid"].get<double>(), 0.2);
  EXPECT_LT(c["rms_difference_mm"].get<double>(), 1.0);
  EXPECT_EQ(c["cells_valid_in_both"].get<std::size_t>(),
            j["grid"]["valid_cells"].get<std::size_t>() -
                c["cells_valid_only_in_device_grid"].get<std::size_t>());
  EXPECT_GT(j["grid_mesh"]["mesh"]["faces"].get<int>(), 1000);
  EXPECT_EQ(j["device"]["steps"].get<int>(), 16);
  fs::remove_all(out);
}

TEST(CheckCalibrationCli, UsageErrors) {
  // Neither --sim nor a session; a missing calibration file.
  const fs::path dir = fs::temp_directory_path();
  EXPECT_EQ(
      run("check-calibration --sim --calib " + (dir / "no_such_calib.yaml").string()).exit_code, 2);
}

}  // namespace
}  // namespace scanmesh
