// Triangulation and grid assembly (docs/acquisition.md).
#include "scanmesh/acquisition/reconstruction.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "scanmesh/core/errors.h"

namespace scanmesh {

void triangulate_peaks(const Calibration& cal, int laser, double angle,
                       const std::vector<LinePeak>& peaks, const Image8* off,
                       std::vector<TriangulatedPoint>& out) {
  if (laser < 0 || laser >= static_cast<int>(cal.lasers.size()))
    throw InvalidInputError("triangulation: the calibration has no laser " + std::to_string(laser));
  const LaserPlane& plane = cal.lasers[laser];
  const Eigen::Isometry3d rig = cal.rig_from_camera();
  const Eigen::Matrix3d back = Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitZ()).matrix();
  const Eigen::Matrix3d to_object = back * rig.linear();
  const Eigen::Vector3d t_object = back * rig.translation();
  for (const LinePeak& p : peaks) {
    const Eigen::Vector3d ray = cal.camera.ray(p.u, p.row);
    const double den = plane.normal.dot(ray);
    // The depth error per pixel grows as 1 / |cos| of the ray-to-sheet-normal angle.
    if (std::abs(den) < 0.05) continue;
    const double t = plane.distance_mm / den;
    if (!(t > 0)) continue;
    TriangulatedPoint q;
    q.p = to_object * (t * ray) + t_object;
    q.confidence = p.confidence * static_cast<float>(std::min(1.0, std::abs(den) / 0.5));
    q.laser = laser;
    if (off && off->width > 0) {
      const int x = std::clamp(static_cast<int>(std::lround(p.u)), 0, off->width - 1);
      const int y = std::clamp(p.row, 0, off->height - 1);
      q.color = off->channels >= 3 ? off->rgb(x, y)
                                   : Rgb8{off->at(x, y)[0], off->at(x, y)[0], off->at(x, y)[0]};
    } else {
      q.color = {128, 128, 128};
    }
    out.push_back(q);
  }
}

RangeGrid assemble_grid(const std::vector<TriangulatedPoint>& points, const GridAssemblyOptions& o,
                        GridAssemblyStats* stats) {
  if (o.n_phi < 2 || o.n_h < 2 || !(o.dh > 0) || !std::isfinite(o.h0) || !std::isfinite(o.phi0))
    throw InvalidInputError("grid assembly: impossible grid size or spacing");
  if (!(o.layer_tolerance_mm > 0) || !(o.min_weight > 0) || o.platter_margin_mm < 0)
    throw InvalidInputError("grid assembly: tolerances must be positive");
  RangeGrid grid(o.n_phi, o.n_h, o.phi0, o.h0, o.dh);
  const double dphi = grid.dphi();
  GridAssemblyStats st;
  st.points = points.size();
  struct Local {
    double phi, h, r;
    float w;
    Rgb8 c;
  };
  std::vector<Local> pts;
  std::vector<std::uint32_t> cell_of;
  pts.reserve(points.size());
  for (const auto& p : points) {
    if (p.confidence < o.min_confidence) {
      ++st.weak_points;
      continue;
    }
    if (o.platter_margin_mm > 0 && p.p.z() < o.platter_margin_mm) {
      ++st.platter_points;
      continue;
    }
    const double r = std::hypot(p.p.x(), p.p.y());
    const double h = p.p.z();
    const double fj = (h - o.h0) / o.dh;
    if (!(r >= o.min_radius_mm) || fj < -1.0 || fj > o.n_h) {
      ++st.outside_points;
      continue;
    }
    const double phi = std::atan2(p.p.y(), p.p.x());
    pts.push_back({phi, h, r, p.confidence, p.color});
  }
  st.used = pts.size();
  // Bucket by nearest cell (counting sort).
  const std::size_t ncell = grid.cell_count();
  std::vector<std::uint32_t> start(ncell + 1, 0), order(pts.size());
  std::vector<std::uint32_t> bucket(pts.size());
  for (std::size_t k = 0; k < pts.size(); ++k) {
    double fi = (pts[k].phi - o.phi0) / dphi;
    int i = grid.wrap_phi(static_cast<int>(std::floor(fi + 0.5)));
    int j = std::clamp(static_cast<int>(std::floor((pts[k].h - o.h0) / o.dh + 0.5)), 0, o.n_h - 1);
    bucket[k] = static_cast<std::uint32_t>(grid.index(i, j));
    ++start[bucket[k] + 1];
  }
  for (std::size_t c = 0; c < ncell; ++c) start[c + 1] += start[c];
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < pts.size(); ++k)
      order[fill[bucket[k]]++] = static_cast<std::uint32_t>(k);
  }
  std::vector<std::uint32_t> near;
  for (int j = 0; j < o.n_h; ++j) {
    for (int i = 0; i < o.n_phi; ++i) {
      near.clear();
      for (int dj = -1; dj <= 1; ++dj) {
        const int jj = j + dj;
        if (jj < 0 || jj >= o.n_h) continue;
        for (int di = -1; di <= 1; ++di) {
          const std::size_t c = grid.index(grid.wrap_phi(i + di), jj);
          for (std::uint32_t q = start[c]; q < start[c + 1]; ++q) near.push_back(order[q]);
        }
      }
      if (near.empty()) continue;
      const double phi_c = grid.phi(i), h_c = grid.h(j);
      auto offsets = [&](const Local& p, double* x, double* y) {
        *x = std::remainder(p.phi - phi_c, 2.0 * std::numbers::pi) / dphi;
        *y = (p.h - h_c) / o.dh;
      };
      double rmax = -1;
      for (std::uint32_t k : near) {
        double x, y;
        offsets(pts[k], &x, &y);
        if (std::abs(x) < 1 && std::abs(y) < 1) rmax = std::max(rmax, pts[k].r);
      }
      if (rmax < 0) continue;
      Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
      Eigen::Vector3d b = Eigen::Vector3d::Zero();
      double wsum = 0, cw = 0, col[3] = {0, 0, 0}, mx = 0, my = 0;
      for (std::uint32_t k : near) {
        const Local& p = pts[k];
        if (p.r < rmax - o.layer_tolerance_mm) continue;
        double x, y;
        offsets(p, &x, &y);
        const double tent = std::max(0.0, 1.0 - std::abs(x)) * std::max(0.0, 1.0 - std::abs(y));
        if (tent <= 0) continue;
        const double w = tent * p.w;
        const Eigen::Vector3d v(1.0, x, y);
        a += w * v * v.transpose();
        b += w * p.r * v;
        wsum += w;
        cw += w * p.w;
        col[0] += w * p.c.r;
        col[1] += w * p.c.g;
        col[2] += w * p.c.b;
        mx += w * x;
        my += w * y;
      }
      if (wsum < o.min_weight) continue;
      mx /= wsum;
      my /= wsum;
      // The support must surround the cell centre, or the fit would extrapolate into a hole.
      if (std::abs(mx) > 0.5 || std::abs(my) > 0.5) continue;
      double r = b[0] / wsum;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(a / wsum);
      if (es.eigenvalues().minCoeff() > 0.02) {
        const Eigen::Vector3d c = a.ldlt().solve(b);
        if (std::isfinite(c[0]) && std::abs(c[0] - r) < o.layer_tolerance_mm) r = c[0];
      }
      if (!(r > 0) || !std::isfinite(r)) continue;
      const float conf = static_cast<float>(std::clamp(cw / wsum * std::min(1.0, wsum), 0.0, 1.0));
      grid.set_sample(i, j, static_cast<float>(r), conf);
      grid.set_color(i, j,
                     {static_cast<std::uint8_t>(std::lround(col[0] / wsum)),
                      static_cast<std::uint8_t>(std::lround(col[1] / wsum)),
                      static_cast<std::uint8_t>(std::lround(col[2] / wsum))});
      ++st.cells;
    }
  }
  if (stats) *stats = st;
  return grid;
}

std::vector<TriangulatedPoint> triangulate_scan(
    const ScanStepSource& source, const Calibration& cal, const LineExtractionOptions& lo,
    ReconstructionStats* stats, const std::function<void(std::size_t, std::size_t)>& progress) {
  if (source.laser_count() > static_cast<int>(cal.lasers.size()))
    throw InvalidInputError("reconstruction: the scan has " + std::to_string(source.laser_count()) +
                            " lasers but the calibration only " +
                            std::to_string(cal.lasers.size()));
  ReconstructionStats st;
  std::vector<TriangulatedPoint> points;
  const std::size_t n = source.step_count();
  for (std::size_t s = 0; s < n; ++s) {
    const ScanStep step = source.step(s);
    // The intrinsics hold for the image size they were calibrated at: on frames of another size
    // every ray would be wrong, silently.
    const int fw = step.laser_off.width, fh = step.laser_off.height;
    if (cal.camera.width > 0 && (fw != cal.camera.width || fh != cal.camera.height))
      throw InvalidInputError("the calibration is for " + std::to_string(cal.camera.width) + "x" +
                              std::to_string(cal.camera.height) + " images, step " +
                              std::to_string(s) + " has " + std::to_string(fw) + "x" +
                              std::to_string(fh) + ": calibrate at the scan's frame size");
    for (std::size_t k = 0; k < step.laser_on.size(); ++k) {
      LineExtractionStats ls;
      const auto peaks = extract_laser_line(step.laser_on[k], step.laser_off, lo, &ls);
      st.line.rows += ls.rows;
      st.line.peaks += ls.peaks;
      st.line.rejected_weak += ls.rejected_weak;
      st.line.rejected_wide += ls.rejected_wide;
      st.line.rejected_secondary += ls.rejected_secondary;
      st.line.rejected_ambient += ls.rejected_ambient;
      st.line.saturated += ls.saturated;
      st.peaks += peaks.size();
      triangulate_peaks(cal, static_cast<int>(k), step.angle_rad, peaks, &step.laser_off, points);
    }
    ++st.steps;
    if (progress) progress(s + 1, n);
  }
  if (stats) *stats = st;
  return points;
}

RangeGrid reconstruct_grid(const ScanStepSource& source, const Calibration& cal,
                           const ReconstructionOptions& o, ReconstructionStats* stats,
                           const std::function<void(std::size_t, std::size_t)>& progress) {
  ReconstructionStats st;
  const std::vector<TriangulatedPoint> points =
      triangulate_scan(source, cal, o.line, &st, progress);
  const std::size_t n = source.step_count();
  RangeGrid grid = assemble_grid(points, o.grid, &st.grid);
  grid.metadata["source"] = "laser scan";
  grid.metadata["steps"] = std::to_string(n);
  grid.metadata["peak_method"] = peak_method_name(o.line.method);
  if (stats) *stats = st;
  return grid;
}

}  // namespace scanmesh
