// Private parts of Scene: painted colour features and hair zones (docs/simulator.md).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "scanmesh/sim/scene.h"

namespace scanmesh::sim {

//! A soft-edged sphere of colour: full `color` (times opacity) within radius * (1 - softness),
//! fading smoothly to nothing at `radius`.
struct Scene::Paint {
  std::string name;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;
  Rgb8 color;
  double softness = 0.4;
  double opacity = 1.0;
};

//! Hair: inside a sphere, above a height, or both (intersection) when both are given.
struct Scene::Zone {
  std::optional<Eigen::Vector3d> center;
  double radius = 0.0;
  std::optional<double> above_z;
  bool contains(const Eigen::Vector3d& p) const {
    if (center && (p - *center).squaredNorm() > radius * radius) return false;
    if (above_z && p.z() <= *above_z) return false;
    return true;
  }
};

}  // namespace scanmesh::sim
