// Small helpers for reading sim YAML with errors that name the source, the line and the key.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <initializer_list>
#include <string>

#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"

namespace scanmesh::sim::detail {

class YamlReader {
 public:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& problem) const {
    throw_format_error_at_line(source_, node.Mark().line, problem);
  }
  [[noreturn]] void fail(const std::string& problem) const {
    throw FileFormatError(source_, problem);
  }

  YAML::Node parse(const std::string& text) const {
    try {
      return YAML::Load(text);
    } catch (const YAML::Exception& e) {
      throw FileFormatError(
          source_, "line " + std::to_string(e.mark.line + 1) + ": malformed YAML: " + e.msg);
    }
  }

  //! Throws if `map` has a key not in `allowed` (catches typos such as `raduis`).
  void check_keys(const YAML::Node& map, const std::string& where,
                  std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) fail(map, where + " must be a mapping");
    for (const auto& kv : map) {
      // A key may itself be a list or a mapping (`? [a]: 1`): not a string, so an error here.
      const std::string key = as<std::string>(kv.first, where + ": a key");
      bool ok = false;
      for (const char* a : allowed) ok = ok || key == a;
      if (!ok) fail(kv.first, where + ": unknown key '" + key + "'");
    }
  }

  YAML::Node required(const YAML::Node& map, const char* key, const std::string& where) const {
    const YAML::Node n = map[key];
    if (!n) fail(map, where + ": missing key '" + std::string(key) + "'");
    return n;
  }

  template <typename T>
  T as(const YAML::Node& n, const std::string& what) const {
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      fail(n, what + " has the wrong type or value");
    }
  }

  double number(const YAML::Node& n, const std::string& what) const {
    const double v = as<double>(n, what);
    if (!std::isfinite(v)) fail(n, what + " must be a finite number");
    return v;
  }

  double positive(const YAML::Node& n, const std::string& what) const {
    const double v = number(n, what);
    if (!(v > 0.0)) fail(n, what + " must be positive, got " + std::to_string(v));
    return v;
  }

  Eigen::Vector3d vec3(const YAML::Node& n, const std::string& what) const {
    if (!n.IsSequence() || n.size() != 3) fail(n, what + " must be a list of 3 numbers");
    return {number(n[0], what), number(n[1], what), number(n[2], what)};
  }

  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

}  // namespace scanmesh::sim::detail
