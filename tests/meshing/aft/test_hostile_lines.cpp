// Hostile and degenerate animation lines (issue 10, item 3): zero-area regions, lines along
// the phi seam, overlapping and repeated lines, non-finite coordinates, empty files. Each must
// give a clear error naming the file or a correct result — never a crash, a hang or regions
// that are not there.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>

#include "aft_test_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::aft {
namespace {

class HostileLines : public ::testing::Test {
 protected:
  HostileLines() : grid_(test::cylinder_grid(100.0, 0.0, 512, 200, 1.0)), surface_(grid_) {}

  //! The region graph, or nullopt after a scanmesh::Error whose message names the file.
  std::optional<RegionGraph> analyze_or_reject(const std::string& body) {
    try {
      const LineSet lines = parse_lines_svg("<svg>" + body + "</svg>", "hostile.svg");
      validate_lines(lines, surface_);
      return analyze_regions(lines, surface_);
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("hostile.svg"), std::string::npos) << e.what();
      return std::nullopt;
    }
  }
  //! Every region that is reported has a positive area and a label point inside itself.
  static void expect_sound(const RegionGraph& g) {
    for (std::size_t r = 0; r < g.regions.size(); ++r) {
      EXPECT_GT(g.regions[r].area, 0) << "region " << r;
      const auto at = g.region_at(g.regions[r].label_point);
      ASSERT_TRUE(at) << "region " << r;
      EXPECT_EQ(*at, static_cast<int>(r));
    }
  }
  double px_area(double w, double h) const { return w * h * surface_.dphi() * surface_.dh(); }

  RangeGrid grid_;
  ScanSurface surface_;
};

TEST_F(HostileLines, ZeroAreaPolygonsGiveNoRegion) {
  // All corners on one line, and a polygon whose corners coincide.
  for (const std::string body :
       {"<polygon points='50,50 100,50 150,50'/>", "<polygon points='60,60 60,60 60,60 60,60'/>",
        "<polygon points='50,50 150,50 50,50 150,50'/>"}) {
    SCOPED_TRACE(body);
    const auto g = analyze_or_reject(body);
    if (g) {
      EXPECT_TRUE(g->regions.empty()) << g->to_text();
    }
  }
}

TEST_F(HostileLines, ZeroAreaPolygonBesideARealOneLeavesTheRealOne) {
  const auto g = analyze_or_reject(
      "<polygon points='50,50 100,50 100,100 50,100'/>"
      "<polygon points='200,50 260,50 230,50'/>");
  if (!g) return;  // rejected with the file named: acceptable
  expect_sound(*g);
  ASSERT_EQ(g->regions.size(), 1u) << g->to_text();
  EXPECT_NEAR(g->regions[0].area, px_area(50, 50), 1e-9);
}

TEST_F(HostileLines, LineAlongThePhiSeamSplitsASquareAcrossIt) {
  // x = 0 and x = 512 are the same meridian; either spelling must split the square in two.
  for (const std::string seam : {"<path d='M 0 20 L 0 180'/>", "<path d='M 512 20 L 512 180'/>"}) {
    SCOPED_TRACE(seam);
    const auto g = analyze_or_reject("<polygon points='472,50 552,50 552,150 472,150'/>" + seam);
    ASSERT_TRUE(g) << "a line on the seam is a valid line";
    expect_sound(*g);
    ASSERT_EQ(g->regions.size(), 2u) << g->to_text();
    EXPECT_NEAR(g->regions[0].area, px_area(40, 100), 1e-9);
    EXPECT_NEAR(g->regions[1].area, px_area(40, 100), 1e-9);
    EXPECT_EQ(g->dangling_ends.size(), 2u);
  }
}

TEST_F(HostileLines, SquareWithAnEdgeOnTheSeamMeshesOnBothSidesOfIt) {
  // The square's left edge lies on phi = 0: meshing must not lose or duplicate that column.
  const LineSet lines =
      parse_lines_svg("<svg><polygon points='0,60 60,60 60,140 0,140'/></svg>", "seam.svg");
  validate_lines(lines, surface_);
  RegionGraph g = analyze_regions(lines, surface_);
  ASSERT_EQ(g.regions.size(), 1u) << g.to_text();
  RegionSettings s;
  s.default_unit_mm = 4.0;
  apply_region_settings(g, s, surface_);
  const AnimationMesh am = build_animation_mesh(g, lines, surface_, s);
  const MeshCheckReport rep = check_mesh(am.mesh);
  EXPECT_TRUE(rep.edge_manifold()) << rep.to_text();
  EXPECT_EQ(rep.duplicate_faces, 0u);
  EXPECT_EQ(rep.self_intersections, 0u);
  EXPECT_EQ(rep.topology.boundary_loops, 1u) << rep.to_text();
  // Area of the mesh = area of the patch on the cylinder (r dphi dh), within the chordal error.
  double area = 0;
  for (const auto& t : am.mesh.triangles)
    area += 0.5 * (am.mesh.positions[t[1]] - am.mesh.positions[t[0]])
                      .cross(am.mesh.positions[t[2]] - am.mesh.positions[t[0]])
                      .norm();
  const double exact = 100.0 * px_area(60, 80);
  EXPECT_NEAR(area, exact, 0.01 * exact);
}

TEST_F(HostileLines, RepeatedAndOverlappingLinesAreRejectedOrMerged) {
  for (const std::string body : {"<path d='M 10 20 L 100 20'/><path d='M 10 20 L 100 20'/>",
                                 "<path d='M 10 20 L 100 20'/><path d='M 50 20 L 150 20'/>",
                                 "<polygon points='50,50 100,50 100,100 50,100'/>"
                                 "<polygon points='50,50 100,50 100,100 50,100'/>",
                                 "<path d='M 10 30 L 100 30 L 10 30'/>"}) {
    SCOPED_TRACE(body);
    const auto g = analyze_or_reject(body);
    if (g) expect_sound(*g);
  }
}

TEST_F(HostileLines, NonFiniteAndEmptyInputsAreRejectedNamingTheFile) {
  for (const std::string body :
       {"<path d='M nan 20 L 100 20'/>", "<path d='M 10 inf L 100 20'/>",
        "<polygon points='1e400,5 10,10 20,20'/>", "<path d='M 10 20 L 1e308 20'/>", "<path d=''/>",
        "<polygon points=''/>", ""}) {
    SCOPED_TRACE(body);
    const auto g = analyze_or_reject(body);
    if (g) {
      EXPECT_TRUE(g->regions.empty()) << g->to_text();
      EXPECT_TRUE(g->segments.empty()) << g->to_text();
    }
  }
}

}  // namespace
}  // namespace scanmesh::aft
