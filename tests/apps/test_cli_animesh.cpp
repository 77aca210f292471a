// End-to-end test of `scanmesh regions` and `scanmesh animesh` on the sample head (seed 000):
// the outputs a user gets (mesh files, report, pictures) and the errors for bad input.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;
using test::run;

const fs::path kConfigs = fs::path(SCANMESH_SOURCE_DIR) / "configs" / "sim";

class CliAnimesh : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("scanmesh_test_cli_animesh_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const auto r = run("sim --scanner " + (kConfigs / "head-scanner-ideal.yaml").string() +
                       " --out " + (dir_ / "head.smg").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string sample_args() {
    return (dir_ / "head.smg").string() + " --lines " + (kConfigs / "head-lines.svg").string() +
           " --settings " + (kConfigs / "head-regions.yaml").string();
  }
  static fs::path dir_;
};
fs::path CliAnimesh::dir_;

TEST_F(CliAnimesh, RegionsPrintsTheGraphAndDrawsTheLayout) {
  const fs::path png = dir_ / "regions.png";
  const auto r = run("regions " + sample_args() + " --png " + png.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("17 regions, 3 openings"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nose"), std::string::npos) << r.output;
  const Image8 img = read_png(png);
  EXPECT_EQ(img.width, 512);
  EXPECT_EQ(img.height, 512);
}

TEST_F(CliAnimesh, AnimeshWritesMeshReportAndPictures) {
  const fs::path out = dir_ / "anim";
  const auto r = run("animesh " + sample_args() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"mesh.ply", "mesh.obj", "animesh.json", "regions.png", "mesh2d.png",
                        "render.png", "min_angle_histogram.png", "radius_ratio_histogram.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const Mesh mesh = read_ply(out / "mesh.ply");
  const auto report = nlohmann::json::parse(std::ifstream(out / "animesh.json"));
  EXPECT_EQ(report["vertices"], mesh.positions.size());
  EXPECT_EQ(report["triangles"], mesh.triangles.size());
  ASSERT_TRUE(mesh.has_face_labels());
  // The acceptance figures of the sample head, as the report states them.
  EXPECT_GE(report["quality"]["min_angle_deg"].get<double>(), 20.0);
  EXPECT_GE(report["quality"]["fraction_min_angle_ge_30"].get<double>(), 0.95);
  EXPECT_TRUE(report["check"]["edge_manifold"].get<bool>());
  EXPECT_EQ(report["check"]["self_intersections"], 0);
  EXPECT_EQ(report["check"]["duplicate_faces"], 0);
  EXPECT_EQ(report["regions"].size(), 17u);
  EXPECT_TRUE(report["seams"].contains("back-seam"));
  // The histograms count every triangle.
  std::size_t in_min_angle_bins = 0, in_q_bins = 0;
  for (const auto& n : report["quality"]["min_angle_histogram_5deg"])
    in_min_angle_bins += n.get<std::size_t>();
  for (const auto& n : report["quality"]["radius_ratio_histogram_0.1"])
    in_q_bins += n.get<std::size_t>();
  EXPECT_EQ(in_min_angle_bins, mesh.triangles.size());
  EXPECT_EQ(in_q_bins, mesh.triangles.size());
  EXPECT_EQ(read_png(out / "radius_ratio_histogram.png").width, 640);
  // mesh2d.png is upright, like the texture: the mesh lies between the crown line (y = 72 from
  // the top) and the neck line (y = 482), so the rows above and below are the texture's own.
  ASSERT_EQ(run("export " + (dir_ / "head.smg").string() + " --texture " +
                (dir_ / "texture.png").string())
                .exit_code,
            0);
  const Image8 texture = read_png(dir_ / "texture.png"), mesh2d = read_png(out / "mesh2d.png");
  ASSERT_EQ(mesh2d.height, texture.height);
  auto changed = [&](int y) {
    int n = 0;
    for (int x = 0; x < texture.width; ++x) n += !(texture.rgb(x, y) == mesh2d.rgb(x, y));
    return n;
  };
  EXPECT_EQ(changed(50), 0);
  EXPECT_EQ(changed(500), 0);
  EXPECT_GT(changed(460), 20) << "mesh edges between the old crown row and the neck";
  EXPECT_GT(changed(100), 20);
}

TEST_F(CliAnimesh, SameInputAndSeedGiveTheSameMesh) {
  const auto a = run("animesh " + sample_args() + " --seed 3 --strategy random --out " +
                     (dir_ / "seed_a").string());
  const auto b = run("animesh " + sample_args() + " --seed 3 --strategy random --out " +
                     (dir_ / "seed_b").string());
  ASSERT_EQ(a.exit_code, 0) << a.output;
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const Mesh ma = read_ply(dir_ / "seed_a" / "mesh.ply"),
             mb = read_ply(dir_ / "seed_b" / "mesh.ply");
  EXPECT_EQ(ma.positions, mb.positions);
  EXPECT_EQ(ma.triangles, mb.triangles);
}

TEST_F(CliAnimesh, LinesLeavingTheScannedAreaAreABadFileAndWriteNothing) {
  // The realistic demo scan has occlusion shadows and hair holes that the sample lines cross.
  const fs::path holes = dir_ / "holes.smg";
  auto r = run("sim --out " + holes.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path out = dir_ / "not_written";
  r = run("animesh " + holes.string() + " --lines " + (kConfigs / "head-lines.svg").string() +
          " --out " + out.string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("head-lines.svg"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("leaves the scanned area"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "mesh.ply"));
}

// A front that cannot close (here: a step budget far too small for any region) still writes
// every output, says so in one line and exits 9, not 0 and not 1 (a bug).
TEST_F(CliAnimesh, OpenFrontsWriteEverythingAndExitNine) {
  const fs::path settings = dir_ / "tiny_budget.yaml";
  std::ofstream(settings) << "unit_mm: 24\nmax_front_steps: 3\n";
  const fs::path out = dir_ / "open";
  const auto r = run("animesh " + (dir_ / "head.smg").string() + " --lines " +
                     (kConfigs / "head-lines.svg").string() + " --settings " + settings.string() +
                     " --out " + out.string());
  EXPECT_EQ(r.exit_code, 9) << r.output;
  EXPECT_NE(r.output.find("scanmesh: incomplete mesh: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("front edges not closed"), std::string::npos) << r.output;
  for (const char* f : {"mesh.ply", "animesh.json", "render.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const auto report = nlohmann::json::parse(std::ifstream(out / "animesh.json"));
  int open_edges = 0;
  for (const auto& region : report["regions"])
    open_edges += region["unmeshed_front_edges"].get<int>();
  EXPECT_GT(open_edges, 0);
}

TEST_F(CliAnimesh, MalformedSettingsNameTheFileAndLine) {
  const fs::path settings = dir_ / "bad.yaml";
  std::ofstream(settings) << "unit_mm: 10\nregions:\n  - {name: nose, point: [256, 282], "
                             "unit_mm: -3}\n";
  const auto r = run("animesh " + (dir_ / "head.smg").string() + " --lines " +
                     (kConfigs / "head-lines.svg").string() + " --settings " + settings.string() +
                     " --out " + (dir_ / "bad_out").string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("bad.yaml"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "bad_out" / "mesh.ply"));
}

}  // namespace
}  // namespace scanmesh
