// End-to-end tests of the scanmesh binary: the demo's outputs, exit codes and error messages.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/texture_layout.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

using test::run;
using test::RunResult;

// One scratch folder per test process, removed when the process exits (ctest runs each test in
// its own process, so leftovers of earlier runs never accumulate in /tmp).
struct ScratchRoot {
  fs::path path = fs::temp_directory_path() / ("scanmesh_test_cli_" + std::to_string(getpid()));
  ~ScratchRoot() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

fs::path scratch_dir(const std::string& name) {
  static const ScratchRoot root;
  const fs::path dir = root.path / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// One demo run shared by the tests that inspect its outputs (it is the slowest step).
class Demo : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    out_ = new fs::path(scratch_dir("demo"));
    result_ = new RunResult(run("demo --out " + out_->string()));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*out_);
    delete out_;
    delete result_;
  }
  static fs::path* out_;
  static RunResult* result_;
};
fs::path* Demo::out_ = nullptr;
RunResult* Demo::result_ = nullptr;

TEST_F(Demo, ProducesEveryListedFile) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  for (const char* name :
       {"scan_raw.smg", "scan.smg", "scan.pcd", "mesh.ply", "mesh.obj", "mesh.mtl", "texture.png",
        "depth.png", "render.png", "fields.smf", "curvature.png", "report.json"}) {
    EXPECT_TRUE(fs::exists(*out_ / name)) << name;
    EXPECT_GT(fs::file_size(*out_ / name), 50u) << name;
  }
  // Atomic writes leave no temporary files behind.
  for (const auto& entry : fs::directory_iterator(*out_))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST_F(Demo, ReportDescribesTheRunAndItsAccuracy) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  std::ifstream in(*out_ / "report.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["raw_grid"]["n_phi"], 512);
  EXPECT_EQ(report["raw_grid"]["n_h"], 512);
  EXPECT_GT(report["grid_mesh"]["mesh"]["faces"].get<long>(), 100000);
  EXPECT_EQ(report["grid_mesh"]["mesh"]["nonmanifold_edges"], 0);
  EXPECT_EQ(report["grid_mesh"]["mesh"]["inconsistently_oriented_edges"], 0);
  EXPECT_GT(report["dropouts"]["occluded"].get<long>(), 0);
  EXPECT_GT(report["dropouts"]["grazing"].get<long>(), 0);
  // Cleaning must catch nearly all simulated spikes; what remains is measured against truth.
  const auto& acc = report["accuracy_vs_ground_truth"];
  EXPECT_LE(acc["spikes_left_after_cleaning"].get<long>(),
            acc["spikes_simulated"].get<long>() / 20);
  // Outside the hair the scanner's sigma is 0.1 mm; the hair zone is simulated 15x noisier.
  EXPECT_LT(acc["outside_hair"]["rms_error_mm"].get<double>(), 0.15);
  EXPECT_LT(std::abs(acc["outside_hair"]["mean_error_mm"].get<double>()), 0.02);
  EXPECT_GT(acc["hair"]["rms_error_mm"].get<double>(),
            acc["outside_hair"]["rms_error_mm"].get<double>());
  EXPECT_LT(
      report["curvature"]["median_rel_error_H_outside_hair_where_abs_H_above_0.005"].get<double>(),
      0.15);
  EXPECT_LT(report["curvature"]["median_normal_error_deg_outside_hair"].get<double>(), 1.0);
  for (const char* key : {"simulate_s", "clean_s", "grid_mesh_s", "curvature_s", "total_s"})
    EXPECT_TRUE(report["timings"].contains(key)) << key;
  EXPECT_TRUE(report["versions"].contains("scanmesh"));
}

TEST_F(Demo, ObjTexcoordsMapEachVertexToItsOwnTexturePixel) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  const RangeGrid grid = read_grid(*out_ / "scan.smg");
  const Image8 texture = read_png(*out_ / "texture.png");
  ASSERT_EQ(texture.width, grid.n_phi());
  ASSERT_EQ(texture.height, grid.n_h());
  std::ifstream obj(*out_ / "mesh.obj");
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector2d> vt;
  std::string line;
  std::size_t corners = 0;
  while (std::getline(obj, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      s >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (tag == "vt") {
      Eigen::Vector2d t;
      s >> t.x() >> t.y();
      vt.push_back(t);
    } else if (tag == "f") {
      std::string corner;
      while (s >> corner) {
        const int vi = std::stoi(corner) - 1;
        const int ti = std::stoi(corner.substr(corner.find('/') + 1)) - 1;
        const Eigen::Vector3d& p = v.at(vi);
        const Eigen::Vector2d& t = vt.at(ti);
        // OBJ's v counts up from the picture's bottom row; the texture is upright, so the
        // picture row is also the grid row counted from the top (core/texture_layout.h).
        const int px = static_cast<int>(std::floor(t.x() * texture.width)) % texture.width;
        const int row = static_cast<int>(std::floor((1.0 - t.y()) * texture.height));
        const int j = texture_row(row, texture.height);  // its own inverse
        // The pixel's cell, lifted to 3D, is the vertex itself, and the pixel has its colour.
        ASSERT_TRUE(grid.valid(px, j));
        EXPECT_LT((grid.cartesian(px, j) - p).norm(), 1e-3) << "corner " << corner;
        EXPECT_EQ(texture.rgb(px, row), grid.color(px, j));
        ++corners;
      }
    }
  }
  EXPECT_GT(corners, 300000u);
}

TEST_F(Demo, InfoDescribesTheGridAndTheMesh) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  const RunResult grid_info = run("info --json " + (*out_ / "scan.smg").string());
  ASSERT_EQ(grid_info.exit_code, 0) << grid_info.output;
  EXPECT_EQ(nlohmann::json::parse(grid_info.output)["kind"], "range grid");
  const RunResult mesh_info = run("info " + (*out_ / "mesh.ply").string());
  ASSERT_EQ(mesh_info.exit_code, 0) << mesh_info.output;
  EXPECT_NE(mesh_info.output.find("faces"), std::string::npos);
}

TEST(Cli, EverySubcommandHasHelp) {
  for (const char* sub : {"sim", "info", "export", "clean", "grid-mesh", "render", "curvature",
                          "fans", "check", "particles", "demo"}) {
    const RunResult r = run(std::string(sub) + " --help");
    EXPECT_EQ(r.exit_code, 0) << sub;
    EXPECT_NE(r.output.find("Usage"), std::string::npos) << sub;
  }
}

TEST(Cli, BadArgumentsGiveOneLineAndExitCodeTwo) {
  for (const char* args : {"", "no-such-command", "sim", "grid-mesh", "demo --max-jump -3",
                           "sim --out x.smg --noise abc"}) {
    const RunResult r = run(args);
    EXPECT_EQ(r.exit_code, 2) << "args: " << args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
}

TEST(Cli, CorruptGridFileIsReportedWithItsNameAndExitCodeFour) {
  const fs::path dir = scratch_dir("corrupt");
  const fs::path bad = dir / "bad.smg";
  std::ofstream(bad) << "SCANMESHGRID but not really";
  const RunResult r = run("export " + bad.string() + " --texture " + (dir / "t.png").string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("bad.smg"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "t.png"));
}

TEST(Cli, MissingInputIsAnIoErrorOrUsageError) {
  const RunResult r = run("info /nonexistent/scan.smg");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("/nonexistent/scan.smg"), std::string::npos) << r.output;
}

TEST(Cli, SameSceneAndSeedGiveByteIdenticalGridFiles) {
  const fs::path dir = scratch_dir("determinism");
  std::ofstream(dir / "scanner.yaml")
      << "n_phi: 128\nn_h: 96\nradius_mm: 300\nh0_mm: 0\ndh_mm: 2.4\n"
         "noise_sigma_mm: 0.1\nspike_probability: 0.01\nseed: 9\n";
  const std::string scanner = (dir / "scanner.yaml").string();
  for (const char* name : {"a.smg", "b.smg"})
    ASSERT_EQ(run("sim --scanner " + scanner + " --out " + (dir / name).string()).exit_code, 0);
  ASSERT_EQ(
      run("sim --scanner " + scanner + " --seed 10 --out " + (dir / "c.smg").string()).exit_code,
      0);
  const auto bytes = [&](const char* name) {
    std::ifstream in(dir / name, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(bytes("a.smg"), bytes("b.smg"));
  EXPECT_NE(bytes("a.smg"), bytes("c.smg"));
  EXPECT_GT(bytes("a.smg").size(), 128u * 96u * 12u);
}

TEST(Cli, FansMeshAnXyzCloudAndCheckFindsItClosedAndManifold) {
  const fs::path dir = scratch_dir("fans");
  {
    // 3000 points on a sphere of radius 50 (Fibonacci spiral: deterministic, even spacing).
    std::ofstream xyz(dir / "sphere.xyz");
    for (int k = 0; k < 3000; ++k) {
      const double z = -1.0 + 2.0 * (k + 0.5) / 3000.0, a = 2.399963229728653 * k;
      xyz << 50 * std::sqrt(1 - z * z) * std::cos(a) << " "
          << 50 * std::sqrt(1 - z * z) * std::sin(a) << " " << 50 * z << "\n";
    }
  }
  const std::string mesh = (dir / "m.ply").string();
  RunResult r = run("fans " + (dir / "sphere.xyz").string() + " --out " + mesh + " --render " +
                    (dir / "r.png").string() + " --histogram " + (dir / "q.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"m.ply", "r.png", "q.png"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  // A sphere's fans are watertight: each property is asked for, so each could fail.
  r = run("check " + mesh +
          " --require non-empty,closed,edge-manifold,vertex-manifold,oriented,"
          "intersection-free,no-degenerate,no-duplicates");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("closed                yes"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("genus                 0"), std::string::npos) << r.output;
  // A mesh with an edge shared by three faces fails the check with its own exit code.
  std::ofstream(dir / "bad.ply")
      << "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
         "property float y\nproperty float z\nelement face 3\n"
         "property list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n";
  r = run("check " + (dir / "bad.ply").string());
  EXPECT_EQ(r.exit_code, 6) << r.output;
  // Malformed input: a clear message naming the file, exit 4.
  std::ofstream(dir / "broken.xyz") << "1 2 3\n4 five 6\n";
  r = run("fans " + (dir / "broken.xyz").string() + " --out " + (dir / "x.ply").string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("broken.xyz"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "x.ply"));
}

// A coloured cloud (x y z r g b a): the mesh keeps the colours, and the report gives the
// checker's verdicts, which the user can trust without running `check`.
TEST(Cli, FansCarryColoursAndReportVerdicts) {
  const fs::path dir = scratch_dir("fans_colour");
  {
    std::ofstream xyz(dir / "sphere.xyz");
    for (int k = 0; k < 2000; ++k) {
      const double z = -1.0 + 2.0 * (k + 0.5) / 2000.0, a = 2.399963229728653 * k;
      xyz << 30 * std::sqrt(1 - z * z) * std::cos(a) << " " << 30 * std::sqrt(1 - z * z) * std::sin(a)
          << " " << 30 * z << " " << (k % 256) << " 40 " << (255 - k % 256) << " 255\n";
    }
  }
  const RunResult r = run("fans " + (dir / "sphere.xyz").string() + " --out " +
                          (dir / "m.ply").string() + " --report " + (dir / "r.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / "r.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_TRUE(j["input_colours"].get<bool>());
  EXPECT_EQ(j["points"], 2000);
  EXPECT_TRUE(j["check"]["verdicts"]["closed"].get<bool>());
  EXPECT_TRUE(j["check"]["verdicts"]["vertex-manifold"].get<bool>());
  EXPECT_EQ(j["check"]["genus"], 0);
  EXPECT_EQ(j["surface_growth"]["bowtie_faces_removed"], 0);
  const Mesh m = read_ply(dir / "m.ply");
  ASSERT_EQ(m.colors.size(), 2000u);
  EXPECT_EQ(m.colors[300].r, 300 % 256);
  EXPECT_EQ(m.colors[300].g, 40);
  EXPECT_EQ(m.colors[300].b, 255 - 300 % 256);
}

TEST(Cli, ParticlesMeshASphereSceneIntoAClosedMesh) {
  const fs::path dir = scratch_dir("particles");
  std::ofstream(dir / "ball.yaml") << "name: ball\nobjects:\n  - {type: sphere, center: [0, 0, 0], "
                                      "radius: 20}\n";
  const RunResult r = run("particles " + (dir / "ball.yaml").string() + " --edge 4 --out " +
                          (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"particles.ply", "particles.png", "particles.json"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  const RunResult c = run("check " + (dir / "out" / "particles.ply").string() +
                          " --require closed,vertex-manifold,oriented,intersection-free");
  EXPECT_EQ(c.exit_code, 0) << c.output;
}

// `check` exits 0 on any edge-manifold mesh; --require states what must hold. A single open
// triangle is edge- and vertex-manifold but not closed, an empty mesh is nothing.
TEST(Cli, CheckRequireSetsTheExitCodeFromTheNamedProperties) {
  const fs::path dir = scratch_dir("check_require");
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face ";
  std::ofstream(dir / "tri.ply") << header
                                 << "1\nproperty list uchar int vertex_indices\nend_header\n"
                                    "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  std::ofstream(dir / "empty.ply") << header
                                   << "0\nproperty list uchar int vertex_indices\nend_header\n"
                                      "0 0 0\n1 0 0\n0 1 0\n";
  const std::string tri = (dir / "tri.ply").string();
  RunResult r = run("check " + tri);
  EXPECT_EQ(r.exit_code, 0) << r.output;  // the legacy verdict: edge-manifold
  EXPECT_NE(r.output.find("closed                NO (1 boundary loops"), std::string::npos)
      << r.output;
  r = run("check " + tri + " --require closed");
  EXPECT_EQ(r.exit_code, 10) << r.output;
  EXPECT_NE(r.output.find("is not closed"), std::string::npos) << r.output;
  r = run("check " + tri + " --require edge-manifold,vertex-manifold,oriented,intersection-free");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = run("check " + (dir / "empty.ply").string() + " --require vertex-manifold,non-empty");
  EXPECT_EQ(r.exit_code, 10) << r.output;
  EXPECT_NE(r.output.find("is not non-empty"), std::string::npos) << r.output;
  // An unknown property or a contradiction is a usage problem, before the file is read.
  r = run("check " + tri + " --require watertight");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("watertight"), std::string::npos) << r.output;
  r = run("check " + tri + " --require intersection-free --no-intersections");
  EXPECT_EQ(r.exit_code, 3) << r.output;
}

// Scan mode: the scan's continuous surface through its implicit view; relaxation terminates
// and reports convergence (docs/particles.md).
TEST(Cli, ParticlesScanModeConvergesOnASimulatedBall) {
  const fs::path dir = scratch_dir("particles_scan");
  std::ofstream(dir / "ball.yaml")
      << "name: ball\nobjects:\n  - {type: sphere, center: [0, 0, 100], "
         "radius: 60}\n";
  std::ofstream(dir / "scanner.yaml")
      << "n_phi: 96\nn_h: 64\nradius_mm: 300\nh0_mm: 20\ndh_mm: 2.5\n"
         "noise_sigma_mm: 0.05\nseed: 3\n";
  const std::string grid = (dir / "g.smg").string();
  RunResult r = run("sim --scene " + (dir / "ball.yaml").string() + " --scanner " +
                    (dir / "scanner.yaml").string() + " --out " + grid);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("clean " + grid + " --out " + (dir / "c.smg").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("particles --grid " + (dir / "c.smg").string() + " --edge 8 --out " +
          (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(converged)"), std::string::npos) << r.output;
  std::ifstream in(dir / "out" / "particles.json");
  std::stringstream json;
  json << in.rdbuf();
  EXPECT_NE(json.str().find("\"converged\": true"), std::string::npos) << json.str();
  EXPECT_NE(json.str().find("\"mode\": \"scan\""), std::string::npos) << json.str();
}

TEST(Cli, CleanFillsSmallHolesOnlyWhenAsked) {
  const fs::path dir = scratch_dir("clean_fill");
  std::ofstream(dir / "scanner.yaml")
      << "n_phi: 128\nn_h: 128\nradius_mm: 300\nh0_mm: 20\ndh_mm: 1.6\n"
         "noise_sigma_mm: 0.05\nseed: 3\n";
  const std::string grid = (dir / "g.smg").string();
  RunResult r = run("sim --scanner " + (dir / "scanner.yaml").string() + " --out " + grid);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("clean " + grid + " --out " + (dir / "plain.smg").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("filled"), std::string::npos) << r.output;
  r = run("clean " + grid + " --out " + (dir / "filled.smg").string() + " --fill-holes 40");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("filled"), std::string::npos) << r.output;
  const RangeGrid plain = read_grid(dir / "plain.smg"), filled = read_grid(dir / "filled.smg");
  const std::size_t added = filled.valid_count() - plain.valid_count();
  ASSERT_GT(filled.valid_count(), plain.valid_count()) << "the head scan has small holes";
  EXPECT_EQ(filled.metadata.at("filled_cells"), std::to_string(added));
  std::size_t zero_confidence = 0;
  for (int j = 0; j < filled.n_h(); ++j)
    for (int i = 0; i < filled.n_phi(); ++i) {
      if (!plain.valid(i, j)) {
        zero_confidence += filled.valid(i, j) && filled.confidence(i, j) == 0.0f ? 1 : 0;
        continue;
      }
      ASSERT_TRUE(filled.valid(i, j));  // filling never removes or changes a cell
      EXPECT_EQ(filled.radius(i, j), plain.radius(i, j));
    }
  EXPECT_EQ(zero_confidence, added);
  r = run("clean " + grid + " --out " + (dir / "bad.smg").string() + " --fill-holes -3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(fs::exists(dir / "bad.smg"));
}

TEST(Cli, SimThenExportThenGridMeshOnASmallScanner) {
  const fs::path dir = scratch_dir("pipeline");
  std::ofstream(dir / "scanner.yaml")
      << "n_phi: 96\nn_h: 64\nradius_mm: 300\nh0_mm: 20\ndh_mm: 2.5\n"
         "noise_sigma_mm: 0.05\nseed: 3\n";
  const std::string grid = (dir / "g.smg").string();
  RunResult r = run("sim --scanner " + (dir / "scanner.yaml").string() + " --out " + grid);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("export " + grid + " --pcd " + (dir / "g.pcd").string() + " --ply " +
          (dir / "g.ply").string() + " --texture " + (dir / "t.png").string() + " --depth " +
          (dir / "d.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"g.pcd", "g.ply", "t.png", "d.png"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  r = run("clean " + grid + " --out " + (dir / "c.smg").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("grid-mesh " + (dir / "c.smg").string() + " --out " + (dir / "m.ply").string() +
          " --obj " + (dir / "m.obj").string() + " --stl " + (dir / "m.stl").string() +
          " --render " + (dir / "r.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"m.ply", "m.obj", "m.mtl", "m_texture.png", "m.stl", "r.png"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  r = run("render " + (dir / "m.ply").string() + " --out " + (dir / "r2.png").string() +
          " --size 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_png(dir / "r2.png").width, 64);
}

TEST(Cli, CurvatureWritesFieldsPicturesAndReportForEachMethod) {
  const fs::path dir = scratch_dir("curvature");
  std::ofstream(dir / "scanner.yaml")
      << "n_phi: 96\nn_h: 64\nradius_mm: 300\nh0_mm: 20\ndh_mm: 2.5\n"
         "noise_sigma_mm: 0.05\nseed: 3\n";
  const std::string grid = (dir / "g.smg").string();
  RunResult r = run("sim --scanner " + (dir / "scanner.yaml").string() + " --out " + grid);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* method : {"analytic", "grid-quadric", "quadric", "seed"}) {
    const fs::path out = dir / method;
    // Cells here are 2.5 x ~5 mm, so the quadric fits need a wider neighbourhood than 6 mm.
    r = run("curvature " + grid + " --out " + out.string() + " --method " + method +
            " --radius 15");
    ASSERT_EQ(r.exit_code, 0) << method << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    const bool seed = std::string(method) == "seed";
    std::vector<std::string> expected = {"fields.smf", "curvature_grey.png", "curvature.json"};
    if (!seed)
      expected.insert(expected.end(), {"mean_curvature.png", "gauss_curvature.png", "normals.png"});
    for (const auto& f : expected) EXPECT_TRUE(fs::exists(out / f)) << method << ": " << f;
    std::ifstream in(out / "curvature.json");
    const nlohmann::json report = nlohmann::json::parse(in);
    EXPECT_EQ(report["method"], seed ? std::string("seed000") : std::string(method));
    EXPECT_GT(report["counts"]["defined_cells"].get<long>(), 96 * 64 / 4) << method;
    EXPECT_LE(report["counts"]["defined_cells"].get<long>(),
              report["counts"]["valid_cells"].get<long>());
    EXPECT_TRUE(report["percentiles"]["k1"].contains("p50")) << method;
    EXPECT_TRUE(report["timings"].contains("total_s"));
    const Image8 grey = read_png(out / "curvature_grey.png");
    EXPECT_EQ(grey.width, 96);
    EXPECT_EQ(grey.height, 64);
    if (!seed) {
      EXPECT_EQ(read_png(out / "mean_curvature.png").width, 96 + 70);
    }
  }
  EXPECT_FALSE(fs::exists(dir / "seed" / "normals.png"));
  r = run("curvature " + grid + " --out " + (dir / "bogus").string() + " --method bogus");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(dir / "bogus"));
}

}  // namespace
}  // namespace scanmesh
