// The simulated turntable camera: rig files, determinism, the camera model's own consistency,
// and ground truth that lies exactly on the scene, on the laser sheet and on the rendered line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <unistd.h>

#include "scanmesh/core/errors.h"
#include "scanmesh/sim/turntable_camera.h"

namespace scanmesh::sim {
namespace {

constexpr double kPi = std::numbers::pi;

Scene sphere_scene(double radius = 50.0, double z = 70.0) {
  return Scene::from_yaml_text(
      "name: ball\nobjects:\n  - {type: sphere, name: ball, center: [0, 0, " + std::to_string(z) +
          "], radius: " + std::to_string(radius) +
          "}\ntexture: {seed: 3, base_color: [200, 200, 200]}\n",
      "test sphere");
}

RigConfig small_rig() {
  // Half resolution keeps the tests quick; the geometry is the built-in one.
  RigConfig r = builtin_ciclop_rig();
  r.width = 640;
  r.height = 480;
  r.intrinsics.fx /= 2;
  r.intrinsics.fy /= 2;
  r.intrinsics.cx = (r.intrinsics.cx + 0.5) / 2 - 0.5;
  r.intrinsics.cy = (r.intrinsics.cy + 0.5) / 2 - 0.5;
  return r;
}

TEST(TurntableRig, YamlRoundTripAndErrors) {
  const RigConfig a = builtin_ciclop_rig();
  const RigConfig b = RigConfig::from_yaml_text(a.to_yaml(), "round trip");
  EXPECT_EQ(b.to_yaml(), a.to_yaml());
  EXPECT_EQ(b.lasers.size(), 2u);
  EXPECT_DOUBLE_EQ(b.intrinsics.k2, a.intrinsics.k2);
  EXPECT_NEAR((b.lasers[1].normal - a.lasers[1].normal).norm(), 0.0, 1e-15);
  // Partial files override the built-in rig.
  const RigConfig c = RigConfig::from_yaml_text("image: {width: 320, height: 240}\nseed: 9\n", "p");
  EXPECT_EQ(c.width, 320);
  EXPECT_EQ(c.seed, 9u);
  EXPECT_DOUBLE_EQ(c.intrinsics.fx, a.intrinsics.fx);
  EXPECT_THROW(RigConfig::from_yaml_text("imgae: {width: 3}\n", "typo"), FileFormatError);
  EXPECT_THROW(RigConfig::from_yaml_text("line_sigma_mm: -1\n", "neg"), FileFormatError);
  EXPECT_THROW(RigConfig::from_yaml_text(
                   "lasers: [{name: a, normal: [0, 0, 0], position_mm: [1, 2, 3]}]\n", "zero"),
               FileFormatError);
  EXPECT_THROW(RigConfig::from_yaml_text("image: [1, 2\n", "bad"), FileFormatError);
}

TEST(TurntableRig, YamlFileReadsLikeItsTextAndNamesTheFileItCannotRead) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("scanmesh_test_rig_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  RigConfig a = small_rig();
  a.seed = 77;
  { std::ofstream(dir / "rig.yaml") << a.to_yaml(); }
  const RigConfig b = RigConfig::from_yaml_file(dir / "rig.yaml");
  EXPECT_EQ(b.to_yaml(), a.to_yaml());
  EXPECT_EQ(b.width, 640);
  { std::ofstream(dir / "bad.yaml") << "image: {width: -5}\n"; }
  try {
    (void)RigConfig::from_yaml_file(dir / "bad.yaml");
    ADD_FAILURE() << "an impossible width was accepted";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)RigConfig::from_yaml_file(dir / "missing.yaml"), IoError);
  EXPECT_THROW((void)RigConfig::from_yaml_file(dir), Error);  // a folder is not a file
  std::filesystem::remove_all(dir);
}

TEST(TurntableCamera, CalibrationShotsFollowThePlanAndRestoreThePattern) {
  RigConfig rig = small_rig();
  rig.width = 320;  // quarter size: this test also runs under the sanitizers
  rig.height = 240;
  rig.intrinsics.fx /= 2;
  rig.intrinsics.fy /= 2;
  rig.intrinsics.cx = (rig.intrinsics.cx + 0.5) / 2 - 0.5;
  rig.intrinsics.cy = (rig.intrinsics.cy + 0.5) / 2 - 0.5;
  TurntableCamera cam(sphere_scene(20.0, 150.0), rig);
  ASSERT_FALSE(cam.pattern().has_value());
  CalibrationPlan plan;
  plan.handheld_views = 2;
  plan.handheld_lasers = false;
  plan.platter_angles_rad = {-0.3, 0.0, 0.3};
  plan.placements = {{.offset_mm = 30.0}, {.offset_mm = 10.0}};
  const auto shots = render_calibration_shots(cam, plan);
  ASSERT_EQ(shots.size(), 2u + 2u * 3u);
  EXPECT_FALSE(cam.pattern().has_value());  // restored
  for (std::size_t i = 0; i < shots.size(); ++i) {
    const CalibrationShot& s = shots[i];
    EXPECT_EQ(s.image.width, 320);
    EXPECT_EQ(s.on_turntable, i >= 2);
    if (!s.on_turntable) {
      EXPECT_TRUE(s.laser_on.empty());
      continue;
    }
    EXPECT_EQ(s.placement, static_cast<int>((i - 2) / 3));
    EXPECT_DOUBLE_EQ(s.angle_rad, plan.platter_angles_rad[(i - 2) % 3]);
    ASSERT_EQ(s.laser_on.size(), 2u);
    // Each laser's frame is brighter than the frame with the lasers off somewhere.
    for (const Image8& lit : s.laser_on) {
      long brighter = 0;
      for (int y = 0; y < lit.height; ++y)
        for (int x = 0; x < lit.width; ++x) brighter += lit.at(x, y)[0] > s.image.at(x, y)[0] + 40;
      EXPECT_GT(brighter, 50);
    }
  }
  // The board turns with the table: the platter shots at other angles differ, and so do the
  // two placements at the same angle.
  EXPECT_NE(shots[2].image.pixels, shots[4].image.pixels);
  EXPECT_NE(shots[3].image.pixels, shots[6].image.pixels);
  // Deterministic: the same plan renders the same pixels.
  const auto again = render_calibration_shots(cam, plan);
  EXPECT_EQ(again[5].laser_on[1].pixels, shots[5].laser_on[1].pixels);
}

TEST(TurntableCamera, DistortionInverseAndProjection) {
  const Scene scene = sphere_scene();
  const TurntableCamera cam(scene, small_rig());
  for (double u : {3.0, 100.25, 319.5, 600.75})
    for (double v : {2.0, 240.5, 470.0}) {
      const Eigen::Vector3d ray = cam.pixel_ray(u, v);
      const auto uv = cam.project(cam.camera_center() + 350.0 * ray);
      ASSERT_TRUE(uv);
      EXPECT_NEAR(uv->x(), u, 1e-7);
      EXPECT_NEAR(uv->y(), v, 1e-7);
    }
  EXPECT_FALSE(cam.project(cam.camera_center() - 100.0 * cam.pixel_ray(320, 240)));
}

TEST(TurntableCamera, RenderIsDeterministicAndSeedDependent) {
  const Scene scene = sphere_scene();
  RigConfig rig = small_rig();
  const TurntableCamera a(scene, rig), b(scene, rig);
  const Image8 fa = a.render(0.3, 1u);
  EXPECT_EQ(fa.pixels, b.render(0.3, 1u).pixels);
  EXPECT_EQ(a.render(0.3, 1u).pixels, fa.pixels);  // from the cache, same bytes
  rig.seed = 2;
  const TurntableCamera c(scene, rig);
  EXPECT_NE(c.render(0.3, 1u).pixels, fa.pixels);
  EXPECT_EQ(fa.width, 640);
  EXPECT_EQ(fa.height, 480);
  EXPECT_EQ(fa.channels, 3);
}

TEST(TurntableCamera, SensorNoiseHasTheConfiguredReadAndShotVariance) {
  // Laser off, so every pixel is shading plus noise; the same frame without noise is the truth.
  const Scene scene = sphere_scene();
  RigConfig clean = small_rig();
  clean.noise_sigma = 0;
  clean.shot_noise_gain = 0;
  RigConfig noisy = small_rig();
  noisy.noise_sigma = 4.0;
  noisy.shot_noise_gain = 0.1;
  const Image8 c = TurntableCamera(scene, clean).render(0.4, 0u);
  const Image8 f = TurntableCamera(scene, noisy).render(0.4, 0u);
  ASSERT_EQ(c.pixels.size(), f.pixels.size());
  // Residual variance per clean value v, away from clipping: 16 + 0.1 v, plus the rounding of
  // both frames (2 x 1/12).
  double ratio_sum = 0, mean_sum = 0;
  long n = 0;
  for (std::size_t i = 0; i < c.pixels.size(); ++i) {
    const double v = c.pixels[i];
    if (v < 30 || v > 200) continue;
    const double d = double(f.pixels[i]) - v;
    ratio_sum += d * d / (16.0 + 0.1 * v + 1.0 / 6.0);
    mean_sum += d;
    ++n;
  }
  ASSERT_GT(n, 20000);
  EXPECT_NEAR(ratio_sum / n, 1.0, 0.03);
  EXPECT_NEAR(mean_sum / n, 0.0, 0.1);
}

TEST(TurntableCamera, LineTruthLiesOnSphereSheetAndRenderedLine) {
  const double radius = 50.0, zc = 70.0;
  const Scene scene = sphere_scene(radius, zc);
  const TurntableCamera cam(scene, small_rig());
  const double angle = 0.7;
  for (int k = 0; k < 2; ++k) {
    const auto truth = cam.laser_line_truth(angle, k);
    const Image8 off = cam.render(angle, 0u), on = cam.render(angle, 1u << k);
    int on_sphere = 0, peak_close = 0;
    for (const auto& t : truth) {
      EXPECT_NEAR(cam.rig().lasers[k].signed_distance(t.point_rig), 0.0, 1e-6);
      const auto uv = cam.project(t.point_rig);
      ASSERT_TRUE(uv);
      EXPECT_NEAR(uv->x(), t.u, 1e-6);
      EXPECT_NEAR(uv->y(), t.row, 1e-6);
      const Eigen::Matrix3d back = Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitZ()).matrix();
      EXPECT_NEAR((back * t.point_rig - t.point_object).norm(), 0.0, 1e-9);
      if (t.on_platform) {
        EXPECT_NEAR(t.point_object.z(), cam.rig().platform_height_mm, 1e-9);
        continue;
      }
      ++on_sphere;
      EXPECT_NEAR((t.point_object - Eigen::Vector3d(0, 0, zc)).norm(), radius, 1e-6);
      // The brightest background-subtracted red pixel of the row is the truth's pixel.
      int best = -1, best_v = -1000;
      for (int x = 0; x < on.width; ++x) {
        const int d = int(on.at(x, t.row)[0]) - int(off.at(x, t.row)[0]);
        if (std::abs(x - t.u) < 15 && d > best_v) best_v = d, best = x;
      }
      if (std::abs(best - t.u) <= 1.0) ++peak_close;
    }
    EXPECT_GT(on_sphere, 150) << "laser " << k;  // the sphere spans ~190 rows at half size
    EXPECT_GT(peak_close, 0.95 * on_sphere) << "laser " << k;
  }
}

TEST(TurntableCamera, LaserOffFrameHasNoLaserAndShadowsAreRespected) {
  const Scene scene = sphere_scene();
  const TurntableCamera cam(scene, small_rig());
  const Image8 off = cam.render(0.0, 0u), on = cam.render(0.0, 3u);
  long brighter = 0;
  for (std::size_t i = 0; i < off.pixels.size(); i += 3)
    brighter += int(on.pixels[i]) - int(off.pixels[i]) > 40;
  EXPECT_GT(brighter, 300);  // two lit lines of several pixels over ~190 rows
  // Every lit platter point sees its laser past the sphere (analytic segment test), and some
  // platter behind the sphere is in its shadow, so the shadow test matters.
  const Eigen::Vector3d centre(0, 0, 70);
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector3d e = cam.rig().lasers[k].position_mm;
    int platter = 0;
    for (const auto& t : cam.laser_line_truth(0.0, k)) {
      if (!t.on_platform) continue;
      ++platter;
      const Eigen::Vector3d d = (e - t.point_rig).normalized();
      const double s_closest = std::max(0.0, d.dot(centre - t.point_rig));
      EXPECT_GT((t.point_rig + s_closest * d - centre).norm(), 50.0 - 1e-6);
    }
    EXPECT_GT(platter, 20);
  }
}

TEST(TurntableCamera, PatternCornersVisibleOnlyWhenFacingTheCamera) {
  const Scene scene = sphere_scene();
  TurntableCamera cam(scene, small_rig());
  EXPECT_THROW(cam.pattern_corner_truth(0.0), InvalidInputError);
  cam.set_pattern(ChessboardPattern::upright(0.0));
  const auto front = cam.pattern_corner_truth(0.0);
  ASSERT_EQ(front.size(), 66u);
  for (const auto& c : front) EXPECT_TRUE(c.has_value());
  for (const auto& c : cam.pattern_corner_truth(kPi)) EXPECT_FALSE(c.has_value());
  // Corners are where black and white squares meet: the 4 diagonal neighbours alternate.
  const Image8 img = cam.render(0.0, 0u);
  int alternating = 0;
  for (const auto& c : front) {
    const int x = int(std::lround(c->x())), y = int(std::lround(c->y()));
    const int a = img.at(x - 3, y - 3)[1], b = img.at(x + 3, y - 3)[1];
    const int d = img.at(x + 3, y + 3)[1], e = img.at(x - 3, y + 3)[1];
    alternating += std::abs(a - b) > 40 && std::abs(b - d) > 40 && std::abs(d - e) > 40;
  }
  EXPECT_EQ(alternating, 66);
}

}  // namespace
}  // namespace scanmesh::sim
