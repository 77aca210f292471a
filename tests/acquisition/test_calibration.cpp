// Calibration from simulated views against the rig the simulator used (issue 9 acceptance:
// focal length 0.2 %, principal point 1 px, laser normals 0.05 deg, axis 0.05 deg and 0.1 mm,
// reprojection RMS close to the corner noise), and the calibration YAML file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/turntable_camera.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

std::vector<CalibrationView> to_views(const std::vector<sim::CalibrationShot>& shots) {
  std::vector<CalibrationView> v;
  for (const auto& s : shots)
    v.push_back({s.image, s.on_turntable, s.angle_rad, s.laser_on, s.placement});
  return v;
}

class CalibrationSim : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = new sim::Scene(sim::Scene::from_yaml_text(
        "objects:\n  - {type: sphere, name: unused, center: [0, 0, 0], radius: 1}\n", "unused"));
    // The design of `scan --calibration` (apps/src/calibration_capture.cpp): the board in three
    // placements on the platter (upright 40 mm in front of the axis, leaning back 20 degrees
    // 40 mm behind it, leaning back 25 degrees 40 mm in front), each at -70..70 degrees every
    // 10 degrees, plus 16 hand-held views.
    sim::CalibrationPlan plan;
    constexpr double kRad = std::numbers::pi / 180;
    plan.placements = {{.offset_mm = 40.0},
                       {.offset_mm = -40.0, .tilt_rad = 20.0 * kRad},
                       {.offset_mm = 40.0, .tilt_rad = 25.0 * kRad}};
    camera_ = new sim::TurntableCamera(*scene_, sim::builtin_ciclop_rig());
    for (int d = -70; d <= 70; d += 10)
      plan.platter_angles_rad.push_back(d * std::numbers::pi / 180);
    shots_ = new std::vector<sim::CalibrationShot>(sim::render_calibration_shots(*camera_, plan));
    report_ = new CalibrationReport(calibrate_scanner(to_views(*shots_), 2));
  }
  static void TearDownTestSuite() {
    delete report_;
    delete shots_;
    delete camera_;
    delete scene_;
  }
  static sim::Scene* scene_;
  static sim::TurntableCamera* camera_;
  static std::vector<sim::CalibrationShot>* shots_;
  static CalibrationReport* report_;
};
sim::Scene* CalibrationSim::scene_ = nullptr;
sim::TurntableCamera* CalibrationSim::camera_ = nullptr;
std::vector<sim::CalibrationShot>* CalibrationSim::shots_ = nullptr;
CalibrationReport* CalibrationSim::report_ = nullptr;

// One test for the expensive calibration set-up: ctest runs each test in its own process, so three
// tests paid for it three times (~80 s each).
TEST_F(CalibrationSim, RecoversTheRigFromSimulatedViews) {
  {
    SCOPED_TRACE("RecoversIntrinsicsLasersAndAxis");
    const Calibration& c = report_->calibration;
    const sim::RigConfig& rig = camera_->rig();
    const auto& t = rig.intrinsics;
    std::printf("  views %d (rejected %d), corners %d, laser points %d, OpenCV RMS %.4f px\n",
                report_->views_detected, report_->views_rejected, c.corners, c.laser_points,
                report_->opencv_rms_px);
    std::printf(
        "  fx %.3f (true %.3f, sigma %.3f)  fy %.3f (%.3f, %.3f)  cx %.3f (%.3f, %.3f)  "
        "cy %.3f (%.3f, %.3f)\n",
        c.camera.fx, t.fx, c.uncertainty.fx, c.camera.fy, t.fy, c.uncertainty.fy, c.camera.cx, t.cx,
        c.uncertainty.cx, c.camera.cy, t.cy, c.uncertainty.cy);
    std::printf("  k1 %.5f (%.5f)  k2 %.5f (%.5f)  p1 %.6f (%.6f)  p2 %.6f (%.6f)\n", c.camera.k1,
                t.k1, c.camera.k2, t.k2, c.camera.p1, t.p1, c.camera.p2, t.p2);
    EXPECT_GE(report_->views_detected, static_cast<int>(shots_->size()) - 2);
    EXPECT_LT(std::abs(c.camera.fx / t.fx - 1.0), 0.002);
    EXPECT_LT(std::abs(c.camera.fy / t.fy - 1.0), 0.002);
    EXPECT_LT(std::abs(c.camera.cx - t.cx), 1.0);
    EXPECT_LT(std::abs(c.camera.cy - t.cy), 1.0);

    const Eigen::Isometry3d cam_from_rig = camera_->camera_from_rig();
    ASSERT_EQ(c.lasers.size(), 2u);
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d n_true = cam_from_rig.linear() * rig.lasers[k].normal;
      const double angle =
          std::acos(std::min(1.0, std::abs(n_true.dot(c.lasers[k].normal)))) * kDeg;
      // Plane offset where it matters: on the axis, mid-height of the scan volume.
      const Eigen::Vector3d p_true =
          cam_from_rig *
          (rig.lasers[k].position_mm -
           rig.lasers[k].signed_distance(Eigen::Vector3d(0, 0, 100)) * rig.lasers[k].normal -
           rig.lasers[k].position_mm + Eigen::Vector3d(0, 0, 100));
      const double offset = std::abs(c.lasers[k].normal.dot(p_true) - c.lasers[k].distance_mm);
      std::printf("  laser %d: normal off by %.4f deg (sigma %.4f), plane offset %.4f mm\n", k,
                  angle, c.uncertainty.laser_normal_deg[k], offset);
      EXPECT_LT(angle, 0.05);
      EXPECT_LT(offset, 0.25);
    }
    const Eigen::Vector3d a_true = cam_from_rig.linear() * Eigen::Vector3d::UnitZ();
    const double axis_angle = std::acos(std::min(1.0, a_true.dot(c.axis_direction))) * kDeg;
    // Distance of the estimated axis line from the true axis over the scan volume (z 0..200).
    double axis_off = 0;
    for (double z : {0.0, 100.0, 200.0}) {
      const Eigen::Vector3d q = cam_from_rig * Eigen::Vector3d(0, 0, z);
      const Eigen::Vector3d d = q - c.axis_origin_mm;
      axis_off = std::max(axis_off, (d - d.dot(c.axis_direction) * c.axis_direction).norm());
    }
    const double height_err =
        c.axis_direction.dot(c.axis_origin_mm - cam_from_rig * Eigen::Vector3d::Zero());
    std::printf(
        "  axis: direction off by %.4f deg (sigma %.4f), line off by %.4f mm (sigma %.4f), "
        "platter height off by %.4f mm\n",
        axis_angle, c.uncertainty.axis_direction_deg, axis_off, c.uncertainty.axis_point_mm,
        height_err);
    EXPECT_LT(axis_angle, 0.05);
    // Issue 9: 0.1 mm. One placement 30 mm off the axis gave 0.109 mm; three placements in front
    // of and behind the axis, two of them leaning, give 0.04-0.05 mm (docs/acquisition.md).
    EXPECT_LT(axis_off, 0.1);
    EXPECT_LT(std::abs(height_err), 0.2);
    // The derived rig frame is the simulator's rig frame.
    const Eigen::Isometry3d rig_from_cam = c.rig_from_camera();
    const Eigen::Vector3d cam_centre = rig_from_cam * Eigen::Vector3d::Zero();
    EXPECT_LT((cam_centre - rig.camera_position_mm).norm(), 0.5);
  }
  {
    SCOPED_TRACE("ReprojectionRmsMatchesTheCornerNoise");
    // The actual corner noise: detected corners against the simulator's exact corners.
    double s = 0;
    int n = 0;
    for (std::size_t i = 0; i < shots_->size(); ++i) {
      camera_->set_pattern((*shots_)[i].pattern);
      const auto truth = camera_->pattern_corner_truth((*shots_)[i].angle_rad);
      if (report_->corners[i].empty()) continue;  // a view OpenCV did not find
      ASSERT_EQ(report_->corners[i].size(), truth.size());
      for (std::size_t k = 0; k < truth.size(); ++k) {
        ASSERT_TRUE(truth[k]);
        s += (report_->corners[i][k] - *truth[k]).squaredNorm();
        n += 2;
      }
    }
    camera_->set_pattern(std::nullopt);
    const double corner_noise = std::sqrt(s / n);
    const double rms = report_->calibration.reprojection_rms_px;
    std::printf(
        "  corner noise (vs truth) %.4f px per coordinate, reprojection RMS %.4f px, "
        "laser RMS %.4f mm\n",
        corner_noise, rms, report_->calibration.laser_rms_mm);
    EXPECT_LT(corner_noise, 0.1);
    EXPECT_LT(rms, 1.25 * corner_noise);
    EXPECT_GT(rms, 0.6 * corner_noise);
  }
  {
    SCOPED_TRACE("YamlRoundTrip");
    const Calibration& c = report_->calibration;
    const auto path =
        std::filesystem::path(SCANMESH_BINARY_DIR) / "test_calibration_roundtrip.yaml";
    c.write_yaml(path);
    const Calibration d = Calibration::read_yaml(path);
    EXPECT_EQ(d.to_yaml(), c.to_yaml());
    EXPECT_EQ(d.camera.fx, c.camera.fx);
    EXPECT_EQ(d.lasers[1].normal, c.lasers[1].normal);
    EXPECT_EQ(d.uncertainty.laser_normal_deg, c.uncertainty.laser_normal_deg);
    std::filesystem::remove(path);
  }
}

TEST(CalibrationFile, RejectsMalformedFiles) {
  Calibration c;
  c.camera = {640, 480, 700, 700, 320, 240, 0, 0, 0, 0, 0};
  c.axis_direction = Eigen::Vector3d(0, -1, 0);
  c.axis_origin_mm = Eigen::Vector3d(0, 50, 400);
  c.lasers.push_back({"left", Eigen::Vector3d(1, 0, 0), 10});
  const std::string good = c.to_yaml();
  EXPECT_NO_THROW(Calibration::from_yaml_text(good, "good"));
  auto bad = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    const auto pos = t.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    t.replace(pos, from.size(), to);
    EXPECT_THROW(Calibration::from_yaml_text(t, "bad.yaml"), FileFormatError) << to;
  };
  bad("format: scanmesh-calibration", "format: other");
  bad("version: 1", "version: 2");
  bad("fx: 700", "fx: -700");
  bad("fy: 700", "fy: abc");
  bad("direction: [0, -1, 0]", "direction: [0, 0, 0]");
  bad("origin_mm: [0, 50, 400]", "origin_mm: [0, 50]");
  bad("normal: [1, 0, 0]", "normal: [0, 0, 0]");
  bad("width: 640", "width: 0");
  EXPECT_THROW(Calibration::from_yaml_text("[1, 2", "x"), FileFormatError);
  EXPECT_THROW(Calibration::from_yaml_text("- 1\n", "x"), FileFormatError);
  EXPECT_THROW(Calibration::read_yaml("/nonexistent/calib.yaml"), IoError);
}

TEST(Calibration, TooFewViewsIsInvalidInput) {
  EXPECT_THROW(calibrate_scanner({}, 2), InvalidInputError);
  CalibrationView blank{Image8(64, 48, 3), true, 0.0, {}};
  EXPECT_THROW(calibrate_scanner({blank, blank, blank}, 2), InvalidInputError);
}

}  // namespace
// The pinhole with Brown-Conrady distortion: the optical axis lands on the principal point; a
// point off the axis without distortion at f * x / z + c; normalize() undoes project().
TEST(CameraModel, ProjectIsThePinholeAndNormalizeItsInverse) {
  CameraModel m;
  m.width = 640;
  m.height = 480;
  m.fx = 700;
  m.fy = 690;
  m.cx = 321;
  m.cy = 239;
  EXPECT_TRUE(m.project({0, 0, 500}).isApprox(Eigen::Vector2d(321, 239)));
  EXPECT_TRUE(m.project({10, -20, 400}).isApprox(Eigen::Vector2d(321 + 700 * 0.025, 239 - 690 * 0.05)));
  m.k1 = -0.2;
  m.k2 = 0.05;
  m.p1 = 0.001;
  m.p2 = -0.002;
  const Eigen::Vector3d p(30, 25, 400);
  const Eigen::Vector2d uv = m.project(p);
  EXPECT_GT((uv - Eigen::Vector2d(321 + 700 * 0.075, 239 + 690 * 0.0625)).norm(), 0.01);  // distorted
  EXPECT_TRUE(m.normalize(uv.x(), uv.y()).isApprox(Eigen::Vector2d(0.075, 0.0625), 1e-6));
}

}  // namespace scanmesh
