// Procedural skin-like texture (docs/simulator.md, "Texture"): base colour modulated by smooth
// 3D value noise at three scales (tone, blotches, pores), sparse freckles, then painted features.
#include <algorithm>
#include <cmath>

#include "random.h"
#include "scene_detail.h"

namespace scanmesh::sim {
namespace {

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

//! Value noise in [0, 1]: hashed lattice values, trilinear interpolation with smoothstep weights.
double value_noise(const Eigen::Vector3d& p, std::uint64_t seed, std::uint64_t octave) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
             iz = static_cast<std::int64_t>(fz);
  auto w = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double ux = w(p.x() - fx), uy = w(p.y() - fy), uz = w(p.z() - fz);
  auto lattice = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
    return detail::to_unit(detail::hash_key(seed, static_cast<std::uint64_t>(a),
                                            static_cast<std::uint64_t>(b),
                                            static_cast<std::uint64_t>(c), octave));
  };
  double v = 0.0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx)
        v += (dx ? ux : 1 - ux) * (dy ? uy : 1 - uy) * (dz ? uz : 1 - uz) *
             lattice(ix + dx, iy + dy, iz + dz);
  return v;
}

}  // namespace

Rgb8 Scene::color_at(const Eigen::Vector3d& p) const {
  const double tone = value_noise(p / 30.0, texture_seed, 1) - 0.5;   // large, smooth
  const double blotch = value_noise(p / 7.0, texture_seed, 2) - 0.5;  // mottling
  const double pore = value_noise(p / 0.9, texture_seed, 3) - 0.5;    // pores, fine
  const double freckle = smoothstep(0.80, 0.90, value_noise(p / 1.6, texture_seed, 4));
  double c[3] = {static_cast<double>(base_color.r), static_cast<double>(base_color.g),
                 static_cast<double>(base_color.b)};
  const double shade = 1.0 + 0.14 * tone + 0.07 * blotch + 0.06 * pore;
  const double redness = 10.0 * blotch;  // blotches are a little redder
  c[0] = c[0] * shade + redness;
  c[1] = c[1] * shade - 0.5 * redness;
  c[2] = c[2] * shade - 0.5 * redness;
  const double freckle_rgb[3] = {150.0, 95.0, 70.0};
  for (int k = 0; k < 3; ++k) c[k] += 0.2 * freckle * (freckle_rgb[k] - c[k]);
  for (const auto& paint : paints) {
    const double d = (p - paint->center).norm();
    const double a = paint->opacity * (1.0 - smoothstep(paint->radius * (1.0 - paint->softness),
                                                        paint->radius + 1e-12, d));
    if (a <= 0.0) continue;
    // Keep a little of the noise inside paints so they do not look flat.
    const double texture = 1.0 + 0.5 * (0.14 * tone + 0.07 * blotch + 0.06 * pore);
    const double pc[3] = {paint->color.r * texture, paint->color.g * texture,
                          paint->color.b * texture};
    for (int k = 0; k < 3; ++k) c[k] += a * (pc[k] - c[k]);
  }
  auto to8 = [](double v) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
  };
  return {to8(c[0]), to8(c[1]), to8(c[2])};
}

}  // namespace scanmesh::sim
