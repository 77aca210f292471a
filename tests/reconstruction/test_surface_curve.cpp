// Curves lifted onto the surface: arc length, curvature, curvature integral, spacing.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/surface_curve.h"
#include "test_support.h"

namespace scanmesh {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<Eigen::Vector2d> latitude(double h, int n) {
  std::vector<Eigen::Vector2d> pts;
  for (int k = 0; k < n; ++k) pts.emplace_back(2 * kPi * k / n, h);
  return pts;
}

TEST(SurfaceCurve, LatitudeCircleArcLengthWithinATenthPercent) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  for (double h : {100.0, 130.0}) {
    const double radius = std::sqrt(80.0 * 80.0 - (h - 100.0) * (h - 100.0));
    for (CurveKind kind : {CurveKind::Polyline, CurveKind::CatmullRom}) {
      const SurfaceCurve curve(surface, latitude(h, 24), kind, /*closed=*/true);
      EXPECT_NEAR(curve.arc_length() / (2 * kPi * radius), 1.0, 1e-3) << "h = " << h;
    }
  }
}

TEST(SurfaceCurve, LatitudeCurvatureAndTotalCurvatureMatchTheCircle) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  const double h = 130.0, radius = std::sqrt(80.0 * 80.0 - 30.0 * 30.0);
  const SurfaceCurve curve(surface, latitude(h, 24), CurveKind::Polyline, true);
  for (double t : {0.3, 5.5, 17.25}) EXPECT_NEAR(*curve.curvature(t) * radius, 1.0, 0.01);
  EXPECT_NEAR(curve.curvature_integral() / (2 * kPi), 1.0, 0.01);
}

// The lifted points of a latitude curve lie on the sphere (centre (0, 0, 100), radius 80) at
// the curve's height, and the parameter points pass through the control points.
TEST(SurfaceCurve, PointsLieOnTheSphereAtTheirParameterPoint) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  const auto controls = latitude(120.0, 12);
  const SurfaceCurve curve(surface, controls, CurveKind::Polyline, true);
  for (int k = 0; k < 12; ++k) {
    const Eigen::Vector2d at = curve.parameter_point(k);
    EXPECT_NEAR(at.x(), controls[k].x(), 1e-9);
    EXPECT_NEAR(at.y(), 120.0, 1e-9);
  }
  for (double t : {0.0, 2.5, 7.75, 11.5}) {
    const auto p = curve.point(t);
    ASSERT_TRUE(p.has_value()) << t;
    EXPECT_NEAR((*p - Eigen::Vector3d(0, 0, 100)).norm(), 80.0, 0.05) << t;
    EXPECT_NEAR(p->z(), curve.parameter_point(t).y(), 1e-6) << t;
  }
}

TEST(SurfaceCurve, MeridianOfTheSphereHasCurvatureOneOverR) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  // A meridian from h = 60 to 140 at phi = 1: an arc of the great circle.
  const SurfaceCurve curve(surface, {{1.0, 60.0}, {1.0, 100.0}, {1.0, 140.0}}, CurveKind::Polyline);
  const double expected = 80.0 * 2 * std::asin(40.0 / 80.0);
  EXPECT_NEAR(curve.arc_length() / expected, 1.0, 1e-3);
  EXPECT_NEAR(*curve.curvature(0.5) * 80.0, 1.0, 0.01);
}

TEST(SurfaceCurve, EqualArcLengthParametersAreEquallySpaced) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  const SurfaceCurve curve(surface, {{0.5, 60.0}, {1.2, 90.0}, {1.0, 120.0}, {2.0, 140.0}});
  const auto ts = curve.equal_arc_length_parameters(11);
  ASSERT_EQ(ts.size(), 11u);
  const double total = curve.arc_length();
  for (std::size_t k = 0; k < ts.size(); ++k)
    EXPECT_NEAR(curve.arc_length_to(ts[k]), total * k / 10.0, 1e-3 * total);
}

TEST(SurfaceCurve, CrossingTheSeamIsSmooth) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  // phi runs past 2 pi: the curve crosses the seam with no jump.
  const SurfaceCurve curve(surface, {{2 * kPi - 0.3, 100.0}, {2 * kPi + 0.3, 100.0}},
                           CurveKind::Polyline);
  EXPECT_NEAR(curve.arc_length(), 80.0 * 0.6, 1e-3);
}

TEST(SurfaceCurve, RejectsCurvesOffTheSurfaceAndDegenerateInput) {
  const auto scan = test::sphere_scan();
  const ScanSurface surface(scan.grid);
  EXPECT_THROW(SurfaceCurve(surface, {{1.0, 100.0}}), InvalidInputError);
  EXPECT_THROW(SurfaceCurve(surface, {{1.0, 100.0}, {1.0, 400.0}}), InvalidInputError);
  EXPECT_THROW(SurfaceCurve(surface, {{1.0, 100.0}, {NAN, 90.0}}), InvalidInputError);
}

}  // namespace
}  // namespace scanmesh
