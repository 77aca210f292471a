// The named triangle measures (triangle_quality.h) against closed forms, and the histogram
// pictures every quality report draws (histogram_picture.h).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/histogram_picture.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/triangle_quality.h"
#include "test_util.h"

namespace scanmesh {
namespace {

using Eigen::Vector3d;

const Vector3d kO(0, 0, 0), kX(1, 0, 0), kY(0, 1, 0);
const Vector3d kApex(0.5, std::sqrt(3.0) / 2, 0);

TEST(TriangleQuality, EquilateralScoresOneOnEveryMeasure) {
  EXPECT_NEAR(radius_ratio(kO, kX, kApex), 1.0, 1e-12);
  EXPECT_NEAR(aspect_ratio(kO, kX, kApex), 1.0, 1e-12);
  EXPECT_NEAR(mean_ratio(kO, kX, kApex), 1.0, 1e-12);
  EXPECT_NEAR(triangle_min_angle(kO, kX, kApex), std::numbers::pi / 3, 1e-12);
}

TEST(TriangleQuality, RightIsoscelesMatchesItsClosedForms) {
  // Legs 1: inradius (2 - sqrt 2) / 2, circumradius sqrt(2) / 2, area 1/2, sum of l^2 = 4.
  const double r_in = (2 - std::sqrt(2.0)) / 2, r_circ = std::sqrt(2.0) / 2;
  EXPECT_NEAR(radius_ratio(kO, kX, kY), 2 * r_in / r_circ, 1e-12);
  EXPECT_NEAR(aspect_ratio(kO, kX, kY), r_circ / (2 * r_in), 1e-12);
  EXPECT_NEAR(mean_ratio(kO, kX, kY), 4 * std::sqrt(3.0) * 0.5 / 4, 1e-12);
  EXPECT_NEAR(triangle_min_angle(kO, kX, kY), std::numbers::pi / 4, 1e-12);
  // The aspect ratio is the radius ratio's inverse, whatever the corner order.
  EXPECT_NEAR(aspect_ratio(kY, kO, kX) * radius_ratio(kX, kY, kO), 1.0, 1e-12);
}

TEST(TriangleQuality, DegenerateTrianglesScoreTheirLimits) {
  const Vector3d mid(0.5, 0, 0);
  EXPECT_EQ(radius_ratio(kO, mid, kX), 0.0);
  EXPECT_TRUE(std::isinf(aspect_ratio(kO, mid, kX)));
  EXPECT_EQ(mean_ratio(kO, mid, kX), 0.0);
  EXPECT_EQ(triangle_min_angle(kO, mid, kX), 0.0);
  EXPECT_EQ(radius_ratio(kO, kO, kO), 0.0);  // all corners in one point
  EXPECT_EQ(mean_ratio(kO, kO, kO), 0.0);
}

TEST(TriangleQuality, ANeedleScoresLowOnEveryMeasure) {
  const Vector3d needle(0.5, 0.01, 0);
  EXPECT_LT(radius_ratio(kO, kX, needle), 0.05);
  EXPECT_GT(aspect_ratio(kO, kX, needle), 20.0);
  EXPECT_LT(mean_ratio(kO, kX, needle), 0.05);
  EXPECT_NEAR(triangle_min_angle(kO, kX, needle), std::atan(0.02), 1e-9);
}

bool is_green(const Image8& image, int x, int y) {
  const Rgb8 c = image.rgb(x, y);
  return c.g > c.r + 50 && c.g > c.b;
}
bool is_red(const Image8& image, int x, int y) {
  const Rgb8 c = image.rgb(x, y);
  return c.r > c.g + 50 && c.r > c.b;
}

TEST(HistogramPicture, BarsTakeTheColourOfTheirBinsGoodness) {
  const std::vector<std::size_t> counts = {10, 10, 10, 10};
  const Image8 image =
      histogram_picture(counts, {"A", "B", "C", "D"}, "TEST", {.begin = 1, .end = 3});
  ASSERT_EQ(image.width, 640);
  ASSERT_EQ(image.height, 400);
  // Four equal bars over a 560-pixel plot from x = 60, bottom at y = 360: the middle of each
  // bar just above the axis.
  const int y = 350;
  const int bar = 560 / 4;
  EXPECT_TRUE(is_red(image, 60 + bar / 2, y));
  EXPECT_TRUE(is_green(image, 60 + bar + bar / 2, y));
  EXPECT_TRUE(is_green(image, 60 + 2 * bar + bar / 2, y));
  EXPECT_TRUE(is_red(image, 60 + 3 * bar + bar / 2, y));
}

TEST(HistogramPicture, AnEmptyBinDrawsNoBar) {
  const Image8 image =
      histogram_picture(std::vector<std::size_t>{0, 5}, {"0", "1"}, "TEST", {.begin = 0, .end = 2});
  EXPECT_FALSE(is_green(image, 60 + 140, 350));
  EXPECT_TRUE(is_green(image, 60 + 280 + 140, 350));
}

TEST(HistogramPicture, LabelsThatDoNotMatchTheBinsAreRefused) {
  EXPECT_THROW(histogram_picture(std::vector<std::size_t>{1, 2}, {"only one"}, "T", {}),
               InvalidInputError);
  EXPECT_THROW(histogram_picture(std::vector<std::size_t>{}, {}, "T", {}), InvalidInputError);
}

TEST(HistogramPicture, WrittenAsAPngOfTheSamePicture) {
  test::TempDir dir;
  const std::vector<std::size_t> counts = {3, 1, 4, 1, 5};
  const std::vector<std::string> labels = {"A", "B", "C", "D", "E"};
  write_histogram_png(dir / "h.png", counts, labels, "PI", {.begin = 2, .end = 5});
  const Image8 back = read_png(dir / "h.png");
  EXPECT_EQ(back.pixels, histogram_picture(counts, labels, "PI", {.begin = 2, .end = 5}).pixels);
}

}  // namespace
}  // namespace scanmesh
