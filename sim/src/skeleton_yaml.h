// Reading skeleton elements from YAML: skeletal scene objects and animated skeletons spell an
// element's type and geometry alike (docs/formats.md), so one reader keeps their errors alike.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

#include "scanmesh/sim/shapes.h"
#include "yaml_util.h"

namespace scanmesh::sim::detail {

//! Reads `type` and the geometry it needs into `element`: `center` for a point, `a` and `b` for
//! a segment. `who` names the element in errors. Name, radius and weight are the caller's.
inline void read_skeleton_element_geometry(const YamlReader& rd, const YAML::Node& node,
                                           const std::string& who, SkeletonElement& element) {
  const auto type = rd.as<std::string>(rd.required(node, "type", who), who + " type");
  if (type == "point") {
    element.type = SkeletonElement::Type::Point;
    element.a = rd.vec3(rd.required(node, "center", who), who + " center");
  } else if (type == "segment") {
    element.type = SkeletonElement::Type::Segment;
    element.a = rd.vec3(rd.required(node, "a", who), who + " a");
    element.b = rd.vec3(rd.required(node, "b", who), who + " b");
  } else {
    rd.fail(node["type"], who + ": unknown element type '" + type + "' (point, segment)");
  }
}

}  // namespace scanmesh::sim::detail
