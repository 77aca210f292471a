// Malformed input files through every scanmesh command that reads them: empty, truncated, wrong
// magic, huge declared sizes (allocation bombs), NaN/Inf coordinates. Each must end with exit 4
// (bad file) or 5 (cannot read), one message naming the file, and no output or temporary file
// left behind — never a crash, a hang, an internal error or an allocation of what the header
// claims.
#include <gtest/gtest.h>

#include <algorithm>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "scanmesh/core/binary_io.h"
#include "scanmesh/core/grid_file.h"

namespace scanmesh::hostile {
namespace {

// The grid file with its trailing CRC recomputed after a patch, so the reader's checks behind the
// checksum are the ones tested.
std::vector<std::uint8_t> with_crc(std::vector<std::uint8_t> bytes) {
  const std::uint32_t crc = crc32_of(bytes.data(), bytes.size() - 4);
  for (int k = 0; k < 4; ++k)
    bytes[bytes.size() - 4 + k] = static_cast<std::uint8_t>(crc >> (8 * k));
  return bytes;
}

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  write_text(path, std::string(bytes.begin(), bytes.end()));
}

class HostileFiles : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(scratch_dir("files"));
    const fs::path& d = *dir_;
    write_text(d / "scanner.yaml", kSmallScannerYaml);
    const RunResult sim =
        run_cli({"sim", "--scene", (kConfigs / "sim" / "sphere.yaml").string(), "--scanner",
                 (d / "scanner.yaml").string(), "--out", (d / "good.smg").string()});
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    const RunResult mesh =
        run_cli({"grid-mesh", (d / "good.smg").string(), "--out", (d / "good.ply").string()});
    ASSERT_EQ(mesh.exit_code, 0) << mesh.output;

    // Grids.
    const std::string grid_text = read_text(d / "good.smg");
    const std::vector<std::uint8_t> grid(grid_text.begin(), grid_text.end());
    write_text(d / "empty.smg", "");
    write_text(d / "truncated.smg", grid_text.substr(0, grid_text.size() / 2));
    write_text(d / "wrong_magic.smg", "ply\nformat ascii 1.0\n" + grid_text.substr(20));
    std::vector<std::uint8_t> flipped = grid;
    flipped[flipped.size() / 2] ^= 0x40;  // one bit: caught by the checksum
    write_bytes(d / "bit_flip.smg", flipped);
    // Header declaring 65535 x 65535 cells (4 G cells, ~55 GB of planes) in a 1.6 KB file.
    std::vector<std::uint8_t> huge = grid;
    for (int k = 0; k < 4; ++k) huge[24 + k] = huge[28 + k] = (k < 2 ? 0xff : 0x00);
    write_bytes(d / "huge_declared.smg", with_crc(huge));
    // Sizes just within the cell limit but far beyond the file length.
    std::vector<std::uint8_t> long_claim = grid;
    const std::uint32_t side = 8000;
    for (int k = 0; k < 4; ++k)
      long_claim[24 + k] = long_claim[28 + k] = static_cast<std::uint8_t>(side >> (8 * k));
    write_bytes(d / "size_beyond_file.smg", with_crc(long_claim));
    // A valid cell with a NaN / infinite radius, checksum intact.
    const RangeGrid g = read_grid(d / "good.smg");
    const std::size_t header = read_le_u32(grid.data() + 20);
    std::size_t valid_cell = 0;
    while (!g.validity()[valid_cell]) ++valid_cell;
    for (const auto& [name, value] :
         {std::pair{"nan_radius.smg", std::numeric_limits<float>::quiet_NaN()},
          std::pair{"inf_radius.smg", std::numeric_limits<float>::infinity()}}) {
      std::vector<std::uint8_t> bad = grid;
      std::uint32_t bits = 0;
      std::memcpy(&bits, &value, 4);
      for (int k = 0; k < 4; ++k)
        bad[header + 4 * valid_cell + k] = static_cast<std::uint8_t>(bits >> (8 * k));
      write_bytes(d / name, with_crc(bad));
    }

    // Meshes and point clouds.
    const std::string ply_text = read_text(d / "good.ply");
    write_text(d / "empty.ply", "");
    write_text(d / "truncated.ply", ply_text.substr(0, ply_text.size() * 2 / 3));
    write_text(d / "wrong_magic.ply", "PLY\n" + ply_text.substr(4));
    write_text(d / "huge_declared.ply",
               "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
               "property float x\nproperty float y\nproperty float z\nelement face 4000000000\n"
               "property list uchar int vertex_indices\nend_header\n0123456789ab");
    const std::string ascii_head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    write_text(d / "nan.ply", ascii_head + "0 0 0\nnan 1 0\n0 1 0\n3 0 1 2\n");
    write_text(d / "inf.ply", ascii_head + "0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n");
    write_text(d / "bad_index.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    write_text(d / "nan.xyz", "0 0 0\n1 0 0\nnan 1 0\n");
    write_text(d / "inf.xyz", "0 0 0\n1 0 0\n0 -inf 0\n");
    write_text(d / "empty.xyz", "");
    write_text(d / "two_columns.xyz", "0 0\n1 1\n");
    const std::string pcd_head =
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
        "POINTS 2\nDATA ascii\n";
    write_text(d / "nan_only.pcd", pcd_head + "nan nan nan\nnan 0 0\n");
    write_text(d / "empty.pcd", "");
    write_text(d / "huge_declared.pcd",
               "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4000000000\n"
               "HEIGHT 1\nDATA binary\n0123456789ab");

    // Configuration files.
    write_text(d / "empty.yaml", "");
    write_text(d / "not_yaml.yaml", "objects: [ {type: sphere, radius: 10\n");
    write_text(d / "nan_scene.yaml",
               "objects:\n  - {type: sphere, center: [0, 0, .nan], radius: 5}\n");
    write_text(d / "deep.yaml", std::string(5000, '[') + std::string(5000, ']'));
    write_text(d / "bad_scanner.yaml", "n_phi: 99999999999\n");
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }

  // Runs a command that must reject `input`: exit 4 or 5 (or 2 for a missing file the argument
  // parser already refuses), a message naming the file, nothing left in `out`.
  static void expect_rejected(const std::vector<std::string>& args, const fs::path& input,
                              const fs::path& out, std::initializer_list<int> codes = {4}) {
    const RunResult r = run_cli(args);
    bool expected_code = false;
    for (int c : codes) expected_code = expected_code || r.exit_code == c;
    EXPECT_TRUE(expected_code) << describe(args, r);
    EXPECT_NE(r.output.find(input.filename().string()), std::string::npos)
        << "message does not name the file\n"
        << describe(args, r);
    EXPECT_TRUE(files_in(out).empty()) << "output left behind\n" << describe(args, r);
  }

  // Every command that reads a grid, writing into a fresh folder.
  static std::vector<std::vector<std::string>> grid_commands(const fs::path& grid,
                                                             const fs::path& out) {
    return {{"info", grid.string()},
            {"export", grid.string(), "--ply", (out / "x.ply").string(), "--pcd",
             (out / "x.pcd").string(), "--texture", (out / "t.png").string()},
            {"clean", grid.string(), "--out", (out / "x.smg").string()},
            {"grid-mesh", grid.string(), "--out", (out / "x.ply").string(), "--stl",
             (out / "x.stl").string()},
            {"curvature", grid.string(), "--out", (out / "curv").string()},
            {"fans", grid.string(), "--out", (out / "x.ply").string()},
            {"particles", "--grid", grid.string(), "--edge", "20", "--out", (out / "p").string()},
            {"regions", grid.string(), "--png", (out / "regions.png").string()},
            {"animesh", grid.string(), "--out", (out / "a").string()}};
  }

  static fs::path* dir_;
};
fs::path* HostileFiles::dir_ = nullptr;

TEST_F(HostileFiles, MalformedGridsAreRejectedByEveryGridCommand) {
  for (const char* name :
       {"empty.smg", "truncated.smg", "wrong_magic.smg", "bit_flip.smg", "huge_declared.smg",
        "size_beyond_file.smg", "nan_radius.smg", "inf_radius.smg"}) {
    const fs::path out = scratch_dir(std::string("grid_out_") + name);
    for (const auto& args : grid_commands(*dir_ / name, out))
      expect_rejected(args, *dir_ / name, out);
  }
}

TEST_F(HostileFiles, MissingGridIsAnIoErrorNamingIt) {
  const fs::path missing = *dir_ / "no_such_scan.smg";
  const fs::path out = scratch_dir("missing_out");
  for (const auto& args : grid_commands(missing, out)) expect_rejected(args, missing, out, {2, 5});
}

TEST_F(HostileFiles, MalformedMeshesAreRejectedByEveryMeshCommand) {
  for (const char* name : {"empty.ply", "truncated.ply", "wrong_magic.ply", "huge_declared.ply",
                           "nan.ply", "inf.ply", "bad_index.ply"}) {
    const fs::path in = *dir_ / name;
    const fs::path out = scratch_dir(std::string("mesh_out_") + name);
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"info", in.string()},
          {"render", in.string(), "--out", (out / "r.png").string()},
          {"check", in.string(), "--histogram", (out / "h.png").string()},
          {"fans", in.string(), "--out", (out / "f.ply").string()},
          {"remesh", in.string(), "--vertices", "50", "--out", (out / "r").string()},
          {"import", in.string(), "--out", (out / "i.smg").string()}})
      expect_rejected(args, in, out);
  }
}

TEST_F(HostileFiles, MalformedPointCloudsAreRejectedByFans) {
  for (const char* name : {"nan.xyz", "inf.xyz", "empty.xyz", "two_columns.xyz", "nan_only.pcd",
                           "empty.pcd", "huge_declared.pcd"}) {
    const fs::path in = *dir_ / name;
    const fs::path out = scratch_dir(std::string("cloud_out_") + name);
    expect_rejected({"fans", in.string(), "--out", (out / "f.ply").string()}, in, out);
  }
}

TEST_F(HostileFiles, MalformedScenesAndScannersAreRejected) {
  for (const char* name : {"empty.yaml", "not_yaml.yaml", "nan_scene.yaml", "deep.yaml"}) {
    const fs::path in = *dir_ / name;
    const fs::path out = scratch_dir(std::string("scene_out_") + name);
    expect_rejected({"sim", "--scene", in.string(), "--scanner", (*dir_ / "scanner.yaml").string(),
                     "--out", (out / "s.smg").string()},
                    in, out);
    expect_rejected({"particles", in.string(), "--edge", "10", "--out", (out / "p").string()}, in,
                    out);
  }
  for (const char* name : {"empty.yaml", "not_yaml.yaml", "deep.yaml", "bad_scanner.yaml"}) {
    const fs::path in = *dir_ / name;
    const fs::path out = scratch_dir(std::string("scanner_out_") + name);
    expect_rejected({"sim", "--scanner", in.string(), "--out", (out / "s.smg").string()}, in, out);
  }
}

// Damaged copies of a recorded session: each returns the file a message must name.
std::vector<fs::path> damaged_sessions(const fs::path& good, const fs::path& dir,
                                       const std::string& prefix) {
  auto copy = [&](const std::string& name) {
    const fs::path d = dir / (prefix + name);
    fs::remove_all(d);
    fs::copy(good, d, fs::copy_options::recursive);
    return d;
  };
  std::vector<fs::path> frames;
  for (const auto& e : fs::directory_iterator(good / "frames")) frames.push_back(e.path());
  std::sort(frames.begin(), frames.end());
  std::vector<fs::path> out;
  {
    const fs::path d = copy("garbage_manifest");
    write_text(d / "session.json", "{\"format\": \"scanmesh-session\", \"steps\": [1, 2");
    out.push_back(d / "session.json");
  }
  {
    const fs::path d = copy("garbage_journal");
    write_text(d / "steps.jsonl", "{\"step\": 0, \"frames\": 7}\n{not json\n");
    out.push_back(d / "steps.jsonl");
  }
  {
    const fs::path d = copy("flipped_frame");
    const fs::path frame = d / "frames" / frames.at(1).filename();
    std::string bytes = read_text(frame);
    bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x5a);
    write_text(frame, bytes);
    out.push_back(frame);
  }
  {
    const fs::path d = copy("missing_frame");
    const fs::path frame = d / "frames" / frames.at(2).filename();
    fs::remove(frame);
    out.push_back(frame);
  }
  return out;
}

// The session folder a damaged file belongs to.
fs::path session_of(const fs::path& damaged) {
  const fs::path parent = damaged.parent_path();
  return parent.filename() == "frames" ? parent.parent_path() : parent;
}

// Sessions and calibrations (issue 31: replay, reconstruct, calibrate and check-calibration
// were never fed damaged files): 4-step sessions of 32 x 24 frames, damaged copies of them,
// and damaged calibration files.
TEST_F(HostileFiles, DamagedSessionsAndCalibrationsAreRejectedByEveryDeviceCommand) {
  const fs::path good = *dir_ / "session", good_calibration = *dir_ / "calibration_session";
  RunResult r = run_cli({"scan", "--sim", "--steps", "4", "--size", "32x24", "--time-scale",
                         "0.01", "--settle", "0.05", "--out", good.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_cli({"scan", "--sim", "--calibration", "--size", "32x24", "--time-scale", "0.01",
               "--out", good_calibration.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // A calibration for 32 x 24 frames (the values need not be good: the files around it are
  // what is damaged).
  const std::string calibration =
      "format: scanmesh-calibration\nversion: 1\nimage: {width: 32, height: 24}\n"
      "intrinsics: {fx: 40, fy: 40, cx: 16, cy: 12}\n"
      "distortion: {k1: 0, k2: 0, p1: 0, p2: 0, k3: 0}\n"
      "axis: {direction: [0, -1, 0], origin_mm: [0, 50, 400]}\n"
      "lasers:\n  - {name: left, normal: [1, 0, 0], distance_mm: 10}\n"
      "  - {name: right, normal: [-1, 0, 0], distance_mm: 10}\n";
  write_text(*dir_ / "calib.yaml", calibration);
  for (const fs::path& damaged : damaged_sessions(good, *dir_, "scan_")) {
    const fs::path session = session_of(damaged);
    SCOPED_TRACE(session.filename().string());
    const fs::path out = scratch_dir("session_out_" + session.filename().string());
    expect_rejected({"replay", session.string(), "--out", (out / "replay").string()}, damaged,
                    out);
    expect_rejected({"reconstruct", session.string(), "--calib", (*dir_ / "calib.yaml").string(),
                     "--out", (out / "grid.smg").string()},
                    damaged, out);
  }
  for (const fs::path& damaged : damaged_sessions(good_calibration, *dir_, "calibration_")) {
    const fs::path session = session_of(damaged);
    SCOPED_TRACE(session.filename().string());
    const fs::path out = scratch_dir("session_out_" + session.filename().string());
    expect_rejected({"calibrate", session.string(), "--out", (out / "calib.yaml").string()},
                    damaged, out);
  }
  for (const auto& [name, text] :
       {std::pair<const char*, std::string>{"empty_calib.yaml", ""},
        {"not_a_calib.yaml", "objects: [1, 2\n"},
        {"nan_calib.yaml", std::string(calibration).replace(calibration.find("fx: 40"), 6,
                                                             "fx: .nan")},
        {"other_format.yaml", "format: something-else\nversion: 1\n"}}) {
    SCOPED_TRACE(name);
    const fs::path calib = *dir_ / name;
    write_text(calib, text);
    const fs::path out = scratch_dir(std::string("calib_out_") + name);
    expect_rejected({"reconstruct", good.string(), "--calib", calib.string(), "--out",
                     (out / "grid.smg").string()},
                    calib, out);
    expect_rejected({"check-calibration", "--calib", calib.string(), "--sim", "--size", "32x24",
                     "--steps", "4", "--report", (out / "check.json").string()},
                    calib, out);
  }
}

TEST_F(HostileFiles, GoodFilesStillWork) {
  // The baseline the rejections above are measured against.
  const fs::path out = scratch_dir("good_out");
  for (const auto& args : grid_commands(*dir_ / "good.smg", out)) {
    const RunResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << describe(args, r);
  }
  EXPECT_FALSE(has_temporary_file(out));
}

}  // namespace
}  // namespace scanmesh::hostile
