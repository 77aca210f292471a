// From laser peaks to a RangeGrid (docs/acquisition.md, "Triangulation" and "Grid assembly"):
// each peak's pixel ray meets its calibrated laser plane; the point is taken to the rig frame and
// turned back by the step angle into the object frame; the points of all steps and lasers are
// resampled onto the cylindrical grid by a weighted local plane fit per cell.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <vector>

#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/acquisition/line_extraction.h"
#include "scanmesh/acquisition/scan_step.h"
#include "scanmesh/core/range_grid.h"

namespace scanmesh {

struct TriangulatedPoint {
  Eigen::Vector3d p;     //!< object frame (mm)
  float confidence = 0;  //!< peak confidence x ray-to-sheet angle factor
  Rgb8 color;            //!< laser-off frame at the peak
  int laser = 0;
};

//! Triangulates one laser's peaks of one step (turntable angle `angle_rad`). `laser_off` gives
//! the colour (may be null: grey). Peaks whose ray is nearly parallel to the sheet are skipped.
void triangulate_peaks(const Calibration& calibration, int laser, double angle_rad,
                       const std::vector<LinePeak>& peaks, const Image8* laser_off,
                       std::vector<TriangulatedPoint>& out);

struct GridAssemblyOptions {
  int n_phi = RangeGrid::kDefaultSize, n_h = RangeGrid::kDefaultSize;
  double phi0 = 0.0, h0 = 0.0, dh = 0.45;
  //! Points closer than this to the platter plane (z = 0) or below it are the turntable
  //! surface, not the object (0 keeps them).
  double platter_margin_mm = 0.6;
  double min_radius_mm = 0.5;
  //! Points more than this inside the outermost point near a cell are hidden surfaces.
  double layer_tolerance_mm = 2.0;
  float min_confidence = 0.05f;  //!< weaker points are ignored
  double min_weight = 0.25;      //!< total tent weight a cell needs to be measured
};

struct GridAssemblyStats {
  std::size_t points = 0, used = 0, platter_points = 0, weak_points = 0, outside_points = 0;
  std::size_t cells = 0;
};

//! Resamples points onto a grid: per cell, a weighted plane r = a + b dphi + c dh through the
//! points within one cell spacing (tent weights x confidence), evaluated at the cell centre
//! (the weighted mean where the fit is ill-conditioned). Cells without support stay holes.
RangeGrid assemble_grid(const std::vector<TriangulatedPoint>& points,
                        const GridAssemblyOptions& options = {},
                        GridAssemblyStats* stats = nullptr);

struct ReconstructionOptions {
  LineExtractionOptions line;
  GridAssemblyOptions grid;
};

struct ReconstructionStats {
  std::size_t steps = 0, peaks = 0;
  LineExtractionStats line;
  GridAssemblyStats grid;
};

//! Extraction and triangulation of every step and laser of a source (the first half of
//! reconstruct_grid): the object-frame points, before grid assembly. Fills stats' steps, peaks
//! and line counts. Throws InvalidInputError when the source's laser count exceeds the
//! calibration's.
std::vector<TriangulatedPoint> triangulate_scan(
    const ScanStepSource& source, const Calibration& calibration,
    const LineExtractionOptions& options = {}, ReconstructionStats* stats = nullptr,
    const std::function<void(std::size_t, std::size_t)>& progress = {});

//! The whole path for a step source: extract, triangulate, assemble. `progress(done, total)`
//! may be empty. Throws InvalidInputError when the source's laser count exceeds the
//! calibration's.
RangeGrid reconstruct_grid(const ScanStepSource& source, const Calibration& calibration,
                           const ReconstructionOptions& options = {},
                           ReconstructionStats* stats = nullptr,
                           const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace scanmesh
