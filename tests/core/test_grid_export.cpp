#include <gtest/gtest.h>

#include <random>

#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/texture_layout.h"
#include "test_util.h"

namespace scanmesh {
namespace {

using test::TempDir;

RangeGrid textured_grid(int n_phi, int n_h) {
  RangeGrid g(n_phi, n_h, 0.1, -20.0, 0.5);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      if ((i * 7 + j * 3) % 5 != 0) g.set_sample(i, j, 50.0f + 0.25f * i + 0.125f * j, 0.5f);
      g.set_color(i, j,
                  {static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
                   static_cast<std::uint8_t>(byte(rng))});
    }
  return g;
}

TEST(GridExport, PlyPointsHaveOneVertexPerValidCell) {
  TempDir dir;
  const RangeGrid grid = textured_grid(48, 32);
  export_ply_points(dir / "points.ply", grid);
  const Mesh cloud = read_ply(dir / "points.ply");
  ASSERT_EQ(cloud.vertex_count(), grid.valid_count());
  EXPECT_EQ(cloud.vertex_count(), 1228u);  // 48 * 32 minus the 308 cells with (7i + 3j) % 5 == 0
  EXPECT_EQ(cloud.face_count(), 0u);
  ASSERT_TRUE(cloud.has_colors());
  std::size_t v = 0;
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i) {
      if (!grid.valid(i, j)) continue;
      const Eigen::Vector3d expected = test::float_precision(grid.cartesian(i, j));
      EXPECT_EQ(cloud.positions[v], expected) << "cell " << i << "," << j;
      EXPECT_EQ(cloud.colors[v], grid.color(i, j));
      ++v;
    }
  const std::string text = test::read_text(dir / "points.ply");
  EXPECT_NE(text.find("property float confidence\nproperty int phi_index\nproperty int h_index\n"),
            std::string::npos);
}

TEST(GridExport, TexturePngIsUprightAndEqualsColorsPixelForPixel) {
  TempDir dir;
  const RangeGrid grid = textured_grid(64, 40);
  export_texture_png(dir / "texture.png", grid);
  const Image8 image = read_png(dir / "texture.png");
  ASSERT_EQ(image.width, 64);
  ASSERT_EQ(image.height, 40);
  ASSERT_EQ(image.channels, 3);
  int mismatches = 0;
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i)
      mismatches += !(image.rgb(i, texture_row(j, grid.n_h())) == grid.color(i, j));
  EXPECT_EQ(mismatches, 0);
  // Upright: the top row is the highest h, the bottom row the lowest.
  for (int i = 0; i < grid.n_phi(); ++i) {
    EXPECT_EQ(image.rgb(i, 0), grid.color(i, grid.n_h() - 1));
    EXPECT_EQ(image.rgb(i, image.height - 1), grid.color(i, 0));
  }
  EXPECT_EQ(texture_image(grid).pixels, image.pixels);
}

TEST(GridExport, DepthImageIsDarkNearAndBrightFarAndBlackInHoles) {
  RangeGrid grid(4, 2);
  grid.set_sample(0, 0, 100.0f);
  grid.set_sample(1, 0, 150.0f);
  grid.set_sample(2, 0, 200.0f);
  grid.set_sample(0, 1, 300.0f);
  const Image8 depth = depth_image(grid);
  ASSERT_EQ(depth.channels, 1);
  ASSERT_EQ(depth.width, 4);
  ASSERT_EQ(depth.height, 2);
  // Upright: grid row 1 (the higher h) is the picture's top row 0.
  EXPECT_EQ(depth.at(0, 1)[0], 40);   // r_min
  EXPECT_EQ(depth.at(1, 1)[0], 94);   // 40 + 215 / 4 = 93.75
  EXPECT_EQ(depth.at(2, 1)[0], 148);  // 40 + 215 / 2 = 147.5
  EXPECT_EQ(depth.at(0, 0)[0], 255);  // r_max
  EXPECT_EQ(depth.at(3, 1)[0], 0);    // invalid
  EXPECT_EQ(depth.at(3, 0)[0], 0);

  const Image8 empty = depth_image(RangeGrid(5, 3));
  EXPECT_EQ(empty.pixels, std::vector<std::uint8_t>(15, 0));
}

TEST(GridExport, DepthPngIsTheDepthImageWithAMillimetreScale) {
  TempDir dir;
  const RangeGrid grid = textured_grid(32, 16);
  export_depth_png(dir / "depth.png", grid);
  const Image8 image = read_png(dir / "depth.png");
  const Image8 depth = depth_image(grid);
  ASSERT_EQ(image.channels, 3);
  ASSERT_GT(image.width, depth.width + 40);  // a legend strip beside the picture
  ASSERT_GE(image.height, depth.height);
  int mismatches = 0;
  for (int y = 0; y < depth.height; ++y)
    for (int x = 0; x < depth.width; ++x) {
      const std::uint8_t g = depth.at(x, y)[0];
      mismatches += !(image.rgb(x, y) == Rgb8{g, g, g});
    }
  EXPECT_EQ(mismatches, 0);
  // The scale's bar runs from the largest radius's grey (255) at the top to the smallest's (40)
  // at the bottom, and the strip carries text (title and the two radii in mm) in black.
  int bar_x = -1;
  for (int x = depth.width; x < image.width && bar_x < 0; ++x)
    if (image.rgb(x, 20) == Rgb8{255, 255, 255} &&
        image.rgb(x, image.height - 10) == Rgb8{40, 40, 40})
      bar_x = x;
  EXPECT_GE(bar_x, 0) << "no grey bar from 255 down to 40 in the legend";
  int ink = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = depth.width; x < image.width; ++x) ink += image.rgb(x, y) == Rgb8{0, 0, 0};
  EXPECT_GT(ink, 100);
}

}  // namespace
}  // namespace scanmesh
