// The built-in head scanned with the built-in scanner (configs/sim/head.yaml,
// configs/scanners/sim-head.yaml): its defects are where they should be.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

using namespace scanmesh;
using namespace scanmesh::sim;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

const SimulatedScan& head_scan() {
  static const SimulatedScan scan = simulate_scan(builtin_head_scene(), builtin_head_scanner());
  return scan;
}

struct Region {
  double phi_min_deg, phi_max_deg, z_min, z_max;
};

template <typename F>
void for_cells(const SimulatedScan& s, Region r, F f) {
  for (int j = 0; j < s.grid.n_h(); ++j)
    for (int i = 0; i < s.grid.n_phi(); ++i) {
      const double phi = s.grid.phi(i) / kDeg, z = s.grid.h(j);
      if (phi >= r.phi_min_deg && phi <= r.phi_max_deg && z >= r.z_min && z <= r.z_max)
        f(i, j, s.truth[s.grid.index(i, j)]);
    }
}

}  // namespace

TEST(HeadScan, FaceLooksTowardMinusX) {
  const auto& s = head_scan();
  EXPECT_EQ(s.grid.n_phi(), 512);
  // The nose tip (phi = pi) stands out of the face, the ears (phi = +-pi/2) stick out sideways.
  double nose = 0.0, cheek = 0.0;
  for_cells(s, {179, 181, 95, 100},
            [&](int, int, const GroundTruthCell& t) { nose = std::max(nose, t.radius); });
  for_cells(s, {150, 152, 95, 100},
            [&](int, int, const GroundTruthCell& t) { cheek = std::max(cheek, t.radius); });
  EXPECT_GT(nose, 115.0);
  EXPECT_GT(nose, cheek + 10.0);
  // Height ~200 mm: the crown is hit, rows above 226 mm are not; the neck leaves the band.
  int crown = 0, above = 0, neck = 0;
  for_cells(s, {0, 360, 215, 220}, [&](int, int, const GroundTruthCell& t) { crown += t.hit; });
  for_cells(s, {0, 360, 228, 240}, [&](int, int, const GroundTruthCell& t) { above += t.hit; });
  for_cells(s, {0, 360, 0, 0.5}, [&](int, int, const GroundTruthCell& t) { neck += t.hit; });
  EXPECT_GT(crown, 100);
  EXPECT_EQ(above, 0);
  EXPECT_EQ(neck, 2 * 512);  // both rows below 0.5 mm hit the neck all around
}

TEST(HeadScan, CellsBehindTheEarAreOccluded) {
  // The +y ear is at phi ~ 80 deg; the camera sits at phi + 20 deg, so the pocket between the
  // ear and the skull at slightly smaller phi is out of its sight.
  int occluded = 0;
  for_cells(head_scan(), {60, 80, 95, 135}, [&](int, int, const GroundTruthCell& t) {
    occluded += t.drop == DropReason::Occluded;
  });
  EXPECT_GT(occluded, 50);
}

TEST(HeadScan, ForeheadHasNoOcclusionDropouts) {
  int occluded = 0, valid = 0;
  const auto& s = head_scan();
  for_cells(s, {165, 195, 145, 180}, [&](int i, int j, const GroundTruthCell& t) {
    occluded += t.drop == DropReason::Occluded;
    valid += s.grid.valid(i, j);
  });
  EXPECT_EQ(occluded, 0);
  EXPECT_GT(valid, 2000);
}

TEST(HeadScan, HairIsNoisierThanFace) {
  const auto& s = head_scan();
  const Scene head = builtin_head_scene();
  auto spread = [&](Region r, bool hair) {
    double sum2 = 0.0;
    int n = 0;
    for_cells(s, r, [&](int i, int j, const GroundTruthCell& t) {
      if (!s.grid.valid(i, j) || t.spike) return;
      const bool in_hair = head.in_hair_zone(t.point);
      if (in_hair != hair) return;
      const double e = s.grid.radius(i, j) - t.radius;
      sum2 += e * e;
      ++n;
    });
    EXPECT_GT(n, 200);
    return std::sqrt(sum2 / std::max(n, 1));
  };
  const double face = spread({150, 210, 60, 180}, false);
  const double hair = spread({0, 40, 120, 200}, true);
  EXPECT_LT(face, 0.15);
  EXPECT_GT(hair, 1.0);
  int speckles = 0;
  for (const auto& t : s.truth) speckles += t.drop == DropReason::HairSpeckle;
  EXPECT_GT(speckles, 1000);
}

TEST(HeadScan, CapAboveTheBandIsAHole) {
  const auto& s = head_scan();
  int hits = 0, valid = 0;
  for_cells(s, {0, 360, 213, 230}, [&](int i, int j, const GroundTruthCell& t) {
    hits += t.hit;
    valid += s.grid.valid(i, j);
  });
  EXPECT_GT(hits, 1000);
  EXPECT_EQ(valid, 0);
}
