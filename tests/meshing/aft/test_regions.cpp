// Region analysis on hand-made line sets whose answers are known by construction.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "aft_test_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/aft/regions.h"

namespace scanmesh::aft {
namespace {

class Regions : public ::testing::Test {
 protected:
  Regions() : grid_(test::cylinder_grid()), surface_(grid_) {}
  RegionGraph analyze(const std::string& body) {
    return analyze_regions(parse_lines_svg("<svg>" + body + "</svg>", "t.svg"), surface_);
  }
  double px_area(double w, double h) const { return w * h * surface_.dphi() * surface_.dh(); }
  //! The FileFormatError message analyze() gives for `body` ("" and a test failure if none).
  std::string analysis_error(const std::string& body) {
    try {
      analyze(body);
    } catch (const FileFormatError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no error for " << body;
    return "";
  }
  std::vector<Region> meshed(const RegionGraph& g) const {
    std::vector<Region> r;
    for (const Region& x : g.regions)
      if (!x.opening) r.push_back(x);
    return r;
  }
  RangeGrid grid_;
  ScanSurface surface_;
};

TEST_F(Regions, GridOfLines) {
  std::string body;
  for (int k = 0; k < 4; ++k) {
    const int c = 50 + 50 * k;
    body += "<path d='M 50 " + std::to_string(c) + " L 200 " + std::to_string(c) + "'/>";
    body += "<path d='M " + std::to_string(c) + " 50 L " + std::to_string(c) + " 200'/>";
  }
  const RegionGraph g = analyze(body);
  EXPECT_EQ(g.nodes.size(), 16u);
  EXPECT_EQ(g.segments.size(), 24u);
  ASSERT_EQ(g.regions.size(), 9u);
  for (const Region& r : g.regions) {
    EXPECT_NEAR(r.area, px_area(50, 50), 1e-9);
    EXPECT_TRUE(r.inner.empty());
    EXPECT_EQ(g.cycles[r.outer].edges.size(), 4u);
  }
  EXPECT_TRUE(g.dangling_ends.empty());
  // Each cell's centre is found in a different region.
  std::vector<int> seen;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const auto r = g.region_at(pixel_to_param(surface_, {75.0 + 50 * i, 75.0 + 50 * j}));
      ASSERT_TRUE(r);
      seen.push_back(*r);
    }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::unique(seen.begin(), seen.end()), seen.end());
  EXPECT_FALSE(g.region_at(pixel_to_param(surface_, {300, 300})));
}

TEST_F(Regions, RingInsideRegionIsAHole) {
  const RegionGraph g = analyze(
      "<polygon points='50,50 200,50 200,200 50,200'/>"
      "<polygon id='opening-eye' points='100,100 150,100 150,150 100,150'/>");
  ASSERT_EQ(g.regions.size(), 2u);
  const auto m = meshed(g);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].inner.size(), 1u);
  EXPECT_NEAR(m[0].area, px_area(150, 150) - px_area(50, 50), 1e-9);
  const auto inner = g.region_at(pixel_to_param(surface_, {125, 125}));
  ASSERT_TRUE(inner);
  EXPECT_TRUE(g.regions[*inner].opening);
  const auto outer = g.region_at(pixel_to_param(surface_, {70, 70}));
  ASSERT_TRUE(outer);
  EXPECT_FALSE(g.regions[*outer].opening);
}

TEST_F(Regions, DanglingInternalLines) {
  // A free-standing line inside, and one attached to the left border.
  const RegionGraph g = analyze(
      "<polygon points='50,50 200,50 200,200 50,200'/>"
      "<path id='ear' d='M 80 80 L 120 120'/>"
      "<path id='fold' d='M 50 160 L 120 160'/>");
  ASSERT_EQ(g.regions.size(), 1u);
  const Region& r = g.regions[0];
  EXPECT_NEAR(r.area, px_area(150, 150), 1e-9);
  ASSERT_EQ(r.inner.size(), 1u);
  EXPECT_EQ(g.cycles[r.inner[0]].edges.size(), 2u);  // the ear line, both ways
  EXPECT_EQ(g.dangling_ends.size(), 3u);
  // The fold is split where it meets the border and appears twice in the outer cycle.
  int fold_uses = 0;
  for (const HalfEdgeRef& e : g.cycles[r.outer].edges) fold_uses += g.segments[e.segment].line == 2;
  EXPECT_EQ(fold_uses, 2);
  EXPECT_EQ(g.cycles[r.outer].edges.size(), 3u);  // the border loop (one junction) + fold x2
}

TEST_F(Regions, LinesAcrossThePhiSeam) {
  // A square from x = 480 to 560 (= 48 after wrapping) cut by a vertical line at x = 10.
  const RegionGraph g = analyze(
      "<polygon points='480,50 560,50 560,150 480,150'/>"
      "<path d='M 10 20 L 10 180'/>");
  ASSERT_EQ(g.regions.size(), 2u);
  std::vector<double> areas{g.regions[0].area, g.regions[1].area};
  std::sort(areas.begin(), areas.end());
  EXPECT_NEAR(areas[0], px_area(38, 100), 1e-9);
  EXPECT_NEAR(areas[1], px_area(42, 100), 1e-9);
  const auto a = g.region_at(pixel_to_param(surface_, {500, 100}));
  const auto b = g.region_at(pixel_to_param(surface_, {30, 100}));
  const auto b2 = g.region_at(pixel_to_param(surface_, {30 + 512, 100}));
  ASSERT_TRUE(a && b && b2);
  EXPECT_NE(*a, *b);
  EXPECT_EQ(*b, *b2);
  EXPECT_EQ(g.dangling_ends.size(), 2u);
}

// Two lines all the way round the axis: with a line across, the band between them is a region
// (as on the sample head: neck, crown and back seam); without one it is an error that names
// both lines and says how to cut the band, not a silently unmeshed band.
TEST_F(Regions, BandBetweenTwoRoundLinesNeedsALineAcross) {
  const std::string loops =
      "<polygon id='low' points='0,50 128,50 256,50 384,50'/>"
      "<polygon id='high' points='0,300 128,300 256,300 384,300'/>";
  const RegionGraph cut = analyze(loops + "<path id='cut' d='M 100 50 L 100 300'/>");
  ASSERT_EQ(meshed(cut).size(), 1u);
  EXPECT_NEAR(meshed(cut)[0].area, px_area(512, 250), 1e-6);
  const std::string band = analysis_error(loops);
  EXPECT_NE(band.find("t.svg"), std::string::npos) << band;
  EXPECT_NE(band.find("line 'low'"), std::string::npos) << band;
  EXPECT_NE(band.find("line 'high'"), std::string::npos) << band;
  EXPECT_NE(band.find("all the way round"), std::string::npos) << band;
  // A line hanging off a round line is not named as going round; two open lines that go
  // round together are named together.
  const std::string together = analysis_error(
      "<path id='stub' d='M 100 50 L 100 80'/>"
      "<path id='west' d='M 0 300 L 256 300'/><path id='east' d='M 256 300 L 512 300'/>"
      "<polygon id='low' points='0,50 128,50 256,50 384,50'/>");
  EXPECT_NE(together.find("line 'low'"), std::string::npos) << together;
  EXPECT_EQ(together.find("'stub'"), std::string::npos) << together;
  EXPECT_NE(together.find("lines 'west' and 'east' (together)"), std::string::npos) << together;
  // One round line alone bounds nothing but the caps: no error, no region.
  EXPECT_TRUE(meshed(analyze("<polygon id='low' points='0,50 128,50 256,50 384,50'/>")).empty());
}

// A smooth line across the phi seam is joined across it before it is smoothed: the spline
// through 500 -> 10 (= 522) stays next to the seam instead of running round the head.
TEST_F(Regions, SmoothLineAcrossThePhiSeamStaysAtTheSeam) {
  const std::string box = "points='500,100 10,100 10,150 500,150'";
  const RegionGraph straight = analyze("<polygon " + box + "/>");
  const RegionGraph smooth = analyze("<polygon class='smooth' " + box + "/>");
  ASSERT_EQ(meshed(straight).size(), 1u);
  ASSERT_EQ(meshed(smooth).size(), 1u);
  EXPECT_NEAR(meshed(straight)[0].area, px_area(22, 50), 1e-9);
  // The spline bulges outwards between the corners it passes through: a little more area.
  EXPECT_GT(meshed(smooth)[0].area, px_area(22, 50));
  EXPECT_LT(meshed(smooth)[0].area, px_area(30, 60));
  for (const auto& seg : smooth.segments)
    for (const auto& p : seg.pts) {
      const double x = param_to_pixel(surface_, p).x();
      const double from_seam = std::min(std::fabs(x - 512 * std::round(x / 512)), 256.0);
      EXPECT_LT(from_seam, 20.0) << x;
    }
}

TEST_F(Regions, EndPointsSnapOntoLines) {
  // The middle line stops 1 px short of the right border: snapped into a T junction.
  const RegionGraph g = analyze(
      "<polygon points='50,50 200,50 200,200 50,200'/>"
      "<path d='M 50 120 L 199 120'/>");
  EXPECT_EQ(g.regions.size(), 2u);
  EXPECT_TRUE(g.dangling_ends.empty());
}

}  // namespace
}  // namespace scanmesh::aft

// Segment initialisation (seed 000 §5.1.2) on a plain cylinder r = 100 mm, where 3D arc length
// along a line of constant h is r * dphi exactly.
namespace scanmesh::aft {
namespace {

TEST(SegmentInit, EquidistantNodeCountAndSpacing) {
  const RangeGrid grid = test::cylinder_grid(100.0, 0.0);
  const ScanSurface surface(grid);
  const LineSet lines = parse_lines_svg("<svg><path d='M 50 200 L 150 200'/></svg>", "t.svg");
  const RegionGraph g = analyze_regions(lines, surface);
  RegionSettings s;
  s.default_unit_mm = 10.0;
  const SegmentNodes nodes = initialise_segments(g, lines, surface, s);
  ASSERT_EQ(nodes.chains.size(), 1u);
  const double arc = 100.0 * 100 * 2 * M_PI / 512;  // s
  const int n_nodes = static_cast<int>(std::floor(arc / 10.0)) + 2;
  EXPECT_EQ(static_cast<int>(nodes.chains[0].size()), n_nodes);
  const double d_prime = arc / (std::floor(arc / 10.0) + 1);
  EXPECT_NEAR(nodes.spacing_mm[0], d_prime, 1e-3);
  for (std::size_t k = 0; k + 1 < nodes.chains[0].size(); ++k) {
    const double dphi =
        nodes.params[nodes.chains[0][k + 1]].x() - nodes.params[nodes.chains[0][k]].x();
    EXPECT_NEAR(100.0 * dphi, d_prime, 1e-3);  // arc between nodes
  }
}

// A square between a 5 mm region (inside) and a 15 mm ring (between it and an outer square):
// its nodes are spaced by the mean of both by default, by the finer unit with
// segment_spacing: finer. The outer square borders the ring alone: 15 mm either way.
TEST(SegmentInit, SpacingBetweenTwoRegionsIsTheFinerUnitOrTheMean) {
  const RangeGrid grid = test::cylinder_grid(100.0, 0.0);
  const ScanSurface surface(grid);
  const LineSet lines = parse_lines_svg(
      "<svg><path d='M 100 150 L 200 150 L 200 250 L 100 250 Z'/>"
      "<path d='M 50 100 L 250 100 L 250 300 L 50 300 Z'/></svg>",
      "t.svg");
  RegionGraph g = analyze_regions(lines, surface);
  ASSERT_EQ(g.regions.size(), 2u);
  ASSERT_EQ(g.segments.size(), 2u);
  const int inner = g.regions[0].area < g.regions[1].area ? 0 : 1;
  g.regions[inner].unit_mm = 5.0;
  g.regions[1 - inner].unit_mm = 15.0;
  const int square = g.segments[0].left_region >= 0 && g.segments[0].right_region >= 0 ? 0 : 1;
  RegionSettings s;
  s.relax_iterations = 0;
  const SegmentNodes mean = initialise_segments(g, lines, surface, s);
  s.segment_spacing = SegmentSpacing::Finer;
  const SegmentNodes finer = initialise_segments(g, lines, surface, s);
  // d_I' = s / (floor(s / d_I) + 1): just below d_I on a ~ 300 mm loop.
  EXPECT_LE(finer.spacing_mm[square], 5.0);
  EXPECT_GT(finer.spacing_mm[square], 4.9);
  EXPECT_LE(mean.spacing_mm[square], 10.0);
  EXPECT_GT(mean.spacing_mm[square], 9.6);
  EXPECT_GT(finer.chains[square].size(), mean.chains[square].size() + 25);
  EXPECT_NEAR(finer.spacing_mm[1 - square], mean.spacing_mm[1 - square], 1e-12);
  EXPECT_GT(finer.spacing_mm[1 - square], 14.0);
}

TEST(SegmentInit, CurvatureModePutsMoreNodesWhereTheLineTurns) {
  const RangeGrid grid = test::cylinder_grid(100.0, 0.0);
  const ScanSurface surface(grid);
  // A zig-zag: straight parts and sharp turns.
  const LineSet lines = parse_lines_svg(
      "<svg><path d='M 50 100 L 70 150 L 90 100 L 110 150 L 130 100'/></svg>", "t.svg");
  const RegionGraph g = analyze_regions(lines, surface);
  RegionSettings s;
  s.default_unit_mm = 10.0;
  s.relax_iterations = 0;
  const auto eq = initialise_segments(g, lines, surface, s);
  s.segment_init = SegmentInit::Curvature;
  const auto cu = initialise_segments(g, lines, surface, s);
  EXPECT_GT(cu.chains[0].size(), eq.chains[0].size());
}

TEST(SegmentInit, RelaxationOffsetsNodesOnCloseParallelLines) {
  const RangeGrid grid = test::cylinder_grid(100.0, 0.0);
  const ScanSurface surface(grid);
  // Two parallel lines 6 rows (3 mm) apart, nodes about 9.4 mm apart: initially aligned.
  const LineSet lines = parse_lines_svg(
      "<svg><path d='M 50 200 L 150 200'/><path d='M 50 206 L 150 206'/></svg>", "t.svg");
  const RegionGraph g = analyze_regions(lines, surface);
  RegionSettings s;
  s.default_unit_mm = 10.0;
  auto min_cross_distance = [&](const SegmentNodes& n) {
    double best = 1e300;
    for (int i : n.chains[0])
      for (int j : n.chains[1]) {
        if (i == n.chains[0].front() || i == n.chains[0].back()) continue;
        if (j == n.chains[1].front() || j == n.chains[1].back()) continue;
        const auto a = surface.position(n.params[i].x(), n.params[i].y());
        const auto b = surface.position(n.params[j].x(), n.params[j].y());
        best = std::min(best, (*a - *b).norm());
      }
    return best;
  };
  s.relax_iterations = 0;
  const double before = min_cross_distance(initialise_segments(g, lines, surface, s));
  s.relax_iterations = 30;
  const double after = min_cross_distance(initialise_segments(g, lines, surface, s));
  EXPECT_NEAR(before, 3.0, 0.05);  // 6 rows of 0.5 mm
  EXPECT_GT(after, before + 1.0);
}

}  // namespace
}  // namespace scanmesh::aft
