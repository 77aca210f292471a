// Cleaning of a grid assembled from laser scans (docs/acquisition.md, "Cleaning"): the steps of
// grid_cleaning.h (spikes, fragments) plus low-confidence (grazing) cells, the turntable surface,
// hair-like noise, and filling of small holes. Each step is switchable and counted. Only hole
// filling adds cells; filled cells get confidence 0, which no measured cell has after the
// low-confidence step, and the grid's metadata records the count.
#pragma once

#include <cstddef>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/core/range_grid.h"

namespace scanmesh {

struct ScanCleaningOptions {
  bool low_confidence = true;
  float min_confidence = 0.1f;  //!< cells below are grazing or weak: removed
  bool platter = true;
  double platter_height_mm = 0.0, platter_margin_mm = 0.6;  //!< rows with h below are removed
  bool hair = true;
  //! A cell farther than this from the median of the predictions of the opposite neighbour pairs
  //! at distances 1 and 2 along 4 directions is hair-like noise (thin strands survive the 3 x 3
  //! spike test because their neighbours are strands too; a strand spoils only the pairs along
  //! its own direction).
  double hair_threshold_mm = 1.5;
  int hair_min_neighbours = 4;  //!< the median needs at least this many pair predictions
  bool spikes_and_fragments = true;
  //! Spike/fragment options; the 3 x 3 median fallback needs 6 neighbours here, because the
  //! rims of scan grids (one row of neighbours at a grazing limit) otherwise lose good cells.
  CleaningOptions spikes = [] {
    CleaningOptions c;
    c.spike_min_neighbours = 6;
    return c;
  }();
  bool fill_holes = true;
  int max_hole_cells = 6;  //!< only holes (4-connected) of at most this many cells are filled
};

struct ScanCleaningReport {
  std::size_t low_confidence_removed = 0, platter_removed = 0, hair_removed = 0;
  CleaningReport spikes;
  std::size_t holes_filled = 0, cells_filled = 0;
  std::size_t valid_before = 0, valid_after = 0;
};

struct HoleFillReport {
  std::size_t holes = 0, cells = 0;
};

//! Fills every hole (4-connected component of invalid cells, phi wrapping) of at most
//! `max_cells` cells that does not touch the first or last row, by a membrane (each cell the
//! mean of its 4-neighbours); filled cells get confidence 0. Throws InvalidInputError for a
//! negative limit.
HoleFillReport fill_small_holes(RangeGrid& grid, int max_cells);

//! Cleans in place, in the order: low confidence, platter, hair, spikes and fragments, holes.
//! Throws InvalidInputError for negative thresholds.
ScanCleaningReport clean_scan_grid(RangeGrid& grid, const ScanCleaningOptions& options = {});

}  // namespace scanmesh
