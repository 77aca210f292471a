// What the commands print (docs/cli.md, "Output"): --json is one JSON object on stdout with the
// result's numbers as numbers, also when the command fails; --quiet prints nothing but errors.
// And the pictures they write are upright and labelled (docs/formats.md, "Texture layout").
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "scanmesh/core/image.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;
using test::run;
using test::run_stdout;

const fs::path kConfigs = fs::path(SCANMESH_SOURCE_DIR) / "configs" / "sim";
const fs::path kCorpus = fs::path(SCANMESH_CORPUS_DIR);

class CliOutput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("scanmesh_test_cli_output_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // A small sphere scan (128 x 64 cells) for the grid commands, and the ideal sample head
    // with its lines for the region pictures.
    std::ifstream ideal(kConfigs / "head-scanner-ideal.yaml");
    std::string yaml((std::istreambuf_iterator<char>(ideal)), {});
    yaml.replace(yaml.find("n_phi: 512"), 10, "n_phi: 128");
    yaml.replace(yaml.find("n_h: 512"), 8, "n_h: 64");
    yaml.replace(yaml.find("dh_mm: 0.45"), 11, "dh_mm: 3.6");
    std::ofstream(dir_ / "small-scanner.yaml") << yaml;
    auto r =
        run("sim --scene " + (kConfigs / "sphere.yaml").string() + " --scanner " +
            (dir_ / "small-scanner.yaml").string() + " --out " + path("sphere.smg") + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = run("sim --scanner " + (kConfigs / "head-scanner-ideal.yaml").string() + " --out " +
            path("head.smg") + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string path(const std::string& name) { return (dir_ / name).string(); }

  // `scanmesh ARGS --json`: stdout must be exactly one JSON object with the exit code.
  static nlohmann::json json_of(const std::string& args, int expected_exit = 0) {
    const auto r = run_stdout(args + " --json");
    EXPECT_EQ(r.exit_code, expected_exit) << args << "\n" << r.output;
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(r.output);
    } catch (const std::exception& e) {
      ADD_FAILURE() << args << ": stdout is not one JSON object: " << e.what() << "\n" << r.output;
      return nlohmann::json::object();
    }
    EXPECT_TRUE(j.is_object()) << args;
    EXPECT_EQ(j.value("exit_code", -1), expected_exit) << args;
    return j;
  }
  static fs::path dir_;
};
fs::path CliOutput::dir_;

TEST_F(CliOutput, JsonOnEveryResultCommandIsOneObjectWithNumbersAsNumbers) {
  const std::string grid = path("sphere.smg");
  nlohmann::json j = json_of("info " + grid);
  EXPECT_EQ(j["kind"], "range grid");
  EXPECT_TRUE(j["valid_cells"].is_number_unsigned());

  j = json_of("sim --scene " + (kConfigs / "sphere.yaml").string() + " --scanner " +
              path("small-scanner.yaml") + " --out " + path("again.smg"));
  EXPECT_EQ(j["grid"]["n_phi"], 128);
  EXPECT_EQ(j["out"], path("again.smg"));

  j = json_of("clean " + grid + " --out " + path("clean.smg"));
  EXPECT_TRUE(j["spikes_removed"].is_number_unsigned());
  EXPECT_GT(j["valid_cells"].get<std::size_t>(), 1000u);

  j = json_of("export " + grid + " --texture " + path("t.png") + " --depth " + path("d.png"));
  EXPECT_EQ(j["outputs"]["texture"], path("t.png"));

  j = json_of("grid-mesh " + grid + " --out " + path("m.ply") + " --render " + path("m.png"));
  EXPECT_GT(j["mesh"]["faces"].get<std::size_t>(), 1000u);
  EXPECT_TRUE(j["mesh"]["euler_characteristic"].is_number_integer());

  j = json_of("check " + path("m.ply"));
  EXPECT_EQ(j["faces"], j["faces"].get<std::size_t>());
  EXPECT_TRUE(j["verdicts"]["edge-manifold"].get<bool>());
  EXPECT_TRUE(j["verdicts"]["intersection-free"].is_boolean());
  EXPECT_TRUE(j["min_angle_deg"].is_number_float());

  j = json_of("render " + path("m.ply") + " --out " + path("r.png"));
  EXPECT_EQ(j["drawn_as"], "triangles");

  j = json_of("curvature " + grid + " --out " + path("curv"));
  EXPECT_GT(j["counts"]["defined_cells"].get<std::size_t>(), 1000u);

  j = json_of("fans " + grid + " --out " + path("f.ply"));
  EXPECT_EQ(j["points"].get<std::size_t>(),
            nlohmann::json::parse(run_stdout("info " + grid + " --json").output)["valid_cells"]
                .get<std::size_t>());
  EXPECT_TRUE(j["check"]["verdicts"]["vertex-manifold"].get<bool>());

  j = json_of("import " + (kCorpus / "points_3" / "kitten.xyz").string() + " --out " +
              path("k.smg"));
  EXPECT_EQ(j["input_points"], 5210);
  EXPECT_FALSE(j["colors"].get<bool>());
}

TEST_F(CliOutput, JsonOfAFailedCommandCarriesTheErrorAndTheExitCode) {
  std::ofstream(dir_ / "broken.ply")
      << "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n";
  const nlohmann::json j = json_of("check " + path("broken.ply"), 4);
  ASSERT_TRUE(j.contains("error")) << j.dump();
  EXPECT_NE(j["error"].get<std::string>().find("broken.ply"), std::string::npos) << j.dump();
  // The same words as the line on stderr.
  const auto r = run("check " + path("broken.ply"));
  EXPECT_NE(r.output.find(j["error"].get<std::string>()), std::string::npos) << r.output;
}

TEST_F(CliOutput, QuietPrintsNothingButErrors) {
  auto r = run("grid-mesh " + path("sphere.smg") + " --out " + path("q.ply") + " --quiet");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output, "");
  EXPECT_TRUE(fs::exists(dir_ / "q.ply"));
  r = run("check " + path("missing.ply") + " --quiet");
  EXPECT_EQ(r.exit_code, 5);
  EXPECT_NE(r.output.find("missing.ply"), std::string::npos);
  EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << "one line: " << r.output;
  r = run("check " + path("q.ply") + " --quiet --json");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // not both
}

// Texture-layout pictures are upright: the sample head's lines (crown at y = 72, neck at
// y = 482 from the top of its 512-row texture) bound the regions, so regions.png changes the
// texture between those rows only. The old upside-down layout would have coloured rows 30..440.
TEST_F(CliOutput, RegionPictureIsUprightAndNamesItsRegions) {
  ASSERT_EQ(run("export " + path("head.smg") + " --texture " + path("head_texture.png")).exit_code,
            0);
  const auto r = run("regions " + path("head.smg") + " --lines " +
                     (kConfigs / "head-lines.svg").string() + " --settings " +
                     (kConfigs / "head-regions.yaml").string() + " --png " + path("regions.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image8 texture = read_png(dir_ / "head_texture.png");
  const Image8 regions = read_png(dir_ / "regions.png");
  ASSERT_EQ(regions.width, texture.width);
  ASSERT_EQ(regions.height, texture.height);
  auto changed_in_row = [&](int y) {
    int n = 0;
    for (int x = 0; x < texture.width; ++x) n += !(texture.rgb(x, y) == regions.rgb(x, y));
    return n;
  };
  EXPECT_EQ(changed_in_row(50), 0) << "above the crown line: no region";
  EXPECT_EQ(changed_in_row(500), 0) << "below the neck line: no region";
  EXPECT_GT(changed_in_row(100), 400) << "between crown and neck: regions";
  EXPECT_GT(changed_in_row(460), 400) << "between the old crown row and the neck: regions";
  // Labels: light boxes with black text, one per region that is not an opening.
  int label_pixels = 0;
  for (int y = 0; y < regions.height; ++y)
    for (int x = 0; x < regions.width; ++x)
      label_pixels += regions.rgb(x, y) == Rgb8{245, 245, 245};
  EXPECT_GT(label_pixels, 17 * 40);
}

TEST_F(CliOutput, RenderViewsAreLabelledAndAnImportWithoutColoursIsGrey) {
  const std::string grid = path("k.smg");
  ASSERT_EQ(run("import " + (kCorpus / "points_3" / "kitten.xyz").string() + " --out " + grid +
                " --texture " + path("k_texture.png") + " --quiet")
                .exit_code,
            0);
  const Image8 texture = read_png(dir_ / "k_texture.png");
  for (int y = 0; y < texture.height; ++y)
    for (int x = 0; x < texture.width; ++x)
      ASSERT_EQ(texture.rgb(x, y), (Rgb8{190, 190, 190})) << "kitten.xyz has no colours";
  ASSERT_EQ(run("grid-mesh " + grid + " --out " + path("k.ply") + " --render " +
                path("k_views.png") + " --quiet")
                .exit_code,
            0);
  const Image8 views = read_png(dir_ / "k_views.png");
  ASSERT_EQ(views.width, 3 * views.height);
  const int view = views.height;
  for (int v = 0; v < 3; ++v) {
    int caption = 0;  // the caption's light grey in the view's top-left corner
    for (int y = 0; y < 40; ++y)
      for (int x = v * view; x < v * view + view / 2; ++x)
        caption += views.rgb(x, y) == Rgb8{220, 220, 220};
    EXPECT_GT(caption, 100) << "view " << v << " has no caption";
  }
  // A point cloud renders as points, not a blank picture.
  ASSERT_EQ(run("render " + (kCorpus / "points_3" / "kitten.xyz").string() + " --out " +
                path("cloud.png") + " --size 200 --quiet")
                .exit_code,
            0);
  const Image8 cloud = read_png(dir_ / "cloud.png");
  const Rgb8 background = cloud.rgb(0, 0);
  int drawn = 0;
  for (int y = 0; y < cloud.height; ++y)
    for (int x = 0; x < cloud.width; ++x) drawn += !(cloud.rgb(x, y) == background);
  EXPECT_GT(drawn, 2000);
}

}  // namespace
}  // namespace scanmesh
