// Camera model and the calibration YAML file (docs/formats.md, "Calibration files").
#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"

namespace scanmesh {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}
  [[noreturn]] void fail(const YAML::Node& n, const std::string& problem) const {
    throw_format_error_at_line(source_, n.Mark().line, problem);
  }
  YAML::Node need(const YAML::Node& map, const char* key, const std::string& where) const {
    if (!map.IsMap()) fail(map, where + " must be a mapping");
    const YAML::Node n = map[key];
    if (!n) fail(map, where + ": missing key '" + key + "'");
    return n;
  }
  double num(const YAML::Node& n, const std::string& what) const {
    double v = 0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, what + " must be a number");
    }
    if (!std::isfinite(v)) fail(n, what + " must be finite");
    return v;
  }
  int integer(const YAML::Node& n, const std::string& what) const {
    try {
      return n.as<int>();
    } catch (const YAML::Exception&) {
      fail(n, what + " must be an integer");
    }
  }
  Vector3d vec3(const YAML::Node& n, const std::string& what) const {
    if (!n.IsSequence() || n.size() != 3) fail(n, what + " must be a list of 3 numbers");
    return {num(n[0], what), num(n[1], what), num(n[2], what)};
  }

 private:
  std::string source_;
};

}  // namespace

Vector2d CameraModel::project(const Vector3d& p) const {
  const double x = p.x() / p.z(), y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  return {fx * xd + cx, fy * yd + cy};
}

Vector2d CameraModel::normalize(double u, double v) const {
  const Vector2d d((u - cx) / fx, (v - cy) / fy);
  Vector2d p = d;
  for (int it = 0; it < 30; ++it) {
    const double x = p.x(), y = p.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    const double dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    const Vector2d next((d.x() - dx) / radial, (d.y() - dy) / radial);
    const double change = (next - p).squaredNorm();
    p = next;
    if (change < 1e-30) break;
  }
  return p;
}

Vector3d CameraModel::ray(double u, double v) const {
  const Vector2d n = normalize(u, v);
  return Vector3d(n.x(), n.y(), 1.0).normalized();
}

Eigen::Isometry3d Calibration::rig_from_camera() const {
  const Vector3d z = axis_direction.normalized();
  const Vector3d to_camera = -axis_origin_mm;  // camera centre is the camera-frame origin
  const Vector3d x = (to_camera - to_camera.dot(z) * z).normalized();
  const Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x;
  r.row(1) = y;
  r.row(2) = z;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() = -r * axis_origin_mm;
  return t;
}

void Calibration::validate() const {
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw InvalidInputError("calibration: " + what);
  };
  const CameraModel& c = camera;
  check(c.width >= 2 && c.width <= 65536 && c.height >= 2 && c.height <= 65536,
        "image size must be 2..65536 pixels");
  check(std::isfinite(c.fx) && std::isfinite(c.fy) && c.fx > 0 && c.fy > 0,
        "fx and fy must be positive");
  for (double v : {c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3})
    check(std::isfinite(v), "principal point and distortion must be finite");
  for (double v : {c.k1, c.k2, c.p1, c.p2, c.k3})
    check(std::abs(v) < 100.0, "distortion coefficients must be below 100 in magnitude");
  check(lasers.size() <= 8, "at most 8 lasers");
  for (const auto& l : lasers)
    check(l.normal.allFinite() && std::abs(l.normal.norm() - 1.0) < 1e-6 &&
              std::isfinite(l.distance_mm),
          "laser '" + l.name + "' needs a unit normal and a finite distance");
  check(axis_direction.allFinite() && std::abs(axis_direction.norm() - 1.0) < 1e-6,
        "the axis direction must be a unit vector");
  check(axis_origin_mm.allFinite(), "the axis origin must be finite");
  const Vector3d to_camera = -axis_origin_mm;
  check((to_camera - to_camera.dot(axis_direction) * axis_direction).norm() > 1e-6,
        "the camera must not sit on the turntable axis");
}

std::string Calibration::to_yaml() const {
  std::ostringstream o;
  o << "# scanmesh scanner calibration (docs/formats.md, \"Calibration files\"); camera frame,\n"
       "# millimetres: x right, y down, z forward.\n";
  o << "format: scanmesh-calibration\nversion: 1\n";
  const CameraModel& c = camera;
  o << "image: {width: " << c.width << ", height: " << c.height << "}\n";
  o << camera_intrinsics_yaml(c);
  o << "axis: {direction: " << format_exact_vector3(axis_direction)
    << ", origin_mm: " << format_exact_vector3(axis_origin_mm) << "}\n";
  o << "lasers:\n";
  for (const auto& l : lasers)
    o << "  - {name: " << (l.name.empty() ? "laser" : l.name)
      << ", normal: " << format_exact_vector3(l.normal)
      << ", distance_mm: " << format_exact_number(l.distance_mm) << "}\n";
  o << "quality: {reprojection_rms_px: " << format_exact_number(reprojection_rms_px)
    << ", laser_rms_mm: " << format_exact_number(laser_rms_mm) << ", views: " << views
    << ", corners: " << corners << ", laser_points: " << laser_points << "}\n";
  const CalibrationUncertainty& u = uncertainty;
  o << "uncertainty:\n" << camera_intrinsics_yaml(u, "  ");
  o << "  axis_direction_deg: " << format_exact_number(u.axis_direction_deg)
    << "\n  axis_point_mm: " << format_exact_number(u.axis_point_mm) << "\n  laser_normal_deg: [";
  for (std::size_t i = 0; i < u.laser_normal_deg.size(); ++i)
    o << (i ? ", " : "") << format_exact_number(u.laser_normal_deg[i]);
  o << "]\n  laser_distance_mm: [";
  for (std::size_t i = 0; i < u.laser_distance_mm.size(); ++i)
    o << (i ? ", " : "") << format_exact_number(u.laser_distance_mm[i]);
  o << "]\n";
  return o.str();
}

Calibration Calibration::from_yaml_text(const std::string& text, const std::string& source) {
  const Reader rd(source);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FileFormatError(source,
                          "line " + std::to_string(e.mark.line + 1) + ": malformed YAML: " + e.msg);
  }
  if (!root.IsMap()) throw FileFormatError(source, "a calibration file must be a YAML mapping");
  Calibration c;
  try {
    const YAML::Node fmtn = rd.need(root, "format", "calibration");
    if (!fmtn.IsScalar() || fmtn.Scalar() != "scanmesh-calibration")
      rd.fail(fmtn, "format must be scanmesh-calibration");
    const int version = rd.integer(rd.need(root, "version", "calibration"), "version");
    if (version != 1) rd.fail(root["version"], "unsupported version " + std::to_string(version));
    const YAML::Node img = rd.need(root, "image", "calibration");
    c.camera.width = rd.integer(rd.need(img, "width", "image"), "image.width");
    c.camera.height = rd.integer(rd.need(img, "height", "image"), "image.height");
    const YAML::Node in = rd.need(root, "intrinsics", "calibration");
    c.camera.fx = rd.num(rd.need(in, "fx", "intrinsics"), "fx");
    c.camera.fy = rd.num(rd.need(in, "fy", "intrinsics"), "fy");
    c.camera.cx = rd.num(rd.need(in, "cx", "intrinsics"), "cx");
    c.camera.cy = rd.num(rd.need(in, "cy", "intrinsics"), "cy");
    const YAML::Node di = rd.need(root, "distortion", "calibration");
    c.camera.k1 = rd.num(rd.need(di, "k1", "distortion"), "k1");
    c.camera.k2 = rd.num(rd.need(di, "k2", "distortion"), "k2");
    c.camera.p1 = rd.num(rd.need(di, "p1", "distortion"), "p1");
    c.camera.p2 = rd.num(rd.need(di, "p2", "distortion"), "p2");
    c.camera.k3 = rd.num(rd.need(di, "k3", "distortion"), "k3");
    const YAML::Node ax = rd.need(root, "axis", "calibration");
    const Vector3d dir = rd.vec3(rd.need(ax, "direction", "axis"), "axis.direction");
    if (!(dir.norm() > 1e-9)) rd.fail(ax, "axis.direction must not be zero");
    c.axis_direction = std::abs(dir.norm() - 1.0) < 1e-12 ? dir : dir.normalized();
    c.axis_origin_mm = rd.vec3(rd.need(ax, "origin_mm", "axis"), "axis.origin_mm");
    const YAML::Node ls = rd.need(root, "lasers", "calibration");
    if (!ls.IsSequence()) rd.fail(ls, "lasers must be a list");
    if (ls.size() > 8) rd.fail(ls, "at most 8 lasers");
    for (const auto& l : ls) {
      LaserPlane p;
      if (l.IsMap() && l["name"] && l["name"].IsScalar()) p.name = l["name"].Scalar();
      const Vector3d n = rd.vec3(rd.need(l, "normal", "laser"), "laser.normal");
      if (!(n.norm() > 1e-9)) rd.fail(l, "laser.normal must not be zero");
      p.normal = std::abs(n.norm() - 1.0) < 1e-12 ? n : n.normalized();
      p.distance_mm = rd.num(rd.need(l, "distance_mm", "laser"), "laser.distance_mm");
      c.lasers.push_back(p);
    }
    if (const YAML::Node q = root["quality"]; q && q.IsMap()) {
      if (q["reprojection_rms_px"]) c.reprojection_rms_px = rd.num(q["reprojection_rms_px"], "rms");
      if (q["laser_rms_mm"]) c.laser_rms_mm = rd.num(q["laser_rms_mm"], "laser_rms_mm");
      if (q["views"]) c.views = rd.integer(q["views"], "views");
      if (q["corners"]) c.corners = rd.integer(q["corners"], "corners");
      if (q["laser_points"]) c.laser_points = rd.integer(q["laser_points"], "laser_points");
    }
    if (const YAML::Node u = root["uncertainty"]; u && u.IsMap()) {
      CalibrationUncertainty& un = c.uncertainty;
      auto opt = [&](const YAML::Node& m, const char* k, double& f) {
        if (m && m.IsMap() && m[k]) f = rd.num(m[k], k);
      };
      opt(u["intrinsics"], "fx", un.fx);
      opt(u["intrinsics"], "fy", un.fy);
      opt(u["intrinsics"], "cx", un.cx);
      opt(u["intrinsics"], "cy", un.cy);
      opt(u["distortion"], "k1", un.k1);
      opt(u["distortion"], "k2", un.k2);
      opt(u["distortion"], "p1", un.p1);
      opt(u["distortion"], "p2", un.p2);
      opt(u["distortion"], "k3", un.k3);
      opt(u, "axis_direction_deg", un.axis_direction_deg);
      opt(u, "axis_point_mm", un.axis_point_mm);
      for (const char* key : {"laser_normal_deg", "laser_distance_mm"}) {
        const YAML::Node s = u[key];
        if (!s) continue;
        if (!s.IsSequence() || s.size() > 8) rd.fail(s, std::string(key) + " must be a short list");
        auto& dst =
            std::string(key) == "laser_normal_deg" ? un.laser_normal_deg : un.laser_distance_mm;
        for (const auto& v : s) dst.push_back(rd.num(v, key));
      }
    }
  } catch (const YAML::Exception& e) {
    throw FileFormatError(source, std::string("unexpected YAML structure: ") + e.what());
  }
  validate_parsed_config(c, source);
  return c;
}

Calibration Calibration::read_yaml(const std::filesystem::path& path) {
  return from_yaml_text(read_config_text(path), path.string());
}

void Calibration::write_yaml(const std::filesystem::path& path) const {
  validate();
  const std::string text = to_yaml();
  write_file_atomically(path, std::string_view(text));
}

}  // namespace scanmesh
