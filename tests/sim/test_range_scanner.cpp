// The simulated cylindrical scanner against exact ground truth (sim/src/range_scanner.cpp).
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <numbers>

#include "scanmesh/core/errors.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

using namespace scanmesh;
using namespace scanmesh::sim;
using Eigen::Vector3d;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Scene sphere_scene() {
  return Scene::from_yaml_text(
      "name: ball\nobjects:\n  - {type: sphere, center: [0, 0, 100], radius: 80}\n", "test sphere");
}

// All defects off: every hit is measured exactly.
ScannerConfig clean_config(int n_phi, int n_h, double h0, double h1) {
  ScannerConfig c;
  c.n_phi = n_phi;
  c.n_h = n_h;
  c.h0_mm = h0;
  c.dh_mm = (h1 - h0) / (n_h - 1);
  c.noise_sigma_mm = 0.0;
  c.grazing_dropout = false;
  c.occlusion = false;
  c.hair = false;
  c.spike_probability = 0.0;
  c.height_band = false;
  return c;
}

double incidence_deg(const RangeGrid& g, int i, const GroundTruthCell& t) {
  const Vector3d dir(-std::cos(g.phi(i)), -std::sin(g.phi(i)), 0.0);
  return std::acos(std::clamp(-dir.dot(t.geometry.normal), -1.0, 1.0)) / kDeg;
}

}  // namespace

TEST(RangeScanner, NoiseFreeSphereIsExact) {
  ScannerConfig c = clean_config(96, 64, 30.0, 170.0);
  c.grazing_dropout = true;
  c.occlusion = true;
  const auto scan = simulate_scan(sphere_scene(), c);
  int checked = 0;
  for (int j = 0; j < c.n_h; ++j)
    for (int i = 0; i < c.n_phi; ++i) {
      const auto& t = scan.truth[scan.grid.index(i, j)];
      const double dz = scan.grid.h(j) - 100.0;
      const double exact = std::sqrt(80.0 * 80.0 - dz * dz);
      ASSERT_TRUE(t.hit);
      EXPECT_NEAR(t.radius, exact, 1e-9);
      EXPECT_NEAR(t.geometry.k1, 1.0 / 80.0, 1e-9);
      EXPECT_NE(t.drop, DropReason::Occluded);  // a lone convex sphere hides nothing
      if (!scan.grid.valid(i, j)) continue;
      EXPECT_NEAR(scan.grid.radius(i, j), exact, 0.01);
      EXPECT_NEAR(scan.grid.radius(i, j), t.radius, 1e-4);  // float storage
      ++checked;
    }
  EXPECT_GT(checked, c.n_phi * c.n_h * 3 / 4);
  EXPECT_EQ(scan.grid.metadata.at("source"), "sim");
  EXPECT_EQ(scan.grid.metadata.at("scene"), "ball");
}

TEST(RangeScanner, GaussianNoiseHasTheConfiguredSigma) {
  ScannerConfig c = clean_config(128, 64, 40.0, 160.0);
  c.noise_sigma_mm = 0.1;
  c.seed = 42;
  const auto scan = simulate_scan(sphere_scene(), c);
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (int j = 0; j < c.n_h; ++j)
    for (int i = 0; i < c.n_phi; ++i) {
      if (!scan.grid.valid(i, j)) continue;
      const double e = scan.grid.radius(i, j) - scan.truth[scan.grid.index(i, j)].radius;
      sum += e;
      sum2 += e * e;
      ++n;
    }
  ASSERT_GT(n, 5000);
  EXPECT_LT(std::abs(sum / n), 0.02);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.1, 0.01);
}

TEST(RangeScanner, GrazingDropoutFollowsTheIncidenceAngle) {
  ScannerConfig c = clean_config(64, 128, 20.0, 180.0);
  c.grazing_dropout = true;
  c.grazing_limit_deg = 60.0;
  const auto scan = simulate_scan(sphere_scene(), c);
  int below = 0, above = 0;
  for (int j = 0; j < c.n_h; ++j)
    for (int i = 0; i < c.n_phi; ++i) {
      const auto& t = scan.truth[scan.grid.index(i, j)];
      if (!t.hit) continue;
      const double a = incidence_deg(scan.grid, i, t);
      if (a < c.grazing_limit_deg - 1.0) {
        EXPECT_NE(t.drop, DropReason::Grazing) << a;
        EXPECT_TRUE(scan.grid.valid(i, j));
        ++below;
      } else if (a > c.grazing_limit_deg + 1.0) {
        EXPECT_EQ(t.drop, DropReason::Grazing) << a;
        EXPECT_FALSE(scan.grid.valid(i, j));
        ++above;
      }
    }
  EXPECT_GT(below, 100);
  EXPECT_GT(above, 100);
}

TEST(RangeScanner, OcclusionMatchesIndependentShadowTest) {
  // A head-sized sphere and a small "ear" sphere sticking out at +y.
  const Scene scene = Scene::from_yaml_text(R"(
name: ear
objects:
  - {type: sphere, name: head, center: [0, 0, 100], radius: 60}
  - {type: sphere, name: ear, center: [0, 76, 100], radius: 12}
)",
                                            "ear scene");
  ScannerConfig c = clean_config(256, 16, 92.0, 108.0);
  c.occlusion = true;
  const auto scan = simulate_scan(scene, c);
  const Vector3d centers[2] = {{0, 0, 100}, {0, 76, 100}};
  const double radii[2] = {60, 12};
  int shadowed = 0, lit = 0;
  for (int j = 0; j < c.n_h; ++j)
    for (int i = 0; i < c.n_phi; ++i) {
      const auto& t = scan.truth[scan.grid.index(i, j)];
      if (!t.hit) continue;
      const double cam_phi = scan.grid.phi(i) + c.camera_baseline_deg * kDeg;
      const Vector3d cam(c.camera_radius_mm * std::cos(cam_phi),
                         c.camera_radius_mm * std::sin(cam_phi), t.point.z());
      // Independent shadow test: the normal must face the camera, and the segment to the
      // camera must stay out of the other sphere (closest point of a segment to a centre).
      bool expected = t.geometry.normal.dot(cam - t.point) <= 0.0;
      bool ambiguous = false;
      for (int k = 0; k < 2; ++k) {
        if (std::abs((t.point - centers[k]).norm() - radii[k]) < 1e-6) continue;  // own sphere
        const Vector3d seg = cam - t.point;
        const double u = std::clamp((centers[k] - t.point).dot(seg) / seg.squaredNorm(), 0.0, 1.0);
        const double d = (t.point + u * seg - centers[k]).norm();
        if (std::abs(d - radii[k]) < 0.01) ambiguous = true;
        expected = expected || d < radii[k];
      }
      if (ambiguous) continue;
      EXPECT_EQ(t.drop == DropReason::Occluded, expected) << "cell " << i << "," << j;
      (expected ? shadowed : lit)++;
      if (expected) {
        EXPECT_FALSE(scan.grid.valid(i, j));
      }
    }
  EXPECT_GT(shadowed, 20);
  EXPECT_GT(lit, 1000);
}

TEST(RangeScanner, SameSeedIsIdenticalAcrossThreadCounts) {
  const Scene head = builtin_head_scene();
  ScannerConfig c = builtin_head_scanner();
  c.n_phi = 128;
  c.n_h = 96;
  c.dh_mm = 230.0 / 95.0;
  c.spike_probability = 0.02;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto a = simulate_scan(head, c);
  omp_set_num_threads(2);
  const auto b = simulate_scan(head, c);
  omp_set_num_threads(saved);
  EXPECT_TRUE(a.grid == b.grid);
  EXPECT_EQ(a.grid.radii(), b.grid.radii());
  EXPECT_EQ(a.grid.validity(), b.grid.validity());
  EXPECT_EQ(a.grid.colors(), b.grid.colors());
  for (std::size_t k = 0; k < a.truth.size(); ++k) {
    EXPECT_EQ(a.truth[k].drop, b.truth[k].drop);
    EXPECT_EQ(a.truth[k].spike, b.truth[k].spike);
  }
  c.seed = 2;
  const auto other = simulate_scan(head, c);
  EXPECT_NE(a.grid.radii(), other.grid.radii());
  EXPECT_EQ(a.grid.colors(), other.grid.colors());  // the texture does not depend on the scan seed
}

TEST(RangeScanner, RowsOutsideTheHeightBandMeasureNothing) {
  ScannerConfig c = clean_config(64, 64, 30.0, 170.0);
  c.height_band = true;
  c.band_min_mm = 60.0;
  c.band_max_mm = 140.0;
  const auto scan = simulate_scan(sphere_scene(), c);
  for (int j = 0; j < c.n_h; ++j) {
    const bool outside = scan.grid.h(j) < 60.0 || scan.grid.h(j) > 140.0;
    int valid = 0;
    for (int i = 0; i < c.n_phi; ++i) {
      valid += scan.grid.valid(i, j);
      if (outside) {
        EXPECT_EQ(scan.truth[scan.grid.index(i, j)].drop, DropReason::OutsideBand);
      }
    }
    EXPECT_EQ(valid, outside ? 0 : c.n_phi) << "row " << j;
  }
}

TEST(RangeScanner, SpikesAreMarkedAndLarge) {
  ScannerConfig c = clean_config(128, 64, 40.0, 160.0);
  c.spike_probability = 0.05;
  const auto scan = simulate_scan(sphere_scene(), c);
  int spikes = 0, valid = 0;
  for (int j = 0; j < c.n_h; ++j)
    for (int i = 0; i < c.n_phi; ++i) {
      const auto& t = scan.truth[scan.grid.index(i, j)];
      if (!scan.grid.valid(i, j)) continue;
      ++valid;
      const double e = std::abs(scan.grid.radius(i, j) - t.radius);
      if (t.spike) {
        ++spikes;
        EXPECT_GE(e, 5.0 - 1e-3);
        EXPECT_LE(e, 40.0 + 1e-3);
      } else {
        EXPECT_LT(e, 1e-3);
      }
    }
  EXPECT_NEAR(static_cast<double>(spikes) / valid, 0.05, 0.015);
}

TEST(RangeScanner, ProgressIsReportedOncePerRow) {
  ScannerConfig c = clean_config(32, 40, 30.0, 170.0);
  int calls = 0, last = 0;
  bool monotone = true;
  simulate_scan(sphere_scene(), c, [&](int done, int total) {
    ++calls;
    monotone = monotone && done == last + 1 && total == 40;
    last = done;
  });
  EXPECT_EQ(calls, 40);
  EXPECT_TRUE(monotone);
}

TEST(RangeScanner, NoHitCellsAreBackgroundAndInvalid) {
  ScannerConfig c = clean_config(32, 32, 0.0, 200.0);  // rows above/below the sphere miss it
  const auto scan = simulate_scan(sphere_scene(), c);
  for (int i = 0; i < c.n_phi; ++i) {
    EXPECT_FALSE(scan.grid.valid(i, 0));
    EXPECT_EQ(scan.truth[scan.grid.index(i, 0)].drop, DropReason::NoHit);
    EXPECT_LT(scan.grid.color(i, 0).r, 40);
  }
}

TEST(RangeScanner, RejectsInvalidConfig) {
  ScannerConfig c;
  c.noise_sigma_mm = -1.0;
  EXPECT_THROW(simulate_scan(sphere_scene(), c), InvalidInputError);
}
