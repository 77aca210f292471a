// Scene and scanner YAML: parsing, errors naming the source, validation (docs/simulator.md).
#include <gtest/gtest.h>

#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"
#include "scanmesh_test_paths.h"

using namespace scanmesh;
using namespace scanmesh::sim;

namespace {

// Expects FileFormatError whose message contains the source name and `needle`.
void expect_format_error(const std::string& yaml, const std::string& needle) {
  try {
    (void)Scene::from_yaml_text(yaml, "my-scene.yaml");
    FAIL() << "no error for: " << yaml;
  } catch (const FileFormatError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("my-scene.yaml"), std::string::npos) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << msg;
  }
}

}  // namespace

TEST(SceneYaml, ParsesAllObjectTypes) {
  const Scene s = Scene::from_yaml_text(R"(
name: zoo
objects:
  - {type: sphere, name: ball, center: [0, 0, 0], radius: 10}
  - {type: cylinder, radius: 5, half_length: 20, axis: [0, 1, 0]}
  - {type: ellipsoid, radii: [1, 2, 3]}
  - {type: torus, major_radius: 20, minor_radius: 4}
  - {type: box, center: [50, 0, 0], half_extents: [1, 2, 3]}
  - type: skeletal
    iso: 0.5
    kernel: wyvill
    elements:
      - {name: p, type: point, center: [0, 0, 0], radius: 10, weight: 1}
      - {name: s, type: segment, a: [0, 0, 0], b: [0, 0, 10], radius: 10, weight: -0.5}
texture:
  seed: 4
  base_color: [10, 20, 30]
  paints:
    - {name: dot, center: [10, 0, 0], radius: 3, color: [255, 0, 0], softness: 0.2}
hair_zones:
  - {center: [0, 0, 0], radius: 5}
  - {above_z: 100}
)",
                                        "zoo");
  EXPECT_EQ(s.name, "zoo");
  ASSERT_EQ(s.objects.size(), 6u);
  EXPECT_EQ(s.objects[0]->name, "ball");
  EXPECT_EQ(s.texture_seed, 4u);
  EXPECT_EQ(s.paints.size(), 1u);
  EXPECT_TRUE(s.in_hair_zone({1, 0, 0}));
  EXPECT_TRUE(s.in_hair_zone({90, 90, 101}));
  EXPECT_FALSE(s.in_hair_zone({90, 90, 0}));
  const Rgb8 dot = s.color_at({10, 0, 0});
  EXPECT_GT(dot.r, 200);
  EXPECT_LT(dot.g, 40);
}

TEST(SceneYaml, MalformedYamlNamesSourceAndLine) {
  expect_format_error("name: x\nobjects: [\n  {type: sphere\n", "line");
}

TEST(SceneYaml, UnknownTypeIsFormatError) {
  expect_format_error("objects:\n  - {type: dodecahedron, radius: 3}\n", "dodecahedron");
  expect_format_error(
      "objects:\n  - type: skeletal\n    elements:\n      - {type: blob, center: [0,0,0], radius: "
      "1}\n",
      "blob");
  expect_format_error(
      "objects:\n  - type: skeletal\n    kernel: blinn\n    elements:\n"
      "      - {type: point, center: [0,0,0], radius: 1}\n",
      "blinn");
}

TEST(SceneYaml, NegativeRadiusIsFormatError) {
  expect_format_error("objects:\n  - {type: sphere, radius: -3}\n", "radius");
  expect_format_error(
      "objects:\n  - type: skeletal\n    elements:\n"
      "      - {name: nose, type: point, center: [0,0,0], radius: -1}\n",
      "nose");
}

TEST(SceneYaml, MissingAndMisspelledKeysAreFormatErrors) {
  expect_format_error("objects:\n  - {type: sphere}\n", "radius");
  expect_format_error("objects:\n  - {type: sphere, raduis: 3}\n", "raduis");
  expect_format_error("name: empty\n", "objects");
  expect_format_error("objects:\n  - {type: sphere, radius: 3, center: [1, 2]}\n", "center");
}

TEST(SceneYaml, BuiltinHeadParses) {
  const Scene head = builtin_head_scene();
  EXPECT_EQ(head.name, "head");
  EXPECT_FALSE(head.objects.empty());
  EXPECT_FALSE(head.paints.empty());
  EXPECT_FALSE(head.hair_zones.empty());
}

TEST(SceneYaml, ShippedSceneFilesParse) {
  for (const char* f : {"head.yaml", "sphere.yaml", "cylinder.yaml"})
    EXPECT_NO_THROW(Scene::from_yaml_file(std::string(SCANMESH_SOURCE_DIR) + "/configs/sim/" + f))
        << f;
}

TEST(ScannerConfigYaml, ShippedHeadScannerEqualsBuiltin) {
  const ScannerConfig a = ScannerConfig::from_yaml_file(std::string(SCANMESH_SOURCE_DIR) +
                                                        "/configs/scanners/sim-head.yaml");
  const ScannerConfig b = builtin_head_scanner();
  EXPECT_EQ(a.n_phi, b.n_phi);
  EXPECT_EQ(a.n_h, b.n_h);
  EXPECT_EQ(a.radius_mm, b.radius_mm);
  EXPECT_EQ(a.h0_mm, b.h0_mm);
  EXPECT_EQ(a.dh_mm, b.dh_mm);
  EXPECT_EQ(a.noise_sigma_mm, b.noise_sigma_mm);
  EXPECT_EQ(a.grazing_limit_deg, b.grazing_limit_deg);
  EXPECT_EQ(a.occlusion, b.occlusion);
  EXPECT_EQ(a.camera_baseline_deg, b.camera_baseline_deg);
  EXPECT_EQ(a.hair_dropout_probability, b.hair_dropout_probability);
  EXPECT_EQ(a.spike_probability, b.spike_probability);
  EXPECT_EQ(a.band_min_mm, b.band_min_mm);
  EXPECT_EQ(a.band_max_mm, b.band_max_mm);
  EXPECT_EQ(a.seed, b.seed);
}

TEST(ScannerConfigYaml, ErrorsNameTheSource) {
  for (const char* text : {"n_phi: [1\n", "n_phii: 5\n", "n_phi: abc\n", "noise_sigma_mm: -1\n"}) {
    try {
      (void)ScannerConfig::from_yaml_text(text, "scan.yaml");
      FAIL() << text;
    } catch (const FileFormatError& e) {
      EXPECT_NE(std::string(e.what()).find("scan.yaml"), std::string::npos) << e.what();
    }
  }
}

TEST(ScannerConfig, ValidateRejectsImpossibleValues) {
  EXPECT_NO_THROW(ScannerConfig{}.validate());
  EXPECT_NO_THROW(builtin_head_scanner().validate());
  auto bad = [](auto change) {
    ScannerConfig c;
    change(c);
    EXPECT_THROW(c.validate(), InvalidInputError);
  };
  bad([](ScannerConfig& c) { c.n_phi = 1; });
  bad([](ScannerConfig& c) { c.n_h = 8193; });
  bad([](ScannerConfig& c) { c.radius_mm = 0.0; });
  bad([](ScannerConfig& c) { c.dh_mm = -0.1; });
  bad([](ScannerConfig& c) { c.noise_sigma_mm = -0.1; });
  bad([](ScannerConfig& c) { c.grazing_limit_deg = 0.0; });
  bad([](ScannerConfig& c) { c.grazing_limit_deg = 91.0; });
  bad([](ScannerConfig& c) { c.hair_dropout_probability = 1.5; });
  bad([](ScannerConfig& c) { c.spike_probability = -0.1; });
  bad([](ScannerConfig& c) { c.camera_radius_mm = -1.0; });
  bad([](ScannerConfig& c) {
    c.band_min_mm = 10.0;
    c.band_max_mm = 10.0;
  });
}
