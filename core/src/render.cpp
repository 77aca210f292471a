#include "scanmesh/core/render.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

constexpr Rgb8 kClay{200, 190, 175};
// Back faces (the inside, seen through a hole, or a flipped triangle) in one slate blue whatever
// the vertex colour: a tint of the colour (the old 0.45/0.5/0.9 factor) turned skin purple where
// the inside of a scanned head showed through its holes, and read as a wrong colour.
const Eigen::Vector3d kBackFace(0.045, 0.06, 0.13);  // linear RGB

struct Camera {
  Eigen::Vector3d forward, right, up;  // forward points from the camera into the scene
  Eigen::Vector3d center;
  double scale = 1.0;  // pixels per millimetre
  int width = 0, height = 0;

  Eigen::Vector3d project(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - center;
    // x right, y down, depth increases away from the camera.
    return {width * 0.5 + scale * d.dot(right), height * 0.5 - scale * d.dot(up), d.dot(forward)};
  }
};

Camera make_camera(const Mesh& mesh, const RenderOptions& o) {
  const double az = o.azimuth_deg * std::numbers::pi / 180.0;
  const double el = o.elevation_deg * std::numbers::pi / 180.0;
  Camera cam;
  const Eigen::Vector3d to_camera(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                  std::sin(el));
  cam.forward = -to_camera;
  cam.right = cam.forward.cross(Eigen::Vector3d::UnitZ());
  if (cam.right.norm() < 1e-9) cam.right = Eigen::Vector3d::UnitY();
  cam.right.normalize();
  cam.up = cam.right.cross(cam.forward).normalized();
  cam.width = o.width;
  cam.height = o.height;
  Eigen::AlignedBox3d box;
  for (const auto& p : mesh.positions) box.extend(p);
  cam.center =
      box.isEmpty() ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(box.center());
  double half_w = 1e-9, half_h = 1e-9;
  for (const auto& p : mesh.positions) {
    const Eigen::Vector3d d = p - cam.center;
    half_w = std::max(half_w, std::abs(d.dot(cam.right)));
    half_h = std::max(half_h, std::abs(d.dot(cam.up)));
  }
  const double usable = 1.0 - 2.0 * o.margin;
  cam.scale = std::min(o.width * 0.5 * usable / half_w, o.height * 0.5 * usable / half_h);
  return cam;
}

struct Shader {
  Eigen::Vector3d to_camera, key_light, fill_light;

  Eigen::Vector3d shade(Eigen::Vector3d n, const Eigen::Vector3d& albedo) const {
    const bool back = n.dot(to_camera) < 0;
    if (back) n = -n;
    const double key = std::max(0.0, n.dot(key_light));
    const double fill = std::max(0.0, n.dot(fill_light));
    const double light = 0.22 + 0.65 * key + 0.25 * fill;
    if (back) return kBackFace * light;
    const Eigen::Vector3d half = (key_light + to_camera).normalized();
    const double spec = std::pow(std::max(0.0, n.dot(half)), 40.0) * 0.25;
    return albedo * light + Eigen::Vector3d::Constant(spec);
  }
};

Eigen::Vector3d to_linear(Rgb8 c) {
  auto lin = [](std::uint8_t v) { return std::pow(v / 255.0, 2.2); };
  return {lin(c.r), lin(c.g), lin(c.b)};
}

std::uint8_t to_srgb(double v) {
  return static_cast<std::uint8_t>(
      std::lround(255.0 * std::pow(std::clamp(v, 0.0, 1.0), 1.0 / 2.2)));
}

class Rasteriser {
 public:
  Rasteriser(const Mesh& mesh, const RenderOptions& o)
      : mesh_(mesh),
        options_(o),
        camera_(make_camera(mesh, o)),
        image_(o.width, o.height, 3),
        depth_(static_cast<std::size_t>(o.width) * o.height,
               std::numeric_limits<double>::infinity()) {
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x) image_.set_rgb(x, y, o.background);
    const Eigen::Vector3d to_cam = -camera_.forward;
    shader_ = {to_cam, (to_cam + 0.6 * camera_.up + 0.5 * camera_.right).normalized(),
               (to_cam - 0.3 * camera_.up - 0.7 * camera_.right).normalized()};
    projected_.reserve(mesh.positions.size());
    for (const auto& p : mesh.positions) projected_.push_back(camera_.project(p));
  }

  Image8 run() {
    if (mesh_.triangles.empty()) {
      draw_points();
      return std::move(image_);
    }
    // A copy of an earlier triangle draws the same pixels: drawn once, so that a file of
    // 100,000 copies of one large triangle costs one triangle's fill, not 100,000.
    const std::vector<char> repeats = faces_repeating_earlier_geometry(mesh_);
    for (std::size_t f = 0; f < mesh_.triangles.size(); ++f)
      if (!repeats[f]) draw_triangle(f);
    return std::move(image_);
  }

 private:
  Eigen::Vector3d vertex_normal(int v, const Eigen::Vector3d& face_normal) const {
    return mesh_.has_normals() ? Eigen::Vector3d(mesh_.normals[v].cast<double>()) : face_normal;
  }
  Eigen::Vector3d albedo(int v) const {
    return options_.use_vertex_colors && mesh_.has_colors() ? to_linear(mesh_.colors[v])
                                                            : to_linear(kClay);
  }

  void draw_triangle(std::size_t f) {
    const auto& t = mesh_.triangles[f];
    const Eigen::Vector3d &a = projected_[t[0]], &b = projected_[t[1]], &c = projected_[t[2]];
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) return;
    Eigen::Vector3d face_n = (mesh_.positions[t[1]] - mesh_.positions[t[0]])
                                 .cross(mesh_.positions[t[2]] - mesh_.positions[t[0]]);
    face_n.normalize();
    const bool back_facing = face_n.dot(shader_.to_camera) < 0;
    std::array<Eigen::Vector3d, 3> n, col;
    for (int k = 0; k < 3; ++k) {
      n[k] = vertex_normal(t[k], face_n);
      // Vertex normals follow the front side; flip them with the face so back faces read as back.
      if (back_facing == (n[k].dot(shader_.to_camera) >= 0)) n[k] = -n[k];
      col[k] = albedo(t[k]);
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 =
        std::min(options_.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 =
        std::min(options_.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      // The row's span inside the triangle, from the three edge functions (each linear in x),
      // widened by a pixel: the exact per-pixel test below decides, and a long sliver costs
      // its rows plus its pixels instead of its whole bounding box (a 1M-triangle fan: 38 s).
      int xa = x0, xb = x1;
      narrow_to_row(a, b, c, y + 0.5, xa, xb);
      for (int x = xa; x <= xb; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
        const double w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double z = w0 * a.z() + w1 * b.z() + w2 * c.z();
        double& zbuf = depth_[static_cast<std::size_t>(y) * options_.width + x];
        if (z >= zbuf) continue;
        zbuf = z;
        const Eigen::Vector3d normal = (w0 * n[0] + w1 * n[1] + w2 * n[2]).normalized();
        Eigen::Vector3d rgb = shader_.shade(normal, w0 * col[0] + w1 * col[1] + w2 * col[2]);
        if (options_.draw_wireframe && std::min({w0, w1, w2}) < 0.04) rgb *= 0.35;
        image_.set_rgb(x, y, {to_srgb(rgb.x()), to_srgb(rgb.y()), to_srgb(rgb.z())});
      }
    }
  }

  // Narrows [xa, xb] to the pixels of row centre py that can lie in triangle (a, b, c): where
  // the row crosses the triangle's edges. A row that misses it gets an empty range.
  static void narrow_to_row(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c, double py, int& xa, int& xb) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& [p, q] : {std::pair{&a, &b}, std::pair{&b, &c}, std::pair{&c, &a}}) {
      const double ya = p->y(), yb = q->y();
      if ((py < std::min(ya, yb)) || (py > std::max(ya, yb))) continue;
      const double x =
          ya == yb ? std::min(p->x(), q->x()) : p->x() + (py - ya) * (q->x() - p->x()) / (yb - ya);
      const double x_other = ya == yb ? std::max(p->x(), q->x()) : x;
      lo = std::min(lo, x);
      hi = std::max(hi, x_other);
    }
    if (!(lo <= hi)) {
      xb = xa - 1;
      return;
    }
    xa = std::max(xa, static_cast<int>(std::floor(lo)) - 1);
    xb = std::min(xb, static_cast<int>(std::ceil(hi)) + 1);
  }

  // A point cloud (no triangles): every point a round splat, z-buffered, sized so that the
  // splats of a surface sampled evenly over the picture about close up (0.7 of the mean spacing
  // the points would have spread over the object's projected box, 1..6 pixels). Shaded by its
  // normal where the cloud has normals; otherwise lit evenly, nearer points brighter.
  void draw_points() {
    const std::size_t n = mesh_.positions.size();
    if (n == 0) return;
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, z0 = 1e300, z1 = -1e300;
    for (const auto& p : projected_) {
      x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
      z0 = std::min(z0, p.z()), z1 = std::max(z1, p.z());
    }
    const double box = std::max(1.0, (x1 - x0) * (y1 - y0));
    const double radius = std::clamp(0.7 * std::sqrt(box / static_cast<double>(n)), 1.0, 6.0);
    const int reach = static_cast<int>(std::ceil(radius));
    const double depth_span = std::max(z1 - z0, 1e-12);
    for (std::size_t v = 0; v < n; ++v) {
      const Eigen::Vector3d& c = projected_[v];
      Eigen::Vector3d rgb;
      if (mesh_.has_normals()) {
        // Points have no front or back: each is lit from the side facing the camera.
        Eigen::Vector3d normal = mesh_.normals[v].cast<double>();
        if (normal.dot(shader_.to_camera) < 0) normal = -normal;
        rgb = shader_.shade(normal, albedo(static_cast<int>(v)));
      } else {
        rgb = albedo(static_cast<int>(v)) * (1.0 - 0.6 * (c.z() - z0) / depth_span);
      }
      const Rgb8 colour{to_srgb(rgb.x()), to_srgb(rgb.y()), to_srgb(rgb.z())};
      const int cx = static_cast<int>(std::floor(c.x())), cy = static_cast<int>(std::floor(c.y()));
      for (int y = std::max(0, cy - reach); y <= std::min(options_.height - 1, cy + reach); ++y)
        for (int x = std::max(0, cx - reach); x <= std::min(options_.width - 1, cx + reach); ++x) {
          const double dx = x + 0.5 - c.x(), dy = y + 0.5 - c.y();
          if (dx * dx + dy * dy > radius * radius) continue;
          double& zbuf = depth_[static_cast<std::size_t>(y) * options_.width + x];
          if (c.z() >= zbuf) continue;
          zbuf = c.z();
          image_.set_rgb(x, y, colour);
        }
    }
  }

  const Mesh& mesh_;
  const RenderOptions& options_;
  Camera camera_;
  Shader shader_;
  Image8 image_;
  std::vector<double> depth_;
  std::vector<Eigen::Vector3d> projected_;
};

}  // namespace

Image8 render_mesh(const Mesh& mesh, const RenderOptions& options) {
  if (options.width < 16 || options.height < 16 || options.width > 8192 || options.height > 8192)
    throw InvalidInputError("render: image size must be 16..8192 pixels, got " +
                            std::to_string(options.width) + " x " + std::to_string(options.height));
  mesh.validate();
  return Rasteriser(mesh, options).run();
}

Image8 hconcat(const std::vector<Image8>& images, Rgb8 background) {
  int width = 0, height = 0;
  for (const auto& im : images) {
    width += im.width;
    height = std::max(height, im.height);
  }
  Image8 out(std::max(width, 1), std::max(height, 1), 3);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) out.set_rgb(x, y, background);
  int x_offset = 0;
  for (const auto& im : images) {
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) out.set_rgb(x_offset + x, y, im.rgb(x, y));
    x_offset += im.width;
  }
  return out;
}

}  // namespace scanmesh
