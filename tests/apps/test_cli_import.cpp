// `scanmesh import` through the command line (issue 25): every import format of the real-data
// corpus, the JSON report, bad files of every format (exit 4 naming the file, nothing written),
// and a quarter turn cut from a scanned mesh that meshes through `animesh` with a line that does
// not close on its own (the data border closes the regions).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <set>
#include <string>

#include "cli_runner.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;
using test::run;
const fs::path kCorpus = SCANMESH_CORPUS_DIR;

class CliImport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("scanmesh_test_cli_import_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path path(const std::string& name) const { return dir_ / name; }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
  }
  fs::path dir_;
};

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

TEST_F(CliImport, ImportsCloudsAndMeshesOfTheCorpusWithAReport) {
  for (const char* file : {"points_3/kitten.xyz", "points_3/hippo1.ply", "meshes/nefertiti.off"}) {
    const auto r = run("import " + (kCorpus / file).string() + " --out " + path("g.smg").string() +
                       " --report " + path("g.json").string() + " --depth " +
                       path("d.png").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("turn covered: 100 %"), std::string::npos) << r.output;
    const RangeGrid g = read_grid(path("g.smg"));
    const auto j = read_json(path("g.json"));
    EXPECT_EQ(j["grid"]["valid_cells"].get<std::size_t>(), g.valid_count()) << file;
    EXPECT_TRUE(j["turn_coverage"]["full_turn"].get<bool>()) << file;
    EXPECT_EQ(j["input_kind"], std::string(file).find("meshes") == 0 ? "mesh" : "point cloud");
    EXPECT_EQ(g.metadata.at("source"), fs::path(file).filename().string());
    EXPECT_TRUE(fs::exists(path("d.png")));
  }
}

TEST_F(CliImport, GridMeshNotesADepthJumpBoundOfHundredsOfRows) {
  // lion-head is 0.7 units across: its grid's rows are 0.0148 apart, so the default bound of
  // 8 (mm) is ~540 rows and no quad is a depth jump. grid-mesh says so and names 8 rows.
  ASSERT_EQ(run("import " + (kCorpus / "meshes/lion-head.off").string() + " --out " +
                path("g.smg").string())
                .exit_code,
            0);
  const RangeGrid g = read_grid(path("g.smg"));
  const auto plain = run("grid-mesh " + path("g.smg").string() + " --out " + path("m.ply").string());
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_NE(plain.output.find("note: --max-jump 8 is"), std::string::npos) << plain.output;
  EXPECT_NE(plain.output.find("0 at depth jumps"), std::string::npos) << plain.output;
  const auto json = run("grid-mesh " + path("g.smg").string() + " --out " +
                        path("m.ply").string() + " --json");
  ASSERT_EQ(json.exit_code, 0);
  EXPECT_NEAR(nlohmann::json::parse(json.output)["depth_jump_bound_rows"].get<double>(),
              8.0 / g.dh(), 1e-6 * 8.0 / g.dh());
  std::ostringstream eight_rows;
  eight_rows << 8 * g.dh();
  const std::string scaled = "grid-mesh " + path("g.smg").string() + " --out " +
                             path("m.ply").string() + " --max-jump " + eight_rows.str();
  const auto text = run(scaled);
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_EQ(text.output.find("note:"), std::string::npos) << text.output;
  const auto j = nlohmann::json::parse(run(scaled + " --json").output);
  EXPECT_GT(j["quads_skipped_for_depth_jumps"].get<int>(), 0);
}

TEST_F(CliImport, BadFilesOfEveryFormatExit4NamingTheFileAndWriteNothing) {
  const std::pair<const char*, std::string> bad[] = {
      {"empty.ply", ""},
      {"trunc.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nend_header\n0 0 0\n"},
      {"bad.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
                  "HEIGHT 1\nPOINTS 1\nDATA binary_compressed\n\x01"},
      {"nan.xyz", "1 2 3\nnan 0 0\n"},
      {"bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"},
      {"bad.obj", "v 0 0 0\nf 1 2 3\n"},
      {"bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\nendsolid\n"},
      {"bad.vtk", "not a vtk file\n"},
      {"bad.vtp", "<VTKFile type=\"ImageData\"></VTKFile>\n"},
      {"axis.xyz", "0 0 0\n0 0 1\n0 0 2\n"},
  };
  for (const auto& [name, text] : bad) {
    write(name, text);
    std::string extra = std::string(name) == "axis.xyz" ? " --axis-point 0,0,0" : "";
    const auto r = run("import " + path(name).string() + " --out " + path("out.smg").string() +
                       " --report " + path("out.json").string() + extra);
    EXPECT_EQ(r.exit_code, 4) << name << ": " << r.output;
    EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("out.smg"))) << name;
    EXPECT_FALSE(fs::exists(path("out.json"))) << name;
  }
  // Impossible options are exit 3.
  write("ok.xyz", "10 0 0\n0 10 0\n-10 0 1\n0 -10 1\n");
  EXPECT_EQ(run("import " + path("ok.xyz").string() + " --out " + path("o.smg").string() +
                " --axis 0,0,0").exit_code, 3);
  EXPECT_EQ(run("import " + path("ok.xyz").string() + " --out " + path("o.smg").string() +
                " --dh -1").exit_code, 3);
}

// The mannequin's triangles whose centre lies within a quarter turn [a0, a0 + pi/2) about the
// vertical axis through (cx, cy), as an OFF file (a scanner that saw only the face side).
std::string quarter_turn_off(const Mesh& m, double cx, double cy, double a0) {
  std::ostringstream off;
  off.precision(17);
  std::vector<std::array<int, 3>> kept;
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3;
    const double a = std::remainder(std::atan2(c.y() - cy, c.x() - cx) - a0 - std::numbers::pi / 4,
                                    2 * std::numbers::pi);
    if (std::abs(a) < std::numbers::pi / 4) kept.push_back(t);
  }
  off << "OFF\n" << m.positions.size() << " " << kept.size() << " 0\n";
  for (const auto& p : m.positions) off << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& t : kept) off << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return off.str();
}

TEST_F(CliImport, QuarterTurnOfAScannedMeshMeshesThroughAnimeshWithAnOpenLine) {
  const Mesh full = read_mesh(kCorpus / "meshes" / "mannequin-devil.off");
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : full.positions) c += p;
  c /= static_cast<double>(full.positions.size());
  write("quarter.off", quarter_turn_off(full, c.x(), c.y(), 0.0));
  std::ostringstream axis;
  axis.precision(17);
  axis << c.x() << "," << c.y() << ",0";
  const auto imp = run("import " + path("quarter.off").string() + " --axis-point " + axis.str() +
                       " --out " + path("q.smg").string() + " --report " + path("q.json").string());
  ASSERT_EQ(imp.exit_code, 0) << imp.output;
  const auto rep = read_json(path("q.json"));
  EXPECT_FALSE(rep["turn_coverage"]["full_turn"].get<bool>());
  ASSERT_EQ(rep["turn_coverage"]["arcs"].size(), 1u);
  const double span = rep["turn_coverage"]["arcs"][0]["span_deg"].get<double>();
  EXPECT_GT(span, 85.0);
  EXPECT_LT(span, 120.0);  // the quarter, plus triangles reaching past its edges
  // One line across the middle of the data, starting and ending outside it (texture pixels:
  // x = column, the line runs past the right edge of the texture where the arc wraps).
  const RangeGrid g = read_grid(path("q.smg"));
  const double start_deg = rep["turn_coverage"]["arcs"][0]["start_deg"].get<double>();
  const double px_per_deg = g.n_phi() / 360.0;
  const double x0 = start_deg * px_per_deg - 4, x1 = (start_deg + span) * px_per_deg + 4;
  const double y = 0.5 * g.n_h();
  std::ostringstream lines;
  lines << "{\"lines\": [{\"id\": \"across\", \"points\": [[" << x0 << ", " << y << "], [" << x1
        << ", " << y << "]]}]}\n";
  write("lines.json", lines.str());
  write("settings.yaml", "unit_mm: 3\n");
  const auto anim = run("animesh " + path("q.smg").string() + " --lines " +
                        path("lines.json").string() + " --settings " +
                        path("settings.yaml").string() + " --out " + path("anim").string());
  ASSERT_EQ(anim.exit_code, 0) << anim.output;
  const auto report = read_json(path("anim") / "animesh.json");
  // The line and the data border make two regions, above and below the line, both meshed.
  ASSERT_EQ(report["regions"].size(), 2u) << report["regions"].dump();
  const Mesh mesh = read_ply(path("anim") / "mesh.ply");
  EXPECT_GT(mesh.face_count(), 100u);
  std::set<int> labels(mesh.face_labels.begin(), mesh.face_labels.end());
  EXPECT_EQ(labels.size(), 2u);
}

}  // namespace
}  // namespace scanmesh
