// End-to-end test of `scanmesh remesh`: the non-manifold two-box input with labels, the report,
// pictures, and the feature-lines errors (exit codes 3 and 4).
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
#include "scanmesh/core/mesh_io.h"

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

}  // namespace
}  // namespace scanmesh
