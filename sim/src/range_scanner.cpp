// The simulated cylindrical range scanner and its defects (docs/simulator.md).
#include "scanmesh/sim/range_scanner.h"

#include "scanmesh/core/grid_file.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <numbers>
#include <sstream>

#include "random.h"
#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"
#include "yaml_util.h"

namespace scanmesh::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kOcclusionOffsetMm = 1e-3;  // shadow rays start this far out along the normal
const Rgb8 kBackground{18, 18, 22};

// Purposes of the counter-based random numbers (part of the hash key).
enum Purpose : std::uint64_t { kNoise = 1, kHairDrop, kHairNoise, kSpike, kSpikeSize, kSpikeSign };

void check(bool ok, const std::string& problem) {
  if (!ok) throw InvalidInputError("scanner config: " + problem);
}

}  // namespace

void ScannerConfig::validate() const {
  check(n_phi >= 2 && n_phi <= 8192, "n_phi must be in [2, 8192], got " + std::to_string(n_phi));
  check(n_h >= 2 && n_h <= 8192, "n_h must be in [2, 8192], got " + std::to_string(n_h));
  // The simulation holds ~160 bytes per cell while it renders: 4 M cells (2048 x 2048) stay
  // below 1 GB, the 64 M a grid file may hold would take over 10 GB.
  check(static_cast<long long>(n_phi) * n_h <= kMaxSimulatedCells,
        "n_phi x n_h must be at most " + std::to_string(kMaxSimulatedCells) +
            " cells (e.g. 2048 x 2048)");
  check(std::isfinite(radius_mm) && radius_mm >= kMinGridLengthMm,
        "radius_mm must be at least 1e-9 mm");
  check(std::isfinite(h0_mm), "h0_mm must be finite");
  check(std::isfinite(dh_mm) && dh_mm >= kMinGridLengthMm, "dh_mm must be at least 1e-9 mm");
  check(radius_mm <= kMaxGridLengthMm && std::abs(h0_mm) <= kMaxGridLengthMm &&
            std::abs(h0_mm + dh_mm * n_h) <= kMaxGridLengthMm,
        "radius_mm and the rows' heights (h0_mm + n_h * dh_mm) must stay within 1e6 mm");
  check(std::isfinite(phi0_rad), "phi0_rad must be finite");
  check(std::isfinite(noise_sigma_mm) && noise_sigma_mm >= 0.0, "noise_sigma_mm must be >= 0");
  check(std::isfinite(grazing_limit_deg) && grazing_limit_deg > 0.0 && grazing_limit_deg <= 90.0,
        "grazing_limit_deg must be in (0, 90]");
  check(
      std::isfinite(camera_baseline_deg) && camera_baseline_deg > 0.0 && camera_baseline_deg < 90.0,
      "camera_baseline_deg must be in (0, 90)");
  check(std::isfinite(camera_radius_mm) && camera_radius_mm > 0.0,
        "camera_radius_mm must be positive");
  check(std::isfinite(hair_noise_sigma_mm) && hair_noise_sigma_mm >= 0.0,
        "hair_noise_sigma_mm must be >= 0");
  check(hair_dropout_probability >= 0.0 && hair_dropout_probability <= 1.0,
        "hair_dropout_probability must be in [0, 1]");
  check(spike_probability >= 0.0 && spike_probability <= 1.0,
        "spike_probability must be in [0, 1]");
  check(!std::isnan(band_min_mm) && !std::isnan(band_max_mm) && band_min_mm < band_max_mm,
        "band_min_mm must be below band_max_mm");
}

ScannerConfig ScannerConfig::from_yaml_text(const std::string& text,
                                            const std::string& source_name) {
  const detail::YamlReader rd(source_name);
  const YAML::Node root = rd.parse(text);
  if (!root.IsMap()) rd.fail(root, "a scanner file must be a mapping of ScannerConfig fields");
  ScannerConfig c;
  for (const auto& kv : root) {
    const std::string key = rd.as<std::string>(kv.first, "key");
    const YAML::Node& v = kv.second;
    auto num = [&](double& field) { field = rd.number(v, key); };
    auto flag = [&](bool& field) { field = rd.as<bool>(v, key); };
    auto integer = [&](int& field) { field = rd.as<int>(v, key); };
    if (key == "n_phi")
      integer(c.n_phi);
    else if (key == "n_h")
      integer(c.n_h);
    else if (key == "radius_mm")
      num(c.radius_mm);
    else if (key == "h0_mm")
      num(c.h0_mm);
    else if (key == "dh_mm")
      num(c.dh_mm);
    else if (key == "phi0_rad")
      num(c.phi0_rad);
    else if (key == "noise_sigma_mm")
      num(c.noise_sigma_mm);
    else if (key == "grazing_dropout")
      flag(c.grazing_dropout);
    else if (key == "grazing_limit_deg")
      num(c.grazing_limit_deg);
    else if (key == "occlusion")
      flag(c.occlusion);
    else if (key == "camera_baseline_deg")
      num(c.camera_baseline_deg);
    else if (key == "camera_radius_mm")
      num(c.camera_radius_mm);
    else if (key == "hair")
      flag(c.hair);
    else if (key == "hair_noise_sigma_mm")
      num(c.hair_noise_sigma_mm);
    else if (key == "hair_dropout_probability")
      num(c.hair_dropout_probability);
    else if (key == "spike_probability")
      num(c.spike_probability);
    else if (key == "height_band")
      flag(c.height_band);
    else if (key == "band_min_mm")
      num(c.band_min_mm);
    else if (key == "band_max_mm")
      num(c.band_max_mm);
    else if (key == "seed")
      c.seed = rd.as<std::uint64_t>(v, key);
    else
      rd.fail(kv.first, "unknown scanner key '" + key + "'");
  }
  validate_parsed_config(c, source_name);
  return c;
}

ScannerConfig ScannerConfig::from_yaml_file(const std::filesystem::path& path) {
  return from_yaml_text(read_config_text(path), path.string());
}

ScannerConfig builtin_head_scanner() {
  // Keep in step with configs/scanners/sim-head.yaml.
  ScannerConfig c;
  c.n_phi = 512;
  c.n_h = 512;
  c.radius_mm = 300.0;
  c.h0_mm = 0.0;
  c.dh_mm = 0.45;  // rows cover z in [0, 229.95] mm
  c.phi0_rad = 0.0;
  c.noise_sigma_mm = 0.1;
  c.grazing_dropout = true;
  c.grazing_limit_deg = 75.0;
  c.occlusion = true;
  c.camera_baseline_deg = 20.0;
  c.camera_radius_mm = 300.0;
  c.hair = true;
  c.hair_noise_sigma_mm = 1.5;
  c.hair_dropout_probability = 0.25;
  c.spike_probability = 0.0005;
  c.height_band = true;
  c.band_min_mm = 0.0;
  c.band_max_mm = 212.0;  // the crown (top ~224 mm) is outside the band: a hole to fill
  c.seed = 1;
  return c;
}

namespace {

// One cell: exact hit, then the defects in a fixed order (docs/simulator.md, "Defects").
void scan_cell(const Scene& scene, const ScannerConfig& c, int i, int j, double phi, double h,
               RangeGrid& grid, GroundTruthCell& truth) {
  const Eigen::Vector3d dir(-std::cos(phi), -std::sin(phi), 0.0);
  const Eigen::Vector3d origin(c.radius_mm * std::cos(phi), c.radius_mm * std::sin(phi), h);
  const auto hit = scene.intersect(origin, dir, 0.0, c.radius_mm);
  if (!hit) {
    truth.drop = DropReason::NoHit;
    grid.set_color(i, j, kBackground);
    return;
  }
  truth.hit = true;
  truth.point = hit->point;
  truth.radius = c.radius_mm - hit->t;
  truth.geometry = scene.geometry(*hit);
  const Eigen::Vector3d& n = truth.geometry.normal;
  if (c.height_band && (h < c.band_min_mm || h > c.band_max_mm)) {
    // Outside the scanner's travel nothing is measured, colour included.
    truth.drop = DropReason::OutsideBand;
    grid.set_color(i, j, kBackground);
    return;
  }
  grid.set_color(i, j, scene.color_at(hit->point));
  const double cos_inc = std::clamp(-dir.dot(n), -1.0, 1.0);
  if (c.grazing_dropout && std::acos(cos_inc) > c.grazing_limit_deg * kDeg) {
    truth.drop = DropReason::Grazing;
    return;
  }
  if (c.occlusion) {
    const double cam_phi = phi + c.camera_baseline_deg * kDeg;
    const Eigen::Vector3d cam(c.camera_radius_mm * std::cos(cam_phi),
                              c.camera_radius_mm * std::sin(cam_phi), hit->point.z());
    const Eigen::Vector3d start = hit->point + kOcclusionOffsetMm * n;
    const Eigen::Vector3d to_cam = cam - start;
    const double dist = to_cam.norm();
    const bool faces = n.dot(cam - hit->point) > 0.0;
    if (!faces || scene.intersect(start, to_cam / dist, 0.0, dist)) {
      truth.drop = DropReason::Occluded;
      return;
    }
  }
  const auto ui = static_cast<std::uint64_t>(i), uj = static_cast<std::uint64_t>(j);
  double r = truth.radius;
  double confidence = std::max(cos_inc, 0.0);
  if (c.hair && scene.in_hair_zone(hit->point)) {
    const double u = detail::to_unit(detail::hash_key(c.seed, ui, uj, kHairDrop));
    if (u < c.hair_dropout_probability) {
      truth.drop = DropReason::HairSpeckle;
      return;
    }
    r += c.hair_noise_sigma_mm * detail::gaussian(detail::hash_key(c.seed, ui, uj, kHairNoise));
    confidence *= 0.3;
  }
  if (c.noise_sigma_mm > 0.0)
    r += c.noise_sigma_mm * detail::gaussian(detail::hash_key(c.seed, ui, uj, kNoise));
  if (c.spike_probability > 0.0 &&
      detail::to_unit(detail::hash_key(c.seed, ui, uj, kSpike)) < c.spike_probability) {
    const double size = 5.0 + 35.0 * detail::to_unit(detail::hash_key(c.seed, ui, uj, kSpikeSize));
    const bool up = detail::to_unit(detail::hash_key(c.seed, ui, uj, kSpikeSign)) < 0.5;
    r += up ? size : -size;
    truth.spike = true;
  }
  if (!(r > 0.0) || !std::isfinite(r)) {  // an outlier through the axis: nothing measurable
    truth.drop = DropReason::NoHit;
    return;
  }
  grid.set_sample(i, j, static_cast<float>(r), static_cast<float>(confidence));
}

}  // namespace

SimulatedScan simulate_scan(const Scene& scene, const ScannerConfig& config,
                            const ProgressFn& progress) {
  config.validate();
  SimulatedScan out{
      RangeGrid(config.n_phi, config.n_h, config.phi0_rad, config.h0_mm, config.dh_mm), {}};
  RangeGrid& grid = out.grid;
  out.truth.resize(grid.cell_count());
  const int n_h = config.n_h;
  int rows_done = 0;
  std::exception_ptr error;
  std::atomic<bool> failed{false};
#pragma omp parallel for schedule(dynamic, 1)
  for (int j = 0; j < n_h; ++j) {
    if (failed.load()) continue;
    try {
      const double h = grid.h(j);
      for (int i = 0; i < config.n_phi; ++i)
        scan_cell(scene, config, i, j, grid.phi(i), h, grid, out.truth[grid.index(i, j)]);
#pragma omp critical(scanmesh_sim_progress)
      {
        ++rows_done;
        if (progress && !failed) progress(rows_done, n_h);
      }
    } catch (...) {
#pragma omp critical(scanmesh_sim_error)
      {
        if (!error) error = std::current_exception();
      }
      failed.store(true);
    }
  }
  if (error) std::rethrow_exception(error);

  auto& md = grid.metadata;
  md["source"] = "sim";
  md["scene"] = scene.name;
  md["seed"] = std::to_string(config.seed);
  md["scanner_radius_mm"] = format_exact_number(config.radius_mm);
  md["noise_sigma_mm"] = format_exact_number(config.noise_sigma_mm);
  md["grazing_dropout"] = config.grazing_dropout ? "true" : "false";
  md["grazing_limit_deg"] = format_exact_number(config.grazing_limit_deg);
  md["occlusion"] = config.occlusion ? "true" : "false";
  md["camera_baseline_deg"] = format_exact_number(config.camera_baseline_deg);
  md["camera_radius_mm"] = format_exact_number(config.camera_radius_mm);
  md["hair"] = config.hair ? "true" : "false";
  md["hair_noise_sigma_mm"] = format_exact_number(config.hair_noise_sigma_mm);
  md["hair_dropout_probability"] = format_exact_number(config.hair_dropout_probability);
  md["spike_probability"] = format_exact_number(config.spike_probability);
  md["height_band"] = config.height_band ? "true" : "false";
  md["band_min_mm"] = format_exact_number(config.band_min_mm);
  md["band_max_mm"] = format_exact_number(config.band_max_mm);
  return out;
}

}  // namespace scanmesh::sim
