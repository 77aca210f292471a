// Laser-line extraction (docs/acquisition.md, "Line extraction").
#include "scanmesh/acquisition/line_extraction.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include <Eigen/Dense>

#include "scanmesh/core/errors.h"

namespace scanmesh {

const char* peak_method_name(PeakMethod m) {
  switch (m) {
    case PeakMethod::CenterOfMass:
      return "com";
    case PeakMethod::Gaussian:
      return "gaussian";
    case PeakMethod::BlaisRioux:
      return "blais-rioux";
  }
  return "?";
}

PeakMethod parse_peak_method(const std::string& name) {
  if (name == "com" || name == "center-of-mass") return PeakMethod::CenterOfMass;
  if (name == "gaussian") return PeakMethod::Gaussian;
  if (name == "blais-rioux") return PeakMethod::BlaisRioux;
  throw InvalidInputError("unknown peak method '" + name +
                          "' (expected com, gaussian or blais-rioux)");
}

void LineExtractionOptions::validate() const {
  auto check = [](bool ok, const char* what) {
    if (!ok) throw InvalidInputError(std::string("line extraction: ") + what);
  };
  check(channel >= 0 && channel < 4, "channel must be 0..3");
  check(std::isfinite(min_peak) && min_peak > 0, "min_peak must be positive");
  check(com_half_window >= 1 && com_half_window <= 32, "com_half_window must be in 1..32");
  check(background_offset >= 2 && background_offset <= 200, "background_offset must be in 2..200");
  check(std::isfinite(max_width_px) && max_width_px > 0, "max_width_px must be positive");
  check(std::isfinite(secondary_ratio) && secondary_ratio > 0, "secondary_ratio must be positive");
  check(secondary_guard_px >= 0, "secondary_guard_px must be >= 0");
  check(saturation_level >= 1 && saturation_level <= 255, "saturation_level must be in 1..255");
  check(first_column >= 0, "first_column must be >= 0");
  check(std::isfinite(max_other_channel_ratio) && max_other_channel_ratio >= 0,
        "max_other_channel_ratio must be >= 0");
}

namespace {

constexpr int kBlock = 32;

void check_frames(const Image8& on, const Image8& off, const LineExtractionOptions& opt) {
  opt.validate();
  if (on.width != off.width || on.height != off.height || on.channels != off.channels ||
      on.pixels.size() != off.pixels.size())
    throw InvalidInputError("line extraction: laser-on and laser-off frames differ in size");
  if (opt.channel >= on.channels)
    throw InvalidInputError("line extraction: the frames have no channel " +
                            std::to_string(opt.channel));
}

// The laser-on minus laser-off difference of the current row, valid over the search columns
// [c0, c1], and its maximum per block of kBlock pixels. A view of buffers allocated once per
// frame pair: passed by value so the hot loops see plain locals.
struct RowDifference {
  std::int16_t* d;
  std::int16_t* bmax;
  int c0, c1, nblocks;
  // The difference at x, clamped to the search columns.
  int at(int x) const { return int(d[std::clamp(x, c0, c1)]); }
};

// pon and poff point at the laser channel of the row's first pixel. The 3-channel case has its
// own loop so the stride is a constant.
void subtract_laser_off(const std::uint8_t* pon, const std::uint8_t* poff, int nc,
                        RowDifference row) {
  if (nc == 3) {
    for (int x = row.c0; x <= row.c1; ++x)
      row.d[x] = static_cast<std::int16_t>(int(pon[3 * x]) - int(poff[3 * x]));
  } else {
    for (int x = row.c0; x <= row.c1; ++x)
      row.d[x] = static_cast<std::int16_t>(int(pon[x * nc]) - int(poff[x * nc]));
  }
}

struct StrongestPixel {
  int value, x;
};

// The maximum of the row difference and its first pixel; fills the block maxima on the way.
StrongestPixel find_strongest_pixel(RowDifference row) {
  int best = -1000, bbest = 0;
  for (int b = 0; b < row.nblocks; ++b) {
    const int x0 = row.c0 + b * kBlock, x1 = std::min(row.c1 + 1, x0 + kBlock);
    std::int16_t m = -32768;
    for (int x = x0; x < x1; ++x) m = std::max(m, row.d[x]);
    row.bmax[b] = m;
    if (m > best) best = m, bbest = b;
  }
  int xm = row.c0 + bbest * kBlock;
  while (row.d[xm] != best) ++xm;
  return {best, xm};
}

// The outermost pixels above half maximum around the peak at xm (xl, xr), the subpixel
// crossings (left, right) and their distance, the full width at half maximum.
struct HalfMaximumFlanks {
  int xl, xr;
  double left, right, width;
};

HalfMaximumFlanks find_half_maximum_flanks(RowDifference row, int xm, int base, double amp) {
  // Half-maximum crossings (subpixel) on both flanks.
  const std::int16_t* d = row.d;
  const int c0 = row.c0, c1 = row.c1;
  const double half = base + 0.5 * amp;
  int xl = xm, xr = xm;
  while (xl > c0 && d[xl - 1] > half) --xl;
  while (xr < c1 && d[xr + 1] > half) ++xr;
  const double left = xl > c0 ? (xl - 1) + (half - d[xl - 1]) / double(d[xl] - d[xl - 1]) : xl;
  const double right = xr < c1 ? xr + (d[xr] - half) / double(d[xr] - d[xr + 1]) : xr;
  const double width = right - left;
  return {xl, xr, left, right, width};
}

// The highest difference outside [lo, hi]: whole blocks outside it by their maxima, the
// blocks it cuts pixel by pixel.
int strongest_outside(RowDifference row, int lo, int hi) {
  int second = -1000;
  for (int b = 0; b < row.nblocks; ++b) {
    const int x0 = row.c0 + b * kBlock, x1 = std::min(row.c1, x0 + kBlock - 1);
    if (x1 < lo || x0 > hi) {
      second = std::max<int>(second, row.bmax[b]);
    } else if (x0 < lo || x1 > hi) {
      for (int x = x0; x <= x1; ++x)
        if (x < lo || x > hi) second = std::max<int>(second, row.d[x]);
    }
  }
  return second;
}

// True if the other channels of 3-channel frames rose too much against the laser channel
// around xm.
bool is_ambient_light(const Image8& on, const Image8& off, int y, RowDifference row, int xm,
                      const LineExtractionOptions& opt) {
  // Summed over the 3-pixel core so a single noisy pixel decides nothing.
  double other = 0, laser = 0;
  for (int x = std::max(row.c0, xm - 1); x <= std::min(row.c1, xm + 1); ++x) {
    laser += row.d[x];
    for (int ch = 0; ch < 3; ++ch)
      if (ch != opt.channel) other += int(on.at(x, y)[ch]) - int(off.at(x, y)[ch]);
  }
  return 0.5 * other > opt.max_other_channel_ratio * laser;
}

// Centroid of the difference above base over [mid - hw, mid + hw]; fallback if nothing is above.
double centre_of_mass(RowDifference row, int base, int mid, int hw, double fallback) {
  double sw = 0, sx = 0;
  for (int x = std::max(row.c0, mid - hw); x <= std::min(row.c1, mid + hw); ++x) {
    const double v = row.d[x] - base;
    if (v <= 0) continue;
    sw += v;
    sx += v * x;
  }
  return sw > 0 ? sx / sw : fallback;
}

// Vertex of a Gaussian fitted around xm (within +-hw), at most 1 px from xm; xm if the fit has
// no maximum.
double gaussian_peak(RowDifference row, int xm, int base, double amp, int hw) {
  // Weighted least-squares parabola through ln(profile) over the samples above 20 % of
  // the peak (3 or more); weights v^2 because var(ln v) ~ 1 / v^2.
  double s[5] = {0, 0, 0, 0, 0}, t[3] = {0, 0, 0};
  for (int x = std::max(row.c0, xm - hw); x <= std::min(row.c1, xm + hw); ++x) {
    const double v = row.d[x] - base;
    if (v < 0.2 * amp && std::abs(x - xm) > 1) continue;
    const double lv = std::log(std::max(0.5, v)), wgt = std::max(0.5, v) * std::max(0.5, v);
    const double dx = x - xm;
    double pw = wgt;
    for (int k = 0; k < 5; ++k) {
      s[k] += pw;
      if (k < 3) t[k] += pw * lv;
      pw *= dx;
    }
  }
  Eigen::Matrix3d a;
  a << s[0], s[1], s[2], s[1], s[2], s[3], s[2], s[3], s[4];
  const Eigen::Vector3d c = a.ldlt().solve(Eigen::Vector3d(t[0], t[1], t[2]));
  double u = xm;
  if (c[2] < 0 && std::isfinite(c[1])) u = xm + std::clamp(-0.5 * c[1] / c[2], -1.0, 1.0);
  return u;
}

// Zero crossing of the derivative filter next to xm; xm if there is none.
double blais_rioux_peak(RowDifference row, int xm, double width) {
  // 4th-order filter for narrow lines, 8th-order (Blais & Rioux 1986) for wide ones.
  const int order = width > 4.0 ? 4 : 2;
  auto g = [&](int x) {
    double v = 0;
    for (int k = 1; k <= order; ++k) v += row.at(x - k) - row.at(x + k);
    return v;
  };
  // The filtered signal goes from < 0 (rising flank) to > 0 (falling flank).
  const int xs = g(xm) > 0 ? xm - 1 : xm;
  const double g0 = g(xs), g1 = g(xs + 1);
  double u = xm;
  if (g0 <= 0 && g1 > 0) u = xs + g0 / (g0 - g1);
  return u;
}

// In [0, 1]: signal to threshold, uniqueness against the secondary peak, saturation.
float peak_confidence(double amp, double sec_amp, bool saturated, double min_peak) {
  const double snr = std::min(1.0, amp / (4.0 * min_peak));
  const double unique = 1.0 - std::clamp(sec_amp / amp, 0.0, 1.0);
  return static_cast<float>(std::clamp(snr * unique * (saturated ? 0.7 : 1.0), 0.0, 1.0));
}

// Counts a rejected row under its reason.
std::nullopt_t reject(std::size_t& reason_count) {
  ++reason_count;
  return std::nullopt;
}

// The laser peak of row y, or nothing if the row's strongest peak fails a check (counted in
// `st` by the reason).
std::optional<LinePeak> find_row_peak(const Image8& on, const Image8& off,
                                      const LineExtractionOptions& opt, RowDifference row, int y,
                                      LineExtractionStats& st) {
  const int nc = on.channels;
  const std::uint8_t* pon = on.at(0, y) + opt.channel;
  const std::uint8_t* poff = off.at(0, y) + opt.channel;
  subtract_laser_off(pon, poff, nc, row);
  const StrongestPixel strongest = find_strongest_pixel(row);
  const int best = strongest.value, xm = strongest.x;
  if (best < opt.min_peak) return reject(st.rejected_weak);
  const int base =
      std::max(0, std::min(row.at(xm - opt.background_offset), row.at(xm + opt.background_offset)));
  const double amp = best - base;
  if (amp < opt.min_peak) return reject(st.rejected_weak);
  const HalfMaximumFlanks f = find_half_maximum_flanks(row, xm, base, amp);
  const double width = f.width;
  if (width > opt.max_width_px) return reject(st.rejected_wide);
  // Secondary peaks beyond the flanks: whole blocks outside [lo, hi], pixels at the edges.
  const int guard = opt.secondary_guard_px;
  const int second = strongest_outside(row, f.xl - guard, f.xr + guard);
  const double sec_amp = second - base;
  if (sec_amp >= opt.min_peak && sec_amp > opt.secondary_ratio * amp)
    return reject(st.rejected_secondary);
  const bool saturated = pon[xm * nc] >= opt.saturation_level;
  // Ambient-light changes brighten every channel in proportion; the laser is nearly pure red.
  if (!saturated && nc == 3 && opt.channel < 3 && opt.max_other_channel_ratio > 0 &&
      is_ambient_light(on, off, y, row, xm, opt))
    return reject(st.rejected_ambient);
  // Centre-of-mass window: wide enough to hold the whole profile (+- 1.5 FWHM) so the
  // truncated tails bias nothing, centred on the half-maximum midpoint.
  const int mid = static_cast<int>(std::lround(0.5 * (f.left + f.right)));
  const int hw = std::max(opt.com_half_window, static_cast<int>(std::ceil(1.5 * width)) + 1);
  double u = xm;
  if (saturated) {
    // A clipped top is flat but still symmetric: its centroid is the centre.
    u = centre_of_mass(row, base, mid, hw, 0.5 * (f.left + f.right));
    ++st.saturated;
  } else {
    switch (opt.method) {
      case PeakMethod::CenterOfMass:
        u = centre_of_mass(row, base, mid, hw, xm);
        break;
      case PeakMethod::Gaussian:
        u = gaussian_peak(row, xm, base, amp, hw);
        break;
      case PeakMethod::BlaisRioux:
        u = blais_rioux_peak(row, xm, width);
        break;
    }
  }
  LinePeak p;
  p.row = y;
  p.u = u;
  p.amplitude = static_cast<float>(amp);
  p.width = static_cast<float>(width);
  p.confidence = peak_confidence(amp, sec_amp, saturated, opt.min_peak);
  p.saturated = saturated;
  return p;
}

}  // namespace

std::vector<LinePeak> extract_laser_line(const Image8& on, const Image8& off,
                                         const LineExtractionOptions& opt,
                                         LineExtractionStats* stats) {
  check_frames(on, off, opt);
  const int w = on.width;
  const int c0 = std::min(opt.first_column, w - 1);
  const int c1 = opt.last_column < 0 ? w - 1 : std::min(opt.last_column, w - 1);
  LineExtractionStats st;
  std::vector<LinePeak> peaks;
  if (w < 3 || c1 - c0 < 2) {
    if (stats) *stats = st;
    return peaks;
  }
  peaks.reserve(static_cast<std::size_t>(on.height));
  // The row difference, and its maximum per block of kBlock pixels so the secondary-peak search
  // visits blocks, not pixels. Plain loops over 16-bit values the compiler vectorises.
  std::vector<std::int16_t> dbuf(static_cast<std::size_t>(w) + kBlock, 0);
  const int nblocks = (c1 - c0 + kBlock) / kBlock;
  std::vector<std::int16_t> bmax(static_cast<std::size_t>(nblocks), 0);
  const RowDifference row{dbuf.data(), bmax.data(), c0, c1, nblocks};
  for (int y = 0; y < on.height; ++y) {
    ++st.rows;
    if (const std::optional<LinePeak> p = find_row_peak(on, off, opt, row, y, st))
      peaks.push_back(*p);
  }
  st.peaks = peaks.size();
  if (stats) *stats = st;
  return peaks;
}

}  // namespace scanmesh
