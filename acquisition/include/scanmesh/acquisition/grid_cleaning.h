// Cleaning of an assembled range grid: spike (outlier) removal and removal of isolated cells
// and tiny fragments. Cleaning only ever invalidates cells: holes stay holes, nothing is filled.
#pragma once

#include <cstddef>

#include "scanmesh/core/range_grid.h"

namespace scanmesh {

struct CleaningOptions {
  //! A cell is a spike if |r - prediction| exceeds
  //! spike_threshold_mm + spike_spread_factor * spread. The prediction is the median of the
  //! means of opposite neighbour pairs (exact on any locally linear surface, however steep);
  //! spread is how much those pair predictions disagree (large at creases and silhouettes).
  double spike_threshold_mm = 2.0;
  double spike_spread_factor = 3.0;
  //! Where fewer than two opposite pairs are complete, the median of the valid 3x3 neighbours
  //! predicts instead, if there are at least this many; fewer means only fragment removal judges.
  int spike_min_neighbours = 3;
  //! Connected pieces (4-neighbourhood, phi wraps) with fewer cells are removed.
  int min_component_cells = 30;
};

struct CleaningReport {
  std::size_t spikes_removed = 0;
  std::size_t fragment_cells_removed = 0;  //!< cells of pieces below min_component_cells
  std::size_t fragments_removed = 0;
  std::size_t components_kept = 0;
  std::size_t valid_before = 0, valid_after = 0;
};

//! Cleans the grid in place. Spike decisions are made on the input (order-independent), then
//! the fragments are removed. Throws InvalidInputError for negative thresholds.
CleaningReport clean_grid(RangeGrid& grid, const CleaningOptions& options = {});

}  // namespace scanmesh
