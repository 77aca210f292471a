// Keyframed skeletal implicit surfaces (docs/formats.md, "Animated skeleton scenes").
#include "scanmesh/sim/animated_skeleton.h"
#include "scanmesh/sim/scene.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"
#include "skeleton_yaml.h"
#include "yaml_util.h"

namespace scanmesh::sim {

using Eigen::Vector3d;

bool AnimatedSkeleton::is_animated_yaml(const std::string& text) {
  try {
    const YAML::Node root = YAML::Load(text);
    return root.IsMap() && root["keyframes"];
  } catch (const YAML::Exception&) {
    return false;
  }
}

AnimatedSkeleton AnimatedSkeleton::from_yaml_text(const std::string& text,
                                                  const std::string& source) {
  const detail::YamlReader rd(source);
  const YAML::Node root = rd.parse(text);
  rd.check_keys(root, "scene", {"name", "iso", "elements", "keyframes"});
  AnimatedSkeleton s;
  s.name = root["name"] ? rd.as<std::string>(root["name"], "name") : "animated";
  if (root["iso"]) s.iso = rd.positive(root["iso"], "iso");
  const YAML::Node list = rd.required(root, "elements", "scene");
  if (!list.IsSequence() || list.size() == 0) rd.fail(list, "'elements' must be a non-empty list");
  if (list.size() > Scene::kMaxElements)
    rd.fail(list, "an animated skeleton holds at most " + std::to_string(Scene::kMaxElements) +
                      " elements, this one " + std::to_string(list.size()));
  for (std::size_t k = 0; k < list.size(); ++k) {
    const YAML::Node e = list[k];
    const std::string who = "element " + std::to_string(k);
    rd.check_keys(e, who, {"name", "type", "center", "a", "b", "radius", "weight"});
    SkeletonElement el;
    el.name = rd.as<std::string>(rd.required(e, "name", who), who + " name");
    for (const auto& other : s.elements)
      if (other.name == el.name) rd.fail(e, who + ": duplicate name '" + el.name + "'");
    detail::read_skeleton_element_geometry(rd, e, who, el);
    el.radius = rd.positive(rd.required(e, "radius", who), who + " radius");
    el.weight = e["weight"] ? rd.number(e["weight"], who + " weight") : 1.0;
    s.elements.push_back(el);
  }
  const YAML::Node frames = rd.required(root, "keyframes", "scene");
  if (!frames.IsSequence() || frames.size() == 0)
    rd.fail(frames, "'keyframes' must be a non-empty list");
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const YAML::Node f = frames[k];
    const std::string who = "keyframe " + std::to_string(k);
    rd.check_keys(f, who, {"time", "positions"});
    Keyframe kf;
    kf.time = rd.number(rd.required(f, "time", who), who + " time");
    if (!s.keyframes.empty() && !(kf.time > s.keyframes.back().time))
      rd.fail(f["time"], who + ": keyframe times must increase");
    // Elements not named in a keyframe keep their geometry from the previous keyframe (or
    // from the element definition for the first keyframe).
    for (std::size_t i = 0; i < s.elements.size(); ++i) {
      kf.a.push_back(s.keyframes.empty() ? s.elements[i].a : s.keyframes.back().a[i]);
      kf.b.push_back(s.keyframes.empty() ? s.elements[i].b : s.keyframes.back().b[i]);
    }
    if (const YAML::Node pos = f["positions"]) {
      if (!pos.IsMap()) rd.fail(pos, who + ": 'positions' must map element names to positions");
      for (const auto& kv : pos) {
        const std::string nm = rd.as<std::string>(kv.first, who + ": an element name");
        const auto it = std::find_if(s.elements.begin(), s.elements.end(),
                                     [&](const SkeletonElement& e) { return e.name == nm; });
        if (it == s.elements.end()) rd.fail(kv.first, who + ": unknown element '" + nm + "'");
        const std::size_t i = static_cast<std::size_t>(it - s.elements.begin());
        if (it->type == SkeletonElement::Type::Point) {
          kf.a[i] = rd.vec3(kv.second, who + " " + nm);
        } else {
          if (!kv.second.IsSequence() || kv.second.size() != 2)
            rd.fail(kv.second, who + " " + nm + ": a segment needs [[ax, ay, az], [bx, by, bz]]");
          kf.a[i] = rd.vec3(kv.second[0], who + " " + nm + " a");
          kf.b[i] = rd.vec3(kv.second[1], who + " " + nm + " b");
        }
      }
    }
    s.keyframes.push_back(std::move(kf));
  }
  for (std::size_t i = 0; i < s.elements.size(); ++i) {
    s.elements[i].a = s.keyframes.front().a[i];
    s.elements[i].b = s.keyframes.front().b[i];
  }
  s.object_at(s.start_time());  // validates radii and segments (throws InvalidInputError)
  return s;
}

AnimatedSkeleton AnimatedSkeleton::from_yaml_file(const std::filesystem::path& path) {
  return from_yaml_text(read_config_text(path), path.string());
}

std::vector<SkeletonElement> AnimatedSkeleton::elements_at(double t) const {
  std::vector<SkeletonElement> out = elements;
  std::size_t k = 0;
  while (k + 1 < keyframes.size() && keyframes[k + 1].time <= t) ++k;
  const Keyframe& f0 = keyframes[k];
  const Keyframe& f1 = keyframes[std::min(k + 1, keyframes.size() - 1)];
  double w = 0.0;
  if (f1.time > f0.time) w = std::clamp((t - f0.time) / (f1.time - f0.time), 0.0, 1.0);
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i].a = (1 - w) * f0.a[i] + w * f1.a[i];
    out[i].b = (1 - w) * f0.b[i] + w * f1.b[i];
  }
  return out;
}

std::shared_ptr<const SceneObject> AnimatedSkeleton::object_at(double t) const {
  return make_skeletal(elements_at(t), iso);
}

double AnimatedSkeleton::time_derivative(const Vector3d& x, double t) const {
  const double range = std::max(end_time() - start_time(), 1e-9);
  const double h = 1e-6 * range;
  // One-sided at the ends of the keyframe range (the motion stops there).
  const double t0 = std::max(t - h, start_time()), t1 = std::min(t + h, end_time());
  if (!(t1 > t0)) return 0.0;
  return (object_at(t1)->field(x).value - object_at(t0)->field(x).value) / (t1 - t0);
}

void AnimatedSkeleton::support_bounds(Vector3d& lo, Vector3d& hi) const {
  lo = Vector3d::Constant(1e300);
  hi = Vector3d::Constant(-1e300);
  for (const Keyframe& f : keyframes)
    for (std::size_t i = 0; i < elements.size(); ++i) {
      const Vector3d r = Vector3d::Constant(elements[i].radius);
      const Vector3d b = elements[i].type == SkeletonElement::Type::Point ? f.a[i] : f.b[i];
      lo = lo.cwiseMin(f.a[i] - r).cwiseMin(b - r);
      hi = hi.cwiseMax(f.a[i] + r).cwiseMax(b + r);
    }
}

}  // namespace scanmesh::sim
