// The device path end to end on the simulated camera: render -> extract -> triangulate -> grid,
// checked against exact geometry (issue 9: sphere probing, dumbbell spacing, the head against
// the direct range simulator), and scan-grid cleaning.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "scanmesh/acquisition/reconstruction.h"
#include "scanmesh/acquisition/scan_cleaning.h"
#include "scanmesh/acquisition/sphere_fit.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/turntable_camera.h"

namespace scanmesh {
namespace {

constexpr double kPi = std::numbers::pi;

// Renders steps on the fly: step i at angle 2 pi i / n.
class RenderedSteps : public ScanStepSource {
 public:
  RenderedSteps(const sim::TurntableCamera& cam, std::size_t n) : cam_(cam), n_(n) {}
  std::size_t step_count() const override { return n_; }
  int laser_count() const override { return cam_.laser_count(); }
  ScanStep step(std::size_t i) const override {
    ScanStep s;
    s.index = i;
    s.angle_rad = 2.0 * kPi * static_cast<double>(i) / static_cast<double>(n_);
    s.laser_off = cam_.render(s.angle_rad, 0u);
    for (int k = 0; k < cam_.laser_count(); ++k)
      s.laser_on.push_back(cam_.render(s.angle_rad, 1u << k));
    return s;
  }

 private:
  const sim::TurntableCamera& cam_;
  std::size_t n_;
};

// The calibration the simulated rig really has (isolates reconstruction from calibration).
Calibration exact_calibration(const sim::TurntableCamera& cam) {
  const sim::RigConfig& rig = cam.rig();
  Calibration c;
  const auto& in = rig.intrinsics;
  c.camera = {rig.width, rig.height, in.fx, in.fy, in.cx, in.cy, in.k1, in.k2, in.p1, in.p2, in.k3};
  const Eigen::Isometry3d t = cam.camera_from_rig();
  for (const auto& l : rig.lasers) {
    const Eigen::Vector3d n = t.linear() * l.normal;
    c.lasers.push_back({l.name, n, n.dot(t * l.position_mm)});
  }
  c.axis_direction = t.linear() * Eigen::Vector3d::UnitZ();
  c.axis_origin_mm = t * Eigen::Vector3d(0, 0, rig.platform_height_mm);
  return c;
}

sim::RigConfig half_rig() {
  sim::RigConfig r = sim::builtin_ciclop_rig();
  r.width = 640;
  r.height = 480;
  r.intrinsics.fx /= 2;
  r.intrinsics.fy /= 2;
  r.intrinsics.cx = (r.intrinsics.cx + 0.5) / 2 - 0.5;
  r.intrinsics.cy = (r.intrinsics.cy + 0.5) / 2 - 0.5;
  return r;
}

std::vector<TriangulatedPoint> scan_points(const sim::TurntableCamera& cam, std::size_t steps) {
  const RenderedSteps src(cam, steps);
  const Calibration cal = exact_calibration(cam);
  std::vector<TriangulatedPoint> pts;
  for (std::size_t i = 0; i < steps; ++i) {
    const ScanStep s = src.step(i);
    for (int k = 0; k < 2; ++k)
      triangulate_peaks(cal, k, s.angle_rad, extract_laser_line(s.laser_on[k], s.laser_off),
                        &s.laser_off, pts);
  }
  return pts;
}

sim::Scene scene_from(const std::string& objects) {
  return sim::Scene::from_yaml_text(
      "objects:\n" + objects + "texture: {seed: 3, base_color: [200, 200, 200]}\n", "test scene");
}

TEST(DevicePath, SphereProbing) {
  // 640 x 480 camera (fx 716 px), read noise 1.5 DN + shot noise, speckle 5 %, 72 steps,
  // both lasers, exact calibration.
  const sim::Scene scene =
      scene_from("  - {type: sphere, name: ball, center: [0, 0, 70], radius: 50}\n");
  const sim::TurntableCamera cam(scene, half_rig());
  const auto pts = scan_points(cam, 72);
  std::vector<Eigen::Vector3d> on;
  for (const auto& p : pts)
    if (p.p.z() > 1.0) on.push_back(p.p);
  const SphereFit f = fit_sphere(on);
  std::printf(
      "  sphere: %zu points, radius %.4f mm (true 50), centre (%.3f %.3f %.3f), RMS %.4f mm\n",
      f.points, f.radius, f.centre.x(), f.centre.y(), f.centre.z(), f.rms);
  EXPECT_GT(f.points, 15000u);
  EXPECT_NEAR(f.radius, 50.0, 0.05);
  EXPECT_LT(f.rms, 0.1);
  EXPECT_LT((f.centre - Eigen::Vector3d(0, 0, 70)).norm(), 0.1);
  // The grid of the same points: every cell's radius against the exact sphere.
  GridAssemblyOptions go;
  go.n_phi = 256;
  go.n_h = 256;
  go.h0 = 15.0;
  go.dh = 0.45;
  GridAssemblyStats gs;
  const RangeGrid g = assemble_grid(pts, go, &gs);
  double ss = 0;
  int n = 0;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i) {
      if (!g.valid(i, j)) continue;
      const double dz = g.h(j) - 70.0;
      ASSERT_LT(std::abs(dz), 50.0);
      const double r_true = std::sqrt(2500.0 - dz * dz);
      ss += std::pow(g.radius(i, j) - r_true, 2) * (1.0 - std::abs(dz) / 50.0 > 0.2);
      n += 1.0 - std::abs(dz) / 50.0 > 0.2;
    }
  std::printf(
      "  sphere grid: %zu cells, RMS radial error %.4f mm over %d cells away from the poles\n",
      g.valid_count(), std::sqrt(ss / n), n);
  EXPECT_GT(n, 15000);
  EXPECT_LT(std::sqrt(ss / n), 0.1);
  EXPECT_GT(gs.platter_points, 0u);
}

TEST(DevicePath, DumbbellSpacing) {
  const sim::Scene scene = scene_from(
      "  - {type: sphere, name: a, center: [-45, 0, 60], radius: 25}\n"
      "  - {type: sphere, name: b, center: [45, 0, 60], radius: 25}\n");
  const sim::TurntableCamera cam(scene, half_rig());
  const auto pts = scan_points(cam, 72);
  std::vector<Eigen::Vector3d> a, b;
  for (const auto& p : pts) {
    if ((p.p - Eigen::Vector3d(-45, 0, 60)).norm() < 28) a.push_back(p.p);
    if ((p.p - Eigen::Vector3d(45, 0, 60)).norm() < 28) b.push_back(p.p);
  }
  const SphereFit fa = fit_sphere(a), fb = fit_sphere(b);
  const double spacing = (fa.centre - fb.centre).norm();
  std::printf(
      "  dumbbell: radii %.4f %.4f mm (true 25), spacing %.4f mm (true 90), RMS %.4f %.4f mm\n",
      fa.radius, fb.radius, spacing, fa.rms, fb.rms);
  EXPECT_GT(fa.points, 1500u);
  EXPECT_GT(fb.points, 1500u);
  EXPECT_NEAR(spacing, 90.0, 0.1);
  EXPECT_NEAR(fa.radius, 25.0, 0.05);
  EXPECT_NEAR(fb.radius, 25.0, 0.05);
}

TEST(DevicePath, HeadMatchesTheDirectRangeSimulator) {
  const sim::Scene scene = sim::builtin_head_scene();
  const sim::TurntableCamera cam(scene, half_rig());
  const RenderedSteps src(cam, 60);
  ReconstructionOptions ro;
  ro.grid.n_phi = 120;
  ro.grid.n_h = 200;
  ro.grid.h0 = 5.0;
  ro.grid.dh = 1.0;
  ReconstructionStats rs;
  RangeGrid device = reconstruct_grid(src, exact_calibration(cam), ro, &rs);
  // The pipeline cleans what it assembles (no hole filling: filled cells are not measured).
  ScanCleaningOptions co;
  co.fill_holes = false;
  // The hair test compares neighbours 2 cells away; at this coarse test grid (3 deg columns, 5 mm
  // at the face) that spans real features, so it is off here (it is meant for 512 x 512 grids).
  co.hair = false;
  const ScanCleaningReport cr = clean_scan_grid(device, co);
  std::printf(
      "  head cleaning: %zu low-confidence, %zu platter, %zu hair, %zu spike, %zu fragment cells\n",
      cr.low_confidence_removed, cr.platter_removed, cr.hair_removed, cr.spikes.spikes_removed,
      cr.spikes.fragment_cells_removed);
  sim::ScannerConfig sc;
  sc.n_phi = 120;
  sc.n_h = 200;
  sc.h0_mm = 5.0;
  sc.dh_mm = 1.0;
  sc.grazing_dropout = false;
  sc.hair = false;
  sc.height_band = false;
  const sim::SimulatedScan direct = sim::simulate_scan(scene, sc);
  double ss = 0;
  int n = 0, big = 0;
  for (int j = 0; j < device.n_h(); ++j)
    for (int i = 0; i < device.n_phi(); ++i) {
      if (!device.valid(i, j) || !direct.grid.valid(i, j)) continue;
      const double d = device.radius(i, j) - direct.grid.radius(i, j);
      ss += d * d;
      big += std::abs(d) > 1.0;
      ++n;
    }
  const double rms = std::sqrt(ss / n);
  std::printf(
      "  head: %zu device cells, %zu direct cells, %d in both, RMS %.4f mm, %d cells > 1 mm "
      "(%zu peaks)\n",
      device.valid_count(), direct.grid.valid_count(), n, rms, big, rs.peaks);
  EXPECT_GT(n, 0.6 * static_cast<double>(direct.grid.valid_count()));
  EXPECT_LT(rms, 0.2);
}

sim::SimulatedScan clean_sphere_scan() {
  const sim::Scene scene =
      scene_from("  - {type: sphere, name: ball, center: [0, 0, 100], radius: 80}\n");
  sim::ScannerConfig sc;
  sc.n_phi = 256;
  sc.n_h = 256;
  sc.h0_mm = 20;
  sc.dh_mm = 0.6;
  sc.noise_sigma_mm = 0.05;
  sc.hair = false;
  return sim::simulate_scan(scene, sc);
}

TEST(ScanCleaning, NeverRemovesCellsOfACleanSphere) {
  RangeGrid g = clean_sphere_scan().grid;
  const std::size_t before = g.valid_count();
  ScanCleaningOptions o;
  o.platter_height_mm = 0.0;  // the sphere is far above the platter
  const ScanCleaningReport r = clean_scan_grid(g, o);
  EXPECT_EQ(r.hair_removed, 0u);
  EXPECT_EQ(r.spikes.spikes_removed, 0u);
  EXPECT_EQ(r.spikes.fragment_cells_removed, 0u);
  EXPECT_EQ(r.low_confidence_removed, 0u);
  EXPECT_EQ(r.platter_removed, 0u);
  EXPECT_GE(g.valid_count(), before);
}

TEST(ScanCleaning, RemovesInjectedSpikesAndHairAndFillsSmallHoles) {
  const RangeGrid clean = clean_sphere_scan().grid;
  RangeGrid g = clean;
  std::vector<std::size_t> injected;
  std::uint64_t state = 12345;
  auto rnd = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  auto valid_cell = [&](int* i, int* j) {
    do {
      *i = static_cast<int>(rnd() * g.n_phi());
      *j = 10 + static_cast<int>(rnd() * (g.n_h() - 20));
    } while (!clean.valid(*i, *j));
  };
  for (int s = 0; s < 60; ++s) {  // spikes: single cells 5..30 mm off
    int i, j;
    valid_cell(&i, &j);
    g.set_sample(
        i, j, clean.radius(i, j) + static_cast<float>((rnd() < 0.5 ? -1 : 1) * (5 + 25 * rnd())));
    injected.push_back(g.index(i, j));
  }
  for (int h = 0; h < 25; ++h) {  // hair: strands of 6..12 cells standing 2..6 mm proud
    int i, j;
    valid_cell(&i, &j);
    const int di = rnd() < 0.5 ? 1 : 0, dj = di ? (rnd() < 0.5 ? 1 : -1) : 1;
    const int len = 6 + static_cast<int>(rnd() * 7);
    for (int k = 0; k < len; ++k) {
      const int ii = g.wrap_phi(i + k * di), jj = j + k * dj;
      if (jj < 0 || jj >= g.n_h() || !clean.valid(ii, jj)) break;
      g.set_sample(ii, jj, clean.radius(ii, jj) + static_cast<float>(2.0 + 4.0 * rnd()));
      injected.push_back(g.index(ii, jj));
    }
  }
  // A small hole of 4 cells inside the surface.
  int hi = 100, hj = 128;
  for (int k = 0; k < 2; ++k)
    for (int q = 0; q < 2; ++q) g.invalidate(hi + k, hj + q);
  ScanCleaningOptions o;
  o.fill_holes = false;
  RangeGrid unfilled = g;
  const ScanCleaningReport r0 = clean_scan_grid(unfilled, o);
  std::size_t removed_injected = 0, removed_clean = 0, removed_far = 0;
  std::vector<char> is_injected(g.cell_count(), 0);
  for (auto k : injected) is_injected[k] = 1;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i) {
      const std::size_t k = g.index(i, j);
      if (!g.validity()[k] || unfilled.validity()[k]) continue;
      if (is_injected[k]) {
        ++removed_injected;
        continue;
      }
      ++removed_clean;
      // A clean cell may go only as collateral right next to injected noise (its neighbour
      // pairs are spoiled), never elsewhere.
      bool near = false;
      for (int dj = -2; dj <= 2; ++dj)
        for (int di = -2; di <= 2; ++di) {
          const int jj = j + dj;
          if (jj >= 0 && jj < g.n_h() && is_injected[g.index(g.wrap_phi(i + di), jj)]) near = true;
        }
      removed_far += !near;
    }
  std::size_t still_bad = 0;
  for (auto k : injected)
    still_bad += unfilled.validity()[k] && std::abs(unfilled.radii()[k] - clean.radii()[k]) > 0.5;
  std::printf(
      "  injected %zu cells: removed %zu (hair step %zu, spike step %zu), clean cells removed "
      "%zu\n",
      injected.size(), removed_injected, r0.hair_removed, r0.spikes.spikes_removed, removed_clean);
  EXPECT_EQ(still_bad, 0u);
  EXPECT_EQ(removed_far, 0u);
  EXPECT_LT(removed_clean, injected.size() / 20);
  EXPECT_GT(r0.hair_removed, 0u);
  // Filling: the removed cells and the 4-cell hole come back as filled (confidence 0), close to
  // the sphere.
  o.fill_holes = true;
  const ScanCleaningReport r1 = clean_scan_grid(g, o);
  EXPECT_GT(r1.cells_filled, 4u);
  for (int k = 0; k < 2; ++k)
    for (int q = 0; q < 2; ++q) {
      ASSERT_TRUE(g.valid(hi + k, hj + q));
      EXPECT_EQ(g.confidence(hi + k, hj + q), 0.0f);
      EXPECT_NEAR(g.radius(hi + k, hj + q), clean.radius(hi + k, hj + q), 0.2);
    }
  EXPECT_EQ(g.metadata.at("filled_cells"), std::to_string(r1.cells_filled));
  ScanCleaningOptions bad;
  bad.hair_threshold_mm = -1;
  EXPECT_THROW(clean_scan_grid(g, bad), InvalidInputError);
}

// fill_small_holes on a cylinder r = 100 + 0.01 (j - 64)^2 mm (smooth along h, constant along
// phi): a 3 x 3 hole across the phi seam and a single cell are filled close to the true radii;
// a hole one cell larger than the limit and one touching the first row stay holes.
TEST(ScanCleaning, FillSmallHolesFillsOnlyInteriorHolesUpToTheLimit) {
  RangeGrid g(64, 128);
  auto truth = [](int j) { return static_cast<float>(100.0 + 0.01 * (j - 64) * (j - 64)); };
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i) g.set_sample(i, j, truth(j), 1.0f);
  for (int i : {62, 63, 0})
    for (int j : {40, 41, 42}) g.invalidate(i, j);  // 9 cells, wrapping round phi = 0
  g.invalidate(20, 90);                             // 1 cell
  for (int i = 30; i < 35; ++i)
    for (int j = 60; j < 62; ++j) g.invalidate(i, j);  // 10 cells: over the limit
  for (int i = 10; i < 12; ++i) g.invalidate(i, 0);    // touches the first row
  const HoleFillReport r = fill_small_holes(g, 9);
  EXPECT_EQ(r.holes, 2u);
  EXPECT_EQ(r.cells, 10u);
  for (int i : {62, 63, 0})
    for (int j : {40, 41, 42}) {
      ASSERT_TRUE(g.valid(i, j));
      EXPECT_EQ(g.confidence(i, j), 0.0f);
      // The membrane is exact along phi; along h it misses the curvature (measured 0.022 mm).
      EXPECT_NEAR(g.radius(i, j), truth(j), 0.03);
    }
  EXPECT_NEAR(g.radius(20, 90), truth(90), 0.01);
  for (int i = 30; i < 35; ++i) EXPECT_FALSE(g.valid(i, 60));
  EXPECT_FALSE(g.valid(10, 0));
  EXPECT_THROW(fill_small_holes(g, -1), InvalidInputError);
  EXPECT_EQ(fill_small_holes(g, 0).cells, 0u);
}

}  // namespace
}  // namespace scanmesh
