// Disk full during a write, without root: the scanmesh child runs with RLIMIT_FSIZE (and SIGXFSZ
// ignored), so any write past the limit fails with EFBIG exactly like ENOSPC on a full disk.
// Every writing command must exit 5 with an I/O error naming the file, leave no partial output
// and no temporary file, and leave an existing output file as it was.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

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

}  // namespace
}  // namespace scanmesh::hostile
