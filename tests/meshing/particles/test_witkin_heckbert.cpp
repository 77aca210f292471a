// Witkin-Heckbert sampler (seed 003 §3.2, eq. 3-11).
#include <gtest/gtest.h>

#include <algorithm>

#include "scanmesh/meshing/particles/witkin_heckbert.h"
#include "test_common.h"

namespace scanmesh::particles {
namespace {

using Eigen::Vector3d;
using namespace testing;

TEST(WitkinHeckbert, SphereSamplesAreOnTheSurfaceAndEvenlySpaced) {
  const auto s = surface_of(sim::make_sphere(Vector3d::Zero(), 1.0), Vector3d::Constant(-1.1),
                            Vector3d::Constant(1.1));
  const SampleResult r = witkin_heckbert_sample(*s, {.sigma = 0.1, .iterations = 300});
  const auto& pts = r.points;
  EXPECT_GT(r.fissions, 0);  // 32 seeds must multiply to cover the sphere
  // Density: at equilibrium (E_i = 0.8 alpha with ~6 neighbours) the spacing is ~2 sigma,
  // i.e. about 4 pi / (sqrt(3)/2 (2 sigma)^2) = 363 particles on the unit sphere.
  EXPECT_GT(pts.size(), 200u);
  EXPECT_LT(pts.size(), 700u);
  std::vector<double> nn;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    EXPECT_NEAR(pts[i].norm(), 1.0, 1e-9);
    double best = 1e9;
    for (std::size_t j = 0; j < pts.size(); ++j)
      if (j != i) best = std::min(best, (pts[i] - pts[j]).norm());
    nn.push_back(best);
  }
  double mean = 0, var = 0;
  for (double d : nn) mean += d / static_cast<double>(nn.size());
  for (double d : nn) var += (d - mean) * (d - mean) / static_cast<double>(nn.size());
  EXPECT_LT(std::sqrt(var) / mean, 0.25);                          // nearly even spreading
  EXPECT_GT(*std::min_element(nn.begin(), nn.end()), 0.3 * mean);  // no clumps
}

TEST(WitkinHeckbert, IsDeterministicForASeed) {
  const auto s = surface_of(sim::make_sphere(Vector3d::Zero(), 1.0), Vector3d::Constant(-1.1),
                            Vector3d::Constant(1.1));
  const SamplerOptions o{.sigma = 0.2, .iterations = 60, .seed = 7};
  EXPECT_EQ(witkin_heckbert_sample(*s, o).points, witkin_heckbert_sample(*s, o).points);
}

}  // namespace
}  // namespace scanmesh::particles
