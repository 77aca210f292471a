// Cleaning of simulated scans: the simulator knows which cells are spikes.
#include <gtest/gtest.h>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh {
namespace {

TEST(GridCleaningSimulated, RemovesSimulatedSpikesOnASphereAndKeepsGoodCells) {
  const sim::Scene scene = sim::Scene::from_yaml_text(
      "name: sphere\nobjects:\n  - {type: sphere, center: [0, 0, 100], radius: 80}\n",
      "test sphere");
  sim::ScannerConfig c;
  c.n_phi = 256;
  c.n_h = 128;
  c.h0_mm = 40.0;
  c.dh_mm = 1.0;
  c.noise_sigma_mm = 0.1;
  c.spike_probability = 0.01;
  c.hair = false;
  c.height_band = false;
  const auto scan = sim::simulate_scan(scene, c);
  RangeGrid grid = scan.grid;
  const CleaningReport report = clean_grid(grid);
  std::size_t spikes = 0, spikes_left = 0, good_removed = 0, good = 0;
  for (std::size_t k = 0; k < grid.cell_count(); ++k) {
    if (!scan.grid.validity()[k]) continue;
    if (scan.truth[k].spike) {
      ++spikes;
      spikes_left += grid.validity()[k];
    } else {
      ++good;
      good_removed += !grid.validity()[k];
    }
  }
  ASSERT_GT(spikes, 100u);
  EXPECT_EQ(spikes_left, 0u);
  EXPECT_LT(static_cast<double>(good_removed) / good, 0.002) << good_removed << " of " << good;
  EXPECT_EQ(report.valid_before - report.valid_after, spikes + good_removed);
}

}  // namespace
}  // namespace scanmesh
