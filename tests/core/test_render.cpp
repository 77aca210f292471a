// The software renderer (render.h): a flat-coloured surface renders in its own colour, back faces
// in one slate colour whatever theirs, a point cloud as points.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "scanmesh/core/render.h"

namespace scanmesh {
namespace {

// A closed-side cylinder of radius 50 around z, faces counter-clockwise seen from outside.
Mesh cylinder(int n_phi, int n_z, Rgb8 colour) {
  Mesh m;
  for (int j = 0; j < n_z; ++j)
    for (int i = 0; i < n_phi; ++i) {
      const double a = 2 * M_PI * i / n_phi;
      m.positions.emplace_back(50 * std::cos(a), 50 * std::sin(a), -40.0 + 80.0 * j / (n_z - 1));
      m.normals.emplace_back(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)),
                             0.0f);
      m.colors.push_back(colour);
    }
  for (int j = 0; j + 1 < n_z; ++j)
    for (int i = 0; i < n_phi; ++i) {
      const int a = j * n_phi + i, b = j * n_phi + (i + 1) % n_phi;
      m.triangles.push_back({a, b, b + n_phi});
      m.triangles.push_back({a, b + n_phi, a + n_phi});
    }
  return m;
}

double linear(std::uint8_t v) { return std::pow(v / 255.0, 2.2); }

// The pixels that are not the background, as linear RGB.
std::vector<Eigen::Vector3d> object_pixels(const Image8& image, Rgb8 background) {
  std::vector<Eigen::Vector3d> out;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb8 c = image.rgb(x, y);
      if (!(c == background)) out.emplace_back(linear(c.r), linear(c.g), linear(c.b));
    }
  return out;
}

TEST(Render, AFlatColouredSurfaceRendersInItsOwnColour) {
  // Shading scales the colour (and adds a little white highlight): the chromaticity of the
  // lit pixels stays the colour's. A tint (the old blue-tinted back faces seen through holes)
  // would shift it.
  for (const Rgb8 colour : {Rgb8{200, 60, 40}, Rgb8{60, 160, 90}, Rgb8{90, 110, 220}}) {
    const RenderOptions o{.width = 200, .height = 200, .azimuth_deg = 0, .elevation_deg = 0};
    const auto pixels = object_pixels(render_mesh(cylinder(96, 12, colour), o), o.background);
    ASSERT_GT(pixels.size(), 5000u);
    const Eigen::Vector3d albedo(linear(colour.r), linear(colour.g), linear(colour.b));
    const Eigen::Vector3d expected = albedo / albedo.sum();
    std::vector<double> error;
    for (const auto& p : pixels) error.push_back((p / p.sum() - expected).cwiseAbs().maxCoeff());
    std::nth_element(error.begin(), error.begin() + error.size() / 2, error.end());
    EXPECT_LT(error[error.size() / 2], 0.02)
        << "median chromaticity off for colour " << int(colour.r) << "," << int(colour.g) << ","
        << int(colour.b);
  }
}

TEST(Render, BackFacesAreOneSlateColourWhateverTheirOwn) {
  // A square in the plane x = 0 facing -x, seen by the camera on +x: only its back. Its colour
  // must not depend on the vertex colour (a hole's inside is not a tint of the surface).
  const RenderOptions o{.width = 120, .height = 120, .azimuth_deg = 0, .elevation_deg = 0};
  auto square = [](Rgb8 colour) {
    Mesh m;
    m.positions = {{0, -10, -10}, {0, 10, -10}, {0, 10, 10}, {0, -10, 10}};
    m.triangles = {{0, 2, 1}, {0, 3, 2}};  // counter-clockwise seen from -x
    m.colors.assign(4, colour);
    return m;
  };
  const Image8 red = render_mesh(square({220, 30, 30}), o);
  const Image8 green = render_mesh(square({30, 220, 30}), o);
  const auto pixels = object_pixels(red, o.background);
  ASSERT_GT(pixels.size(), 5000u);
  EXPECT_EQ(red.pixels, green.pixels);
  for (const auto& p : pixels) EXPECT_GT(p.z(), 1.5 * p.x());  // slate blue, not the colour
}

TEST(Render, APointCloudIsDrawnAsPoints) {
  Mesh cloud = cylinder(64, 16, {200, 190, 175});
  cloud.triangles.clear();
  const RenderOptions o{.width = 200, .height = 200, .azimuth_deg = 0, .elevation_deg = 10};
  const auto lit = object_pixels(render_mesh(cloud, o), o.background);
  EXPECT_GT(lit.size(), 2000u);  // splats, not a blank picture
  EXPECT_LT(lit.size(), 200u * 200u);
  cloud.normals.clear();  // no normals: still drawn
  EXPECT_GT(object_pixels(render_mesh(cloud, o), o.background).size(), 2000u);
}

}  // namespace
}  // namespace scanmesh
