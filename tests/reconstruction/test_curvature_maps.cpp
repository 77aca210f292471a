// Curvature and normal pictures (curvature_maps.h): sizes, colours, legend, font.
#include <gtest/gtest.h>

#include <cmath>

#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/curvature_maps.h"

namespace scanmesh {
namespace {

int count_pixels(const Image8& image, int x0, int y0, int x1, int y1, Rgb8 unlike) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += image.rgb(x, y) == unlike ? 0 : 1;
  return n;
}

TEST(GreyMap, ScalesClampsAndBlackensUndefinedCells) {
  const std::vector<float> v = {0.0f, 1.0f, 2.0f, 5.0f, -1.0f, 1.0f};
  const std::vector<std::uint8_t> d = {1, 1, 1, 1, 1, 0};
  const Image8 image = grey_map(v, d, 3, 2, 2.0);
  ASSERT_EQ(image.width, 3);
  ASSERT_EQ(image.height, 2);
  ASSERT_EQ(image.channels, 1);
  // Upright: grid row 0 (the lowest h) is the picture's bottom row.
  EXPECT_EQ(image.at(0, 1)[0], 0);
  EXPECT_EQ(image.at(1, 1)[0], 128);  // 1 / 2 of 255, rounded
  EXPECT_EQ(image.at(2, 1)[0], 255);
  EXPECT_EQ(image.at(0, 0)[0], 255);  // 5 clamped
  EXPECT_EQ(image.at(1, 0)[0], 0);    // negative clamped
  EXPECT_EQ(image.at(2, 0)[0], 0);    // undefined: black
}

TEST(GreyMap, AutomaticScaleIsThe99thPercentile) {
  std::vector<float> v(100);
  for (int k = 0; k < 100; ++k) v[k] = static_cast<float>(k);
  const std::vector<std::uint8_t> d(100, 1);
  const Image8 image = grey_map(v, d, 10, 10);
  EXPECT_EQ(image.at(8, 0)[0], 255);  // value 98 (row 9, the top) = the 99th percentile
  EXPECT_EQ(image.at(9, 5)[0], 128);  // value 49 (row 4): 49 / 98 of 255
  EXPECT_THROW(grey_map(v, d, 10, 9), InvalidInputError);
}

TEST(DivergingMap, PositiveRedNegativeBlueZeroWhiteUndefinedGreyAndALegend) {
  constexpr int w = 40, h = 30;
  std::vector<float> v(w * h);
  std::vector<std::uint8_t> d(w * h, 1);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) v[j * w + i] = i < 10 ? 0.02f : i < 20 ? -0.02f : 0.0f;
  d[5 * w + 30] = 0;
  const Image8 image = diverging_map(v, d, w, h, "H [1/mm]", 0.02);
  ASSERT_EQ(image.channels, 3);
  EXPECT_EQ(image.width, w + 70);
  EXPECT_GE(image.height, h);
  const Rgb8 pos = image.rgb(3, 3), neg = image.rgb(15, 3);
  EXPECT_GT(pos.r, pos.b + 100) << int(pos.r) << " " << int(pos.g) << " " << int(pos.b);
  EXPECT_GT(neg.b, neg.r + 100) << int(neg.r) << " " << int(neg.g) << " " << int(neg.b);
  EXPECT_EQ(image.rgb(25, 3), (Rgb8{255, 255, 255}));
  EXPECT_EQ(image.rgb(30, h - 1 - 5), (Rgb8{40, 40, 40}));  // grid row 5, upright
  // Half the scale is half way to the end colour, the same distance on both sides.
  std::vector<float> half = {0.01f, -0.01f};
  const Image8 h2 = diverging_map(half, {1, 1}, 2, 1, "K", 0.02);
  EXPECT_NEAR(h2.rgb(0, 0).r, (255 + 200) / 2.0, 1.0);
  EXPECT_NEAR(h2.rgb(1, 0).b, (255 + 200) / 2.0, 1.0);
  // Legend: the title's ink at the top, the colour bar (red at the top, blue at the bottom)
  // and the three labels to its right.
  const Rgb8 white{255, 255, 255};
  EXPECT_GT(count_pixels(image, w, 0, w + 70, 14, white), 30);                  // title
  EXPECT_GT(count_pixels(image, w + 20, 14, w + 70, image.height, white), 60);  // labels
  const Rgb8 bar_top = image.rgb(w + 8, 21), bar_bottom = image.rgb(w + 8, image.height - 11);
  EXPECT_GT(bar_top.r, bar_top.b + 100);
  EXPECT_GT(bar_bottom.b, bar_bottom.r + 100);
}

TEST(DivergingMap, AutomaticScaleIsSymmetric) {
  // |values| 1..100 with alternating signs: the 98th percentile of |v| is 98.
  std::vector<float> v(100);
  for (int k = 0; k < 100; ++k) v[k] = static_cast<float>((k % 2 ? -1 : 1) * (k + 1));
  const Image8 image = diverging_map(v, std::vector<std::uint8_t>(100, 1), 100, 1, "x");
  EXPECT_EQ(image.rgb(97, 0), (Rgb8{40, 90, 200}));  // -98: full blue
  EXPECT_EQ(image.rgb(98, 0), (Rgb8{200, 40, 40}));  // +99: clamped full red
  EXPECT_EQ(image.rgb(99, 0), (Rgb8{40, 90, 200}));  // -100: clamped full blue
  EXPECT_NE(image.rgb(96, 0), (Rgb8{200, 40, 40}));  // +97: not quite full
}

TEST(NormalMap, MapsUnitNormalsToRgbAndUndefinedToBlack) {
  SurfaceFields f;
  f.resize(3, 2);
  f.defined[0] = 1;
  f.normal[0] = Eigen::Vector3f(1, 0, 0);
  f.defined[4] = 1;
  f.normal[4] = Eigen::Vector3f(0, -1, 0);
  const Image8 image = normal_map(f);
  ASSERT_EQ(image.width, 3);
  ASSERT_EQ(image.height, 2);
  EXPECT_EQ(image.rgb(0, 1), (Rgb8{255, 128, 128}));  // cell (0, 0): the bottom row
  EXPECT_EQ(image.rgb(1, 0), (Rgb8{128, 0, 128}));    // cell (1, 1): the top row
  EXPECT_EQ(image.rgb(2, 0), (Rgb8{0, 0, 0}));
}

// Every map of a grid plane is upright (core/texture_layout.h): a field that grows with h is
// brightest (grey), reddest (diverging) at the TOP of the picture, and the highest row's normals
// are the top row's colour.
TEST(Maps, AreUprightTheHighestRowAtTheTop) {
  constexpr int w = 8, h = 16;
  std::vector<float> v(w * h);
  const std::vector<std::uint8_t> d(w * h, 1);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) v[j * w + i] = static_cast<float>(j) - 7.5f;  // grows with h
  const Image8 grey = grey_map(v, d, w, h, 7.5);
  for (int i = 0; i < w; ++i) {
    EXPECT_EQ(grey.at(i, 0)[0], 255) << "top row = the highest h";
    EXPECT_EQ(grey.at(i, h - 1)[0], 0) << "bottom row = the lowest h (negative, clamped)";
  }
  const Image8 div = diverging_map(v, d, w, h, "H", 7.5);
  EXPECT_EQ(div.rgb(3, 0), (Rgb8{200, 40, 40}));      // +7.5 at the top: full red
  EXPECT_EQ(div.rgb(3, h - 1), (Rgb8{40, 90, 200}));  // -7.5 at the bottom: full blue
  SurfaceFields f;
  f.resize(w, h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      f.defined[j * w + i] = 1;
      f.normal[j * w + i] = j == h - 1 ? Eigen::Vector3f(0, 0, 1) : Eigen::Vector3f(0, 0, -1);
    }
  const Image8 normals = normal_map(f);
  for (int i = 0; i < w; ++i) {
    EXPECT_EQ(normals.rgb(i, 0), (Rgb8{128, 128, 255}));  // +z: the top row only
    EXPECT_EQ(normals.rgb(i, 1), (Rgb8{128, 128, 0}));
  }
}

TEST(DrawText, DrawsGlyphPixelsScalesAndClips) {
  Image8 image(80, 20, 3, 0);
  const Rgb8 ink{255, 255, 0}, black{0, 0, 0};
  draw_text(image, 1, 1, "H [1/mm]", ink);
  const int drawn = count_pixels(image, 0, 0, 80, 20, black);
  EXPECT_GT(drawn, 40);
  EXPECT_EQ(count_pixels(image, 0, 9, 80, 20, black), 0);  // 7 rows high from y = 1
  // Scale 2: every pixel becomes a 2 x 2 block.
  Image8 big(160, 40, 3, 0);
  draw_text(big, 2, 2, "H [1/mm]", ink, 2);
  EXPECT_EQ(count_pixels(big, 0, 0, 160, 40, black), 4 * drawn);
  // Lower case without a glyph draws as upper case; text off the image is clipped.
  Image8 a(6, 7, 1, 0), b(6, 7, 1, 0);
  draw_text(a, 0, 0, "k", ink);
  draw_text(b, 0, 0, "K", ink);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_NO_THROW(draw_text(a, -3, -4, "+1.2e-2 -0.5 = 3 : 7", ink, 3));
  // Every digit has a glyph of its own.
  std::vector<std::vector<std::uint8_t>> digits;
  for (char c = '0'; c <= '9'; ++c) {
    Image8 g(6, 7, 1, 0);
    draw_text(g, 0, 0, std::string(1, c), ink);
    for (const auto& other : digits) EXPECT_NE(other, g.pixels) << c;
    digits.push_back(g.pixels);
  }
}

}  // namespace
}  // namespace scanmesh
