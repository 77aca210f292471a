// The simulated turntable camera (docs/acquisition.md, "Camera and laser model").
#include "scanmesh/sim/turntable_camera.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>

#include "random.h"
#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"
#include "yaml_util.h"

namespace scanmesh::sim {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kBackgroundDn = 10.0;
constexpr double kShadowOffsetMm = 1e-3;
constexpr double kLaserGreen = 0.12, kLaserBlue = 0.08;  // a red laser's leak into G and B
enum Kind : std::uint8_t { kNone = 0, kSceneHit = 1, kPlatformHit = 2, kBoardHit = 3 };
enum Purpose : std::uint64_t { kPixelNoise = 11, kSpeckle = 12 };

Eigen::Matrix3d rot_z(double a) {
  return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix();
}

std::uint64_t angle_bits(double a) {
  std::uint64_t b = 0;
  std::memcpy(&b, &a, sizeof b);
  return b;
}

void check(bool ok, const std::string& problem) {
  if (!ok) throw InvalidInputError("turntable rig: " + problem);
}

bool finite3(const Vector3d& v) { return v.allFinite(); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Camera model

Vector2d CameraIntrinsics::distort_to_pixel(const Vector2d& xy) const {
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  return {fx * xd + cx, fy * yd + cy};
}

Vector2d CameraIntrinsics::pixel_to_normalized(const Vector2d& uv) const {
  const Vector2d d((uv.x() - cx) / fx, (uv.y() - cy) / fy);
  // Newton on distort(p) = d with a numeric Jacobian-free closed form of the derivatives.
  Vector2d p = d;
  for (int it = 0; it < 50; ++it) {
    const double x = p.x(), y = p.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);  // d radial / d r2
    const Vector2d f(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - d.x(),
                     y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - d.y());
    Eigen::Matrix2d j;
    j(0, 0) = radial + x * dradial * 2.0 * x + 2.0 * p1 * y + p2 * 6.0 * x;
    j(0, 1) = x * dradial * 2.0 * y + 2.0 * p1 * x + p2 * 2.0 * y;
    j(1, 0) = y * dradial * 2.0 * x + p1 * 2.0 * x + 2.0 * p2 * y;
    j(1, 1) = radial + y * dradial * 2.0 * y + p1 * 6.0 * y + 2.0 * p2 * x;
    const Vector2d step = j.partialPivLu().solve(f);
    p -= step;
    if (step.squaredNorm() < 1e-30) break;
  }
  return p;
}

// ---------------------------------------------------------------------------------------------
// Rig config

void RigConfig::validate() const {
  check(width >= 16 && width <= 8192 && height >= 16 && height <= 8192,
        "image size must be within 16..8192 pixels");
  const auto& in = intrinsics;
  check(std::isfinite(in.fx) && std::isfinite(in.fy) && in.fx > 0 && in.fy > 0,
        "fx and fy must be positive");
  check(std::isfinite(in.cx) && std::isfinite(in.cy), "cx and cy must be finite");
  for (double k : {in.k1, in.k2, in.p1, in.p2, in.k3})
    check(std::isfinite(k) && std::abs(k) < 10.0,
          "distortion coefficients must be finite and small");
  check(finite3(camera_position_mm) && finite3(camera_look_at_mm),
        "camera position and look-at must be finite");
  check((camera_look_at_mm - camera_position_mm).norm() > 1e-6,
        "camera look_at must differ from its position");
  const Vector3d fwd = (camera_look_at_mm - camera_position_mm).normalized();
  check(std::abs(fwd.z()) < 0.99, "camera must not look straight up or down the axis");
  check(std::isfinite(camera_roll_rad), "camera roll must be finite");
  check(lasers.size() <= 8, "at most 8 lasers");
  for (const auto& l : lasers) {
    check(finite3(l.position_mm) && finite3(l.normal) && std::abs(l.normal.norm() - 1.0) < 1e-9,
          "laser '" + l.name + "' needs a finite position and a unit normal");
  }
  check(std::isfinite(line_sigma_mm) && line_sigma_mm > 0 && line_sigma_mm < 50,
        "line_sigma_mm must be in (0, 50)");
  for (double v :
       {laser_power, ambient, noise_sigma, shot_noise_gain, speckle_contrast, bloom_fraction})
    check(std::isfinite(v) && v >= 0.0, "laser_power, ambient and noise parameters must be >= 0");
  check(speckle_contrast <= 1.0 && bloom_fraction <= 1.0,
        "speckle_contrast and bloom_fraction must be <= 1");
  check(std::isfinite(bloom_radius_px) && bloom_radius_px > 0 && bloom_radius_px <= 8,
        "bloom_radius_px must be in (0, 8]");
  check(std::isfinite(platform_radius_mm) && platform_radius_mm > 0 &&
            std::isfinite(platform_height_mm),
        "platform radius must be positive and its height finite");
}

RigConfig RigConfig::from_yaml_text(const std::string& text, const std::string& source_name) {
  const detail::YamlReader rd(source_name);
  const YAML::Node root = rd.parse(text);
  RigConfig c = builtin_ciclop_rig();
  if (!root || root.IsNull()) return c;
  rd.check_keys(root, "rig",
                {"image", "intrinsics", "distortion", "camera", "lasers", "line_sigma_mm",
                 "laser_power", "ambient", "noise_sigma", "shot_noise_gain", "speckle_contrast",
                 "bloom_fraction", "bloom_radius_px", "platform", "seed"});
  auto opt_num = [&](const YAML::Node& map, const char* key, double& field, const std::string& w) {
    if (map[key]) field = rd.number(map[key], w + "." + key);
  };
  if (const auto n = root["image"]) {
    rd.check_keys(n, "image", {"width", "height"});
    if (n["width"]) c.width = rd.as<int>(n["width"], "image.width");
    if (n["height"]) c.height = rd.as<int>(n["height"], "image.height");
  }
  if (const auto n = root["intrinsics"]) {
    rd.check_keys(n, "intrinsics", {"fx", "fy", "cx", "cy"});
    opt_num(n, "fx", c.intrinsics.fx, "intrinsics");
    opt_num(n, "fy", c.intrinsics.fy, "intrinsics");
    opt_num(n, "cx", c.intrinsics.cx, "intrinsics");
    opt_num(n, "cy", c.intrinsics.cy, "intrinsics");
  }
  if (const auto n = root["distortion"]) {
    rd.check_keys(n, "distortion", {"k1", "k2", "p1", "p2", "k3"});
    opt_num(n, "k1", c.intrinsics.k1, "distortion");
    opt_num(n, "k2", c.intrinsics.k2, "distortion");
    opt_num(n, "p1", c.intrinsics.p1, "distortion");
    opt_num(n, "p2", c.intrinsics.p2, "distortion");
    opt_num(n, "k3", c.intrinsics.k3, "distortion");
  }
  if (const auto n = root["camera"]) {
    rd.check_keys(n, "camera", {"position_mm", "look_at_mm", "roll_deg"});
    if (n["position_mm"]) c.camera_position_mm = rd.vec3(n["position_mm"], "camera.position_mm");
    if (n["look_at_mm"]) c.camera_look_at_mm = rd.vec3(n["look_at_mm"], "camera.look_at_mm");
    if (n["roll_deg"]) c.camera_roll_rad = rd.number(n["roll_deg"], "camera.roll_deg") * kDeg;
  }
  if (const auto n = root["lasers"]) {
    if (!n.IsSequence()) rd.fail(n, "lasers must be a list");
    c.lasers.clear();
    for (const auto& l : n) {
      rd.check_keys(l, "laser", {"name", "position_mm", "normal"});
      LaserConfig lc;
      lc.name = l["name"] ? rd.as<std::string>(l["name"], "laser.name")
                          : "laser" + std::to_string(c.lasers.size());
      lc.position_mm = rd.vec3(rd.required(l, "position_mm", "laser"), "laser.position_mm");
      const Vector3d nrm = rd.vec3(rd.required(l, "normal", "laser"), "laser.normal");
      if (!(nrm.norm() > 1e-9)) rd.fail(l, "laser.normal must not be zero");
      lc.normal = nrm.normalized();
      c.lasers.push_back(lc);
    }
  }
  opt_num(root, "line_sigma_mm", c.line_sigma_mm, "rig");
  opt_num(root, "laser_power", c.laser_power, "rig");
  opt_num(root, "ambient", c.ambient, "rig");
  opt_num(root, "noise_sigma", c.noise_sigma, "rig");
  opt_num(root, "shot_noise_gain", c.shot_noise_gain, "rig");
  opt_num(root, "speckle_contrast", c.speckle_contrast, "rig");
  opt_num(root, "bloom_fraction", c.bloom_fraction, "rig");
  opt_num(root, "bloom_radius_px", c.bloom_radius_px, "rig");
  if (const auto n = root["platform"]) {
    rd.check_keys(n, "platform", {"enabled", "radius_mm", "height_mm", "color"});
    if (n["enabled"]) c.platform = rd.as<bool>(n["enabled"], "platform.enabled");
    opt_num(n, "radius_mm", c.platform_radius_mm, "platform");
    opt_num(n, "height_mm", c.platform_height_mm, "platform");
    if (n["color"]) {
      const Vector3d col = rd.vec3(n["color"], "platform.color");
      if ((col.array() < 0).any() || (col.array() > 255).any())
        rd.fail(n["color"], "platform.color must be 3 numbers in 0..255");
      c.platform_color = {static_cast<std::uint8_t>(col.x()), static_cast<std::uint8_t>(col.y()),
                          static_cast<std::uint8_t>(col.z())};
    }
  }
  if (root["seed"]) c.seed = rd.as<std::uint64_t>(root["seed"], "seed");
  validate_parsed_config(c, source_name);
  return c;
}

RigConfig RigConfig::from_yaml_file(const std::filesystem::path& path) {
  return from_yaml_text(read_config_text(path), path.string());
}

std::string RigConfig::to_yaml() const {
  std::ostringstream o;
  o << "image: {width: " << width << ", height: " << height << "}\n";
  o << camera_intrinsics_yaml(intrinsics);
  o << "camera: {position_mm: " << format_exact_vector3(camera_position_mm)
    << ", look_at_mm: " << format_exact_vector3(camera_look_at_mm)
    << ", roll_deg: " << format_exact_number(camera_roll_rad / kDeg) << "}\n";
  o << "lasers:\n";
  for (const auto& l : lasers)
    o << "  - {name: " << l.name << ", position_mm: " << format_exact_vector3(l.position_mm)
      << ", normal: " << format_exact_vector3(l.normal) << "}\n";
  o << "line_sigma_mm: " << format_exact_number(line_sigma_mm)
    << "\nlaser_power: " << format_exact_number(laser_power)
    << "\nambient: " << format_exact_number(ambient)
    << "\nnoise_sigma: " << format_exact_number(noise_sigma)
    << "\nshot_noise_gain: " << format_exact_number(shot_noise_gain)
    << "\nspeckle_contrast: " << format_exact_number(speckle_contrast)
    << "\nbloom_fraction: " << format_exact_number(bloom_fraction)
    << "\nbloom_radius_px: " << format_exact_number(bloom_radius_px) << "\n";
  o << "platform: {enabled: " << (platform ? "true" : "false")
    << ", radius_mm: " << format_exact_number(platform_radius_mm)
    << ", height_mm: " << format_exact_number(platform_height_mm) << ", color: ["
    << int(platform_color.r) << ", " << int(platform_color.g) << ", " << int(platform_color.b)
    << "]}\n";
  o << "seed: " << seed << "\n";
  return o.str();
}

RigConfig builtin_ciclop_rig() {
  RigConfig c;
  c.intrinsics = {1432.0, 1429.5, 641.3, 478.6, 0.06, -0.12, 4e-4, -3e-4, 0.0};
  c.camera_position_mm = {400.0, 0.0, 105.0};
  c.camera_look_at_mm = {0.0, 1.5, 103.0};
  c.camera_roll_rad = 0.3 * kDeg;
  const Vector3d axis_point(0.0, 0.0, 105.0);
  // Two lasers 30 degrees either side of the camera, their sheets meant to contain the axis,
  // mounted with a small tilt (0.4 deg) and a small miss of the axis (0.4 mm), as real ones are.
  for (int side : {-1, 1}) {
    LaserConfig l;
    l.name = side < 0 ? "left" : "right";
    const double a = side * 30.0 * kDeg;
    l.position_mm = axis_point + 400.0 * Vector3d(std::cos(a), std::sin(a), 0.0);
    const Vector3d in_plane = (l.position_mm - axis_point).normalized();
    Vector3d n = Vector3d::UnitZ().cross(in_plane).normalized();
    n = Eigen::AngleAxisd(0.4 * kDeg * side, in_plane) * n;
    l.normal = n.normalized();
    l.position_mm += 0.4 * side * l.normal;
    c.lasers.push_back(l);
  }
  return c;
}

RigConfig rig_at_size(RigConfig rig, int width, int height) {
  const double sx = static_cast<double>(width) / rig.width;
  const double sy = static_cast<double>(height) / rig.height;
  rig.intrinsics.fx *= sx;
  rig.intrinsics.cx = (rig.intrinsics.cx + 0.5) * sx - 0.5;
  rig.intrinsics.fy *= sy;
  rig.intrinsics.cy = (rig.intrinsics.cy + 0.5) * sy - 0.5;
  rig.width = width;
  rig.height = height;
  rig.validate();
  return rig;
}

// ---------------------------------------------------------------------------------------------
// Pattern

Vector3d ChessboardPattern::corner(int c, int r) const {
  return pose * Vector3d(c * square_mm, r * square_mm, 0.0);
}

ChessboardPattern ChessboardPattern::upright(double platform_height_mm, double bottom_mm,
                                             double offset_mm) {
  ChessboardPattern p;
  // Board x runs along +y of the object frame (left to right seen from +x), board y runs down
  // (-z), so the board's z = x cross y points to -x, away from the camera at angle 0 (OpenCV's
  // convention: the printed side is seen looking along +z).
  Eigen::Matrix3d r;
  r.col(0) = Vector3d::UnitY();
  r.col(1) = -Vector3d::UnitZ();
  r.col(2) = r.col(0).cross(r.col(1));
  p.pose.linear() = r;
  const double width = (p.corner_cols - 1) * p.square_mm;
  const double height = (p.corner_rows - 1) * p.square_mm;
  p.pose.translation() = Vector3d(offset_mm, -0.5 * width, platform_height_mm + bottom_mm + height);
  return p;
}

// ---------------------------------------------------------------------------------------------
// Rendering

struct TurntableCamera::SurfaceHit {
  double t = 0;
  Vector3d p_rig, n_rig, albedo;
  Kind kind = kNone;
};

struct TurntableCamera::HitBuffer {
  double angle = 0;
  int width = 0, height = 0;
  std::vector<Eigen::Vector3f> point, normal, albedo;
  std::vector<std::uint8_t> kind;
};

TurntableCamera::TurntableCamera(const Scene& scene, RigConfig rig)
    : scene_(scene), rig_(std::move(rig)) {
  rig_.validate();
  const Vector3d z = (rig_.camera_look_at_mm - rig_.camera_position_mm).normalized();
  const Vector3d x0 = z.cross(Vector3d::UnitZ()).normalized();
  const Vector3d y0 = z.cross(x0);
  const double cr = std::cos(rig_.camera_roll_rad), sr = std::sin(rig_.camera_roll_rad);
  const Vector3d x = cr * x0 + sr * y0, y = -sr * x0 + cr * y0;
  Eigen::Matrix3d r;
  r.row(0) = x;
  r.row(1) = y;
  r.row(2) = z;
  camera_from_rig_.setIdentity();
  camera_from_rig_.linear() = r;
  camera_from_rig_.translation() = -r * rig_.camera_position_mm;
  normalized_.resize(static_cast<std::size_t>(rig_.width) * rig_.height);
#pragma omp parallel for schedule(static)
  for (int yy = 0; yy < rig_.height; ++yy)
    for (int xx = 0; xx < rig_.width; ++xx)
      normalized_[static_cast<std::size_t>(yy) * rig_.width + xx] =
          rig_.intrinsics.pixel_to_normalized(Vector2d(xx, yy)).cast<float>();
}

TurntableCamera::~TurntableCamera() = default;

void TurntableCamera::set_pattern(std::optional<ChessboardPattern> pattern) {
  if (pattern) {
    check(pattern->corner_cols >= 2 && pattern->corner_rows >= 2 && pattern->square_mm > 0 &&
              pattern->margin_mm >= 0,
          "chessboard needs at least 2 x 2 corners and a positive square size");
  }
  pattern_ = std::move(pattern);
  if (pattern_) board_from_object_ = pattern_->pose.inverse();
  const std::lock_guard lock(cache_mutex_);
  cache_.reset();
}

std::optional<Vector2d> TurntableCamera::project(const Vector3d& p_rig) const {
  const Vector3d pc = camera_from_rig_ * p_rig;
  if (!(pc.z() > 1e-9)) return std::nullopt;
  return rig_.intrinsics.distort_to_pixel(Vector2d(pc.x() / pc.z(), pc.y() / pc.z()));
}

Vector3d TurntableCamera::pixel_ray(double u, double v) const {
  const Vector2d n = rig_.intrinsics.pixel_to_normalized(Vector2d(u, v));
  return (camera_from_rig_.linear().transpose() * Vector3d(n.x(), n.y(), 1.0)).normalized();
}

std::optional<TurntableCamera::SurfaceHit> TurntableCamera::cast(const Vector3d& origin_rig,
                                                                 const Vector3d& dir_rig,
                                                                 const Turn& turn) const {
  const Vector3d o = turn.to_object * origin_rig, d = turn.to_object * dir_rig;
  constexpr double kFar = 1e5;
  std::optional<SurfaceHit> best;
  if (pattern_) {
    const auto& pt = *pattern_;
    const Vector3d nb = pt.pose.linear().col(2);
    const double den = nb.dot(d);
    if (std::abs(den) > 1e-12) {
      const double t = nb.dot(pt.pose.translation() - o) / den;
      if (t > 1e-9) {
        const Vector3d q = board_from_object_ * (o + t * d);
        const double s = pt.square_mm, m = pt.margin_mm;
        if (q.x() >= -s - m && q.x() <= pt.corner_cols * s + m && q.y() >= -s - m &&
            q.y() <= pt.corner_rows * s + m) {
          SurfaceHit h;
          h.t = t;
          h.kind = kBoardHit;
          h.p_rig = origin_rig + t * dir_rig;
          const Vector3d n_obj = den < 0 ? nb : Vector3d(-nb);
          h.n_rig = turn.to_rig * n_obj;
          double a = 0.5;  // the back of the board is plain grey
          if (den > 0) {   // the printed side faces -z (OpenCV board convention)
            const bool inside = q.x() >= -s && q.x() <= pt.corner_cols * s && q.y() >= -s &&
                                q.y() <= pt.corner_rows * s;
            const long parity =
                static_cast<long>(std::floor(q.x() / s)) + static_cast<long>(std::floor(q.y() / s));
            a = (inside && parity % 2 == 0) ? pt.black_albedo : pt.white_albedo;
          }
          h.albedo = Vector3d::Constant(a);
          best = h;
        }
      }
    }
  } else {
    if (auto hit = scene_.intersect(o, d, 0.0, kFar)) {
      SurfaceHit h;
      h.t = hit->t;
      h.kind = kSceneHit;
      h.p_rig = origin_rig + hit->t * dir_rig;
      const Vector3d n = scene_.geometry(*hit).normal;
      h.n_rig = turn.to_rig * (n.dot(d) > 0 ? Vector3d(-n) : n);
      const Rgb8 c = scene_.color_at(hit->point);
      h.albedo = Vector3d(c.r, c.g, c.b) / 255.0;
      best = h;
    }
  }
  if (rig_.platform && std::abs(d.z()) > 1e-12) {
    const double t = (rig_.platform_height_mm - o.z()) / d.z();
    if (t > 1e-9 && (!best || t < best->t)) {
      const Vector3d q = o + t * d;
      if (q.head<2>().norm() <= rig_.platform_radius_mm) {
        SurfaceHit h;
        h.t = t;
        h.kind = kPlatformHit;
        h.p_rig = origin_rig + t * dir_rig;
        h.n_rig = d.z() < 0 ? Vector3d::UnitZ() : Vector3d(-Vector3d::UnitZ());
        h.albedo =
            Vector3d(rig_.platform_color.r, rig_.platform_color.g, rig_.platform_color.b) / 255.0;
        best = h;
      }
    }
  }
  return best;
}

TurntableCamera::Turn::Turn(double angle) : to_object(rot_z(-angle)), to_rig(rot_z(angle)) {}

bool TurntableCamera::laser_reaches(const Vector3d& p_rig, int laser, const Turn& turn) const {
  const Vector3d to_laser = rig_.lasers[laser].position_mm - p_rig;
  const double dist = to_laser.norm();
  const Vector3d dir = to_laser / dist;
  const auto h = cast(p_rig + kShadowOffsetMm * dir, dir, turn);
  return !h || h->t >= dist - 2 * kShadowOffsetMm;
}

std::shared_ptr<const TurntableCamera::HitBuffer> TurntableCamera::hits(double angle) const {
  {
    const std::lock_guard lock(cache_mutex_);
    if (cache_ && angle_bits(cache_->angle) == angle_bits(angle)) return cache_;
  }
  auto buf = std::make_shared<HitBuffer>();
  buf->angle = angle;
  buf->width = rig_.width;
  buf->height = rig_.height;
  const std::size_t n = static_cast<std::size_t>(rig_.width) * rig_.height;
  buf->point.assign(n, Eigen::Vector3f::Zero());
  buf->normal.assign(n, Eigen::Vector3f::Zero());
  buf->albedo.assign(n, Eigen::Vector3f::Zero());
  buf->kind.assign(n, kNone);
  const Eigen::Matrix3d rig_from_camera = camera_from_rig_.linear().transpose();
  const Vector3d c = rig_.camera_position_mm;
  const int w = rig_.width, hgt = rig_.height;
  const Turn turn(angle);
  auto normalized_at = [&](double u, double v) {
    // Bilinear interpolation of the per-pixel table (for anti-aliasing sub-samples).
    u = std::clamp(u, 0.0, w - 1.0);
    v = std::clamp(v, 0.0, hgt - 1.0);
    const int x0 = std::min(static_cast<int>(u), w - 2),
              y0 = std::min(static_cast<int>(v), hgt - 2);
    const double fu = u - x0, fv = v - y0;
    auto at = [&](int x, int y) {
      return normalized_[static_cast<std::size_t>(y) * w + x].cast<double>();
    };
    return Vector2d((1 - fv) * ((1 - fu) * at(x0, y0) + fu * at(x0 + 1, y0)) +
                    fv * ((1 - fu) * at(x0, y0 + 1) + fu * at(x0 + 1, y0 + 1)));
  };
#pragma omp parallel for schedule(dynamic, 4)
  for (int y = 0; y < hgt; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const Vector2d nm = normalized_[i].cast<double>();
      const Vector3d dir = (rig_from_camera * Vector3d(nm.x(), nm.y(), 1.0)).normalized();
      const auto h = cast(c, dir, turn);
      if (!h) continue;
      Vector3d albedo = h->albedo;
      bool near_edge = false;
      if (h->kind == kBoardHit && pattern_) {
        // Only pixels whose footprint may hold a printed edge need the box filter.
        const Vector3d q = board_from_object_ * (turn.to_object * h->p_rig);
        const double s = pattern_->square_mm, m = pattern_->margin_mm;
        const double footprint = 3.0 * h->t / std::min(rig_.intrinsics.fx, rig_.intrinsics.fy);
        auto near = [&](double v, double lo, double hi) {
          const double g = std::abs(std::remainder(v, s));
          return g < footprint || std::abs(v - (lo - m)) < footprint ||
                 std::abs(v - (hi + m)) < footprint;
        };
        near_edge = near(q.x(), -s, pattern_->corner_cols * s) ||
                    near(q.y(), -s, pattern_->corner_rows * s);
      }
      if (near_edge) {
        // Box-filter the printed squares over the pixel (3 x 3 samples).
        albedo.setZero();
        for (int sy = -1; sy <= 1; ++sy)
          for (int sx = -1; sx <= 1; ++sx) {
            const Vector2d q = normalized_at(x + sx / 3.0, y + sy / 3.0);
            const Vector3d ds = (rig_from_camera * Vector3d(q.x(), q.y(), 1.0)).normalized();
            const auto hs = cast(c, ds, turn);
            albedo += hs ? hs->albedo : Vector3d::Zero();
          }
        albedo /= 9.0;
      }
      buf->point[i] = h->p_rig.cast<float>();
      buf->normal[i] = h->n_rig.cast<float>();
      buf->albedo[i] = albedo.cast<float>();
      buf->kind[i] = h->kind;
    }
  }
  std::shared_ptr<const HitBuffer> result = std::move(buf);
  const std::lock_guard lock(cache_mutex_);
  cache_ = result;
  return result;
}

Image8 TurntableCamera::render(double angle, unsigned laser_mask) const {
  const auto buf = hits(angle);
  const Turn turn(angle);
  const int w = rig_.width, hgt = rig_.height;
  const std::size_t n = static_cast<std::size_t>(w) * hgt;
  const Vector3d cam = rig_.camera_position_mm;
  const std::uint64_t abits = angle_bits(angle);
  std::vector<float> base(n * 3, 0.0f), laser(n, 0.0f);
  const double sigma = rig_.line_sigma_mm;
  bool any_laser = false;
  for (int k = 0; k < laser_count(); ++k) any_laser = any_laser || ((laser_mask >> k) & 1u);
#pragma omp parallel for schedule(dynamic, 8)
  for (int y = 0; y < hgt; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (buf->kind[i] == kNone) {
        for (int ch = 0; ch < 3; ++ch) base[3 * i + ch] = static_cast<float>(kBackgroundDn);
        continue;
      }
      const Vector3d p = buf->point[i].cast<double>();
      const Vector3d nrm = buf->normal[i].cast<double>();
      const Vector3d a = buf->albedo[i].cast<double>();
      const double facing = std::max(0.0, nrm.dot((cam - p).normalized()));
      const double shade = rig_.ambient * (0.35 + 0.65 * facing);
      for (int ch = 0; ch < 3; ++ch)
        base[3 * i + ch] = static_cast<float>(kBackgroundDn + 245.0 * a[ch] * shade);
      if (!any_laser) continue;
      double lsum = 0.0;
      for (int k = 0; k < laser_count(); ++k) {
        if (!((laser_mask >> k) & 1u)) continue;
        const auto& l = rig_.lasers[k];
        const double f = l.signed_distance(p);
        if (std::abs(f) > 5.0 * sigma) continue;
        const double lit = nrm.dot((l.position_mm - p).normalized());
        if (lit <= 0.0 || !laser_reaches(p, k, turn)) continue;
        const double speckle = std::max(
            0.0, 1.0 + rig_.speckle_contrast *
                           detail::gaussian(detail::hash_key(rig_.seed, abits, k, i, kSpeckle)));
        lsum += rig_.laser_power * a[0] * lit * std::exp(-0.5 * f * f / (sigma * sigma)) * speckle;
      }
      laser[i] = static_cast<float>(lsum);
    }
  }
  // Blooming: light above saturation in the red channel spills into the neighbours (all
  // channels, symmetric, so it widens bright lines without moving their centre).
  std::vector<float> bloom(n, 0.0f);
  if (any_laser && rig_.bloom_fraction > 0.0) {
    const int rad = std::min(4, static_cast<int>(std::ceil(2.5 * rig_.bloom_radius_px)));
    std::vector<double> kern;
    double ksum = 0.0;
    for (int dy = -rad; dy <= rad; ++dy)
      for (int dx = -rad; dx <= rad; ++dx) {
        const double wgt =
            (dx == 0 && dy == 0) ? 0.0 : std::exp(-std::hypot(dx, dy) / rig_.bloom_radius_px);
        kern.push_back(wgt);
        ksum += wgt;
      }
    // Only saturated pixels bloom (a few thousand along the lines), so each spreads its excess
    // over its neighbours: O(saturated x kernel) instead of a kernel sum at every pixel. The
    // sums run serially in pixel order, so the frame is the same for any thread count.
    const double gain = rig_.bloom_fraction / ksum;
    for (std::size_t i = 0; i < n; ++i) {
      const float e = base[3 * i] + laser[i] - 255.0f;
      if (!(e > 0.0f)) continue;
      const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
      int ki = 0;
      for (int dy = -rad; dy <= rad; ++dy)
        for (int dx = -rad; dx <= rad; ++dx, ++ki) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= w || yy >= hgt) continue;
          bloom[static_cast<std::size_t>(yy) * w + xx] += static_cast<float>(gain * kern[ki] * e);
        }
    }
  }
  Image8 img(w, hgt, 3);
  const double laser_weight[3] = {1.0, kLaserGreen, kLaserBlue};
#pragma omp parallel for schedule(static)
  for (int y = 0; y < hgt; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      // One counter-based key per pixel, one mix per channel: the noise is still a pure
      // function of (seed, angle, lasers, pixel, channel), at a fraction of the hashing cost.
      const std::uint64_t key = detail::hash_key(rig_.seed, abits, laser_mask, i, kPixelNoise);
      for (int ch = 0; ch < 3; ++ch) {
        const double v = base[3 * i + ch] + laser_weight[ch] * laser[i] + bloom[i];
        const double sd = std::sqrt(rig_.noise_sigma * rig_.noise_sigma +
                                    rig_.shot_noise_gain * std::max(0.0, v));
        const double noisy = v + sd * detail::gaussian_from_bits(
                                          detail::mix64(key + static_cast<std::uint64_t>(ch)));
        img.pixels[3 * i + ch] =
            static_cast<std::uint8_t>(std::clamp(std::floor(noisy + 0.5), 0.0, 255.0));
      }
    }
  return img;
}

std::vector<LinePointTruth> TurntableCamera::laser_line_truth(double angle, int laser) const {
  if (laser < 0 || laser >= laser_count())
    throw InvalidInputError("turntable camera: no laser " + std::to_string(laser));
  const auto buf = hits(angle);
  const Turn turn(angle);
  const auto& l = rig_.lasers[laser];
  const int w = rig_.width, hgt = rig_.height;
  const Vector3d cam = rig_.camera_position_mm;
  std::vector<std::vector<LinePointTruth>> rows(hgt);
#pragma omp parallel for schedule(dynamic, 8)
  for (int y = 0; y < hgt; ++y) {
    for (int x = 0; x + 1 < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (buf->kind[i] == kNone || buf->kind[i + 1] == kNone) continue;
      const double f0 = l.signed_distance(buf->point[i].cast<double>());
      const double f1 = l.signed_distance(buf->point[i + 1].cast<double>());
      if ((f0 > 0) == (f1 > 0)) continue;
      // Illinois regula falsi on the exact ray casts along the row.
      double ua = x, ub = x + 1, fa = f0, fb = f1;
      int side = 0;
      std::optional<SurfaceHit> hit;
      double u = ua, fu = fa;
      for (int it = 0; it < 80; ++it) {
        u = (std::abs(fb - fa) > 0) ? (ua * fb - ub * fa) / (fb - fa) : 0.5 * (ua + ub);
        if (!(u > ua && u < ub)) u = 0.5 * (ua + ub);
        hit = cast(cam, pixel_ray(u, y), turn);
        if (!hit) break;
        fu = l.signed_distance(hit->p_rig);
        if (std::abs(fu) < 1e-10 || ub - ua < 1e-10) break;
        if ((fu > 0) == (fb > 0)) {
          ub = u;
          fb = fu;
          if (side == -1) fa *= 0.5;
          side = -1;
        } else {
          ua = u;
          fa = fu;
          if (side == 1) fb *= 0.5;
          side = 1;
        }
      }
      // A sign change across a depth jump converges to the jump, not to a point on the plane.
      if (!hit || std::abs(fu) > 1e-6) continue;
      if (hit->n_rig.dot((l.position_mm - hit->p_rig).normalized()) <= 0.0) continue;
      if (hit->n_rig.dot((cam - hit->p_rig).normalized()) <= 0.0) continue;
      if (!laser_reaches(hit->p_rig, laser, turn)) continue;
      LinePointTruth t;
      t.row = y;
      t.u = u;
      t.point_rig = hit->p_rig;
      t.point_object = turn.to_object * hit->p_rig;
      t.on_platform = hit->kind != kSceneHit;
      rows[y].push_back(t);
    }
  }
  std::vector<LinePointTruth> out;
  for (auto& r : rows) out.insert(out.end(), r.begin(), r.end());
  return out;
}

std::vector<std::optional<Vector2d>> TurntableCamera::pattern_corner_truth(double angle) const {
  if (!pattern_) throw InvalidInputError("turntable camera: no calibration pattern is set");
  const auto& pt = *pattern_;
  std::vector<std::optional<Vector2d>> out(static_cast<std::size_t>(pt.corner_cols) *
                                           pt.corner_rows);
  const Eigen::Matrix3d to_rig = rot_z(angle);
  const Vector3d normal = to_rig * pt.pose.linear().col(2);
  for (int r = 0; r < pt.corner_rows; ++r)
    for (int c = 0; c < pt.corner_cols; ++c) {
      const Vector3d p = to_rig * pt.corner(c, r);
      if (normal.dot(rig_.camera_position_mm - p) >= 0.0) continue;  // sees the back
      const auto uv = project(p);
      if (!uv || uv->x() < 0 || uv->y() < 0 || uv->x() > rig_.width - 1 ||
          uv->y() > rig_.height - 1)
        continue;
      out[static_cast<std::size_t>(r) * pt.corner_cols + c] = *uv;
    }
  return out;
}

ChessboardPattern place_on_platter(const ChessboardPattern& board, double platform_height_mm,
                                   double bottom_mm, const BoardPlacement& placement) {
  ChessboardPattern p = board;
  p.pose = ChessboardPattern::upright(platform_height_mm).pose;
  p.pose.translation() =
      Vector3d(placement.offset_mm, placement.shift_mm - 0.5 * (p.corner_cols - 1) * p.square_mm,
               platform_height_mm + bottom_mm + (p.corner_rows - 1) * p.square_mm);
  if (placement.tilt_rad != 0) {
    // Lean back about the bottom edge (the line x = offset on the platter top, along y): the
    // top moves away from the camera side (-x).
    const Vector3d hinge(placement.offset_mm, 0.0, platform_height_mm);
    Eigen::Isometry3d lean = Eigen::Isometry3d::Identity();
    lean.linear() = Eigen::AngleAxisd(-placement.tilt_rad, Vector3d::UnitY()).toRotationMatrix();
    lean.translation() = hinge - lean.linear() * hinge;
    p.pose = lean * p.pose;
  }
  return p;
}

std::vector<ChessboardPattern> handheld_board_poses(const CalibrationPlan& plan,
                                                    double platform_height_mm) {
  const ChessboardPattern up =
      place_on_platter(plan.board, platform_height_mm, plan.platter_bottom_mm,
                       BoardPlacement{.offset_mm = plan.platter_offset_mm});
  // Hand-held: the board tilted about its centre by up to ~30 degrees, moved toward the camera.
  const Vector3d centre_board(0.5 * (up.corner_cols - 1) * up.square_mm,
                              0.5 * (up.corner_rows - 1) * up.square_mm, 0.0);
  std::vector<ChessboardPattern> poses;
  for (int i = 0; i < plan.handheld_views; ++i) {
    // Spread over the image and over tilts up to ~35 degrees (golden-angle sequence).
    const double a = 2.399963 * i;
    const double f = (i + 0.5) / std::max(1, plan.handheld_views);
    const double tilt = 35.0 * kDeg * std::sqrt(f);
    const double tilt_x = tilt * std::cos(a), tilt_y = tilt * std::sin(a);
    const double roll = 10.0 * kDeg * std::sin(3.0 * a);
    ChessboardPattern p = up;
    const Eigen::Matrix3d r =
        (Eigen::AngleAxisd(tilt_x, Vector3d::UnitX()) *
         Eigen::AngleAxisd(tilt_y, Vector3d::UnitY()) * Eigen::AngleAxisd(roll, Vector3d::UnitZ()))
            .toRotationMatrix();
    const Vector3d centre_obj = up.pose * centre_board;
    const Vector3d moved =
        centre_obj + Vector3d(40.0 + 50.0 * std::sin(1.7 * a), 70.0 * std::cos(1.3 * a) * f,
                              45.0 + 45.0 * std::sin(2.1 * a) * f);
    p.pose.linear() = up.pose.linear() * r;
    p.pose.translation() = moved - p.pose.linear() * centre_board;
    poses.push_back(p);
  }
  return poses;
}

std::vector<CalibrationShot> render_calibration_shots(TurntableCamera& camera,
                                                      const CalibrationPlan& plan) {
  const auto saved = camera.pattern();
  const double ph = camera.rig().platform_height_mm;
  std::vector<CalibrationShot> shots;
  for (const ChessboardPattern& p : handheld_board_poses(plan, ph)) {
    camera.set_pattern(p);
    CalibrationShot s;
    s.image = camera.render(0.0, 0u);
    if (plan.handheld_lasers)
      for (int k = 0; k < camera.laser_count(); ++k)
        s.laser_on.push_back(camera.render(0.0, 1u << k));
    s.pattern = p;
    shots.push_back(std::move(s));
  }
  std::vector<double> angles = plan.platter_angles_rad;
  if (angles.empty())
    for (int d = -70; d <= 70; d += 10) angles.push_back(d * kDeg);
  std::vector<BoardPlacement> placements = plan.placements;
  if (placements.empty()) placements.push_back({.offset_mm = plan.platter_offset_mm});
  for (std::size_t k = 0; k < placements.size(); ++k) {
    const ChessboardPattern up =
        place_on_platter(plan.board, ph, plan.platter_bottom_mm, placements[k]);
    camera.set_pattern(up);
    for (double a : angles) {
      CalibrationShot s;
      s.on_turntable = true;
      s.angle_rad = a;
      s.image = camera.render(a, 0u);
      for (int l = 0; l < camera.laser_count(); ++l)
        s.laser_on.push_back(camera.render(a, 1u << l));
      s.pattern = up;
      s.placement = static_cast<int>(k);
      shots.push_back(std::move(s));
    }
  }
  camera.set_pattern(saved);
  return shots;
}

}  // namespace scanmesh::sim
