// Disk full during a write, without root: the scanmesh child runs with RLIMIT_FSIZE (and SIGXFSZ
// ignored), so any write past the limit fails with EFBIG exactly like ENOSPC on a full disk.
// Every writing command must exit 5 with an I/O error naming the file, leave no partial output
// and no temporary file, and leave an existing output file as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "../acquisition/session_compare.h"
#include "cli_runner.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"

namespace scanmesh::hostile {
namespace {

// Bytes: smaller than every file the commands below write from the 64 x 48 scan. The sanitizer
// tree links clang's libomp, which needs a 1 KB shared-memory file before main, hence 1 KB there.
#ifdef SCANMESH_LLVM_OPENMP
constexpr long long kTinyLimit = 1024;
#else
constexpr long long kTinyLimit = 64;
#endif

// A 64 x 48 scan: big enough that every output (even the depth PNG) exceeds kTinyLimit.
constexpr const char* kScannerYaml =
    "n_phi: 64\nn_h: 48\nradius_mm: 300.0\nh0_mm: 30.0\ndh_mm: 3.0\nnoise_sigma_mm: 0.05\n"
    "spike_probability: 0.0\nband_min_mm: 0.0\nband_max_mm: 212.0\nseed: 3\n";

class DiskFull : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    in_ = new fs::path(scratch_dir("disk_full_inputs"));
    write_text(*in_ / "scanner.yaml", kScannerYaml);
    const RunResult sim =
        run_cli({"sim", "--scene", (kConfigs / "sim" / "sphere.yaml").string(), "--scanner",
                 (*in_ / "scanner.yaml").string(), "--out", (*in_ / "scan.smg").string()});
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    const RunResult mesh =
        run_cli({"grid-mesh", (*in_ / "scan.smg").string(), "--out", (*in_ / "mesh.ply").string()});
    ASSERT_EQ(mesh.exit_code, 0) << mesh.output;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*in_);
    delete in_;
  }

  void SetUp() override {
    out_ = scratch_dir(std::string("disk_full_") +
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { fs::remove_all(out_); }

  // Puts an old version of each output in place, runs `args` with the file-size limit and checks
  // the outcome. `outputs` are paths relative to out_ that the command would write.
  void expect_io_error_and_nothing_lost(const std::vector<std::string>& args,
                                        const std::vector<std::string>& outputs,
                                        long long limit = kTinyLimit) {
    std::map<std::string, std::string> before;
    for (const std::string& o : outputs) {
      fs::create_directories((out_ / o).parent_path());
      const std::string old = "previous content of " + o + ", which must survive\n";
      write_text(out_ / o, old);
      before[o] = old;
    }
    const std::set<std::string> files_before = files_in(out_);
    const RunResult r = run_cli(args, limit);
    EXPECT_EQ(r.exit_code, 5) << describe(args, r);
    EXPECT_NE(r.output.find("scanmesh: I/O error: "), std::string::npos) << describe(args, r);
    // The message names the output that failed (a file in the output folder) and says why.
    EXPECT_NE(r.output.find("'" + out_.string() + "/"), std::string::npos) << describe(args, r);
    EXPECT_TRUE(r.output.find("File too large") != std::string::npos ||
                r.output.find("free disk space") != std::string::npos)
        << describe(args, r);
    EXPECT_FALSE(has_temporary_file(out_)) << describe(args, r);
    for (const auto& [o, old] : before) EXPECT_EQ(read_text(out_ / o), old) << o;
    // Nothing new: every file scanmesh writes is larger than the limit, so none can be complete.
    EXPECT_EQ(files_in(out_), files_before) << describe(args, r);
  }

  std::string in(const char* name) const { return (*in_ / name).string(); }
  std::string out(const std::string& name) const { return (out_ / name).string(); }

  static fs::path* in_;
  fs::path out_;
};
fs::path* DiskFull::in_ = nullptr;

TEST_F(DiskFull, Sim) {
  expect_io_error_and_nothing_lost({"sim", "--scene", (kConfigs / "sim" / "sphere.yaml").string(),
                                    "--scanner", in("scanner.yaml"), "--out", out("scan.smg")},
                                   {"scan.smg"});
}

TEST_F(DiskFull, ExportEveryFormat) {
  std::vector<const char*> outputs = {"--pcd=cloud.pcd", "--ply=cloud.ply", "--texture=t.png"};
#ifndef SCANMESH_LLVM_OPENMP
  outputs.push_back("--depth=d.png");  // ~700 bytes: below the 1 KB limit of the sanitizer tree
#endif
  for (const char* flag_and_name : outputs) {
    const std::string s(flag_and_name);
    const std::string flag = s.substr(0, s.find('=')), name = s.substr(s.find('=') + 1);
    expect_io_error_and_nothing_lost({"export", in("scan.smg"), flag, out(name)}, {name});
  }
}

TEST_F(DiskFull, Clean) {
  expect_io_error_and_nothing_lost({"clean", in("scan.smg"), "--out", out("clean.smg")},
                                   {"clean.smg"});
}

TEST_F(DiskFull, GridMeshEveryFormat) {
  expect_io_error_and_nothing_lost({"grid-mesh", in("scan.smg"), "--out", out("m.ply")}, {"m.ply"});
  expect_io_error_and_nothing_lost({"grid-mesh", in("scan.smg"), "--stl", out("m.stl")}, {"m.stl"});
  expect_io_error_and_nothing_lost({"grid-mesh", in("scan.smg"), "--obj", out("m.obj")}, {"m.obj"});
  expect_io_error_and_nothing_lost({"grid-mesh", in("scan.smg"), "--render", out("r.png")},
                                   {"r.png"});
}

TEST_F(DiskFull, Render) {
  expect_io_error_and_nothing_lost(
      {"render", in("mesh.ply"), "--out", out("r.png"), "--size", "64"}, {"r.png"});
}

TEST_F(DiskFull, Curvature) {
  expect_io_error_and_nothing_lost({"curvature", in("scan.smg"), "--out", out("curv")},
                                   {"curv/fields.smf"});
}

TEST_F(DiskFull, Fans) {
  expect_io_error_and_nothing_lost({"fans", in("scan.smg"), "--out", out("f.ply")}, {"f.ply"});
}

TEST_F(DiskFull, CheckHistogram) {
  expect_io_error_and_nothing_lost({"check", in("mesh.ply"), "--histogram", out("h.png")},
                                   {"h.png"});
}

TEST_F(DiskFull, Particles) {
  expect_io_error_and_nothing_lost(
      {"particles", "--grid", in("scan.smg"), "--edge", "20", "--out", out("p")},
      {"p/particles.ply"});
}

TEST_F(DiskFull, Demo) {
  expect_io_error_and_nothing_lost({"demo", "--scene", (kConfigs / "sim" / "sphere.yaml").string(),
                                    "--scanner", in("scanner.yaml"), "--out", out("demo")},
                                   {"demo/scan_raw.smg"});
}

TEST_F(DiskFull, FailureMidwayThroughTheDemoKeepsEveryFinishedFileWhole) {
  // A limit between the small and the large outputs: the two 37 KB grids are written, the 49 KB
  // PCD after them fails.
  const std::vector<std::string> args = {
      "demo",      "--scene",          (kConfigs / "sim" / "sphere.yaml").string(),
      "--scanner", in("scanner.yaml"), "--out",
      out("demo")};
  const RunResult r = run_cli(args, 40000);
  EXPECT_EQ(r.exit_code, 5) << describe(args, r);
  EXPECT_TRUE(r.output.find("File too large") != std::string::npos ||
              r.output.find("free disk space") != std::string::npos)
      << describe(args, r);
  EXPECT_FALSE(has_temporary_file(out_)) << describe(args, r);
  EXPECT_FALSE(files_in(out_ / "demo").empty()) << "the failure was not midway\n"
                                                << describe(args, r);
  // Whatever was written is whole: every grid and mesh written before the failure reads back.
  for (const std::string& name : files_in(out_ / "demo")) {
    const fs::path p = out_ / "demo" / name;
    if (p.extension() == ".smg") {
      EXPECT_NO_THROW((void)read_grid(p)) << p;
    }
    if (p.extension() == ".ply") {
      EXPECT_NO_THROW((void)read_ply(p)) << p;
    }
  }
}

// --- the commands added since the first round (issue 31) ------------------------------------

TEST_F(DiskFull, Remesh) {
  // Staged outputs are named by their final name, not ".mesh.ply.tmp.PID.N".
  expect_io_error_and_nothing_lost(
      {"remesh", in("mesh.ply"), "--vertices", "100", "--out", out("r")}, {"r/mesh.ply"});
  const RunResult r = run_cli({"remesh", in("mesh.ply"), "--vertices", "100", "--out", out("r2")},
                              kTinyLimit);
  EXPECT_NE(r.output.find("/r2/"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(".tmp."), std::string::npos) << r.output;
}

TEST_F(DiskFull, Import) {
  expect_io_error_and_nothing_lost({"import", in("mesh.ply"), "--out", out("imported.smg")},
                                   {"imported.smg"});
}

// A ring drawn over the 64 x 48 scan (grid pixels, rows from the top).
void write_ring_lines(const fs::path& path) {
  write_text(path, R"({"lines": [{"id": "ring", "closed": true,
                       "points": [[4, 5], [20, 5], [20, 11], [4, 11]]}]})");
}

TEST_F(DiskFull, RegionsPicture) {
  write_ring_lines(out_ / "ring.json");
  expect_io_error_and_nothing_lost(
      {"regions", in("scan.smg"), "--lines", out("ring.json"), "--png", out("regions.png")},
      {"regions.png"});
}

TEST_F(DiskFull, Animesh) {
  write_ring_lines(out_ / "ring.json");
  expect_io_error_and_nothing_lost(
      {"animesh", in("scan.smg"), "--lines", out("ring.json"), "--out", out("a")},
      {"a/mesh.ply"});
}

// The device commands. ctest runs every test in its own process, so each fixture's set-up runs
// once per test: the scan sessions are cheap; the calibration (a 320 x 240 calibration session,
// where the chessboard is found in enough views, and its computation) is made once in the one
// test that needs it.
class DiskFullDevices : public DiskFull {
 protected:
  static void SetUpTestSuite() {
    dev_ = new fs::path(scratch_dir("disk_full_devices"));
    std::vector<std::string> small = small_scan_args();
    small.push_back((*dev_ / "small_scan").string());
    const RunResult small_scan = run_cli(small);
    ASSERT_EQ(small_scan.exit_code, 0) << small_scan.output;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dev_);
    delete dev_;
  }
  static std::string dev(const char* name) { return (*dev_ / name).string(); }
  // A 7-step scan of 32 x 24 frames (~0.2 KB each; ~0.5 KB of journal per step), up to --out.
  static std::vector<std::string> small_scan_args() {
    return {"scan",   "--sim",   "--steps",      "7",    "--lasers", "2",
            "--size", "32x24",   "--time-scale", "0.01", "--settle", "0.05",
            "--out"};
  }
  static fs::path* dev_;
};
fs::path* DiskFullDevices::dev_ = nullptr;

// The whole calibration (OpenCV detection, the Ceres adjustment) runs here, under the
// sanitizers too; then reconstruct and check-calibration with that calibration.
TEST_F(DiskFullDevices, CalibrateReconstructAndCheckCalibration) {
  const RunResult scan = run_cli({"scan", "--sim", "--steps", "4", "--size", "320x240",
                                  "--time-scale", "0.01", "--out", dev("scan")});
  ASSERT_EQ(scan.exit_code, 0) << scan.output;
  const RunResult session =
      run_cli({"scan", "--sim", "--calibration", "--size", "320x240", "--time-scale", "0.01",
               "--out", dev("calibration_session")});
  ASSERT_EQ(session.exit_code, 0) << session.output;
  const RunResult calibrate =
      run_cli({"calibrate", dev("calibration_session"), "--out", dev("calib.yaml")});
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.output;
  expect_io_error_and_nothing_lost(
      {"calibrate", dev("calibration_session"), "--out", out("calib.yaml")}, {"calib.yaml"});
  expect_io_error_and_nothing_lost(
      {"reconstruct", dev("scan"), "--calib", dev("calib.yaml"), "--out", out("grid.smg")},
      {"grid.smg"});
  expect_io_error_and_nothing_lost({"check-calibration", "--calib", dev("calib.yaml"), "--sim",
                                    "--size", "320x240", "--steps", "8", "--report",
                                    out("check.json")},
                                   {"check.json"});
}

TEST_F(DiskFullDevices, Replay) {
  // The contact sheet (written first) of 32 x 24 tiles is ~1.1 KB: above the sanitizer tree's
  // 1 KB limit too.
  expect_io_error_and_nothing_lost({"replay", dev("small_scan"), "--out", out("replay")},
                                   {"replay/contact_sheet.png"});
}

// A scan that runs out of disk keeps the steps it recorded, with no torn journal line, and
// --resume (with space again) completes it to the session an uninterrupted scan records.
TEST_F(DiskFullDevices, ScanKeepsItsStepsAndResumes) {
  std::vector<std::string> args = small_scan_args();
  args.push_back(out("session"));
  // Every frame and the session header fit under 2,000 bytes; the step journal outgrows it
  // after about four steps.
  const RunResult r = run_cli(args, 2000);
  EXPECT_EQ(r.exit_code, 5) << describe(args, r);
  EXPECT_NE(r.output.find("scanmesh: I/O error: cannot append to '" + out("session") +
                          "/steps.jsonl'"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--resume"), std::string::npos) << r.output;
  EXPECT_FALSE(has_temporary_file(out_ / "session")) << r.output;
  const std::string journal = read_text(out_ / "session" / "steps.jsonl");
  EXPECT_FALSE(journal.empty()) << "the failure was not midway";
  EXPECT_EQ(journal.back(), '\n') << "torn journal line";
  const std::size_t steps_kept = static_cast<std::size_t>(
      std::count(journal.begin(), journal.end(), '\n'));
  EXPECT_GT(steps_kept, 0u);
  EXPECT_LT(steps_kept, 7u);
  std::vector<std::string> resume = args;
  resume.push_back("--resume");
  const RunResult resumed = run_cli(resume);
  ASSERT_EQ(resumed.exit_code, 0) << describe(resume, resumed);
  EXPECT_TRUE(test::sessions_identical(out_ / "session", *dev_ / "small_scan"));
}

}  // namespace
}  // namespace scanmesh::hostile
