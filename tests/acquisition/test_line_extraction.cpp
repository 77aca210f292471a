// Laser-line extraction against synthetic profiles and against the simulated camera's exact
// line centres (issue 9 acceptance: subpixel RMS < 0.1 px, no peaks from background or ambient).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "scanmesh/acquisition/line_extraction.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/turntable_camera.h"

namespace scanmesh {
namespace {

// A frame pair whose every row holds a Gaussian line of sigma `s` at `centre(y)`.
template <typename Centre>
std::pair<Image8, Image8> synthetic(int w, int h, double amp, double s, Centre centre,
                                    double pedestal = 40.0) {
  Image8 on(w, h, 3), off(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double c = centre(y);
      const double v = pedestal + amp * std::exp(-0.5 * (x - c) * (x - c) / (s * s));
      on.at(x, y)[0] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
      off.at(x, y)[0] = static_cast<std::uint8_t>(pedestal);
    }
  return {on, off};
}

TEST(LineExtraction, SyntheticGaussianAllMethods) {
  auto centre = [](int y) { return 20.0 + 0.137 * y; };
  const auto [on, off] = synthetic(64, 100, 180.0, 1.6, centre);
  for (PeakMethod m : {PeakMethod::CenterOfMass, PeakMethod::Gaussian, PeakMethod::BlaisRioux}) {
    LineExtractionOptions o;
    o.method = m;
    const auto peaks = extract_laser_line(on, off, o);
    ASSERT_EQ(peaks.size(), 100u) << peak_method_name(m);
    double worst = 0;
    for (const auto& p : peaks) worst = std::max(worst, std::abs(p.u - centre(p.row)));
    // 8-bit quantisation only: well under a tenth of a pixel.
    EXPECT_LT(worst, 0.03) << peak_method_name(m);
    EXPECT_FALSE(peaks[0].saturated);
    EXPECT_NEAR(peaks[0].width, 2.3548 * 1.6, 0.15);
    EXPECT_EQ(peak_method_name(parse_peak_method(peak_method_name(m))),
              std::string(peak_method_name(m)));
  }
  EXPECT_THROW(parse_peak_method("steger"), InvalidInputError);
}

TEST(LineExtraction, SaturatedTopIsCentred) {
  auto centre = [](int y) { return 30.0 + 0.31 * y; };
  const auto [on, off] = synthetic(70, 50, 900.0, 1.8, centre);
  LineExtractionStats st;
  const auto peaks = extract_laser_line(on, off, {}, &st);
  ASSERT_EQ(peaks.size(), 50u);
  EXPECT_EQ(st.saturated, 50u);
  for (const auto& p : peaks) {
    EXPECT_TRUE(p.saturated);
    EXPECT_NEAR(p.u, centre(p.row), 0.05);
    EXPECT_LT(p.confidence, 0.8f);
  }
}

TEST(LineExtraction, RejectsSecondaryPeaksWideBumpsAndBadInput) {
  auto [on, off] = synthetic(80, 3, 150.0, 1.5, [](int) { return 20.0; });
  // Row 1: a second line as strong as 70 % of the first, far away: ambiguous, rejected.
  for (int x = 0; x < 80; ++x)
    on.at(x, 1)[0] = static_cast<std::uint8_t>(
        on.at(x, 1)[0] + std::lround(105.0 * std::exp(-0.5 * (x - 60.0) * (x - 60.0) / 2.25)));
  // Row 2: a broad bump (an ambient change), no line.
  for (int x = 0; x < 80; ++x)
    on.at(x, 2)[0] = static_cast<std::uint8_t>(
        40 + std::lround(100.0 * std::exp(-0.5 * (x - 40.0) * (x - 40.0) / 400.0)));
  LineExtractionStats st;
  const auto peaks = extract_laser_line(on, off, {}, &st);
  ASSERT_EQ(peaks.size(), 1u);
  EXPECT_EQ(peaks[0].row, 0);
  EXPECT_EQ(st.rejected_secondary, 1u);
  EXPECT_EQ(st.rejected_wide + st.rejected_weak, 1u);
  EXPECT_THROW(extract_laser_line(on, Image8(10, 3, 3), {}), InvalidInputError);
  LineExtractionOptions bad;
  bad.min_peak = -1;
  EXPECT_THROW(extract_laser_line(on, off, bad), InvalidInputError);
}

sim::Scene ball() {
  return sim::Scene::from_yaml_text(
      "objects:\n  - {type: sphere, name: ball, center: [0, 0, 70], radius: 50}\n"
      "texture: {seed: 3, base_color: [200, 200, 200]}\n",
      "ball");
}

struct Errors {
  double rms = 0;
  int matched = 0, truth_rows = 0, unmatched_peaks = 0;
};

// Compares peaks with the exact centres of the rows that have exactly one truth point, either on
// the object or on the platter (where the lines are steep and dim in the image).
Errors compare(const std::vector<LinePeak>& peaks, const std::vector<sim::LinePointTruth>& truth,
               int height, bool platter = false) {
  std::vector<int> count(height, 0), any(height, 0);
  std::vector<double> u(height, 0);
  for (const auto& t : truth) {
    ++any[t.row];
    if (t.on_platform == platter) ++count[t.row], u[t.row] = t.u;
  }
  Errors e;
  for (int c : count) e.truth_rows += c == 1;
  double s = 0;
  for (const auto& p : peaks) {
    if (any[p.row] == 0) {
      ++e.unmatched_peaks;
      continue;
    }
    if (count[p.row] != 1 || any[p.row] != 1) continue;
    const double err = p.u - u[p.row];
    if (std::abs(err) > 3.0) {
      ++e.unmatched_peaks;
      continue;
    }
    s += err * err;
    ++e.matched;
  }
  e.rms = e.matched ? std::sqrt(s / e.matched) : 1e9;
  return e;
}

TEST(LineExtraction, SubpixelAccuracyOnRenderedFramesWithNoise) {
  // Full 1280 x 960 frames of the built-in rig (read noise 1.5 DN + shot noise, speckle 5 %,
  // saturation and blooming), a 50 mm sphere above the platter, two angles, both lasers. The
  // acceptance is on the object; the dim, steep lines on the dark platter are reported.
  const sim::Scene scene = ball();
  const sim::TurntableCamera cam(scene, sim::builtin_ciclop_rig());
  for (PeakMethod m : {PeakMethod::CenterOfMass, PeakMethod::Gaussian, PeakMethod::BlaisRioux}) {
    double s = 0, sp = 0;
    int n = 0, np = 0, truth_rows = 0, unmatched = 0;
    for (double angle : {0.0, 2.1}) {
      const Image8 off = cam.render(angle, 0u);
      for (int k = 0; k < 2; ++k) {
        LineExtractionOptions o;
        o.method = m;
        const auto peaks = extract_laser_line(cam.render(angle, 1u << k), off, o);
        const Errors e = compare(peaks, cam.laser_line_truth(angle, k), off.height);
        const Errors ep = compare(peaks, cam.laser_line_truth(angle, k), off.height, true);
        sp += ep.rms * ep.rms * ep.matched;
        np += ep.matched;
        s += e.rms * e.rms * e.matched;
        n += e.matched;
        truth_rows += e.truth_rows;
        unmatched += e.unmatched_peaks;
      }
    }
    const double rms = std::sqrt(s / n);
    std::printf(
        "  %-12s object: RMS %.4f px over %d rows (truth rows %d, peaks without truth %d); "
        "platter: RMS %.4f px over %d rows\n",
        peak_method_name(m), rms, n, truth_rows, unmatched, std::sqrt(sp / std::max(1, np)), np);
    EXPECT_LT(rms, 0.1) << peak_method_name(m);
    EXPECT_GT(n, 0.9 * truth_rows) << peak_method_name(m);
    EXPECT_EQ(unmatched, 0) << peak_method_name(m);
  }
}

TEST(LineExtraction, NoPeaksFromBackgroundOrAmbientLight) {
  const sim::Scene scene = sim::builtin_head_scene();
  sim::RigConfig rig = sim::builtin_ciclop_rig();
  rig.width = 640;
  rig.height = 480;
  rig.intrinsics.fx /= 2;
  rig.intrinsics.fy /= 2;
  rig.intrinsics.cx /= 2;
  rig.intrinsics.cy /= 2;
  const sim::TurntableCamera a(scene, rig);
  rig.seed = 77;  // another laser-off frame: only the noise differs
  const sim::TurntableCamera b(scene, rig);
  rig.ambient *= 1.3;  // the room light got brighter between the two frames
  const sim::TurntableCamera brighter(scene, rig);
  const Image8 off = a.render(1.0, 0u);
  LineExtractionStats st;
  EXPECT_TRUE(extract_laser_line(b.render(1.0, 0u), off, {}, &st).empty());
  EXPECT_EQ(st.rows, 480u);
  EXPECT_TRUE(extract_laser_line(brighter.render(1.0, 0u), off).empty());
  // With the laser on under the brighter room light every peak is still on the line.
  const auto peaks = extract_laser_line(brighter.render(1.0, 1u), off);
  const Errors e = compare(peaks, a.laser_line_truth(1.0, 0), 480);
  EXPECT_GT(e.matched, 0.8 * e.truth_rows);
  EXPECT_LT(e.rms, 0.15);
  EXPECT_EQ(e.unmatched_peaks, 0);
}

}  // namespace
}  // namespace scanmesh
