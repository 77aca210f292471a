// The simulated cylindrical range scanner: rays from a circle of radius R toward the axis at
// every (phi, h), with the defects real scanners have (docs/simulator.md).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "scanmesh/core/range_grid.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh::sim {

struct ScannerConfig {
  //! Largest simulated grid (cells), so that a simulation stays below 1 GB of memory.
  static constexpr long long kMaxSimulatedCells = 1ll << 22;
  int n_phi = 512, n_h = 512;
  double radius_mm = 300.0;  //!< scanner circle R (rays start here)
  double h0_mm = 0.0;        //!< height of row 0
  double dh_mm = 0.45;       //!< row spacing
  double phi0_rad = 0.0;
  // Defects, each switchable. All random choices come from `seed`.
  double noise_sigma_mm = 0.0;  //!< Gaussian range noise
  bool grazing_dropout = true;
  double grazing_limit_deg = 75.0;  //!< drop if angle(ray, normal) exceeds this
  bool occlusion = true;
  double camera_baseline_deg = 20.0;  //!< triangulation camera offset around the axis
  double camera_radius_mm = 300.0;
  bool hair = true;
  double hair_noise_sigma_mm = 1.5;
  double hair_dropout_probability = 0.25;
  double spike_probability = 0.0;  //!< outliers: r off by 5..40 mm
  bool height_band = true;
  double band_min_mm = -1e9, band_max_mm = 1e9;  //!< rows outside measure nothing
  std::uint64_t seed = 1;

  //! Throws InvalidInputError for impossible values (non-positive sizes, sigma < 0, ...).
  void validate() const;
  static ScannerConfig from_yaml_file(const std::filesystem::path& path);
  static ScannerConfig from_yaml_text(const std::string& text, const std::string& source_name);
};

//! Why a cell has no measurement (or None).
enum class DropReason : std::uint8_t { None, NoHit, OutsideBand, Grazing, Occluded, HairSpeckle };

//! Exact truth for one cell: the noise-free hit, its radius and differential geometry.
struct GroundTruthCell {
  bool hit = false;
  double radius = 0.0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  SurfaceGeometry geometry;
  DropReason drop = DropReason::None;
  bool spike = false;  //!< this cell's measurement was replaced by an outlier
};

struct SimulatedScan {
  RangeGrid grid;
  std::vector<GroundTruthCell> truth;  //!< indexed by RangeGrid::index(i, j)
};

//! Called with (rows done, rows total) while scanning; may be empty.
using ProgressFn = std::function<void(int, int)>;

//! Scans the scene. Deterministic: same scene + config (incl. seed) gives identical output,
//! regardless of thread count.
SimulatedScan simulate_scan(const Scene& scene, const ScannerConfig& config,
                            const ProgressFn& progress = {});

//! Scanner defaults used by the demo for the built-in head (configs/scanners/sim-head.yaml).
ScannerConfig builtin_head_scanner();

}  // namespace scanmesh::sim
