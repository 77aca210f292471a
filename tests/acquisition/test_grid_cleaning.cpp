// Grid cleaning: spikes and fragments go, smooth surfaces and holes stay as they are.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/core/errors.h"

namespace scanmesh {
namespace {

// A smooth bumpy surface of revolution with steep parts, as a scan of a head would have.
RangeGrid smooth_grid(int n_phi = 128, int n_h = 96) {
  RangeGrid grid(n_phi, n_h, 0.0, 0.0, 0.5);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      const double r = 70.0 + 8.0 * std::sin(3.0 * grid.phi(i)) + 4.0 * std::cos(0.2 * grid.h(j));
      grid.set_sample(i, j, static_cast<float>(r));
    }
  return grid;
}

TEST(GridCleaning, SmoothSurfaceLosesNoCell) {
  RangeGrid grid = smooth_grid();
  const RangeGrid before = grid;
  const CleaningReport report = clean_grid(grid);
  EXPECT_EQ(report.spikes_removed, 0u);
  EXPECT_EQ(report.fragment_cells_removed, 0u);
  EXPECT_EQ(report.components_kept, 1u);
  EXPECT_EQ(grid, before);
}

TEST(GridCleaning, RemovesEverySpikeAndNothingElse) {
  RangeGrid grid = smooth_grid();
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> col(0, grid.n_phi() - 1), row(1, grid.n_h() - 2);
  std::uniform_real_distribution<float> size(5.0f, 40.0f);
  std::set<std::size_t> spikes;
  while (spikes.size() < 60) {
    const int i = col(rng), j = row(rng);
    const std::size_t k = grid.index(i, j);
    bool isolated = true;  // keep spikes apart so each has a clean neighbourhood
    for (std::size_t s : spikes) {
      const int si = static_cast<int>(s % grid.n_phi()), sj = static_cast<int>(s / grid.n_phi());
      const int di = std::min(std::abs(si - i), grid.n_phi() - std::abs(si - i));
      if (di <= 2 && std::abs(sj - j) <= 2) isolated = false;
    }
    if (!isolated) continue;
    const float sign = (spikes.size() % 2) ? 1.0f : -1.0f;
    grid.set_sample(i, j, grid.radius(i, j) + sign * size(rng));
    spikes.insert(k);
  }
  const CleaningReport report = clean_grid(grid);
  EXPECT_EQ(report.spikes_removed, 60u);
  for (std::size_t k = 0; k < grid.cell_count(); ++k)
    EXPECT_EQ(grid.validity()[k] == 0, spikes.count(k) == 1) << "cell " << k;
}

TEST(GridCleaning, RemovesSmallFragmentsAcrossTheSeamAwareOfWrapping) {
  RangeGrid grid(64, 40, 0.0, 0.0, 1.0);
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 30; ++i) grid.set_sample(i, j, 50.0f);  // the main piece
  for (int j = 10; j < 13; ++j)
    for (int i = 40; i < 43; ++i) grid.set_sample(i, j, 50.0f);  // 9-cell fragment
  grid.set_sample(50, 30, 50.0f);                                // single speckle
  // A strip on columns 62, 63 joins the main piece through the seam: it must stay.
  for (int j = 0; j < 40; ++j) {
    grid.set_sample(62, j, 50.0f);
    grid.set_sample(63, j, 50.0f);
  }
  const CleaningReport report = clean_grid(grid);
  EXPECT_EQ(report.fragments_removed, 2u);
  EXPECT_EQ(report.fragment_cells_removed, 10u);
  EXPECT_EQ(report.components_kept, 1u);
  EXPECT_EQ(grid.valid_count(), 32u * 40u);
}

TEST(GridCleaning, NeverFillsHoles) {
  RangeGrid grid = smooth_grid();
  for (int j = 30; j < 40; ++j)
    for (int i = 50; i < 70; ++i) grid.invalidate(i, j);
  const std::size_t valid = grid.valid_count();
  clean_grid(grid);
  for (int j = 30; j < 40; ++j)
    for (int i = 50; i < 70; ++i) EXPECT_FALSE(grid.valid(i, j));
  EXPECT_EQ(grid.valid_count(), valid);  // hole edges are not mistaken for spikes
}

TEST(GridCleaning, RejectsImpossibleOptions) {
  RangeGrid grid = smooth_grid(16, 8);
  CleaningOptions o;
  o.spike_threshold_mm = -1.0;
  EXPECT_THROW(clean_grid(grid, o), InvalidInputError);
  o = {};
  o.min_component_cells = 0;
  EXPECT_THROW(clean_grid(grid, o), InvalidInputError);
}

}  // namespace
}  // namespace scanmesh
