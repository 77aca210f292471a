// Scene: objects, YAML parsing, ray queries, exact geometry (docs/simulator.md).
#include "scanmesh/sim/scene.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <sstream>

#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/shapes.h"
#include "scene_detail.h"
#include "skeleton_yaml.h"
#include "yaml_util.h"

namespace scanmesh::sim {

using Eigen::Vector3d;

SurfaceGeometry geometry_from_field(const FieldSample& f) {
  SurfaceGeometry g;
  const double gn = f.gradient.norm();
  if (!(gn > 0.0) || !std::isfinite(gn)) return g;  // singular point: no geometry
  const Vector3d n = f.gradient / gn;
  g.normal = n;
  // Orthonormal tangent basis (t1, t2) of the plane normal to n.
  const Vector3d helper = std::abs(n.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  const Vector3d t1 = n.cross(helper).normalized();
  const Vector3d t2 = n.cross(t1);
  Eigen::Matrix<double, 3, 2> t;
  t << t1, t2;
  // Shape operator in the tangent basis: T^T H T / |grad|. With value < 0 inside and the
  // gradient outward, a convex surface has a positive definite restriction (sphere: 1/R).
  const Eigen::Matrix2d s = t.transpose() * f.hessian * t / gn;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (s + s.transpose()));
  g.k2 = eig.eigenvalues()(0);
  g.k1 = eig.eigenvalues()(1);
  g.dir1 = (t * eig.eigenvectors().col(1)).normalized();
  g.dir2 = (t * eig.eigenvectors().col(0)).normalized();
  return g;
}

namespace {

using detail::YamlReader;

std::shared_ptr<const SceneObject> parse_skeletal(const YamlReader& rd, const YAML::Node& node,
                                                  const std::string& where) {
  rd.check_keys(node, where, {"type", "name", "iso", "kernel", "elements"});
  double iso = 0.5;
  if (node["iso"]) iso = rd.positive(node["iso"], where + " iso");
  if (node["kernel"]) {
    const auto kernel = rd.as<std::string>(node["kernel"], where + " kernel");
    // Decision (seed 003 names no kernel): Wyvill only; see docs/simulator.md.
    if (kernel != "wyvill")
      rd.fail(node["kernel"], where + ": unknown kernel '" + kernel + "' (supported: wyvill)");
  }
  const YAML::Node list = rd.required(node, "elements", where);
  if (!list.IsSequence() || list.size() == 0)
    rd.fail(list, where + ": 'elements' must be a non-empty list");
  if (list.size() > Scene::kMaxElements)
    rd.fail(list, where + ": a skeletal object holds at most " +
                      std::to_string(Scene::kMaxElements) + " elements, this one " +
                      std::to_string(list.size()));
  std::vector<SkeletonElement> elements;
  for (std::size_t k = 0; k < list.size(); ++k) {
    const YAML::Node e = list[k];
    std::string who = where + " element " + std::to_string(k);
    if (e.IsMap() && e["name"])
      who = where + " element '" + rd.as<std::string>(e["name"], who) + "'";
    rd.check_keys(e, who, {"name", "type", "center", "a", "b", "radius", "weight"});
    SkeletonElement s;
    s.name =
        e["name"] ? rd.as<std::string>(e["name"], who + " name") : "element" + std::to_string(k);
    detail::read_skeleton_element_geometry(rd, e, who, s);
    if (s.type == SkeletonElement::Type::Segment && (s.a - s.b).norm() < 1e-9)
      rd.fail(e, who + ": segment end points coincide");
    s.radius = rd.positive(rd.required(e, "radius", who), who + " radius");
    s.weight = e["weight"] ? rd.number(e["weight"], who + " weight") : 1.0;
    elements.push_back(s);
  }
  return make_skeletal(std::move(elements), iso);
}

std::shared_ptr<const SceneObject> parse_object(const YamlReader& rd, const YAML::Node& node,
                                                std::size_t index) {
  std::string where = "object " + std::to_string(index);
  if (!node.IsMap()) rd.fail(node, where + " must be a mapping");
  if (node["name"]) where = "object '" + rd.as<std::string>(node["name"], where + " name") + "'";
  const auto type = rd.as<std::string>(rd.required(node, "type", where), where + " type");
  auto center = [&] {
    return node["center"] ? rd.vec3(node["center"], where + " center") : Vector3d::Zero().eval();
  };
  auto axis = [&] {
    const Vector3d a =
        node["axis"] ? rd.vec3(node["axis"], where + " axis") : Vector3d::UnitZ().eval();
    if (a.norm() < 1e-12) rd.fail(node["axis"], where + ": axis must be non-zero");
    return a;
  };
  auto positive3 = [&](const char* key) {
    const YAML::Node n = rd.required(node, key, where);
    const Vector3d v = rd.vec3(n, where + " " + key);
    if (!(v.minCoeff() > 0.0)) rd.fail(n, where + ": all " + key + " must be positive");
    return v;
  };
  std::shared_ptr<const SceneObject> obj;
  if (type == "sphere") {
    rd.check_keys(node, where, {"type", "name", "center", "radius"});
    obj = make_sphere(center(), rd.positive(rd.required(node, "radius", where), where + " radius"));
  } else if (type == "cylinder") {
    rd.check_keys(node, where, {"type", "name", "center", "axis", "radius", "half_length"});
    std::optional<double> hl;
    if (node["half_length"]) hl = rd.positive(node["half_length"], where + " half_length");
    obj = make_cylinder(center(), axis(),
                        rd.positive(rd.required(node, "radius", where), where + " radius"), hl);
  } else if (type == "ellipsoid") {
    rd.check_keys(node, where, {"type", "name", "center", "radii"});
    obj = make_ellipsoid(center(), positive3("radii"));
  } else if (type == "torus") {
    rd.check_keys(node, where, {"type", "name", "center", "axis", "major_radius", "minor_radius"});
    obj =
        make_torus(center(), axis(),
                   rd.positive(rd.required(node, "major_radius", where), where + " major_radius"),
                   rd.positive(rd.required(node, "minor_radius", where), where + " minor_radius"));
  } else if (type == "box") {
    rd.check_keys(node, where, {"type", "name", "center", "half_extents"});
    obj = make_box(center(), positive3("half_extents"));
  } else if (type == "skeletal") {
    obj = parse_skeletal(rd, node, where);
  } else {
    rd.fail(node["type"], where + ": unknown object type '" + type +
                              "' (sphere, cylinder, ellipsoid, torus, box, skeletal)");
  }
  auto named = std::const_pointer_cast<SceneObject>(obj);
  named->name =
      node["name"] ? rd.as<std::string>(node["name"], where) : type + std::to_string(index);
  return obj;
}

Rgb8 parse_color(const YamlReader& rd, const YAML::Node& n, const std::string& what) {
  if (!n.IsSequence() || n.size() != 3) rd.fail(n, what + " must be a list of 3 integers 0..255");
  Rgb8 c;
  std::uint8_t* out[3] = {&c.r, &c.g, &c.b};
  for (int k = 0; k < 3; ++k) {
    const int v = rd.as<int>(n[k], what);
    if (v < 0 || v > 255) rd.fail(n[k], what + " components must be in 0..255");
    *out[k] = static_cast<std::uint8_t>(v);
  }
  return c;
}

void parse_texture(const YamlReader& rd, const YAML::Node& node, Scene& scene) {
  rd.check_keys(node, "texture", {"seed", "base_color", "paints"});
  if (node["seed"]) scene.texture_seed = rd.as<std::uint64_t>(node["seed"], "texture seed");
  if (node["base_color"])
    scene.base_color = parse_color(rd, node["base_color"], "texture base_color");
  if (const YAML::Node list = node["paints"]) {
    if (!list.IsSequence()) rd.fail(list, "texture paints must be a list");
    if (list.size() > Scene::kMaxPaints)
      rd.fail(list, "a texture holds at most " + std::to_string(Scene::kMaxPaints) +
                        " paints, this one " + std::to_string(list.size()));
    for (std::size_t k = 0; k < list.size(); ++k) {
      const YAML::Node p = list[k];
      std::string who = "paint " + std::to_string(k);
      if (p.IsMap() && p["name"]) who = "paint '" + rd.as<std::string>(p["name"], who) + "'";
      rd.check_keys(p, who, {"name", "center", "radius", "color", "softness", "opacity"});
      auto paint = std::make_shared<Scene::Paint>();
      paint->name = p["name"] ? rd.as<std::string>(p["name"], who) : who;
      paint->center = rd.vec3(rd.required(p, "center", who), who + " center");
      paint->radius = rd.positive(rd.required(p, "radius", who), who + " radius");
      paint->color = parse_color(rd, rd.required(p, "color", who), who + " color");
      if (p["softness"]) {
        paint->softness = rd.number(p["softness"], who + " softness");
        if (paint->softness < 0.0 || paint->softness > 1.0)
          rd.fail(p["softness"], who + ": softness must be in [0, 1]");
      }
      if (p["opacity"]) {
        paint->opacity = rd.number(p["opacity"], who + " opacity");
        if (paint->opacity < 0.0 || paint->opacity > 1.0)
          rd.fail(p["opacity"], who + ": opacity must be in [0, 1]");
      }
      scene.paints.push_back(paint);
    }
  }
}

void parse_hair_zones(const YamlReader& rd, const YAML::Node& list, Scene& scene) {
  if (!list.IsSequence()) rd.fail(list, "hair_zones must be a list");
  for (std::size_t k = 0; k < list.size(); ++k) {
    const YAML::Node z = list[k];
    const std::string who = "hair zone " + std::to_string(k);
    rd.check_keys(z, who, {"name", "center", "radius", "above_z"});
    auto zone = std::make_shared<Scene::Zone>();
    if (z["center"] || z["radius"]) {
      zone->center = rd.vec3(rd.required(z, "center", who), who + " center");
      zone->radius = rd.positive(rd.required(z, "radius", who), who + " radius");
    }
    if (z["above_z"]) zone->above_z = rd.number(z["above_z"], who + " above_z");
    if (!zone->center && !zone->above_z)
      rd.fail(z, who + ": needs center + radius, above_z, or both");
    scene.hair_zones.push_back(zone);
  }
}

}  // namespace

Scene Scene::from_yaml_text(const std::string& text, const std::string& source_name) {
  const YamlReader rd(source_name);
  const YAML::Node root = rd.parse(text);
  if (!root.IsMap()) rd.fail(root, "a scene file must be a mapping with 'objects'");
  rd.check_keys(root, "scene", {"name", "objects", "texture", "hair_zones"});
  Scene scene;
  scene.name = root["name"] ? rd.as<std::string>(root["name"], "scene name") : source_name;
  const YAML::Node objects = rd.required(root, "objects", "scene");
  if (!objects.IsSequence() || objects.size() == 0)
    rd.fail(objects, "scene 'objects' must be a non-empty list");
  // Every ray meets every object: the simulation's time grows with their count.
  if (objects.size() > Scene::kMaxObjects)
    rd.fail(objects, "a scene holds at most " + std::to_string(Scene::kMaxObjects) +
                         " objects, this one " + std::to_string(objects.size()));
  try {
    for (std::size_t k = 0; k < objects.size(); ++k)
      scene.objects.push_back(parse_object(rd, objects[k], k));
  } catch (const InvalidInputError& e) {  // a check inside make_* the parser did not repeat
    throw FileFormatError(source_name, e.what());
  }
  if (root["texture"]) parse_texture(rd, root["texture"], scene);
  if (root["hair_zones"]) parse_hair_zones(rd, root["hair_zones"], scene);
  return scene;
}

Scene Scene::from_yaml_file(const std::filesystem::path& path) {
  return from_yaml_text(read_config_text(path), path.string());
}

std::optional<RayHit> Scene::intersect(const Vector3d& origin, const Vector3d& unit_dir,
                                       double t_min, double t_max) const {
  std::optional<RayHit> best;
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const double limit = best ? best->t : t_max;
    if (auto t = objects[k]->intersect(origin, unit_dir, t_min, limit)) {
      if (!best || *t < best->t) best = RayHit{*t, origin + *t * unit_dir, static_cast<int>(k)};
    }
  }
  return best;
}

Eigen::AlignedBox3d Scene::bounds() const {
  Eigen::AlignedBox3d box;
  for (const auto& o : objects) box.extend(o->bounds());
  return box;
}

SurfaceGeometry Scene::geometry(const RayHit& hit) const {
  if (hit.object < 0 || hit.object >= static_cast<int>(objects.size()))
    throw InvalidInputError("ray hit refers to no object of scene '" + name + "'");
  return geometry_from_field(objects[hit.object]->field(hit.point));
}

bool Scene::in_hair_zone(const Vector3d& p) const {
  for (const auto& z : hair_zones)
    if (z->contains(p)) return true;
  return false;
}

Scene builtin_head_scene() { return Scene::from_yaml_text(builtin_head_yaml(), "built-in head"); }

}  // namespace scanmesh::sim
