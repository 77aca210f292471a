// A simulated scene: analytic shapes and skeleton-based implicit surfaces (seed 003 eq. 1-2),
// each with exact field, gradient and Hessian, so every surface point has a known normal and
// known principal curvatures. Scenes are read from YAML (docs/formats.md, "Scene files").
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/core/color.h"
#include "scanmesh/core/surface_curvature.h"

namespace scanmesh::sim {

//! Exact differential geometry of a surface point. Normal points outward; curvatures use the
//! convention k > 0 where the surface bends away from the normal (a sphere of radius R has
//! k1 = k2 = 1/R); k1 >= k2; dir1/dir2 are unit principal directions.
using SurfaceGeometry = SurfaceCurvature;

//! Value, gradient and Hessian of an implicit function. Convention for all objects: value < 0
//! inside, > 0 outside, gradient pointing outward.
struct FieldSample {
  double value = 0.0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
};

//! Principal curvatures and directions of the level set through x from the field derivatives
//! (Goldman 2005): shape operator = P H P / |grad F| restricted to the tangent plane.
SurfaceGeometry geometry_from_field(const FieldSample& f);

struct RayHit {
  double t = 0.0;         //!< ray parameter (direction is unit length, so t is in mm)
  Eigen::Vector3d point;  //!< exact hit point
  int object = -1;        //!< index of the scene object hit
};

//! One object of a scene (an analytic shape or a whole skeletal implicit surface).
class SceneObject {
 public:
  virtual ~SceneObject() = default;
  virtual FieldSample field(const Eigen::Vector3d& x) const = 0;
  //! First intersection with t in [t_min, t_max] along origin + t * unit_dir, if any.
  virtual std::optional<double> intersect(const Eigen::Vector3d& origin,
                                          const Eigen::Vector3d& unit_dir, double t_min,
                                          double t_max) const = 0;
  //! A box containing the object's solid (huge extents for unbounded shapes such as an
  //! infinite cylinder), so meshers and probes know where to look.
  virtual Eigen::AlignedBox3d bounds() const = 0;
  std::string name;
};

class Scene {
 public:
  //! Most objects a scene file may hold (every ray is tested against each).
  static constexpr std::size_t kMaxObjects = 1000;
  //! Most elements of one skeletal object (or an animated skeleton), and most texture paints:
  //! every field or colour evaluation sums over all of them (one object of 20,000 elements, a
  //! 1.8 MB file, kept `sim` busy for minutes). The built-in head has 16 elements.
  static constexpr std::size_t kMaxElements = 256;
  static constexpr std::size_t kMaxPaints = 256;
  //! Parses a scene YAML file / text. Throws FileFormatError (naming the source and the key)
  //! for malformed YAML, unknown shape types, missing or impossible parameters.
  static Scene from_yaml_file(const std::filesystem::path& path);
  static Scene from_yaml_text(const std::string& text, const std::string& source_name);

  //! Nearest hit over all objects, or nullopt.
  std::optional<RayHit> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_dir,
                                  double t_min, double t_max) const;
  SurfaceGeometry geometry(const RayHit& hit) const;
  //! Union of the objects' bounds (empty for an empty scene).
  Eigen::AlignedBox3d bounds() const;
  //! Procedural skin-like colour with painted features at a surface point (deterministic).
  Rgb8 color_at(const Eigen::Vector3d& p) const;
  //! True if p lies in a "hair" zone (noisier, speckled measurement).
  bool in_hair_zone(const Eigen::Vector3d& p) const;

  std::string name;
  std::vector<std::shared_ptr<const SceneObject>> objects;
  // Colour and hair-zone descriptions are private details of scene.cpp, kept here by value.
  struct Paint;
  struct Zone;
  std::vector<std::shared_ptr<const Paint>> paints;
  std::vector<std::shared_ptr<const Zone>> hair_zones;
  Rgb8 base_color{224, 172, 140};
  std::uint64_t texture_seed = 1;
};

//! The built-in head scene (configs/sim/head.yaml, compiled into the binary).
Scene builtin_head_scene();
//! The text of the built-in head scene YAML.
const std::string& builtin_head_yaml();

}  // namespace scanmesh::sim
