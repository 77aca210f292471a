// Simulated scans with exact ground truth for the reconstruction tests.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh::test {

inline sim::ScannerConfig clean_scanner(int n_phi, int n_h, double h0, double dh,
                                        double noise = 0.0) {
  sim::ScannerConfig c;
  c.n_phi = n_phi;
  c.n_h = n_h;
  c.h0_mm = h0;
  c.dh_mm = dh;
  c.noise_sigma_mm = noise;
  c.hair = false;
  c.height_band = false;
  c.spike_probability = 0.0;
  c.occlusion = false;
  return c;
}

inline sim::SimulatedScan scan_yaml(const std::string& objects, const sim::ScannerConfig& c) {
  return sim::simulate_scan(sim::Scene::from_yaml_text("name: t\nobjects:\n" + objects, "test"), c);
}

// Sphere r = 80 centred at z = 100; 512 x 512 rows over z in [20, 180].
inline sim::SimulatedScan sphere_scan(double noise = 0.0) {
  return scan_yaml("  - {type: sphere, center: [0, 0, 100], radius: 80}\n",
                   clean_scanner(512, 512, 20.0, 160.0 / 511, noise));
}

inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * (v.size() - 1));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

//! True if every cell within `margin` cells of (i, j) is valid ("away from holes").
inline bool away_from_holes(const RangeGrid& g, int i, int j, int margin) {
  for (int dj = -margin; dj <= margin; ++dj) {
    const int jj = j + dj;
    if (jj < 0 || jj >= g.n_h()) return false;
    for (int di = -margin; di <= margin; ++di)
      if (!g.valid(g.wrap_phi(i + di), jj)) return false;
  }
  return true;
}

}  // namespace scanmesh::test
