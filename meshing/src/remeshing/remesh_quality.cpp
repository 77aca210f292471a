// Quality report and pictures of a remeshing result (seed 001 §5.3).
#include "scanmesh/meshing/remeshing/remesh_quality.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/histogram_picture.h"
#include "scanmesh/core/render.h"
#include "scanmesh/meshing/mesh_check.h"

#include "../kernel/triangle_grid.h"

namespace scanmesh::remeshing {

namespace {

using Vec3 = Eigen::Vector3d;

// Nearest-triangle distances: the kernel's triangle grid searched shell by shell.
class NearestTriangle {
 public:
  explicit NearestTriangle(const Mesh& m)
      : m_(m), grid_(layout_for(m), boxes(m, true), boxes(m, false)) {}

  double distance(const Vec3& p) const {
    const auto c = grid_.cell_of(p);
    const auto& n = grid_.layout().dims;
    const double cell = grid_.layout().cell;
    double best = std::numeric_limits<double>::max();
    const long long maxr = std::max({n[0], n[1], n[2]});
    for (long long r = 0; r <= maxr; ++r) {
      // Everything within r cells is checked; the rest is at least r * cell away from p's cell.
      if (r > 0 && best < std::pow(static_cast<double>(r - 1) * cell, 2)) break;
      for (long long z = c[2] - r; z <= c[2] + r; ++z)
        for (long long y = c[1] - r; y <= c[1] + r; ++y)
          for (long long x = c[0] - r; x <= c[0] + r; ++x) {
            if (std::max({std::abs(x - c[0]), std::abs(y - c[1]), std::abs(z - c[2])}) != r)
              continue;
            if (x < 0 || y < 0 || z < 0 || x >= n[0] || y >= n[1] || z >= n[2]) continue;
            for (const int f : grid_.triangles_in(grid_.flat(x, y, z))) {
              const auto& t = m_.triangles[f];
              best = std::min(
                  best, point_triangle_squared_distance(p, m_.positions[t[0]], m_.positions[t[1]],
                                                        m_.positions[t[2]]));
            }
          }
    }
    return std::sqrt(best);
  }

 private:
  // Cells of about two mean edges hold a handful of faces each on a surface; a cell from the
  // box's volume per face held ~160 faces of the demo head, and a query tests 27 cells. At most
  // ~8 cells per face, and no more than 512 along an axis.
  static kernel::TriangleGrid::Layout layout_for(const Mesh& m) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max());
    Vec3 hi = -lo;
    for (const auto& p : m.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Vec3 ext = (hi - lo).cwiseMax(1e-9);
    const double faces = std::max<double>(1, static_cast<double>(m.triangles.size()));
    double edge_sum = 0;
    for (const auto& t : m.triangles) edge_sum += (m.positions[t[0]] - m.positions[t[1]]).norm();
    double cell = 2 * edge_sum / faces;
    cell = std::max({cell, std::cbrt(ext.prod() / (8 * faces)), ext.maxCoeff() / 512, 1e-9});
    kernel::TriangleGrid::Layout layout{lo, cell, {}};
    for (int i = 0; i < 3; ++i)
      layout.dims[i] = std::max(1, static_cast<int>(std::ceil(ext[i] / cell)));
    return layout;
  }
  // The triangles' box corners: the lower ones or the upper ones.
  static std::vector<Vec3> boxes(const Mesh& m, bool lower) {
    std::vector<Vec3> out(m.triangles.size());
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
      const auto& t = m.triangles[f];
      Vec3 c = m.positions[t[0]];
      for (int k : t)
        c = lower ? Vec3(c.cwiseMin(m.positions[k])) : Vec3(c.cwiseMax(m.positions[k]));
      out[f] = c;
    }
    return out;
  }

  const Mesh& m_;
  kernel::TriangleGrid grid_;
};

Rgb8 ramp(double t) {  // blue -> cyan -> yellow -> red
  t = std::clamp(t, 0.0, 1.0);
  const double r = std::clamp(2 * t - 0.5, 0.0, 1.0) * 255;
  const double g = std::clamp(t < 0.5 ? 2 * t : 2 - 2 * t + 0.4, 0.0, 1.0) * 255;
  const double b = std::clamp(1 - 2 * t, 0.0, 1.0) * 255;
  return {static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g), static_cast<std::uint8_t>(b)};
}

// Distinct neighbours per vertex.
std::vector<int> valences(const Mesh& m) {
  std::vector<std::vector<int>> nb(m.positions.size());
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (i != j) nb[t[i]].push_back(t[j]);
  std::vector<int> valence(nb.size());
  for (std::size_t v = 0; v < nb.size(); ++v) {
    std::sort(nb[v].begin(), nb[v].end());
    valence[v] = static_cast<int>(std::unique(nb[v].begin(), nb[v].end()) - nb[v].begin());
  }
  return valence;
}

// The mesh from the default view and turned by 90 deg, side by side.
Image8 two_views(const Mesh& s, int view_size, bool wireframe) {
  RenderOptions o;
  o.width = o.height = view_size;
  o.draw_wireframe = wireframe;
  Image8 a = render_mesh(s, o);
  o.azimuth_deg += 90;
  return hconcat({a, render_mesh(s, o)});
}

}  // namespace

std::array<double, 2> sampled_distance(const Mesh& a, const Mesh& b) {
  std::vector<Vec3> samples = a.positions;
  for (const auto& t : a.triangles) {
    const Vec3 &p = a.positions[t[0]], &q = a.positions[t[1]], &r = a.positions[t[2]];
    samples.push_back((p + q + r) / 3);
    samples.push_back(0.5 * (p + q));
    samples.push_back((4 * p + q + r) / 6);
  }
  const NearestTriangle grid(b);
  std::vector<double> d(samples.size());
#pragma omp parallel for schedule(dynamic, 1024)
  for (std::size_t i = 0; i < samples.size(); ++i) d[i] = grid.distance(samples[i]);
  double mx = 0, sum = 0;
  for (double x : d) {
    mx = std::max(mx, x);
    sum += x;
  }
  return {mx, d.empty() ? 0.0 : sum / static_cast<double>(d.size())};
}

int optimal_valence(VertexKind kind, int sides) {
  if (kind == VertexKind::Free) return 6;
  if (kind == VertexKind::Skeleton) return 2 * sides + 2;
  return 0;
}

RemeshQuality evaluate_remesh(const Mesh& input, const RemeshResult& r, bool check_si) {
  RemeshQuality q;
  const Mesh& m = r.mesh;
  q.vertices = m.positions.size();
  q.faces = m.triangles.size();
  double amin = 10, asum = 0, qsum = 0;
  std::size_t ge30 = 0;
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
    const double ang = triangle_min_angle(a, b, c);
    amin = std::min(amin, ang);
    asum += ang;
    if (ang >= std::numbers::pi / 6 - 1e-12) {
      ++ge30;
    } else if (r.kind.size() == m.positions.size()) {
      int worst = 0;  // 3 branch, 2 boundary, 1 other skeleton, 0 free
      for (int v : t) {
        if (r.kind[v] == VertexKind::Branch) worst = std::max(worst, 3);
        if (r.kind[v] == VertexKind::Skeleton) worst = std::max(worst, r.sides[v] == 1 ? 2 : 1);
      }
      ++(worst == 3   ? q.bad_at_branch
         : worst == 2 ? q.bad_at_boundary
         : worst == 1 ? q.bad_at_skeleton
                      : q.bad_interior);
    }
    q.angle_histogram[std::clamp(static_cast<int>(ang * 180 / std::numbers::pi / 5), 0, 11)]++;
    const double ar = aspect_ratio(a, b, c);
    qsum += std::min(ar, 1e6);
    q.aspect_ratio_max = std::max(q.aspect_ratio_max, ar);
    q.aspect_ratio_histogram[std::clamp(static_cast<int>((ar - 1) * 10), 0, 9)]++;
  }
  const double nf = std::max<double>(1, static_cast<double>(q.faces));
  q.min_angle_deg = amin * 180 / std::numbers::pi;
  q.mean_min_angle_deg = asum / nf * 180 / std::numbers::pi;
  q.fraction_min_angle_ge_30 = static_cast<double>(ge30) / nf;
  q.aspect_ratio_mean = qsum / nf;
  const std::vector<int> valence = valences(m);
  for (std::size_t v = 0; v < q.vertices; ++v) {
    const int opt = optimal_valence(r.kind[v], r.sides[v]);
    if (opt == 0) continue;
    ++q.valence_counted;
    q.valence_optimal += valence[v] == opt;
  }
  q.fraction_irregular =
      q.valence_counted ? 1.0 - static_cast<double>(q.valence_optimal) / q.valence_counted : 0.0;
  const auto d1 = sampled_distance(m, input), d2 = sampled_distance(input, m);
  q.hausdorff_out_to_in = d1[0];
  q.hausdorff_in_to_out = d2[0];
  q.hausdorff = std::max(d1[0], d2[0]);
  q.mean_distance = d1[1];
  Vec3 lo = input.positions[0], hi = lo;
  for (const auto& p : input.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  q.bbox_diagonal = (hi - lo).norm();
  if (check_si) {
    const MeshCheckReport rep = check_mesh(m, {.self_intersections = true});
    q.self_intersections_checked = true;
    q.self_intersections = rep.self_intersections;
  }
  return q;
}

std::string RemeshQuality::to_json() const {
  // Ordered: the report reads top-down from counts to angles, valences and distances.
  nlohmann::ordered_json j;
  j["vertices"] = vertices;
  j["faces"] = faces;
  j["min_angle_deg"] = min_angle_deg;
  j["mean_min_angle_deg"] = mean_min_angle_deg;
  j["below_30_at"] = {{"branch", bad_at_branch},
                      {"boundary", bad_at_boundary},
                      {"skeleton", bad_at_skeleton},
                      {"interior", bad_interior}};
  j["fraction_min_angle_ge_30"] = fraction_min_angle_ge_30;
  j["aspect_ratio_mean"] = aspect_ratio_mean;
  // A degenerate face has Q = infinity, which JSON cannot hold.
  j["aspect_ratio_max"] = std::isfinite(aspect_ratio_max) ? aspect_ratio_max : 1e308;
  j["aspect_ratio_histogram"] = aspect_ratio_histogram;
  j["min_angle_histogram_5deg"] = angle_histogram;
  j["valence_counted"] = valence_counted;
  j["valence_optimal"] = valence_optimal;
  j["fraction_irregular"] = fraction_irregular;
  j["hausdorff_mm"] = hausdorff;
  j["hausdorff_output_to_input_mm"] = hausdorff_out_to_in;
  j["hausdorff_input_to_output_mm"] = hausdorff_in_to_out;
  j["mean_distance_mm"] = mean_distance;
  j["bbox_diagonal_mm"] = bbox_diagonal;
  j["self_intersections"] =
      self_intersections_checked ? nlohmann::ordered_json(self_intersections) : nullptr;
  return j.dump(2) + "\n";
}

Image8 render_quality(const RemeshResult& r, int view_size) {
  const Mesh& m = r.mesh;
  const std::vector<int> valence = valences(m);
  std::vector<int> mark(m.positions.size(), 0);
  for (std::size_t v = 0; v < valence.size(); ++v)
    if (const int opt = optimal_valence(r.kind[v], r.sides[v]))
      mark[v] = valence[v] > opt ? 1 : (valence[v] < opt ? -1 : 0);
  // Unshared corners so each face has its own colour; irregular corners white / black.
  Mesh s;
  for (const auto& t : m.triangles) {
    const double q = aspect_ratio(m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]);
    const Rgb8 c = ramp(q - 1);
    const int base = static_cast<int>(s.positions.size());
    for (int k = 0; k < 3; ++k) {
      s.positions.push_back(m.positions[t[k]]);
      s.colors.push_back(mark[t[k]] > 0 ? Rgb8{255, 255, 255} : mark[t[k]] < 0 ? Rgb8{0, 0, 0} : c);
    }
    s.triangles.push_back({base, base + 1, base + 2});
  }
  return two_views(s, view_size, true);
}

Image8 render_density(const Mesh& input, const std::vector<double>& density, int view_size) {
  if (density.size() != input.positions.size())
    throw InvalidInputError("render_density: " + std::to_string(density.size()) +
                            " density values for " + std::to_string(input.positions.size()) +
                            " vertices");
  double lo = 1e300, hi = -1e300;
  for (double p : density) {
    lo = std::min(lo, std::log(p));
    hi = std::max(hi, std::log(p));
  }
  Mesh s = input;
  s.colors.resize(input.positions.size());
  for (std::size_t v = 0; v < density.size(); ++v)
    s.colors[v] = ramp(hi > lo ? (std::log(density[v]) - lo) / (hi - lo) : 0.5);
  return two_views(s, view_size, false);
}

Image8 quality_histograms(const RemeshQuality& q) {
  std::vector<std::string> q_labels, angle_labels;
  for (std::size_t i = 0; i < q.aspect_ratio_histogram.size(); ++i)
    q_labels.push_back(i + 1 < q.aspect_ratio_histogram.size() ? "1." + std::to_string(i) : "1.9+");
  for (std::size_t i = 0; i < q.angle_histogram.size(); ++i)
    angle_labels.push_back(std::to_string(5 * i));
  // Green: Q below 1.9 (about a 30-30-120 deg triangle has Q = 2) and min angles from 30 deg.
  return hconcat({histogram_picture(q.aspect_ratio_histogram, q_labels,
                                    "ASPECT RATIO Q = R_CIRC / 2 R_IN", {.begin = 0, .end = 9}),
                  histogram_picture(q.angle_histogram, angle_labels, "MIN ANGLE PER TRIANGLE [DEG]",
                                    {.begin = 6, .end = q.angle_histogram.size()})},
                 {255, 255, 255});
}

}  // namespace scanmesh::remeshing
