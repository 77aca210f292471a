// Hostile inputs, round two (issue 32; docs/safety.md, "Findings"): each test feeds the
// scanmesh binary one of the inputs that once crashed it, ended in an "internal error", replaced
// a device node or left files behind, and checks the documented exit code, a message naming the
// file or option, and that nothing new is left. Work that used to grow quadratically is timed in
// bench/bench_hostile, not here: these tests only check the outcome.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/types.h>

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "scanmesh/core/binary_io.h"
#include "scanmesh/core/grid_file.h"

namespace scanmesh::hostile {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A message never prints a number with dozens of digits (DBL_MAX in full was 309).
bool has_runaway_number(const std::string& text) {
  return std::regex_search(text, std::regex("[0-9]{40}"));
}

std::string ascii_cloud_ply(const std::vector<std::array<double, 3>>& points) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(points.size()) +
                  "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
  for (const auto& p : points) {
    char line[128];
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
    s += line;
  }
  return s;
}

// Points on a wavy sheet, 30 x 30: a cloud the fans mesh.
std::vector<std::array<double, 3>> sheet_points() {
  std::vector<std::array<double, 3>> pts;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      pts.push_back({i + 0.3 * std::sin(j), j + 0.2 * std::cos(i), 0.5 * std::sin(0.3 * i)});
  return pts;
}

std::string xyz_text(const std::vector<std::array<double, 3>>& points) {
  std::string s;
  for (const auto& p : points) {
    char line[128];
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
    s += line;
  }
  return s;
}

class HostileRoundTwo : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(scratch_dir("round_two"));
    write_text(*dir_ / "scanner.yaml", kSmallScannerYaml);
    const RunResult sim = run_cli({"sim", "--scene", (kConfigs / "sim" / "sphere.yaml").string(),
                                   "--scanner", (*dir_ / "scanner.yaml").string(), "--out",
                                   (*dir_ / "good.smg").string()});
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    const RunResult mesh = run_cli(
        {"grid-mesh", (*dir_ / "good.smg").string(), "--out", (*dir_ / "good.ply").string()});
    ASSERT_EQ(mesh.exit_code, 0) << mesh.output;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static fs::path path(const std::string& name) { return *dir_ / name; }
  static fs::path* dir_;
};
fs::path* HostileRoundTwo::dir_ = nullptr;

// --- crashes -------------------------------------------------------------------------------

TEST_F(HostileRoundTwo, FarOutliersInACloudAreMeshedAroundNotCrashedOn) {
  // One point at 1e308 (PLY doubles) crashed CellGrid::visit_ball; one at 1e20 (XYZ, PCD)
  // asked for a grid larger than memory.
  std::vector<std::array<double, 3>> pts = sheet_points();
  pts.push_back({1e308, 0, 0});
  write_text(path("far.ply"), ascii_cloud_ply(pts));
  pts.back() = {1e20, 0, 0};
  write_text(path("far.xyz"), xyz_text(pts));
  std::string pcd = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " +
                    std::to_string(pts.size()) + "\nHEIGHT 1\nPOINTS " +
                    std::to_string(pts.size()) + "\nDATA ascii\n" + xyz_text(pts);
  write_text(path("far.pcd"), pcd);
  for (const char* name : {"far.ply", "far.xyz", "far.pcd"}) {
    const fs::path out = path(std::string(name) + ".mesh.ply");
    const std::vector<std::string> args{"fans", path(name).string(), "--out", out.string()};
    const RunResult r = run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << describe(args, r);
    // The far point is written as it is (double coordinates where float overflows), so the
    // mesh reads back: info rejected an infinite coordinate before.
    const RunResult info = run_cli({"info", out.string()});
    EXPECT_EQ(info.exit_code, 0) << info.output;
    const RunResult check = run_cli({"check", out.string(), "--require", "non-empty"});
    EXPECT_EQ(check.exit_code, 0) << check.output;
  }
}

TEST_F(HostileRoundTwo, AFaceWithAMillionCornersIsCheckedWithoutRecursion) {
  // The vertex-manifold test's recursive union-find overflowed the stack.
  std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1000000";
  ply.reserve(ply.size() + 2'000'010);
  for (int i = 0; i < 1'000'000; ++i) ply += i % 3 == 0 ? " 0" : (i % 3 == 1 ? " 1" : " 2");
  ply += "\n";
  write_text(path("big_face.ply"), ply);
  const std::vector<std::string> args{"check", path("big_face.ply").string()};
  const RunResult r = run_cli(args);
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 6) << describe(args, r);
  EXPECT_TRUE(contains(r.output, "vertex-manifold")) << r.output;
  EXPECT_TRUE(contains(r.output, "duplicate")) << r.output;
}

TEST_F(HostileRoundTwo, ThreadCountHasAnUpperBound) {
  write_text(path("sheet.xyz"), xyz_text(sheet_points()));
  const std::vector<std::string> args{"fans", path("sheet.xyz").string(), "--threads", "100000",
                                      "--out", path("t.ply").string()};
  const RunResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 2) << describe(args, r);
  EXPECT_TRUE(contains(r.output, "--threads")) << r.output;
  EXPECT_FALSE(fs::exists(path("t.ply")));
}

// --- numeric options -----------------------------------------------------------------------

TEST_F(HostileRoundTwo, NumericOptionsRefuseNanNegativeAndAbsurdValuesNamingTheOption) {
  const std::string mesh = path("good.ply").string(), grid = path("good.smg").string();
  const fs::path out = path("opt_out");
  struct Case {
    std::vector<std::string> args;
    std::string option;
  };
  const std::vector<Case> cases = {
      {{"remesh", mesh, "--vertices", "50", "--gamma", "-1", "--out", out.string()}, "--gamma"},
      {{"remesh", mesh, "--vertices", "50", "--gamma", "nan", "--out", out.string()}, "--gamma"},
      {{"remesh", mesh, "--vertices", "50", "--needle-angle", "1000", "--out", out.string()},
       "--needle-angle"},
      {{"remesh", mesh, "--vertices", "50", "--kink-reach", "-1", "--out", out.string()},
       "--kink-reach"},
      {{"remesh", mesh, "--vertices", "50", "--theta-dist", "-5", "--out", out.string()},
       "--theta-dist"},
      {{"remesh", mesh, "--vertices", "50", "--clip", "inf", "--out", out.string()}, "--clip"},
      {{"curvature", grid, "--radius", "1e300", "--out", out.string()}, "--radius"},
      {{"clean", grid, "--spike-mm", "-1", "--out", (out / "c.smg").string()}, "--spike-mm"},
      {{"fans", mesh, "--alpha", "nan", "--out", (out / "f.ply").string()}, "--alpha"},
      {{"render", mesh, "--azimuth", "nan", "--out", (out / "r.png").string()}, "--azimuth"},
      {{"sim", "--noise", "-0.5", "--out", (out / "s.smg").string()}, "--noise"},
      {{"scan", "--sim", "--fps", "0", "--out", out.string()}, "--fps"},
      {{"scan", "--sim", "--fps", "-1", "--out", out.string()}, "--fps"},
      {{"scan", "--sim", "--fps", "nan", "--out", out.string()}, "--fps"},
      {{"scan", "--sim", "--settle", "-1", "--out", out.string()}, "--settle"},
      {{"scan", "--sim", "--discard", "-1", "--out", out.string()}, "--discard"},
      {{"check-calibration", "--sim", "--max-rms", "nan"}, "--max-rms"},
      {{"particles", (kConfigs / "sim" / "sphere.yaml").string(), "--edge", "-2", "--out",
        out.string()},
       "--edge"},
      // Seeds are unsigned: "-1" used to wrap round to 2^64 - 1 without a word.
      {{"sim", "--seed", "-1", "--out", (out / "s.smg").string()}, "--seed"},
      {{"demo", "--seed", "-1", "--out", out.string()}, "--seed"},
      {{"particles", (kConfigs / "sim" / "sphere.yaml").string(), "--seed", "-3", "--out",
        out.string()},
       "--seed"},
      {{"sim", "--seed", "1e3", "--out", (out / "s.smg").string()}, "--seed"},
  };
  for (const Case& c : cases) {
    const RunResult r = run_cli(c.args);
    EXPECT_TRUE(r.exit_code == 2 || r.exit_code == 3) << describe(c.args, r);
    EXPECT_TRUE(contains(r.output, c.option)) << describe(c.args, r);
    EXPECT_FALSE(has_runaway_number(r.output)) << describe(c.args, r);
    EXPECT_FALSE(fs::exists(out)) << describe(c.args, r);
  }
}

// --- "internal error" for bad input ----------------------------------------------------------

TEST_F(HostileRoundTwo, AGridSpanningKilometresIsABadFile) {
  // dh = 1e300 ran into "cannot create std::vector larger than max_size()".
  std::string bytes = read_text(path("good.smg"));
  std::vector<std::uint8_t> b(bytes.begin(), bytes.end());
  const double dh = 1e300;
  std::uint64_t bits = 0;
  std::memcpy(&bits, &dh, 8);
  for (int k = 0; k < 8; ++k) b[48 + k] = static_cast<std::uint8_t>(bits >> (8 * k));
  const std::uint32_t crc = crc32_of(b.data(), b.size() - 4);
  for (int k = 0; k < 4; ++k) b[b.size() - 4 + k] = static_cast<std::uint8_t>(crc >> (8 * k));
  write_text(path("huge_dh.smg"), std::string(b.begin(), b.end()));
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"info", path("huge_dh.smg").string()},
        {"particles", "--grid", path("huge_dh.smg").string(), "--edge", "5", "--out",
         path("huge_dh_out").string()},
        {"grid-mesh", path("huge_dh.smg").string(), "--out", path("huge_dh.ply").string()}}) {
    const RunResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 4) << describe(args, r);
    EXPECT_TRUE(contains(r.output, "huge_dh.smg")) << r.output;
    EXPECT_FALSE(has_runaway_number(r.output)) << r.output;
  }
  EXPECT_FALSE(fs::exists(path("huge_dh_out")));
  EXPECT_FALSE(fs::exists(path("huge_dh.ply")));
}

TEST_F(HostileRoundTwo, AParticleEdgeTooFineForTheSceneIsInvalidInputAndLeavesNoFolder) {
  const std::vector<std::string> args{"particles", (kConfigs / "sim" / "sphere.yaml").string(),
                                      "--edge", "1e-9", "--out", path("fine").string()};
  const RunResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 3) << describe(args, r);
  EXPECT_TRUE(contains(r.output, "edge length too small")) << r.output;
  EXPECT_FALSE(fs::exists(path("fine")));
}

TEST_F(HostileRoundTwo, RemeshOutputOntoAFileOrAnUncreatablePathFailsBeforeTheWork) {
  write_text(path("occupied"), "keep me");
  for (const fs::path& out : {path("occupied"), path("occupied") / "below"}) {
    const std::vector<std::string> args{"remesh", path("good.ply").string(), "--vertices", "60",
                                        "--out", out.string()};
    const RunResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 5) << describe(args, r);
    EXPECT_TRUE(contains(r.output, "occupied")) << r.output;
    EXPECT_FALSE(contains(r.output, "remesh:")) << "the remesh ran first:\n" << r.output;
  }
  EXPECT_EQ(read_text(path("occupied")), "keep me");
}

TEST_F(HostileRoundTwo, MetadataThatIsNotUtf8StillGivesValidJsonAndAllOutputs) {
  RangeGrid g = read_grid(path("good.smg"));
  g.metadata["operator"] = std::string("\xff\xfe M\xfcller", 10);  // Latin-1, not UTF-8
  write_grid(path("latin1.smg"), g);
  const RunResult info = run_cli({"info", path("latin1.smg").string(), "--json"});
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_TRUE(nlohmann::json::accept(info.output)) << info.output;
  const RunResult curv =
      run_cli({"curvature", path("latin1.smg").string(), "--out", path("latin1_curv").string()});
  ASSERT_EQ(curv.exit_code, 0) << curv.output;
  EXPECT_TRUE(nlohmann::json::accept(read_text(path("latin1_curv") / "curvature.json")));
}

// --- work bounded by the content ------------------------------------------------------------

TEST_F(HostileRoundTwo, RepeatedStructureIsCheckedRenderedAndMeshedOnce) {
  // 20,000 copies of one triangle: each copy was tested against every other.
  std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 20000\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0\n1 0 0\n0 1 0\n";
  for (int i = 0; i < 20000; ++i) ply += "3 0 1 2\n";
  write_text(path("copies.ply"), ply);
  const RunResult check = run_cli({"check", path("copies.ply").string()});
  EXPECT_TRUE(contains(check.output, "19999 duplicate faces")) << check.output;
  EXPECT_TRUE(contains(check.output, "intersection-free     yes")) << check.output;
  const RunResult render =
      run_cli({"render", path("copies.ply").string(), "--out", path("copies.png").string()});
  EXPECT_EQ(render.exit_code, 0) << render.output;

  // A fan of 20,000 triangles round one vertex: the checker's manifold test is O(k log k), and
  // the intersection test declines (every box overlaps at the centre) instead of 2e8 tests.
  std::string fan = "ply\nformat ascii 1.0\nelement vertex 20001\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 20000\n"
                    "property list uchar int vertex_indices\nend_header\n0 0 0\n";
  for (int i = 0; i < 20000; ++i)
    fan += std::to_string(std::cos(2 * M_PI * i / 20000)) + " " +
           std::to_string(std::sin(2 * M_PI * i / 20000)) + " 0\n";
  for (int i = 0; i < 20000; ++i)
    fan += "3 0 " + std::to_string(1 + i) + " " + std::to_string(1 + (i + 1) % 20000) + "\n";
  write_text(path("fan.ply"), fan);
  const RunResult fan_check = run_cli({"check", path("fan.ply").string()});
  EXPECT_EQ(fan_check.exit_code, 0) << fan_check.output;
  EXPECT_TRUE(contains(fan_check.output, "vertex-manifold       yes")) << fan_check.output;
  EXPECT_TRUE(contains(fan_check.output, "boundary loops        1")) << fan_check.output;

  // 20,000 copies of one point beside a real sheet: meshed once, counted in the report.
  std::vector<std::array<double, 3>> pts = sheet_points();
  for (int i = 0; i < 20000; ++i) pts.push_back({5, 5, 0.5 * std::sin(1.5)});
  write_text(path("dup.xyz"), xyz_text(pts));
  const std::vector<std::string> args{"fans", path("dup.xyz").string(), "--out",
                                      path("dup.ply").string(), "--report",
                                      path("dup.json").string()};
  const RunResult fans = run_cli(args);
  ASSERT_EQ(fans.exit_code, 0) << describe(args, fans);
  const auto report = nlohmann::json::parse(read_text(path("dup.json")));
  ASSERT_TRUE(report.contains("duplicate_points")) << report.dump(2);
  EXPECT_EQ(report["duplicate_points"].get<int>(), 19999) << report.dump(2);  // all but the first
}

TEST_F(HostileRoundTwo, PlyHeadersWithManyPropertiesOrElementsAreReadInLinearTime) {
  std::string props = "ply\nformat ascii 1.0\nelement vertex 0\n";
  for (int i = 0; i < 100000; ++i) props += "property float p" + std::to_string(i) + "\n";
  props += "property float p7\nend_header\n";  // the duplicate is found (by the hash) and named
  write_text(path("props.ply"), props);
  const RunResult r = run_cli({"info", path("props.ply").string()});
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_TRUE(contains(r.output, "duplicate property 'p7'")) << r.output;
  EXPECT_TRUE(contains(r.output, "props.ply")) << r.output;
}

TEST_F(HostileRoundTwo, ARegionUnitBelowTheFloorIsRefusedLikeTheGlobalOne) {
  write_text(path("fine_region.yaml"),
             "unit_mm: 4\nregions:\n  - {point: [12, 8], unit_mm: 0.05}\n");
  const std::vector<std::string> args{"animesh", path("good.smg").string(), "--settings",
                                      path("fine_region.yaml").string(), "--out",
                                      path("am").string()};
  const RunResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 4) << describe(args, r);
  EXPECT_TRUE(contains(r.output, "regions[0].unit_mm")) << r.output;
  EXPECT_TRUE(contains(r.output, "min_unit_mm")) << r.output;
  EXPECT_FALSE(fs::exists(path("am")));
}

TEST_F(HostileRoundTwo, ConfigurationsBeyondTheirLimitsAreRefusedBeforeTheWork) {
  std::string big = "objects:\n";
  while (big.size() < (std::size_t{5} << 20))
    big += "  - {type: sphere, center: [0, 0, 100], radius: 5}\n";
  write_text(path("big_scene.yaml"), big);
  std::string many = "objects:\n";
  for (int i = 0; i < 1001; ++i) many += "  - {type: sphere, center: [0, 0, 100], radius: 5}\n";
  write_text(path("many_objects.yaml"), many);
  write_text(path("big_scanner.yaml"), "n_phi: 8192\nn_h: 8192\n");
  struct Case {
    std::vector<std::string> args;
    std::string file, says;
  };
  const std::vector<Case> cases = {
      {{"sim", "--scene", path("big_scene.yaml").string()}, "big_scene.yaml", "bytes"},
      {{"sim", "--scene", path("many_objects.yaml").string()}, "many_objects.yaml", "at most"},
      {{"sim", "--scanner", path("big_scanner.yaml").string()}, "big_scanner.yaml", "cells"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"--out", path("never.smg").string()});
    const RunResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 4) << describe(args, r);
    EXPECT_TRUE(contains(r.output, c.file)) << r.output;
    EXPECT_TRUE(contains(r.output, c.says)) << r.output;
    EXPECT_FALSE(fs::exists(path("never.smg")));
  }
}

TEST_F(HostileRoundTwo, OnlyRegularFilesAreRead) {
  fs::create_symlink("/dev/zero", path("zero.xyz"));
  fs::create_symlink("/dev/zero", path("zero.ply"));
  ASSERT_EQ(mkfifo(path("pipe.xyz").c_str(), 0600), 0);
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"fans", path("zero.xyz").string(), "--out",
                                 path("z.ply").string()},
        {"info", path("zero.ply").string()},
        {"check", path("zero.ply").string()},
        {"fans", path("pipe.xyz").string(), "--out", path("z.ply").string()}}) {
    const RunResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 4) << describe(args, r);
    EXPECT_TRUE(contains(r.output, "not a regular file")) << r.output;
  }
  EXPECT_FALSE(fs::exists(path("z.ply")));
}

// --- outputs ---------------------------------------------------------------------------------

TEST_F(HostileRoundTwo, OutputsNeverReplaceAFifoOrASymbolicLink) {
  ASSERT_EQ(mkfifo(path("out_fifo.ply").c_str(), 0600), 0);
  write_text(path("link_target.ply"), "original");
  fs::create_symlink(path("link_target.ply"), path("out_link.ply"));
  for (const char* name : {"out_fifo.ply", "out_link.ply"}) {
    const std::vector<std::string> args{"grid-mesh", path("good.smg").string(), "--out",
                                        path(name).string()};
    const RunResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 5) << describe(args, r);
    EXPECT_TRUE(contains(r.output, name)) << r.output;
    EXPECT_TRUE(contains(r.output, "replaces only regular files")) << r.output;
  }
  struct stat st {};
  ASSERT_EQ(lstat(path("out_fifo.ply").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_TRUE(fs::is_symlink(path("out_link.ply")));
  EXPECT_EQ(read_text(path("link_target.ply")), "original");
}

TEST_F(HostileRoundTwo, TemporariesOfAKilledRunAreRemovedByTheNextRun) {
  // A process that has ended: its pid names the orphan, as a kill between fsync and rename
  // leaves it.
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  const fs::path folder = scratch_dir("round_two_orphans");
  const fs::path orphan = folder / (".mesh.ply.tmp." + std::to_string(child) + ".0");
  write_text(orphan, "half a mesh");
  const RunResult r = run_cli(
      {"grid-mesh", path("good.smg").string(), "--out", (folder / "mesh.ply").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(orphan));
  EXPECT_TRUE(fs::exists(folder / "mesh.ply"));
}

TEST_F(HostileRoundTwo, AFullDiskLeavesNoNewFileOrFolder) {
  const long long limit =
#ifdef SCANMESH_LLVM_OPENMP
      1024;
#else
      200;
#endif
  const fs::path folder = scratch_dir("round_two_full");
  struct Case {
    std::vector<std::string> args;
  };
  const std::vector<std::vector<std::string>> runs = {
      {"grid-mesh", path("good.smg").string(), "--out", (folder / "g.ply").string(), "--obj",
       (folder / "g.obj").string(), "--render", (folder / "g.png").string()},
      {"curvature", path("good.smg").string(), "--out", (folder / "curv").string()},
      {"remesh", path("good.ply").string(), "--vertices", "60", "--out",
       (folder / "rm").string()},
      {"particles", (kConfigs / "sim" / "sphere.yaml").string(), "--edge", "4", "--out",
       (folder / "pa").string()},
  };
  for (const auto& args : runs) {
    const RunResult r = run_cli(args, limit);
    EXPECT_EQ(r.exit_code, 5) << describe(args, r);
    EXPECT_TRUE(files_in(folder).empty()) << describe(args, r);
    EXPECT_TRUE(fs::is_empty(folder)) << describe(args, r);  // no new folder either
  }
  const std::vector<std::string> pcd{"export", path("good.smg").string(), "--pcd",
                                     (folder / "g.pcd").string()};
  const RunResult r = run_cli(pcd, limit);
  EXPECT_EQ(r.exit_code, 5) << describe(pcd, r);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

// --- sessions --------------------------------------------------------------------------------

TEST_F(HostileRoundTwo, ResumeCapturesDamagedAndMissingFramesAgain) {
  const fs::path session = path("session");
  const std::vector<std::string> scan{"scan", "--sim", "--steps", "12", "--size", "160x120",
                                      "--time-scale", "0.01", "--out", session.string()};
  ASSERT_EQ(run_cli(scan).exit_code, 0);
  std::vector<fs::path> frames;
  for (const auto& e : fs::directory_iterator(session / "frames")) frames.push_back(e.path());
  std::sort(frames.begin(), frames.end());
  ASSERT_GT(frames.size(), 20u);
  write_text(frames[20], "not a png");  // step 6
  fs::remove(frames[9]);                // step 3
  std::vector<std::string> resume = scan;
  resume.push_back("--resume");
  const RunResult r = run_cli(resume);
  ASSERT_EQ(r.exit_code, 0) << describe(resume, r);
  EXPECT_TRUE(contains(r.output, "step 3 is damaged")) << r.output;
  EXPECT_TRUE(contains(r.output, "capturing again from step 3")) << r.output;
  const RunResult replay = run_cli({"replay", session.string(), "--out", path("rp").string()});
  EXPECT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_TRUE(contains(replay.output, "12 of 12 steps")) << replay.output;

  // A frame replaced by a link to a device is refused by the replay, naming the frame.
  fs::remove(frames[4]);
  fs::create_symlink("/dev/zero", frames[4]);
  const RunResult linked = run_cli({"replay", session.string(), "--out", path("rp2").string()});
  EXPECT_EQ(linked.exit_code, 4) << linked.output;
  EXPECT_TRUE(contains(linked.output, frames[4].filename().string())) << linked.output;
  EXPECT_FALSE(fs::exists(path("rp2")));
}

// --- variants found by re-testing round two (5 Dec 2026): the same kinds of input, further ----

TEST_F(HostileRoundTwo, MoreThanOnePercentOfFarOutliersAreMeshedAround) {
  // 3 % of the points scattered up to 1e308 (more than the 1 % quantile box left out): the
  // box grew to 1e154, the cell edge overflowed to infinity and a NaN cell index crashed the
  // neighbour search; with 1e30 the fans ran 8 s and left a few hundred triangles.
  std::vector<std::array<double, 3>> pts = sheet_points();
  const std::size_t sheet = pts.size();
  std::uint64_t state = 17;
  auto uniform = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  for (int k = 0; k < 30; ++k) {
    std::array<double, 3> p{};
    for (double& c : p) c = (uniform() < 0.5 ? -1 : 1) * std::pow(10.0, 308.0 * uniform());
    pts.push_back(p);
  }
  write_text(path("scatter.xyz"), xyz_text(pts));
  write_text(path("sheet.xyz"), xyz_text(std::vector(pts.begin(), pts.begin() + sheet)));
  nlohmann::json counts;
  for (const char* name : {"sheet.xyz", "scatter.xyz"}) {
    const std::vector<std::string> args{"fans", path(name).string(), "--out",
                                        path(std::string(name) + ".ply").string(), "--json"};
    const RunResult r = run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << describe(args, r);
    counts[name] = nlohmann::json::parse(r.output.substr(r.output.find('{')))["triangles"];
  }
  EXPECT_EQ(counts["scatter.xyz"], counts["sheet.xyz"]) << counts.dump();
}

TEST_F(HostileRoundTwo, AClusterFarDenserThanTheCloudIsRefusedNotMeshedForMinutes) {
  // 5,000 points within 1e-9 of one point beside a 10,000-point sheet (not exact copies, which
  // are meshed once): every neighbour query in that one cell was O(5,000).
  std::vector<std::array<double, 3>> pts;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j)
      pts.push_back({i + 0.3 * std::sin(j), j + 0.2 * std::cos(i), 0.5 * std::sin(0.3 * i)});
  for (int k = 0; k < 5000; ++k)
    pts.push_back(
        {10 + 1e-9 * std::sin(k), 10 + 1e-9 * std::cos(3.0 * k), 1e-9 * std::sin(7.0 * k)});
  write_text(path("cluster.xyz"), xyz_text(pts));
  const std::vector<std::string> args{"fans", path("cluster.xyz").string(), "--out",
                                      path("cluster.ply").string()};
  const RunResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 3) << describe(args, r);
  EXPECT_TRUE(contains(r.output, "cluster.xyz")) << r.output;
  EXPECT_TRUE(contains(r.output, "one grid cell")) << r.output;
  EXPECT_FALSE(fs::exists(path("cluster.ply")));
}

TEST_F(HostileRoundTwo, InfoOnAFifoIsRefusedNotWaitedOn) {
  for (const char* name : {"fifo.smg", "fifo.ply"}) {
    ASSERT_EQ(mkfifo(path(name).c_str(), 0600), 0);
    const std::vector<std::string> args{"info", path(name).string()};
    const RunResult r = run_cli(args);  // hung until a writer came
    EXPECT_EQ(r.exit_code, 4) << describe(args, r);
    EXPECT_TRUE(contains(r.output, "not a regular file")) << r.output;
  }
}

TEST_F(HostileRoundTwo, AFileSizeLimitEndsWithExitFiveAndNoFileNotWithSigxfsz) {
  // `ulimit -f` leaves SIGXFSZ at its default (kill): the binary ignores it itself, so the write
  // fails with EFBIG and the outputs are taken back (exit 153 left a texture and a temporary).
  const fs::path folder = scratch_dir("round_two_fsize");
  const std::vector<std::string> args{"grid-mesh", path("good.smg").string(), "--obj",
                                      (folder / "m.obj").string()};
  const RunResult r = run_cli(args, 20000, /*ignore_sigxfsz=*/false);
  EXPECT_EQ(r.exit_code, 5) << describe(args, r);
  EXPECT_TRUE(files_in(folder).empty()) << "left behind: " << files_in(folder).size();
  fs::remove_all(folder);
}

TEST_F(HostileRoundTwo, UnitSizesThatAskForMillionsOfTrianglesAreRefusedBeforeTheWork) {
  // The settings may lower min_unit_mm; a unit far below the grid's resolution then ran for
  // minutes and past 1 GB. The estimated triangle count is bounded instead.
  const fs::path settings = path("fine.yaml");
  write_text(settings, "unit_mm: 0.05\nmin_unit_mm: 0.01\n");
  write_text(path("ring.json"),
             R"({"lines": [{"id": "ring", "closed": true,
                 "points": [[4, 5], [20, 5], [20, 11], [4, 11]]}]})");
  const std::vector<std::string> args{
      "animesh",    path("good.smg").string(), "--lines", path("ring.json").string(),
      "--settings", settings.string(),         "--out",   path("fine_out").string()};
  const RunResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 3) << describe(args, r);
  EXPECT_TRUE(contains(r.output, "raise unit_mm")) << r.output;
  EXPECT_FALSE(fs::exists(path("fine_out")));
}

TEST_F(HostileRoundTwo, AnimeshOutputOntoAFileFailsBeforeReadingTheLines) {
  // The folder is made first: a bad --out is found before the lines (here malformed) are read.
  write_text(path("not_a_folder"), "x");
  write_text(path("bad_lines.svg"), "<svg><path d='M 1'/></svg>");
  const std::vector<std::string> args{"animesh", path("good.smg").string(),
                                      "--lines", path("bad_lines.svg").string(),
                                      "--out",   path("not_a_folder").string()};
  const RunResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 5) << describe(args, r);
  EXPECT_EQ(read_text(path("not_a_folder")), "x");
}

TEST_F(HostileRoundTwo, ScenesWithTooManyElementsOrBytesAreRefusedBeforeParsing) {
  // One skeletal object of 300 elements (every field evaluation sums over all of them) and a
  // scene over the 2 MiB configuration limit given to `particles`, which parsed it whole first.
  std::string skeletal = "objects:\n  - type: skeletal\n    elements:\n";
  for (int k = 0; k < 300; ++k)
    skeletal += "      - {type: point, center: [" + std::to_string(k) + ", 0, 0], radius: 5}\n";
  write_text(path("many_elements.yaml"), skeletal);
  RunResult r = run_cli(
      {"sim", "--scene", path("many_elements.yaml").string(), "--out", path("me.smg").string()});
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_TRUE(contains(r.output, "at most 256 elements")) << r.output;
  std::string big = "objects:\n";
  while (big.size() < (std::size_t{3} << 20)) big += "# padding padding padding padding padding\n";
  write_text(path("big_scene.yaml"), big);
  r = run_cli({"particles", path("big_scene.yaml").string(), "--edge", "5", "--out",
               path("big_out").string()});
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_TRUE(contains(r.output, "big_scene.yaml")) << r.output;
  EXPECT_FALSE(fs::exists(path("big_out")));
}

TEST_F(HostileRoundTwo, GridLengthsBelowAPicometreAreABadFile) {
  // Radii of 1e-30 mm put every cell on the axis: fans and curvature ran for seconds and made
  // nothing. The reader now refuses them like lengths beyond 1e6 mm.
  RangeGrid tiny = read_grid(path("good.smg"));
  for (int j = 0; j < tiny.n_h(); ++j)
    for (int i = 0; i < tiny.n_phi(); ++i)
      if (tiny.valid(i, j)) tiny.set_sample(i, j, 1e-30f, tiny.confidence(i, j));
  write_grid(path("tiny.smg"), tiny);
  for (const char* command : {"info", "fans", "curvature"}) {
    std::vector<std::string> args{command, path("tiny.smg").string()};
    if (std::string(command) != "info")
      args.insert(args.end(), {"--out", path("tiny_out").string()});
    const RunResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 4) << describe(args, r);
    EXPECT_TRUE(contains(r.output, "tiny.smg")) << r.output;
  }
}

TEST_F(HostileRoundTwo, RemeshDropsCopiesOfAFaceInsteadOfPolishingThem) {
  // Ten copies of one triangle (an STL's repeated facet): the remesher kept them as stacked
  // seams and its polish ran for half a minute; the copies are dropped before the work.
  std::string stl = "solid copies\n";
  for (int k = 0; k < 10; ++k)
    stl +=
        "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 100 0 0\nvertex 0 100 0\n"
        "endloop\nendfacet\n";
  stl += "endsolid copies\n";
  write_text(path("copies.stl"), stl);
  const std::vector<std::string> args{"remesh", path("copies.stl").string(), "--vertices", "100",
                                      "--out",  path("copies_out").string(), "--json"};
  const RunResult r = run_cli(args);
  ASSERT_EQ(r.exit_code, 0) << describe(args, r);
  const auto j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  EXPECT_EQ(j["prepare"]["repeated_faces_removed"], 9) << j.dump();
  EXPECT_NEAR(j["stats"]["output_vertices"].get<double>(), 100, 1);
}

TEST_F(HostileRoundTwo, ACalibrationSessionWithoutItsStepsIsABadFile) {
  // Its step journal missing or empty: exit 3 ("no views") on two lines before; a damaged
  // session is a bad file (exit 4) naming the file.
  const fs::path session = path("calibration_session");
  const std::vector<std::string> scan{"scan",   "--sim",   "--calibration",
                                      "--size", "160x120", "--time-scale",
                                      "0.01",   "--out",   session.string()};
  ASSERT_EQ(run_cli(scan).exit_code, 0);
  write_text(session / "steps.jsonl", "");
  const std::vector<std::string> calibrate{"calibrate", session.string(), "--out",
                                           path("c.yaml").string()};
  RunResult r = run_cli(calibrate);
  EXPECT_EQ(r.exit_code, 4) << describe(calibrate, r);
  EXPECT_TRUE(contains(r.output, "steps.jsonl")) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  fs::remove(session / "steps.jsonl");
  r = run_cli(calibrate);
  EXPECT_EQ(r.exit_code, 4) << describe(calibrate, r);
  EXPECT_TRUE(contains(r.output, "steps.jsonl")) << r.output;
  EXPECT_FALSE(fs::exists(path("c.yaml")));
}

TEST_F(HostileRoundTwo, ACalibrationForOtherFrameSizesIsRefusedNamingBothSizes) {
  // A 640 x 480 calibration on 160 x 120 frames ran, with every ray wrong.
  write_text(path("cal640.yaml"),
             "format: scanmesh-calibration\nversion: 1\nimage: {width: 640, height: 480}\n"
             "intrinsics: {fx: 700, fy: 700, cx: 320, cy: 240}\n"
             "distortion: {k1: 0, k2: 0, p1: 0, p2: 0, k3: 0}\n"
             "axis: {direction: [0, -1, 0], origin_mm: [0, 50, 400]}\n"
             "lasers:\n  - {name: left, normal: [1, 0, 0], distance_mm: 10}\n"
             "  - {name: right, normal: [-1, 0, 0], distance_mm: 10}\n");
  const fs::path session = path("small_frames");
  ASSERT_EQ(run_cli({"scan", "--sim", "--steps", "4", "--size", "160x120", "--time-scale", "0.01",
                     "--out", session.string()})
                .exit_code,
            0);
  const std::vector<std::string> args{"reconstruct", session.string(),
                                      "--calib",     path("cal640.yaml").string(),
                                      "--out",       path("wrong.smg").string()};
  const RunResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 3) << describe(args, r);
  EXPECT_TRUE(contains(r.output, "640x480")) << r.output;
  EXPECT_TRUE(contains(r.output, "160x120")) << r.output;
  EXPECT_FALSE(fs::exists(path("wrong.smg")));
}

}  // namespace
}  // namespace scanmesh::hostile
