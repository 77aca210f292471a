// Curvature and normal pictures (the labels use core's bitmap font, image_text.h)
// (docs/reconstruction.md, "Curvature pictures").
#include "scanmesh/reconstruction/curvature_maps.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/image_text.h"
#include "scanmesh/core/texture_layout.h"

namespace scanmesh {

namespace {

// ---- scales and colours ------------------------------------------------------------------------

void check_plane_sizes(const std::vector<float>& values, const std::vector<std::uint8_t>& defined,
                       int width, int height, const char* what) {
  if (width < 1 || height < 1 ||
      values.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height) ||
      defined.size() != values.size())
    throw InvalidInputError(std::string(what) + ": " + std::to_string(values.size()) +
                            " values and " + std::to_string(defined.size()) +
                            " flags do not fit a " + std::to_string(width) + " x " +
                            std::to_string(height) + " image");
}

// The q-quantile (q in [0, 1]) of |value| (or value) over the defined, finite cells; 0 if none.
double quantile(const std::vector<float>& values, const std::vector<std::uint8_t>& defined,
                double q, bool absolute) {
  std::vector<float> v;
  v.reserve(values.size());
  for (std::size_t k = 0; k < values.size(); ++k)
    if (defined[k] && std::isfinite(values[k]))
      v.push_back(absolute ? std::abs(values[k]) : values[k]);
  if (v.empty()) return 0.0;
  const auto nth = v.begin() + static_cast<std::ptrdiff_t>(std::lround(q * (v.size() - 1)));
  std::nth_element(v.begin(), nth, v.end());
  return *nth;
}

// A scale that is positive whatever the data: the quantile, else the largest |value|, else 1.
double automatic_scale(const std::vector<float>& values, const std::vector<std::uint8_t>& defined,
                       double q) {
  double s = quantile(values, defined, q, true);
  if (!(s > 0.0)) s = quantile(values, defined, 1.0, true);
  return s > 0.0 ? s : 1.0;
}

std::uint8_t to_byte(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0l, 255l));
}

// Blue - white - red for t in [-1, 1]; the ends are a muted blue and red that stay readable
// when printed in grey (equal lightness on both sides, so the sign is not a brightness cue).
Rgb8 diverging_color(double t) {
  t = std::clamp(t, -1.0, 1.0);
  constexpr double kBlue[3] = {40, 90, 200}, kRed[3] = {200, 40, 40};
  const double* end = t < 0 ? kBlue : kRed;
  const double a = std::abs(t);
  return {to_byte(255 + a * (end[0] - 255)), to_byte(255 + a * (end[1] - 255)),
          to_byte(255 + a * (end[2] - 255))};
}

// "+1.2e-2" style: sign, one decimal, exponent without leading zeros; "0" for zero.
std::string scale_label(double v) {
  if (v == 0.0) return "0";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%+.1e", v);
  std::string s = buf;
  const std::size_t e = s.find('e');
  if (e == std::string::npos || e + 2 >= s.size()) return s;
  std::string exponent = s.substr(e + 2);  // digits after the exponent's sign
  const std::string exponent_sign = s[e + 1] == '-' ? "-" : "";
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return s.substr(0, e + 1) + exponent_sign + exponent;
}

constexpr int kLegendWidth = 70;
constexpr int kLegendMinHeight = 120;  // room for the title, bar and three labels
const Rgb8 kLegendBackground{255, 255, 255};
const Rgb8 kLegendInk{0, 0, 0};
const Rgb8 kUndefinedDiverging{40, 40, 40};

}  // namespace

Image8 grey_map(const std::vector<float>& values, const std::vector<std::uint8_t>& defined,
                int width, int height, double scale) {
  check_plane_sizes(values, defined, width, height, "grey map");
  if (!(scale > 0.0) || !std::isfinite(scale)) scale = automatic_scale(values, defined, 0.99);
  Image8 image(width, height, 1, 0);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * width + i;
      if (!defined[k] || !std::isfinite(values[k])) continue;  // undefined: black
      image.at(i, texture_row(j, height))[0] = to_byte(255.0 * values[k] / scale);
    }
  return image;
}

Image8 diverging_map(const std::vector<float>& values, const std::vector<std::uint8_t>& defined,
                     int width, int height, const std::string& title, double scale) {
  check_plane_sizes(values, defined, width, height, "diverging map");
  if (!(scale > 0.0) || !std::isfinite(scale)) scale = automatic_scale(values, defined, 0.98);
  const int image_height = std::max(height, kLegendMinHeight);
  Image8 image(width + kLegendWidth, image_height, 3, 255);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * width + i;
      const bool ok = defined[k] && std::isfinite(values[k]);
      image.set_rgb(i, texture_row(j, height),
                    ok ? diverging_color(values[k] / scale) : kUndefinedDiverging);
    }

  // Legend: title on top, a vertical colour bar (+scale at the top, -scale at the bottom) and
  // tick labels to its right.
  const int x0 = width;
  for (int j = 0; j < image_height; ++j)
    for (int i = x0; i < image.width; ++i) image.set_rgb(i, j, kLegendBackground);
  draw_text(image, x0 + 3, 4, title, kLegendInk);
  const int bar_x = x0 + 4, bar_w = 12;
  const int bar_top = 20, bar_bottom = image_height - 10;  // inclusive
  for (int y = bar_top; y <= bar_bottom; ++y) {
    const double t = 1.0 - 2.0 * (y - bar_top) / static_cast<double>(bar_bottom - bar_top);
    for (int x = bar_x; x < bar_x + bar_w; ++x) image.set_rgb(x, y, diverging_color(t));
  }
  const std::array<std::pair<double, int>, 3> ticks = {
      {{scale, bar_top}, {0.0, (bar_top + bar_bottom) / 2}, {-scale, bar_bottom}}};
  for (const auto& [value, y] : ticks) {
    for (int x = bar_x + bar_w; x < bar_x + bar_w + 3; ++x) image.set_rgb(x, y, kLegendInk);
    draw_text(image, bar_x + bar_w + 4, y - text_height() / 2, scale_label(value), kLegendInk);
  }
  return image;
}

Image8 normal_map(const SurfaceFields& fields) {
  if (fields.n_phi < 1 || fields.n_h < 1 ||
      fields.size() != static_cast<std::size_t>(fields.n_phi) * fields.n_h ||
      fields.normal.size() != fields.size())
    throw InvalidInputError("normal map: surface fields have inconsistent sizes");
  Image8 image(fields.n_phi, fields.n_h, 3, 0);
  for (int j = 0; j < fields.n_h; ++j)
    for (int i = 0; i < fields.n_phi; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * fields.n_phi + i;
      if (!fields.defined[k]) continue;
      const Eigen::Vector3f& n = fields.normal[k];
      if (!n.allFinite()) continue;
      image.set_rgb(i, texture_row(j, fields.n_h),
                    {to_byte(127.5 * (n.x() + 1.0)), to_byte(127.5 * (n.y() + 1.0)),
                     to_byte(127.5 * (n.z() + 1.0))});
    }
  return image;
}

}  // namespace scanmesh
