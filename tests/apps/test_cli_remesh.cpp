// End-to-end tests of `scanmesh remesh`: the non-manifold two-box input with labels, the report,
// pictures, and the feature-lines errors (exit codes 3 and 4); the README's command on the
// demo's raw scan mesh; OFF / OBJ / STL inputs.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../meshing/remeshing/remesh_test_meshes.h"
#include "core/test_util.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

std::pair<int, std::string> run(const std::string& args) {
  const std::string command =
      (fs::path(SCANMESH_BINARY_DIR) / "apps" / "scanmesh").string() + " " + args + " 2>&1";
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return {-1, ""};
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(CliRemesh, TwoBoxesWithLabelsAndFeatureErrors) {
  const fs::path dir =
      fs::temp_directory_path() / ("scanmesh_test_cli_remesh_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_ply(dir / "boxes.ply", test::two_boxes(10, 8));
  auto [code, out] =
      run("remesh " + (dir / "boxes.ply").string() +
          " --vertices 250 --features auto --sharp 45 --uniform --out " + (dir / "out").string());
  ASSERT_EQ(code, 0) << out;
  for (const char* f : {"mesh.ply", "report.json", "quality.png", "histograms.png"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  const Mesh m = read_ply(dir / "out" / "mesh.ply");
  EXPECT_EQ(m.positions.size(), 250u);
  ASSERT_TRUE(m.has_face_labels());
  std::size_t wall = 0;
  for (int l : m.face_labels) wall += l == 3;
  EXPECT_GT(wall, 0u);
  const auto report = nlohmann::json::parse(std::ifstream(dir / "out" / "report.json"));
  EXPECT_EQ(report["quality"]["vertices"], 250);
  EXPECT_EQ(report["quality"]["self_intersections"], 0);
  EXPECT_EQ(report["stats"]["branch_vertices"], 12);
  // A feature line between vertices without an edge: invalid input (3).
  std::ofstream(dir / "bad_edge.txt") << "scanmesh_feature_lines 1\nline 0 500\n";
  std::tie(code, out) =
      run("remesh " + (dir / "boxes.ply").string() + " --vertices 250 --features " +
          (dir / "bad_edge.txt").string() + " --out " + (dir / "o2").string());
  EXPECT_EQ(code, 3) << out;
  // A malformed file: bad file (4), named in the message.
  std::ofstream(dir / "broken.txt") << "scanmesh_feature_lines 1\nline 0 x\n";
  std::tie(code, out) =
      run("remesh " + (dir / "boxes.ply").string() + " --vertices 250 --features " +
          (dir / "broken.txt").string() + " --out " + (dir / "o3").string());
  EXPECT_EQ(code, 4) << out;
  EXPECT_NE(out.find("broken.txt"), std::string::npos) << out;
  fs::remove_all(dir);
}

// What a new user runs from the README: the demo's own mesh (a raw scan: hair crumbs, pin-holes,
// a ragged border) remeshed with no clean-up flags. The clean-up must start by itself and the
// count must be met; without it the target cannot be met and the command must say so.
TEST(CliRemeshScan, ReadmeCommandOnTheDemoMeshNeedsNoFlags) {
  const fs::path dir =
      fs::temp_directory_path() / ("scanmesh_test_cli_remesh_scan_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto [code, out] = run("demo --out " + (dir / "demo").string());
  ASSERT_EQ(code, 0) << out;
  std::tie(code, out) = run("remesh " + (dir / "demo" / "mesh.ply").string() +
                            " --vertices 20000 --out " + (dir / "r").string());
  ASSERT_EQ(code, 0) << out;
  EXPECT_NE(out.find("looks like a scan"), std::string::npos) << out;
  for (const char* f : {"mesh.ply", "report.json", "quality.png", "histograms.png", "density.png"})
    EXPECT_TRUE(fs::exists(dir / "r" / f)) << f;
  EXPECT_EQ(read_ply(dir / "r" / "mesh.ply").positions.size(), 20000u);
  const auto q = nlohmann::json::parse(std::ifstream(dir / "r" / "report.json"))["quality"];
  EXPECT_EQ(q["self_intersections"], 0);
  EXPECT_GE(q["fraction_min_angle_ge_30"].get<double>(), 0.995);
  EXPECT_LE(q["fraction_irregular"].get<double>(), 0.10);
  // Measured 17.8 deg (9.3 before the clean-up opened necks and veils: faces with all corners
  // on the border across a strip narrower than an output edge); issue 27's goal is 15.
  EXPECT_GE(q["min_angle_deg"].get<double>(), 15.0);
  // --no-prepare: the raw scan's thousands of boundary loops hold more fixed vertices than
  // the target. Invalid input (3), the reason named, nothing written.
  std::tie(code, out) = run("remesh " + (dir / "demo" / "mesh.ply").string() +
                            " --vertices 5000 --no-prepare --out " + (dir / "r2").string());
  EXPECT_EQ(code, 3) << out;
  EXPECT_NE(out.find("fixed branch vertices"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "r2" / "mesh.ply"));
  fs::remove_all(dir);
}

// Meshes other tools write: OFF, OBJ and STL go through info, check, render and remesh alike.
TEST(CliRemesh, ReadsOffObjAndStl) {
  const test::TempDir scratch;  // removed even when an assertion ends the test early
  const fs::path& dir = scratch.path();
  const Mesh boxes = test::two_boxes(10, 4);
  Mesh box;  // one closed box (STL and OBJ have no face labels or seams)
  for (std::size_t f = 0; f < boxes.triangles.size(); ++f)
    if (boxes.face_labels[f] != 2) box.triangles.push_back(boxes.triangles[f]);  // box A + wall
  box.positions = boxes.positions;
  {
    std::vector<int> map(box.positions.size(), -1);
    Mesh compact;
    for (auto& t : box.triangles) {
      for (int& c : t) {
        if (map[c] < 0) {
          map[c] = static_cast<int>(compact.positions.size());
          compact.positions.push_back(box.positions[c]);
        }
        c = map[c];
      }
      compact.triangles.push_back(t);
    }
    box = compact;
  }
  {
    std::ofstream off(dir / "box.off");
    off << "OFF\n" << box.positions.size() << " " << box.triangles.size() << " 0\n";
    for (const auto& p : box.positions) off << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const auto& t : box.triangles) off << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  }
  write_obj(dir / "box.obj", box);
  write_stl(dir / "box.stl", box);
  for (const char* name : {"box.off", "box.obj", "box.stl"}) {
    const std::string file = (dir / name).string();
    auto [code, out] = run("info " + file + " --json");
    ASSERT_EQ(code, 0) << name << ": " << out;
    const auto j = nlohmann::json::parse(out);
    EXPECT_EQ(j["faces"], box.triangles.size()) << name << ": " << out;
    std::tie(code, out) = run("check " + file + " --require closed,vertex-manifold");
    EXPECT_EQ(code, 0) << name << ": " << out;
    std::tie(code, out) = run("render " + file + " --out " + (dir / (std::string(name) + ".png")).string());
    EXPECT_EQ(code, 0) << name << ": " << out;
    EXPECT_TRUE(fs::exists(dir / (std::string(name) + ".png"))) << name;
    std::tie(code, out) = run("remesh " + file + " --vertices 150 --features auto --out " +
                              (dir / (std::string(name) + "_r")).string());
    ASSERT_EQ(code, 0) << name << ": " << out;
    EXPECT_EQ(read_ply(dir / (std::string(name) + "_r") / "mesh.ply").positions.size(), 150u);
  }
}

}  // namespace
}  // namespace scanmesh
