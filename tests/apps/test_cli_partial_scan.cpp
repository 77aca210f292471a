// Partial scans through the command line (issue 25 item 2): a grid whose data cover only a
// quarter turn round the face, as an imported face scan would, run through every grid stage
// and through `animesh` with a line that does not close on its own (docs/animation-meshes.md,
// "Partial scans: the data border").
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;
using test::run;

const fs::path kConfigs = fs::path(SCANMESH_SOURCE_DIR) / "configs" / "sim";

// The data keep the columns [first, end) of the turn, round the face at phi = pi.
struct Quarter {
  int first, end;
};

RangeGrid keep_columns(RangeGrid grid, Quarter q) {
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i)
      if (i < q.first || i >= q.end) grid.invalidate(i, j);
  return grid;
}

void write_text(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

class CliPartialScan : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("scanmesh_test_cli_partial_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // The sample head, 512 columns, and a coarse one (128 x 128) for the particle mesher, whose
    // full-resolution run takes minutes.
    const fs::path coarse_scanner = dir_ / "coarse-scanner.yaml";
    std::ifstream ideal(kConfigs / "head-scanner-ideal.yaml");
    std::string yaml((std::istreambuf_iterator<char>(ideal)), {});
    yaml.replace(yaml.find("n_phi: 512"), 10, "n_phi: 128");
    yaml.replace(yaml.find("n_h: 512"), 8, "n_h: 128");
    yaml.replace(yaml.find("dh_mm: 0.45"), 11, "dh_mm: 1.8");
    write_text(coarse_scanner, yaml);
    for (const auto& [scanner, name, quarter] :
         {std::tuple{kConfigs / "head-scanner-ideal.yaml", "head", Quarter{192, 320}},
          std::tuple{coarse_scanner, "coarse", Quarter{48, 80}}}) {
      const fs::path full = dir_ / (std::string(name) + "-full.smg");
      const auto r = run("sim --scanner " + scanner.string() + " --out " + full.string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
      write_grid(dir_ / (std::string(name) + ".smg"), keep_columns(read_grid(full), quarter));
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string grid() { return (dir_ / "head.smg").string(); }
  static fs::path dir_;
};
fs::path CliPartialScan::dir_;

TEST_F(CliPartialScan, AnimeshWithALineThatDoesNotCloseFindsTheRegionsOfTheBorder) {
  // Across the face under the eyes, from outside the data to outside the data (y counts down
  // from the top of the upright 512-row texture: h row 235 is y = 512 - 235).
  const fs::path lines = dir_ / "across.json";
  write_text(lines, R"({"lines": [{"id": "across", "points": [[150, 277], [360, 277]]}]})");
  const fs::path out = dir_ / "anim";
  const auto r = run("animesh " + grid() + " --lines " + lines.string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("data border (auto)"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(out / "animesh.json");
  EXPECT_EQ(j["regions"].size(), 2u) << j["regions"].dump();
  EXPECT_TRUE(j["data_border"]["on"].get<bool>());
  EXPECT_EQ(j["data_border"]["clipped_lines"], 1);
  EXPECT_TRUE(j["check"]["edge_manifold"].get<bool>());
  EXPECT_EQ(j["check"]["self_intersections"], 0);
  EXPECT_EQ(j["check"]["boundary_loops"], 1);
  for (const auto& region : j["regions"]) EXPECT_EQ(region["unmeshed_front_edges"], 0);
  // Today's behaviour without the border: the line leaves the scanned area.
  const auto off = run("regions " + grid() + " --lines " + lines.string() + " --data-border off");
  EXPECT_EQ(off.exit_code, 4) << off.output;
  EXPECT_NE(off.output.find("leaves the scanned area"), std::string::npos) << off.output;
}

TEST_F(CliPartialScan, RegionsWithoutLinesIsTheWholePatchAndTheSettingsCanTurnTheBorderOff) {
  const auto r = run("regions " + grid());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(" 1 regions, 0 openings"), std::string::npos) << r.output;
  const fs::path settings = dir_ / "border-off.yaml";
  write_text(settings, "data_border: off\n");
  const auto off = run("regions " + grid() + " --settings " + settings.string());
  ASSERT_EQ(off.exit_code, 0) << off.output;
  EXPECT_NE(off.output.find(" 0 regions"), std::string::npos) << off.output;
  EXPECT_EQ(off.output.find("data border"), std::string::npos) << off.output;
  // The option wins over the file.
  const auto on =
      run("regions " + grid() + " --settings " + settings.string() + " --data-border on");
  EXPECT_NE(on.output.find(" 1 regions"), std::string::npos) << on.output;
}

TEST_F(CliPartialScan, EveryGridStageRunsOnAPartialGrid) {
  const fs::path cleaned = dir_ / "clean.smg";
  auto r = run("clean " + grid() + " --out " + cleaned.string() + " --fill-holes 50");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const RangeGrid before = read_grid(grid()), after = read_grid(cleaned);
  // Cleaning removes spikes and fragments; it must not eat the patch nor fill the missing turn.
  EXPECT_GT(after.valid_count(), before.valid_count() * 99 / 100);
  EXPECT_LE(after.valid_count(), before.valid_count());

  const fs::path ply = dir_ / "grid-mesh.ply";
  r = run("grid-mesh " + grid() + " --out " + ply.string() + " --render " +
          (dir_ / "grid-mesh.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Mesh mesh = read_ply(ply);
  ASSERT_GT(mesh.triangles.size(), 20000u);
  // No triangle outside the covered columns [192, 320) of 512 (phi0 = 0).
  const double dphi = 2 * M_PI / 512;
  for (const auto& p : mesh.positions) {
    const double phi = std::atan2(p.y(), p.x()) + (p.y() < 0 ? 2 * M_PI : 0.0);
    EXPECT_GT(phi, (192 - 0.5) * dphi);
    EXPECT_LT(phi, (319 + 0.5) * dphi);
  }

  const fs::path curvature = dir_ / "curvature";
  r = run("curvature " + grid() + " --out " + curvature.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"fields.smf", "curvature_grey.png", "mean_curvature.png",
                        "gauss_curvature.png", "normals.png", "curvature.json"})
    EXPECT_TRUE(fs::exists(curvature / f)) << f;
  const nlohmann::json cj = read_json(curvature / "curvature.json");
  // The fields cover the patch's cells, and no statistic is NaN (written as null) for want of
  // the missing three quarters.
  EXPECT_EQ(cj["counts"]["valid_cells"], before.valid_count());
  EXPECT_GT(cj["counts"]["defined_cells"].get<double>(), 0.9 * before.valid_count());
  EXPECT_EQ(cj.dump().find("null"), std::string::npos) << cj.dump();

  const fs::path exported = dir_ / "export";
  fs::create_directories(exported);
  r = run("export " + grid() + " --ply " + (exported / "points.ply").string() + " --texture " +
          (exported / "texture.png").string() + " --depth " + (exported / "depth.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"points.ply", "texture.png", "depth.png"})
    EXPECT_TRUE(fs::exists(exported / f)) << f;

  const fs::path particles = dir_ / "particles";
  r = run("particles --grid " + (dir_ / "coarse.smg").string() + " --edge 8 --out " +
          particles.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json pj = read_json(particles / "particles.json");
  // One open patch: a disc (Euler characteristic 1, one boundary loop), not the open band of
  // a full turn.
  EXPECT_GT(pj["mesh"]["triangles"].get<int>(), 500) << pj.dump();
  EXPECT_EQ(pj["mesh"]["nonmanifold_edges"], 0) << pj.dump();
  EXPECT_EQ(pj["mesh"]["boundary_loops"], 1) << pj.dump();
  EXPECT_EQ(pj["mesh"]["euler_characteristic"], 1) << pj.dump();
  EXPECT_TRUE(pj["converged"].get<bool>()) << pj.dump();
}

}  // namespace
}  // namespace scanmesh
