#include <gtest/gtest.h>

#include <cmath>

#include "aft_test_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/animation_lines.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::aft {
namespace {

TEST(AnimationLinesSvg, PathCommandsAbsoluteAndRelative) {
  const std::string svg = R"(<svg xmlns="http://www.w3.org/2000/svg">
  <path id="a" d="M 10 20 L 30 20 l 0 10 H 50 v 5 Z"/>
  <polyline class="seam" data-spacing-mm="2.5" points="1,2 3,4 5,9"/>
  <polygon id="opening-eye" points="100,100 120,100 110,120"/>
  <path id="curve" d="M0 0 C 10 0 10 10 20 10 Q 30 10 30 20"/>
</svg>)";
  const LineSet set = parse_lines_svg(svg, "t.svg");
  ASSERT_EQ(set.lines.size(), 4u);
  const AnimationLine& a = set.lines[0];
  EXPECT_EQ(a.id, "a");
  EXPECT_TRUE(a.closed);
  ASSERT_EQ(a.pixels.size(), 5u);
  EXPECT_EQ(a.pixels[2], Eigen::Vector2d(30, 30));
  EXPECT_EQ(a.pixels[3], Eigen::Vector2d(50, 30));
  EXPECT_EQ(a.pixels[4], Eigen::Vector2d(50, 35));
  EXPECT_EQ(set.lines[1].kind, LineKind::Seam);
  EXPECT_DOUBLE_EQ(set.lines[1].node_spacing_mm, 2.5);
  EXPECT_EQ(set.lines[2].kind, LineKind::Opening);
  EXPECT_TRUE(set.lines[2].closed);
  const AnimationLine& c = set.lines[3];
  EXPECT_FALSE(c.closed);
  EXPECT_NEAR(c.pixels.back().x(), 30, 1e-12);
  EXPECT_NEAR(c.pixels.back().y(), 20, 1e-12);
  // Cubic midpoint at t = 0.5: (0 + 3*10 + 3*10 + 20) / 8 = 10, (0 + 0 + 30 + 10) / 8 = 5.
  bool found = false;
  for (const auto& p : c.pixels) found |= (p - Eigen::Vector2d(10, 5)).norm() < 1e-9;
  EXPECT_TRUE(found);
  EXPECT_EQ(c.source, "t.svg:5");
}

// class "smooth" turns a polyline or polygon into the Catmull-Rom spline through its points:
// it passes through every drawn point and bulges between them; without it the drawn corners
// stay. A closed octagon approximating a circle gets much closer to the circle.
TEST(AnimationLinesSvg, SmoothClassDrawsTheSplineThroughThePoints) {
  std::string octagon;
  for (int k = 0; k < 8; ++k)
    octagon += std::to_string(200 + 40 * std::cos(k * M_PI / 4)) + "," +
               std::to_string(200 + 40 * std::sin(k * M_PI / 4)) + " ";
  const LineSet set =
      parse_lines_svg("<svg><polygon id='o' points='" + octagon +
                          "'/><polygon class='opening smooth' points='" + octagon + "'/></svg>",
                      "t.svg");
  ASSERT_EQ(set.lines.size(), 2u);
  const AnimationLine &straight = set.lines[0], &smooth = set.lines[1];
  EXPECT_FALSE(straight.smooth);
  EXPECT_TRUE(smooth.smooth);
  EXPECT_EQ(smooth.kind, LineKind::Opening);
  EXPECT_TRUE(smooth.closed);
  const std::vector<Eigen::Vector2d> polygon = line_curve(straight, 512),
                                     spline = line_curve(smooth, 512);
  EXPECT_EQ(polygon.size(), 8u);
  ASSERT_GT(spline.size(), 8u * 10);
  for (const auto& corner : polygon) {
    double nearest = 1e9;
    for (const auto& p : spline) nearest = std::min(nearest, (p - corner).norm());
    EXPECT_LT(nearest, 1e-9);  // through every drawn point
  }
  const auto worst_radius_error = [](const std::vector<Eigen::Vector2d>& c) {
    double worst = 0;
    for (std::size_t k = 0; k < c.size(); ++k) {
      // The straight pieces' midpoints too (for the octagon: its chords, 40 cos 22.5 = 36.96).
      const Eigen::Vector2d mid = 0.5 * (c[k] + c[(k + 1) % c.size()]);
      worst = std::max(worst, std::abs((mid - Eigen::Vector2d(200, 200)).norm() - 40));
    }
    return worst;
  };
  EXPECT_GT(worst_radius_error(polygon), 3.0);
  EXPECT_LT(worst_radius_error(spline), 0.5);
}

TEST(AnimationLinesSvg, ErrorsNameFileAndLine) {
  try {
    parse_lines_svg("<svg>\n<path d=\"M 0 0 A 1 1 0 0 0 5 5\"/>\n</svg>", "x.svg");
    FAIL();
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("x.svg: line 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_lines_svg("<svg><path d=\"M 0 0 L\"/></svg>", "x.svg"), FileFormatError);
  EXPECT_THROW(parse_lines_svg("<svg><path d=\"M 1 1\"/></svg>", "x.svg"), FileFormatError);
  EXPECT_THROW(parse_lines_svg("<html></html>", "x.svg"), FileFormatError);
  EXPECT_THROW(parse_lines_svg("<svg><path d='M 0 0 L 1 1' transform='scale(2)'/></svg>", "x.svg"),
               FileFormatError);
}

TEST(AnimationLinesJson, FormAndErrors) {
  const LineSet set = parse_lines_json(
      R"({"lines": [{"id": "m", "kind": "opening", "closed": true, "smooth": true,
                     "points": [[10, 10], [20, 10], [20, 20], [10, 20]]},
                    {"kind": "seam", "spacing_mm": 3, "points": [[0, 0], [5, 5]]}]})",
      "l.json");
  ASSERT_EQ(set.lines.size(), 2u);
  EXPECT_EQ(set.lines[0].kind, LineKind::Opening);
  EXPECT_TRUE(set.lines[0].smooth);
  EXPECT_GT(line_curve(set.lines[0], 512).size(), 20u);  // the spline is flattened
  EXPECT_EQ(set.lines[1].id, "line-2");
  EXPECT_THROW(parse_lines_json(R"({"lines": [{"points": [[0, 0]]}]})", "l.json"), FileFormatError);
  EXPECT_THROW(
      parse_lines_json(R"({"lines": [{"kind": "x", "points": [[0, 0], [1, 1]]}]})", "l.json"),
      FileFormatError);
  EXPECT_THROW(parse_lines_json("[1, 2", "l.json"), FileFormatError);
}

TEST(AnimationLines, SurfaceChecks) {
  RangeGrid grid = test::cylinder_grid();
  for (int i = 200; i < 220; ++i)
    for (int j = 100; j < 120; ++j) grid.invalidate(i, j);
  const ScanSurface surface(grid);
  const LineSet ok = parse_lines_svg("<svg><path d='M 10 10 L 100 10'/></svg>", "ok.svg");
  EXPECT_NO_THROW(validate_lines(ok, surface));
  const LineSet hole =
      parse_lines_svg("<svg><path id='h' d='M 150 110 L 300 110'/></svg>", "h.svg");
  try {
    validate_lines(hole, surface);
    FAIL();
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("'h' (h.svg:1) leaves the scanned area"),
              std::string::npos)
        << e.what();
  }
  const LineSet outside = parse_lines_svg("<svg><path d='M 10 10 L 10 450'/></svg>", "o.svg");
  EXPECT_THROW(validate_lines(outside, surface), FileFormatError);
  const LineSet tiny = parse_lines_svg("<svg><path d='M 10 10 L 11 10'/></svg>", "s.svg");
  EXPECT_THROW(validate_lines(tiny, surface), FileFormatError);
  // Self-intersection is found by the region analysis.
  const LineSet eight =
      parse_lines_svg("<svg><path id='eight' d='M 10 10 L 50 50 L 50 10 L 10 50'/></svg>", "e.svg");
  try {
    analyze_regions(eight, surface);
    FAIL();
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("intersects itself"), std::string::npos) << e.what();
  }
}

TEST(RegionSettings, ParseAndErrors) {
  const RegionSettings s = parse_region_settings(R"(
unit_mm: 5
strategy: random
seed: 7
repair_rounds: 0
regions:
  - {name: nose, point: [256, 200], unit_mm: 2.5, mesher: aft}
)",
                                                 "r.yaml");
  EXPECT_DOUBLE_EQ(s.default_unit_mm, 5);
  EXPECT_EQ(s.repair_rounds, 0);
  EXPECT_THROW(parse_region_settings("repair_rounds: -2", "r.yaml"), FileFormatError);
  EXPECT_EQ(s.max_front_steps, 0);  // automatic
  EXPECT_EQ(parse_region_settings("max_front_steps: 5000", "r.yaml").max_front_steps, 5000);
  for (const char* bad : {"max_front_steps: -1", "max_front_steps: x", "max_front_steps: 1.5"})
    EXPECT_THROW(parse_region_settings(bad, "r.yaml"), FileFormatError) << bad;
  EXPECT_TRUE(s.parallel_postprocessing);
  EXPECT_FALSE(
      parse_region_settings("parallel_postprocessing: false", "r.yaml").parallel_postprocessing);
  EXPECT_THROW(parse_region_settings("parallel_postprocessing: maybe", "r.yaml"), FileFormatError);
  EXPECT_TRUE(s.valence_flips);
  EXPECT_FALSE(parse_region_settings("valence_flips: false", "r.yaml").valence_flips);
  EXPECT_THROW(parse_region_settings("valence_flips: 1", "r.yaml"), FileFormatError);
  EXPECT_DOUBLE_EQ(s.repair_goal_deg, 20.5);
  EXPECT_DOUBLE_EQ(parse_region_settings("repair_goal_deg: 30.5", "r.yaml").repair_goal_deg, 30.5);
  for (const char* bad : {"repair_goal_deg: 5", "repair_goal_deg: 60", "repair_goal_deg: x"})
    EXPECT_THROW(parse_region_settings(bad, "r.yaml"), FileFormatError) << bad;
  EXPECT_DOUBLE_EQ(s.deviation_goal_mm, 0);  // off
  EXPECT_DOUBLE_EQ(parse_region_settings("deviation_goal_mm: 1.5", "r.yaml").deviation_goal_mm,
                   1.5);
  for (const char* bad :
       {"deviation_goal_mm: -1", "deviation_goal_mm: .inf", "deviation_goal_mm: x"})
    EXPECT_THROW(parse_region_settings(bad, "r.yaml"), FileFormatError) << bad;
  EXPECT_EQ(s.segment_spacing, SegmentSpacing::Mean);
  EXPECT_EQ(parse_region_settings("segment_spacing: finer", "r.yaml").segment_spacing,
            SegmentSpacing::Finer);
  EXPECT_THROW(parse_region_settings("segment_spacing: min", "r.yaml"), FileFormatError);
  try {
    parse_region_settings("strategy: widest", "r.yaml");
    ADD_FAILURE() << "strategy: widest was accepted";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("strategy must be random, shortest or longest"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(s.strategy, EdgeStrategy::Random);
  ASSERT_EQ(s.regions.size(), 1u);
  EXPECT_DOUBLE_EQ(*s.regions[0].unit_mm, 2.5);
  // Scaling changes every unit size and nothing else.
  const RegionSettings fine = s.with_units_scaled(0.25);
  EXPECT_DOUBLE_EQ(fine.default_unit_mm, 1.25);
  EXPECT_DOUBLE_EQ(*fine.regions[0].unit_mm, 0.625);
  EXPECT_DOUBLE_EQ(fine.min_unit_mm, s.min_unit_mm);
  EXPECT_EQ(fine.seed, 7u);
  EXPECT_EQ(fine.regions[0].name, "nose");
  EXPECT_NO_THROW(parse_region_settings(R"({"unit_mm": 4, "regions": []})", "r.json"));
  EXPECT_THROW(parse_region_settings("unit_mm: -1", "r.yaml"), FileFormatError);
  EXPECT_THROW(parse_region_settings("bogus: 1", "r.yaml"), FileFormatError);
  EXPECT_THROW(parse_region_settings("regions: [{unit_mm: 2}]", "r.yaml"), FileFormatError);
  EXPECT_THROW(parse_region_settings("mesher: quad", "r.yaml"), FileFormatError);
  EXPECT_THROW(parse_region_settings("unit_mm: [1", "r.yaml"), FileFormatError);
}

}  // namespace
TEST(AnimationLines, KindsHaveTheNamesOfTheFileFormat) {
  EXPECT_STREQ(to_string(LineKind::Normal), "line");
  EXPECT_STREQ(to_string(LineKind::Opening), "opening");
  EXPECT_STREQ(to_string(LineKind::Seam), "seam");
  EXPECT_STREQ(to_string(LineKind::DataBorder), "data-border");
}

}  // namespace scanmesh::aft
