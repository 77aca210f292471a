#include "scanmesh/core/range_grid.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

RangeGrid::RangeGrid(int n_phi, int n_h, double phi0, double h0, double dh)
    : n_phi_(n_phi), n_h_(n_h), phi0_(phi0), h0_(h0), dh_(dh) {
  if (n_phi < 2 || n_h < 2)
    throw InvalidInputError("range grid needs at least 2 x 2 cells, got " + std::to_string(n_phi) +
                            " x " + std::to_string(n_h));
  if (!(dh > 0.0) || !std::isfinite(dh))
    throw InvalidInputError("range grid height step dh must be positive, got " +
                            std::to_string(dh));
  if (!std::isfinite(phi0) || !std::isfinite(h0))
    throw InvalidInputError("range grid origin phi0/h0 must be finite");
  const std::size_t n = cell_count();
  radius_.assign(n, 0.0f);
  valid_.assign(n, 0);
  confidence_.assign(n, 0.0f);
  color_.assign(n, Rgb8{});
}

double RangeGrid::dphi() const { return 2.0 * std::numbers::pi / n_phi_; }

int RangeGrid::wrap_phi(int i) const {
  const int m = i % n_phi_;
  return m < 0 ? m + n_phi_ : m;
}

void RangeGrid::set_sample(int i, int j, float r, float confidence) {
  if (!(r > 0.0f) || !std::isfinite(r))
    throw InvalidInputError("range grid radius must be positive and finite, got " +
                            std::to_string(r));
  const std::size_t k = index(i, j);
  radius_[k] = r;
  valid_[k] = 1;
  confidence_[k] = std::isfinite(confidence) ? std::clamp(confidence, 0.0f, 1.0f) : 0.0f;
}

void RangeGrid::invalidate(int i, int j) {
  const std::size_t k = index(i, j);
  radius_[k] = 0.0f;
  valid_[k] = 0;
  confidence_[k] = 0.0f;
}

std::size_t RangeGrid::valid_count() const {
  std::size_t n = 0;
  for (auto v : valid_) n += v != 0;
  return n;
}

Eigen::Vector3d RangeGrid::to_cartesian(double phi, double h, double r) {
  return {r * std::cos(phi), r * std::sin(phi), h};
}

Eigen::Vector3d RangeGrid::cartesian(int i, int j) const {
  return to_cartesian(phi(i), h(j), radius(i, j));
}

std::optional<double> RangeGrid::sample_radius(double phi_value, double h_value) const {
  if (!std::isfinite(phi_value) || !std::isfinite(h_value)) return std::nullopt;
  const double v = (h_value - h0_) / dh_;
  if (v < 0.0 || v > n_h_ - 1) return std::nullopt;
  double u = std::fmod((phi_value - phi0_) / dphi(), static_cast<double>(n_phi_));
  if (u < 0.0) u += n_phi_;
  const int i0 = std::min(static_cast<int>(u), n_phi_ - 1);
  const int j0 = std::min(static_cast<int>(v), n_h_ - 2);
  const double fu = u - i0, fv = v - j0;
  const int i1 = wrap_phi(i0 + 1), j1 = j0 + 1;
  if (!valid(i0, j0) || !valid(i1, j0) || !valid(i0, j1) || !valid(i1, j1)) return std::nullopt;
  const double bottom = (1 - fu) * radius(i0, j0) + fu * radius(i1, j0);
  const double top = (1 - fu) * radius(i0, j1) + fu * radius(i1, j1);
  return (1 - fv) * bottom + fv * top;
}

}  // namespace scanmesh
