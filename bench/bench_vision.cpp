// bench_vision: laser-line extraction frames per second at 1280 x 960 on one core, against a
// straightforward threshold + centre-of-mass extractor written like Horus's, with the accuracy
// of both against the simulator's exact line centres; then the reconstruction time of a
// 400-step session whose frames are cached in memory. Prints a table.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "bench_support.h"
#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/acquisition/line_extraction.h"
#include "scanmesh/acquisition/reconstruction.h"
#include "scanmesh/sim/turntable_camera.h"

using namespace scanmesh;

namespace {

// Like Horus (laser_segmentation.py): red difference, threshold, then per row the centre of
// mass of every pixel above the threshold; no window, no subpixel model, no rejection.
std::vector<LinePeak> horus_like(const Image8& on, const Image8& off, int threshold) {
  std::vector<LinePeak> out;
  for (int y = 0; y < on.height; ++y) {
    const std::uint8_t* a = on.at(0, y);
    const std::uint8_t* b = off.at(0, y);
    double s = 0, sx = 0;
    for (int x = 0; x < on.width; ++x) {
      int d = int(a[3 * x]) - int(b[3 * x]);
      if (d < threshold) continue;
      s += d;
      sx += double(d) * x;
    }
    if (s > 0) out.push_back({y, sx / s, 0.f, 0.f, 1.f, false});
  }
  return out;
}

struct Accuracy {
  double rms = 0;
  int matched = 0, wrong = 0;
};

Accuracy accuracy(const std::vector<LinePeak>& peaks, const std::vector<sim::LinePointTruth>& truth,
                  int height) {
  std::vector<int> count(height, 0);
  std::vector<double> u(height, 0);
  std::vector<char> obj(height, 0);
  for (const auto& t : truth) ++count[t.row], u[t.row] = t.u, obj[t.row] = !t.on_platform;
  Accuracy a;
  double s = 0;
  for (const auto& p : peaks) {
    if (count[p.row] != 1 || !obj[p.row]) continue;
    const double e = p.u - u[p.row];
    if (std::abs(e) > 3) {
      ++a.wrong;
      continue;
    }
    s += e * e;
    ++a.matched;
  }
  a.rms = a.matched ? std::sqrt(s / a.matched) : 0;
  return a;
}

class CachedSteps : public ScanStepSource {
 public:
  CachedSteps(std::vector<ScanStep> frames, std::size_t n) : frames_(std::move(frames)), n_(n) {}
  std::size_t step_count() const override { return n_; }
  int laser_count() const override { return static_cast<int>(frames_[0].laser_on.size()); }
  ScanStep step(std::size_t i) const override {
    ScanStep s = frames_[i % frames_.size()];
    s.index = i;
    s.angle_rad = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n_);
    return s;
  }

 private:
  std::vector<ScanStep> frames_;
  std::size_t n_;
};

}  // namespace

int main() {
  const sim::Scene head = sim::builtin_head_scene();
  const sim::TurntableCamera cam(head, sim::builtin_ciclop_rig());
  const int kFrames = 6;
  std::printf("bench_vision: built-in head, built-in rig 1280 x 960, %d angles x 2 lasers\n",
              kFrames);
  std::vector<ScanStep> steps;
  std::vector<std::vector<sim::LinePointTruth>> truth;
  for (int f = 0; f < kFrames; ++f) {
    ScanStep s;
    s.angle_rad = 2.0 * std::numbers::pi * f / kFrames;
    s.laser_off = cam.render(s.angle_rad, 0u);
    for (int k = 0; k < 2; ++k) {
      s.laser_on.push_back(cam.render(s.angle_rad, 1u << k));
      truth.push_back(cam.laser_line_truth(s.angle_rad, k));
    }
    steps.push_back(std::move(s));
  }
  std::printf("\n%-26s %10s %10s %12s %10s %8s\n", "extractor", "ms/frame", "frames/s", "vs anchor",
              "RMS px", "wrong");
  auto run = [&](const char* name,
                 const std::function<std::vector<LinePeak>(const Image8&, const Image8&)>& fn,
                 double anchor_s) {
    const double t = bench::time_median(5,
                                        [&] {
                                          for (const auto& s : steps)
                                            for (const auto& on : s.laser_on)
                                              (void)fn(on, s.laser_off);
                                        }) /
                     (2.0 * kFrames);
    double ss = 0;
    int n = 0, wrong = 0;
    for (int f = 0; f < kFrames; ++f)
      for (int k = 0; k < 2; ++k) {
        const Accuracy a =
            accuracy(fn(steps[f].laser_on[k], steps[f].laser_off), truth[2 * f + k], 960);
        ss += a.rms * a.rms * a.matched;
        n += a.matched;
        wrong += a.wrong;
      }
    std::printf("%-26s %10.3f %10.1f %11.2fx %10.4f %8d\n", name, 1e3 * t, 1.0 / t,
                anchor_s > 0 ? anchor_s / t : 1.0, std::sqrt(ss / std::max(1, n)), wrong);
    return t;
  };
  const double anchor = run(
      "Horus-like threshold+CoM",
      [](const Image8& on, const Image8& off) { return horus_like(on, off, 25); }, 0.0);
  for (PeakMethod m : {PeakMethod::CenterOfMass, PeakMethod::Gaussian, PeakMethod::BlaisRioux}) {
    LineExtractionOptions o;
    o.method = m;
    const std::string name = std::string("scanmesh ") + peak_method_name(m);
    run(
        name.c_str(),
        [o](const Image8& on, const Image8& off) { return extract_laser_line(on, off, o); },
        anchor);
  }
  std::printf(
      "(goal: >= 600 frames/s = 20x a 30 fps camera; one core, no threads in extraction)\n");

  // Reconstruction of a 400-step session: the frames of the angles above are reused cyclically
  // (rendering 400 full-size head steps takes ~10 min); the work per step is the same.
  Calibration cal;
  const auto& in = cam.rig().intrinsics;
  cal.camera = {1280, 960, in.fx, in.fy, in.cx, in.cy, in.k1, in.k2, in.p1, in.p2, in.k3};
  const Eigen::Isometry3d t = cam.camera_from_rig();
  for (const auto& l : cam.rig().lasers) {
    const Eigen::Vector3d n = t.linear() * l.normal;
    cal.lasers.push_back({l.name, n, n.dot(t * l.position_mm)});
  }
  cal.axis_direction = t.linear() * Eigen::Vector3d::UnitZ();
  cal.axis_origin_mm = t * Eigen::Vector3d::Zero();
  const CachedSteps session(steps, 400);
  ReconstructionStats st;
  const double t0 = bench::now();
  const RangeGrid g = reconstruct_grid(session, cal, {}, &st);
  const double dt = bench::now() - t0;
  std::printf(
      "\nreconstruction of a 400-step, 2-laser session (800 laser frames, frames cached in "
      "memory): %.2f s (%.2f ms/step): %zu peaks, %zu grid cells of 512 x 512\n",
      dt, 1e3 * dt / 400, st.peaks, g.valid_count());
  return 0;
}
