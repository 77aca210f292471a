// An animated skeleton-based implicit surface (seed 003 §1-3: the skeleton moves, the surface
// blends and tears): skeleton elements with keyframed positions, linearly interpolated in time.
// Scene file format: docs/formats.md, "Animated skeleton scenes".
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "scanmesh/sim/scene.h"
#include "scanmesh/sim/shapes.h"

namespace scanmesh::sim {

class AnimatedSkeleton {
 public:
  struct Keyframe {
    double time = 0.0;
    //! Per element (same order as elements): a (point or segment start) and b (segment end).
    std::vector<Eigen::Vector3d> a, b;
  };

  //! Throws FileFormatError naming the source, line and key for malformed input; keyframe
  //! times must increase strictly; at least one keyframe.
  static AnimatedSkeleton from_yaml_file(const std::filesystem::path& path);
  static AnimatedSkeleton from_yaml_text(const std::string& text, const std::string& source);
  //! True if the YAML text has a top-level `keyframes` key (an animated scene).
  static bool is_animated_yaml(const std::string& text);

  double start_time() const { return keyframes.front().time; }
  double end_time() const { return keyframes.back().time; }
  //! Element geometry at time t (clamped to the keyframe range, linear in between).
  std::vector<SkeletonElement> elements_at(double t) const;
  //! The surface at time t (value < 0 inside, gradient outward, like every SceneObject).
  std::shared_ptr<const SceneObject> object_at(double t) const;
  //! dF/dt of the field value at x and time t: central difference in time, exact up to
  //! O(h^2) because positions are linear in t between keyframes (h = 1e-6 of the range).
  double time_derivative(const Eigen::Vector3d& x, double t) const;
  //! Axis-aligned box containing every element's support over all keyframes.
  void support_bounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const;

  std::string name;
  double iso = 0.5;
  std::vector<SkeletonElement> elements;  //!< types, radii, weights; geometry of keyframe 0
  std::vector<Keyframe> keyframes;
};

}  // namespace scanmesh::sim
