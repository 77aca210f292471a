// The cylindrical range grid: the central data type of scanmesh (docs/formats.md, "RangeGrid").
//
// Cell (i, j) holds the radius r measured at angle phi_i = phi0 + i * 2*pi / n_phi (wraps around)
// and height h_j = h0 + j * dh, in the turntable frame (z = rotation axis, millimetres, radians).
// Cartesian: x = r cos(phi), y = r sin(phi), z = h. Holes are explicit: an invalid cell has no
// radius, and nothing here invents one.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/core/color.h"

namespace scanmesh {

class RangeGrid {
 public:
  static constexpr int kDefaultSize = 512;

  //! An empty (all cells invalid) grid. Throws InvalidInputError for non-positive sizes or dh.
  RangeGrid(int n_phi = kDefaultSize, int n_h = kDefaultSize, double phi0 = 0.0, double h0 = 0.0,
            double dh = 1.0);

  int n_phi() const { return n_phi_; }
  int n_h() const { return n_h_; }
  std::size_t cell_count() const { return static_cast<std::size_t>(n_phi_) * n_h_; }
  double phi0() const { return phi0_; }
  double h0() const { return h0_; }
  double dh() const { return dh_; }
  double dphi() const;

  //! Angle and height of cell column i / row j (i is not wrapped).
  double phi(int i) const { return phi0_ + i * dphi(); }
  double h(int j) const { return h0_ + j * dh_; }

  //! Column index i taken modulo n_phi (phi wraps around 2*pi).
  int wrap_phi(int i) const;
  //! Linear index of cell (i, j): rows of constant h are contiguous, like the texture image.
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * n_phi_ + static_cast<std::size_t>(i);
  }

  bool valid(int i, int j) const { return valid_[index(i, j)] != 0; }
  float radius(int i, int j) const { return radius_[index(i, j)]; }
  float confidence(int i, int j) const { return confidence_[index(i, j)]; }
  Rgb8 color(int i, int j) const { return color_[index(i, j)]; }

  //! Marks the cell valid with radius r (> 0, finite) and confidence in [0, 1].
  void set_sample(int i, int j, float r, float confidence = 1.0f);
  //! Marks the cell invalid; its radius and confidence become 0, its colour is kept.
  void invalidate(int i, int j);
  void set_color(int i, int j, Rgb8 c) { color_[index(i, j)] = c; }

  std::size_t valid_count() const;

  //! Cartesian position of a cell (meaningful only for valid cells).
  Eigen::Vector3d cartesian(int i, int j) const;
  static Eigen::Vector3d to_cartesian(double phi, double h, double r);

  //! Bilinear interpolation of r at any (phi, h). phi wraps; h must lie within the rows.
  //! Returns nullopt when any of the four surrounding cells is invalid or h is outside the grid,
  //! so interpolation never crosses a hole.
  std::optional<double> sample_radius(double phi, double h) const;

  //! Raw planes in index() order, for file I/O and bulk algorithms.
  const std::vector<float>& radii() const { return radius_; }
  const std::vector<std::uint8_t>& validity() const { return valid_; }
  const std::vector<float>& confidences() const { return confidence_; }
  const std::vector<Rgb8>& colors() const { return color_; }
  std::vector<float>& radii() { return radius_; }
  std::vector<std::uint8_t>& validity() { return valid_; }
  std::vector<float>& confidences() { return confidence_; }
  std::vector<Rgb8>& colors() { return color_; }

  //! Free-form provenance (source, scene, seed, scanner ...), stored in grid files.
  std::map<std::string, std::string> metadata;

  friend bool operator==(const RangeGrid&, const RangeGrid&) = default;

 private:
  int n_phi_, n_h_;
  double phi0_, h0_, dh_;
  std::vector<float> radius_;
  std::vector<std::uint8_t> valid_;
  std::vector<float> confidence_;
  std::vector<Rgb8> color_;
};

}  // namespace scanmesh
