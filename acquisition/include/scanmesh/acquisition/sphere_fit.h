// Least-squares spheres for probing tests (docs/acquisition.md, "Checking a calibration"):
// the VDI/VDE 2634-2 style probing error (fitted radius, point-to-sphere distances) and the
// sphere-spacing error of a dumbbell, measured on triangulated points.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <utility>
#include <vector>

namespace scanmesh {

struct SphereFit {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0;
  double rms = 0;            //!< RMS of (|p - centre| - radius) over the points used
  double max_abs = 0;        //!< largest |p - centre| - radius over the points used
  std::size_t points = 0;    //!< points used
  std::size_t rejected = 0;  //!< points left out as outliers (fit_sphere_trimmed)
};

//! Algebraic fit (linear in centre and r^2 - |c|^2), then Gauss-Newton on the geometric
//! distances. Throws InvalidInputError for fewer than 4 points or a degenerate (planar) set.
SphereFit fit_sphere(const std::vector<Eigen::Vector3d>& points);

//! fit_sphere, then repeatedly drops points farther than max(floor_mm, k_sigma x RMS) from the
//! sphere and refits (stray points of the platter or of a neighbouring object). Stops when
//! nothing more is dropped or after `rounds`.
SphereFit fit_sphere_trimmed(const std::vector<Eigen::Vector3d>& points, double k_sigma = 4.0,
                             double floor_mm = 0.3, int rounds = 5);

//! Splits a point set in two along its principal horizontal direction (the x-y direction of
//! largest spread), at the middle of the gap between the two groups' centroids — the two balls
//! of a dumbbell standing on the turntable. Iterates the split like 2-means along that line.
std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>> split_two_objects(
    const std::vector<Eigen::Vector3d>& points);

}  // namespace scanmesh
