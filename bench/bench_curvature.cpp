// Curvature benchmark: normals and principal curvatures of the 512 x 512 head, by scanmesh's
// analytic and quadric methods and by PCL (NormalEstimationOMP + PrincipalCurvaturesEstimation,
// the anchor) on the same points in the same run. Prints median times, the time ratios and the
// median errors of all three against the simulator's exact curvature.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "anchors_pcl.h"
#include "bench_support.h"
#include "scanmesh/reconstruction/surface_fields.h"
#include "scanmesh/sim/range_scanner.h"

namespace {

using namespace scanmesh;

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

using bench::time_median;

bool away_from_holes(const RangeGrid& g, int i, int j, int margin) {
  for (int dj = -margin; dj <= margin; ++dj) {
    if (j + dj < 0 || j + dj >= g.n_h()) return false;
    for (int di = -margin; di <= margin; ++di)
      if (!g.valid(g.wrap_phi(i + di), j + dj)) return false;
  }
  return true;
}

// Per-cell estimate in a common form: unsigned principal curvature magnitudes (PCL's are
// unsigned) and an unoriented normal.
struct Estimate {
  bool ok = false;
  double kmax = 0, kmin = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

struct Errors {
  double kmax_rel = NAN, kmin_abs = NAN, normal_deg = NAN;
  std::size_t cells = 0;
};

Errors compare(const sim::SimulatedScan& scan, const std::vector<Estimate>& est,
               const std::vector<std::uint8_t>& common) {
  std::vector<double> kmax, kmin, ang;
  for (std::size_t k = 0; k < est.size(); ++k) {
    if (!common[k]) continue;
    const auto& t = scan.truth[k].geometry;
    const double tmax = std::max(std::abs(t.k1), std::abs(t.k2));
    const double tmin = std::min(std::abs(t.k1), std::abs(t.k2));
    kmax.push_back(std::abs(est[k].kmax - tmax) / tmax);
    kmin.push_back(std::abs(est[k].kmin - tmin));
    ang.push_back(std::acos(std::min(1.0, std::abs(est[k].normal.dot(t.normal)))) * 180.0 / M_PI);
  }
  return {median(kmax), median(kmin), median(ang), kmax.size()};
}

std::vector<Estimate> from_fields(const SurfaceFields& f) {
  std::vector<Estimate> e(f.size());
  for (std::size_t k = 0; k < f.size(); ++k) {
    if (!f.defined[k]) continue;
    e[k] = {true, std::max(std::abs(f.k1[k]), std::abs(f.k2[k])),
            std::min(std::abs(f.k1[k]), std::abs(f.k2[k])), f.normal[k].cast<double>()};
  }
  return e;
}

std::vector<Estimate> run_pcl(const RangeGrid& g, double radius) {
  std::vector<Eigen::Vector3d> pts;
  std::vector<std::size_t> cell_of_point;
  for (std::size_t k = 0; k < g.cell_count(); ++k) {
    if (!g.validity()[k]) continue;
    pts.push_back(g.cartesian(static_cast<int>(k % g.n_phi()), static_cast<int>(k / g.n_phi())));
    cell_of_point.push_back(k);
  }
  const auto pcl = bench::pcl_principal_curvatures(pts, radius, 2);
  std::vector<Estimate> e(g.cell_count());
  for (std::size_t p = 0; p < pts.size(); ++p)
    if (pcl[p].ok) e[cell_of_point[p]] = {true, pcl[p].pc1, pcl[p].pc2, pcl[p].normal};
  return e;
}

void run_case(const char* name, double sigma, double radius) {
  sim::ScannerConfig c = sim::builtin_head_scanner();
  c.noise_sigma_mm = sigma;
  c.spike_probability = 0.0;
  c.hair = false;
  const auto scan = sim::simulate_scan(sim::builtin_head_scene(), c);
  const RangeGrid& g = scan.grid;

  SurfaceFields analytic, grid_quadric, quadric;
  std::vector<Estimate> pcl_est;
  const double t_analytic = time_median(5, [&] { analytic = compute_fields_analytic(g); });
  const double t_grid =
      time_median(3, [&] { grid_quadric = compute_fields_grid_quadric(g, {.radius_mm = radius}); });
  const double t_quadric =
      time_median(3, [&] { quadric = compute_fields_quadric(g, {.radius_mm = radius}); });
  const double t_pcl = time_median(3, [&] { pcl_est = run_pcl(g, radius); });

  const auto a = from_fields(analytic), gq = from_fields(grid_quadric), q = from_fields(quadric);
  // Compare all methods on the same cells: defined by every method and away from holes.
  std::vector<std::uint8_t> common(g.cell_count(), 0);
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i) {
      const std::size_t k = g.index(i, j);
      const auto& t = scan.truth[k].geometry;
      common[k] = a[k].ok && gq[k].ok && q[k].ok && pcl_est[k].ok && away_from_holes(g, i, j, 3) &&
                  std::max(std::abs(t.k1), std::abs(t.k2)) > 1e-3;
    }
  std::printf("\n== %s (noise sigma %.2f mm, neighbourhood radius %.1f mm)\n", name, sigma, radius);
  std::printf("%-28s %10s %14s %16s %14s %9s\n", "method", "time [s]", "|kmax| rel err",
              "|kmin| err[1/mm]", "normal [deg]", "cells");
  const auto row = [&](const char* label, double seconds, const std::vector<Estimate>& e) {
    const Errors err = compare(scan, e, common);
    std::printf("%-28s %10.3f %14.4f %16.5f %14.3f %9zu\n", label, seconds, err.kmax_rel,
                err.kmin_abs, err.normal_deg, err.cells);
  };
  row("scanmesh analytic", t_analytic, a);
  row("scanmesh grid-quadric", t_grid, gq);
  row("scanmesh quadric", t_quadric, q);
  row("PCL normals+principal curv.", t_pcl, pcl_est);
  std::printf(
      "time ratio PCL / analytic: %.1fx   PCL / grid-quadric: %.1fx   PCL / quadric: %.1fx\n",
      t_pcl / t_analytic, t_pcl / t_grid, t_pcl / t_quadric);
}

}  // namespace

int main() {
  std::printf("scanmesh curvature benchmark: 512 x 512 built-in head, 2 threads where parallel\n");
  run_case("exact head", 0.0, 6.0);
  run_case("noisy head", 0.1, 6.0);
  return 0;
}
