// Reading and writing configuration files (scene, scanner, rig, calibration YAML): errors name
// the file and, where the parser knows it, the line; numbers are written to read back exactly.
// Shared by sim and acquisition, which may not include each other; no YAML types here, so core
// stays free of the parser.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"

namespace scanmesh {

//! The whole configuration file as text, at most kMaxConfigFileBytes. Throws IoError (names the
//! file and the OS reason) or FileFormatError (a directory, device or oversized file).
inline std::string read_config_text(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path, kMaxConfigFileBytes);
  return std::string(bytes.begin(), bytes.end());
}

//! `value` as text that reads back as the same double ("%.17g"), so configuration files and
//! metadata written by scanmesh round-trip bit for bit.
inline std::string format_exact_number(double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", value);
  return buf;
}

//! "[x, y, z]" (a YAML flow list), each coordinate as format_exact_number writes it.
inline std::string format_exact_vector3(const Eigen::Vector3d& v) {
  return "[" + format_exact_number(v.x()) + ", " + format_exact_number(v.y()) + ", " +
         format_exact_number(v.z()) + "]";
}

//! The `intrinsics` and `distortion` lines of a camera, written alike in rig and calibration files
//! (docs/formats.md), each line led by `indent`. `Camera` is any type with the pinhole fx, fy,
//! cx, cy and the Brown-Conrady k1, k2, p1, p2, k3 (or their uncertainties).
template <typename Camera>
std::string camera_intrinsics_yaml(const Camera& c, const std::string& indent = "") {
  return indent + "intrinsics: {fx: " + format_exact_number(c.fx) +
         ", fy: " + format_exact_number(c.fy) + ", cx: " + format_exact_number(c.cx) +
         ", cy: " + format_exact_number(c.cy) + "}\n" + indent +
         "distortion: {k1: " + format_exact_number(c.k1) + ", k2: " + format_exact_number(c.k2) +
         ", p1: " + format_exact_number(c.p1) + ", p2: " + format_exact_number(c.p2) +
         ", k3: " + format_exact_number(c.k3) + "}\n";
}

//! Throws FileFormatError "<source>: line N: <problem>" for the 0-based `line`, or without the
//! line when it is negative (a node the parser built, not read, has no position).
[[noreturn]] inline void throw_format_error_at_line(const std::string& source, int line,
                                                    const std::string& problem) {
  if (line >= 0) throw FileFormatError(source, "line " + std::to_string(line + 1) + ": " + problem);
  throw FileFormatError(source, problem);
}

//! Runs `config.validate()` on a configuration parsed from `source`. A value it rejects came from
//! the file, so its InvalidInputError is reported as a FileFormatError naming the file.
template <typename Config>
void validate_parsed_config(const Config& config, const std::string& source) {
  try {
    config.validate();
  } catch (const InvalidInputError& e) {
    throw FileFormatError(source, e.what());
  }
}

}  // namespace scanmesh
