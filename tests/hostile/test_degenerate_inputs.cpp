// Well-formed but degenerate inputs: point clouds that are collinear, coincident, too small or
// planar; grids with no valid cell, a single cell, a single row (a circle) or a single column
// along the phi seam. A command may refuse them (exit 3 or 4 with a message, no output) or
// succeed with a valid result — never crash, hang, report an internal error or write garbage.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"

namespace scanmesh::hostile {
namespace {

// Exit 0 with every named output a valid file, or 3/4 with nothing left in `out`.
void expect_clean_outcome(const std::vector<std::string>& args, const fs::path& out,
                          const std::vector<fs::path>& meshes = {}) {
  const RunResult r = run_cli(args);
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 3 || r.exit_code == 4) << describe(args, r);
  EXPECT_FALSE(has_temporary_file(out)) << describe(args, r);
  if (r.exit_code != 0) {
    EXPECT_TRUE(files_in(out).empty()) << "output left behind\n" << describe(args, r);
    EXPECT_NE(r.output.find("scanmesh: "), std::string::npos) << describe(args, r);
    return;
  }
  for (const fs::path& m : meshes) {
    ASSERT_TRUE(fs::exists(m)) << m << "\n" << describe(args, r);
    Mesh mesh;
    ASSERT_NO_THROW(mesh = read_ply(m)) << m;
    EXPECT_NO_THROW(mesh.validate()) << m;
    for (const auto& t : mesh.triangles)
      EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) << m << ": degenerate triangle";
  }
}

class Degenerate : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path cloud(const std::string& name, const std::vector<Eigen::Vector3d>& points) {
    std::string text;
    for (const auto& p : points)
      text +=
          std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
    write_text(dir_ / name, text);
    return dir_ / name;
  }

  fs::path grid(const std::string& name, const std::vector<std::pair<int, int>>& valid_cells,
                int n_phi = 32, int n_h = 16) {
    RangeGrid g(n_phi, n_h, 0.0, 50.0, 5.0);
    for (const auto& [i, j] : valid_cells) g.set_sample(i, j, 80.0f + 0.5f * j);
    write_grid(dir_ / name, g);
    return dir_ / name;
  }

  void fans_on(const fs::path& input) {
    const fs::path out = dir_ / ("out_" + input.filename().string());
    fs::create_directories(out);
    expect_clean_outcome({"fans", input.string(), "--out", (out / "f.ply").string()}, out,
                         {out / "f.ply"});
  }

  void grid_commands_on(const fs::path& input) {
    const std::string stem = "out_" + input.stem().string();
    const auto fresh = [&](const std::string& what) {
      const fs::path out = dir_ / (stem + "_" + what);
      fs::create_directories(out);
      return out;
    };
    fs::path out = fresh("mesh");
    expect_clean_outcome({"grid-mesh", input.string(), "--out", (out / "m.ply").string()}, out,
                         {out / "m.ply"});
    out = fresh("curvature");
    expect_clean_outcome({"curvature", input.string(), "--out", (out / "c").string()}, out);
    out = fresh("fans");
    expect_clean_outcome({"fans", input.string(), "--out", (out / "f.ply").string()}, out,
                         {out / "f.ply"});
    out = fresh("particles");
    expect_clean_outcome(
        {"particles", "--grid", input.string(), "--edge", "10", "--out", (out / "p").string()},
        out);
    out = fresh("clean");
    expect_clean_outcome({"clean", input.string(), "--out", (out / "c.smg").string()}, out);
    out = fresh("export");
    expect_clean_outcome({"export", input.string(), "--ply", (out / "e.ply").string(), "--pcd",
                          (out / "e.pcd").string(), "--depth", (out / "d.png").string()},
                         out);
  }

  fs::path dir_;
};

TEST_F(Degenerate, CollinearCloud) {
  std::vector<Eigen::Vector3d> pts;
  for (int k = 0; k < 200; ++k) pts.emplace_back(0.5 * k, 0.25 * k, -0.1 * k);
  fans_on(cloud("collinear.xyz", pts));
}

TEST_F(Degenerate, CoincidentCloud) {
  fans_on(cloud("coincident.xyz", std::vector<Eigen::Vector3d>(200, Eigen::Vector3d(1, 2, 3))));
}

TEST_F(Degenerate, TinyClouds) {
  fans_on(cloud("one.xyz", {{1, 2, 3}}));
  fans_on(cloud("two.xyz", {{0, 0, 0}, {1, 0, 0}}));
  fans_on(cloud("three.xyz", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
}

TEST_F(Degenerate, TwoCoincidentClustersAndAPlane) {
  std::vector<Eigen::Vector3d> pts(100, Eigen::Vector3d(0, 0, 0));
  pts.insert(pts.end(), 100, Eigen::Vector3d(10, 0, 0));
  fans_on(cloud("two_clusters.xyz", pts));
  std::vector<Eigen::Vector3d> plane;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) plane.emplace_back(i, j, 0.0);
  fans_on(cloud("plane.xyz", plane));  // regular and flat: must succeed
  const fs::path out = dir_ / "out_plane.xyz" / "f.ply";
  ASSERT_TRUE(fs::exists(out));
  EXPECT_GT(read_ply(out).face_count(), 0u);
}

TEST_F(Degenerate, GridWithoutValidCells) { grid_commands_on(grid("none.smg", {})); }

TEST_F(Degenerate, GridWithOneValidCell) { grid_commands_on(grid("one.smg", {{3, 4}})); }

TEST_F(Degenerate, GridWithOneRow) {
  std::vector<std::pair<int, int>> cells;
  for (int i = 0; i < 32; ++i) cells.emplace_back(i, 7);  // a circle: collinear in (phi, h)
  grid_commands_on(grid("row.smg", cells));
}

TEST_F(Degenerate, GridWithOneColumnOnTheSeam) {
  std::vector<std::pair<int, int>> cells;
  for (int j = 0; j < 16; ++j) cells.emplace_back(0, j);  // a line along phi = 0
  grid_commands_on(grid("seam_column.smg", cells));
}

TEST_F(Degenerate, GridColumnsBesideTheSeam) {
  std::vector<std::pair<int, int>> cells;
  for (int j = 0; j < 16; ++j) {
    cells.emplace_back(0, j);
    cells.emplace_back(31, j);  // the last column: neighbours across the seam only
  }
  grid_commands_on(grid("seam_strip.smg", cells));
}

}  // namespace
}  // namespace scanmesh::hostile
