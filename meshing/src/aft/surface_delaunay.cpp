// The alternative region mesher: surface Delaunay refinement after Chew (seed 000 §4.3.4,
// [Che93]) — the thesis's own recommendation. docs/animation-meshes.md "Surface Delaunay".
//
// Start from the constrained Delaunay triangulation of the region's boundary nodes, then insert
// the surface circumcentre (Def. 4.5: the centre of the sphere through the three points that lies
// on the surface) of every non-ideal triangle — min angle < 30° or larger than the size
// bound — largest first, until none is left. Decisions where this project differs from Chew:
// - Segment edges are shared with the neighbouring regions and must not be split (the AFT keeps
//   them too), so a circumcentre that lies outside the region, behind a constraint edge, or too
//   close to an existing node is not inserted and its triangle is left as it is (counted).
//   Chew would split the constraint instead.
// - Only the start — the constrained Delaunay triangulation of the boundary nodes — is built in
//   the region's (phi, h) plane (phi scaled by the region's mean radius; CGAL). Everything after
//   runs on the surface in 3D: the triangulation is made Delaunay by Lawson flips with the
//   max-min-angle rule evaluated on the 3D triangles (the plane metric is badly distorted on
//   steep flanks such as ears and nose, where a plane CDT refines without end), a circumcentre
//   is located by walking across 3D triangles from its bad triangle (stopping at a segment
//   edge = "separated by a constraint"), and every size and angle measure is 3D.
// - A region that winds all the way around the axis has no planar parameter domain: it is
//   meshed by the AFT instead (RegionMeshStats::mesher says which mesher ran).
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "aft_internal.h"

namespace scanmesh::aft::detail {

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
//! The NodeStore index of a triangulation vertex (-1: not assigned yet).
struct NodeTag {
  int node = -1;
};
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<NodeTag, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
// Boundary chords never cross (regions are faces of a planar graph), so constraint
// intersections are an error, not something to construct.
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<
    Kernel, Tds, CGAL::No_constraint_intersection_requiring_constructions_tag>;
using Point = Kernel::Point_2;

constexpr double kMinAngle = 30.0 * M_PI / 180.0;  // Chew's bound

//! Planar circumcentre of a 3D triangle and its radius; nullopt for a degenerate triangle.
std::optional<std::pair<Vector3d, double>> circumcircle(const Vector3d& a, const Vector3d& b,
                                                        const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, n = ab.cross(ac);
  const double n2 = n.squaredNorm();
  if (n2 < 1e-24) return std::nullopt;
  const Vector3d to_centre =
      (ac.squaredNorm() * n.cross(ab) + ab.squaredNorm() * ac.cross(n)) / (2.0 * n2);
  return std::make_pair(a + to_centre, to_centre.norm());
}

bool inside_polygons(const Vector2d& p, const std::vector<std::vector<Vector2d>>& polygons) {
  bool inside = false;  // even-odd over the outer boundary and the holes
  for (const auto& poly : polygons)
    for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
      const Vector2d &a = poly[i], &b = poly[j];
      if ((a.y() > p.y()) != (b.y() > p.y()) &&
          p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
        inside = !inside;
    }
  return inside;
}

class SurfaceDelaunayMesher {
 public:
  SurfaceDelaunayMesher(NodeStore& nodes, const ScanSurface& surface, const RegionMeshInput& in,
                        RegionMeshStats& stats)
      : N_(nodes), S_(surface), in_(in), stats_(stats) {}

  //! Empty optional: the region has no planar parameter domain (caller falls back to the AFT).
  std::optional<std::vector<std::array<int, 3>>> run() {
    if (in_.front.empty() || in_.polygons.empty()) return std::vector<std::array<int, 3>>{};
    if (!choose_parameter_frame()) return std::nullopt;
    if (!insert_boundary()) return std::nullopt;
    if (!refine()) return std::nullopt;
    return triangles();
  }

 private:
  // The unwrapping reference and the phi scale: phi near phi_ref_, x = phi * scale_.
  bool choose_parameter_frame() {
    phi_ref_ = in_.polygons.front().front().x();
    for (const auto& poly : in_.polygons) {
      double winding = 0;  // total phi travelled around the closed polygon
      for (std::size_t i = 0; i < poly.size(); ++i)
        winding += wrap_angle(poly[(i + 1) % poly.size()].x() - poly[i].x());
      if (std::abs(winding) > M_PI) return false;  // goes once around the axis
    }
    double radius_sum = 0;
    for (const auto& e : in_.front) radius_sum += std::hypot(N_.pos[e[0]].x(), N_.pos[e[0]].y());
    scale_ = std::max(radius_sum / in_.front.size(), 1e-3);  // (run() returned if it is empty)
    return true;
  }

  Vector2d unwrapped(const Vector2d& param) const {
    return {phi_ref_ + wrap_angle(param.x() - phi_ref_), param.y()};
  }
  Point plane_point(const Vector2d& param) const {
    const Vector2d u = unwrapped(param);
    return {u.x() * scale_, u.y()};
  }

  // The polygons keep the node order of the front; re-unwrap them against phi_ref_ so the
  // inside test and the plane agree.
  bool inside_region(const Vector2d& param) const {
    return inside_polygons(unwrapped(param), polygons_);
  }

  bool insert_boundary() {
    polygons_.clear();
    for (const auto& poly : in_.polygons) {
      std::vector<Vector2d> p;
      for (const Vector2d& q : poly) p.push_back(unwrapped(q));
      // keep each polygon continuous (a region narrower than pi never needs more)
      for (std::size_t i = 1; i < p.size(); ++i)
        p[i].x() = p[i - 1].x() + wrap_angle(p[i].x() - p[i - 1].x());
      polygons_.push_back(std::move(p));
    }
    try {
      for (const auto& e : in_.front) {
        const auto a = vertex_of(e[0]), b = vertex_of(e[1]);
        if (!a || !b) return false;
        if (*a != *b) cdt_.insert_constraint(*a, *b);
      }
    } catch (const std::exception&) {
      return false;  // crossing chords: leave the region to the AFT
    }
    return true;
  }

  std::optional<Cdt::Vertex_handle> vertex_of(int node) {
    if (const auto it = node_vertex_.find(node); it != node_vertex_.end()) return it->second;
    const Cdt::Vertex_handle v = cdt_.insert(plane_point(N_.params[node]));
    if (v->info().node >= 0) return std::nullopt;  // coincides with another node
    v->info().node = node;
    node_vertex_.emplace(node, v);
    return v;
  }

  static int node(Cdt::Vertex_handle v) { return v->info().node; }

  // The region's faces of the plane CDT: flood fill from the faces beside the front edges
  // across unconstrained edges. The front has the region on its left as seen from outside;
  // whether that is the plane's left depends on the parametrisation, so both sides are
  // tried and the side whose fill stays finite is the region. (A centroid-in-polygon test
  // misjudged slivers along nearly straight chains.) Empty: no consistent side.
  std::optional<std::vector<std::array<int, 3>>> domain_faces() const {
    std::vector<Cdt::Face_handle> left, right;
    for (const auto& e : in_.front) {
      Cdt::Face_handle f;
      int i = 0;
      if (!cdt_.is_edge(node_vertex_.at(e[0]), node_vertex_.at(e[1]), f, i)) return std::nullopt;
      // Edge (f, i) runs ccw(i) -> cw(i) with f on its left.
      const bool f_is_left = f->vertex(cdt_.ccw(i))->info().node == e[0];
      left.push_back(f_is_left ? f : f->neighbor(i));
      right.push_back(f_is_left ? f->neighbor(i) : f);
    }
    for (const bool plane_left : {true, false}) {
      std::set<Cdt::Face_handle> seen;
      std::vector<Cdt::Face_handle> stack = plane_left ? left : right;
      bool finite = true;
      while (!stack.empty() && finite) {
        const Cdt::Face_handle f = stack.back();
        stack.pop_back();
        if (cdt_.is_infinite(f)) finite = false;
        if (!finite || !seen.insert(f).second) continue;
        for (int k = 0; k < 3; ++k)
          if (!f->is_constrained(k)) stack.push_back(f->neighbor(k));
      }
      if (!finite) continue;
      std::vector<std::array<int, 3>> out;
      for (const Cdt::Face_handle f : seen) {
        std::array<int, 3> t{node(f->vertex(0)), node(f->vertex(1)), node(f->vertex(2))};
        if (!plane_left) std::swap(t[1], t[2]);  // the plane's clockwise is the front's left
        out.push_back(t);
      }
      std::sort(out.begin(), out.end());  // deterministic, independent of handle addresses
      return out;
    }
    return std::nullopt;
  }

  // ---- the triangulation on the surface (after the plane CDT start) ----------------------

  void set_triangle(int t, const std::array<int, 3>& v) {
    tris_[t] = v;
    for (int k = 0; k < 3; ++k) owner_[directed_edge_key(v[k], v[(k + 1) % 3])] = t;
  }
  void drop_edges(int t) {
    const auto& v = tris_[t];
    for (int k = 0; k < 3; ++k) owner_.erase(directed_edge_key(v[k], v[(k + 1) % 3]));
  }
  //! The triangle with the directed edge (a, b), or -1.
  int owner(int a, int b) const {
    const auto it = owner_.find(directed_edge_key(a, b));
    return it == owner_.end() ? -1 : it->second;
  }
  //! The triangle on the other side of directed edge (a, b): the owner of (b, a), or -1.
  int across(int a, int b) const { return owner(b, a); }
  bool constrained(int a, int b) const { return constraint_.count(edge_key(a, b)) > 0; }

  bool build_surface_triangulation() {
    for (const auto& e : in_.front)
      if (constraint_.insert(edge_key(e[0], e[1])).second) segment_edges_.push_back({e[0], e[1]});
    const auto domain = domain_faces();
    if (!domain) return false;
    const std::vector<std::array<int, 3>>& start = *domain;
    tris_.resize(start.size());
    for (std::size_t t = 0; t < start.size(); ++t) set_triangle(static_cast<int>(t), start[t]);
    lawson_flips(all_edges());
    return true;
  }

  //! Every edge of the triangulation (undirected keys, sorted).
  std::vector<std::uint64_t> all_edges() const {
    std::vector<std::uint64_t> all;
    for (const auto& t : tris_)
      for (int k = 0; k < 3; ++k) all.push_back(edge_key(t[k], t[(k + 1) % 3]));
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    return all;
  }

  bool faces_out(int a, int b, int c) const {
    const Vector3d n = (N_.pos[b] - N_.pos[a]).cross(N_.pos[c] - N_.pos[a]);
    const Vector3d m = N_.normal[a] + N_.normal[b] + N_.normal[c];
    return n.dot(m) > 0.3 * n.norm() * m.norm();  // within ~70 deg of the surface normal
  }

  // Flips edge {a, b} if that raises the smaller of the two 3D minimum angles (the max-min
  // angle rule, Delaunay's in the plane) and both new triangles face outwards.
  bool flip_if_better(int a, int b, std::vector<std::uint64_t>& queue) {
    if (constrained(a, b)) return false;
    int t1 = owner(a, b);
    if (t1 < 0) std::swap(a, b), t1 = owner(a, b);
    if (t1 < 0) return false;
    const int t2 = owner(b, a);
    if (t2 < 0) return false;
    const int c = third(t1, a, b), d = third(t2, b, a);
    if (c < 0 || d < 0 || c == d || owner(c, d) >= 0 || owner(d, c) >= 0) return false;
    const auto& P = N_.pos;
    const double before = std::min(min_angle(P[a], P[b], P[c]), min_angle(P[b], P[a], P[d]));
    const double after = std::min(min_angle(P[c], P[a], P[d]), min_angle(P[d], P[b], P[c]));
    if (after <= before + 1e-9 || !faces_out(c, a, d) || !faces_out(d, b, c)) return false;
    if (!convex_quad(a, b, c, d)) return false;
    drop_edges(t1);
    drop_edges(t2);
    set_triangle(t1, {c, a, d});
    set_triangle(t2, {d, b, c});
    for (const auto& [x, y] : {std::pair{a, d}, {d, b}, {b, c}, {c, a}})
      queue.push_back(edge_key(x, y));
    return true;
  }

  // The new diagonal c-d must cross the old one a-b seen along the quad's mean normal: a
  // non-convex quad flipped folds one triangle over the other (the angle rule alone allows it).
  bool convex_quad(int a, int b, int c, int d) const {
    const auto& P = N_.pos;
    const Vector3d n = ((P[b] - P[a]).cross(P[c] - P[a]) + (P[a] - P[b]).cross(P[d] - P[b]));
    auto side = [&](const Vector3d& p, const Vector3d& q, const Vector3d& x) {
      return (q - p).cross(x - p).dot(n);
    };
    return side(P[c], P[d], P[a]) * side(P[c], P[d], P[b]) < 0 &&
           side(P[a], P[b], P[c]) * side(P[a], P[b], P[d]) < 0;
  }

  int third(int t, int a, int b) const {
    for (int k = 0; k < 3; ++k)
      if (tris_[t][k] == a && tris_[t][(k + 1) % 3] == b) return tris_[t][(k + 2) % 3];
    return -1;
  }

  void lawson_flips(std::vector<std::uint64_t> queue) {
    std::size_t guard = 0;
    while (!queue.empty() && guard++ < 200000) {
      const std::uint64_t e = queue.back();
      queue.pop_back();
      flip_if_better(edge_key_first(e), edge_key_second(e), queue);
    }
  }

  // Barycentric coordinates of x projected onto the plane of triangle t.
  Eigen::Vector3d barycentric(int t, const Vector3d& x) const {
    const Vector3d &a = N_.pos[tris_[t][0]], &b = N_.pos[tris_[t][1]], &c = N_.pos[tris_[t][2]];
    const Vector3d n = (b - a).cross(c - a);
    const double area2 = n.squaredNorm();
    if (area2 < 1e-24) return Eigen::Vector3d::Constant(-1);
    return {(c - b).cross(x - b).dot(n) / area2, (a - c).cross(x - c).dot(n) / area2,
            (b - a).cross(x - a).dot(n) / area2};
  }

  // Walks from triangle `from` to the triangle containing x; -1 if the walk would cross a
  // segment edge or the region border (x is separated from `from` by a constraint) or loops.
  int locate(int from, const Vector3d& x) const {
    int t = from;
    for (int step = 0; step < 500; ++step) {
      const Eigen::Vector3d w = barycentric(t, x);
      int worst = 0;
      for (int k = 1; k < 3; ++k)
        if (w[k] < w[worst]) worst = k;
      if (w[worst] >= -1e-9) return t;
      // coordinate k belongs to vertex k: leave across the opposite edge (k+1, k+2)
      const int a = tris_[t][(worst + 1) % 3], b = tris_[t][(worst + 2) % 3];
      if (constrained(a, b)) return -1;
      const int next = across(a, b);
      if (next < 0) return -1;
      t = next;
    }
    return -1;
  }

  struct Candidate {
    double radius;
    std::array<int, 3> nodes;
  };

  //! The surface point on the line origin + t dir, |t| <= reach, with the smallest |t|.
  std::optional<SurfaceHit> nearest_hit(const Vector3d& origin, const Vector3d& dir,
                                        double reach) const {
    const auto hits = S_.intersect_segment(origin, dir, -reach, reach);
    if (hits.empty()) return std::nullopt;
    return *std::min_element(hits.begin(), hits.end(), [](const auto& p, const auto& q) {
      return std::abs(p.t) < std::abs(q.t);
    });
  }

  // Non-ideal (Chew): min angle below 30°, or circumradius above the size bound, or the
  // triangle's centre farther from the surface than the chordal tolerance.
  std::optional<Candidate> non_ideal(const std::array<int, 3>& v) const {
    const Vector3d &a = N_.pos[v[0]], &b = N_.pos[v[1]], &c = N_.pos[v[2]];
    const auto cc = circumcircle(a, b, c);
    if (!cc) return std::nullopt;
    const double radius = cc->second;
    if (radius < 0.5 * in_.min_unit_mm) return std::nullopt;  // never refine below the floor
    // An equilateral triangle of edge `unit` has circumradius unit / sqrt(3).
    const bool too_big = radius > size_bound_factor_ * in_.unit_mm / std::sqrt(3.0);
    const bool too_sharp = min_angle(a, b, c) < kMinAngle;
    bool too_far = false;
    if (!too_big && !too_sharp) {
      // Sagitta along the triangle normal (the closest-point projection can jump to another
      // part of the surface under the chin or behind an ear and report centimetres).
      const Vector3d n = (b - a).cross(c - a).normalized();
      const auto hit = nearest_hit((a + b + c) / 3.0, n, radius);
      too_far = (hit ? std::abs(hit->t) : 0.0) > in_.chordal_tolerance_mm;
    }
    if (!too_big && !too_sharp && !too_far) return std::nullopt;
    return Candidate{radius, v};
  }

  // Def. 4.5: the sphere through a, b, c whose centre lies on the surface. The centres of all
  // spheres through the three points lie on the line through the planar circumcentre along the
  // triangle normal; intersect that line with the surface near the triangle.
  std::optional<Vector3d> surface_circumcentre(const Vector3d& a, const Vector3d& b,
                                               const Vector3d& c) const {
    const auto cc = circumcircle(a, b, c);
    if (!cc) return std::nullopt;
    const auto& [centre, radius] = *cc;
    const Vector3d n = (b - a).cross(c - a).normalized();
    if (const auto hit = nearest_hit(centre, n, radius)) return hit->point;
    const auto pr = S_.project(centre);  // the line only grazes the surface: project
    if (!pr) return std::nullopt;
    return pr->point;
  }

  bool crowds(const Vector3d& x, const std::array<int, 3>& host, double clearance) const {
    for (int k = 0; k < 3; ++k) {
      if ((N_.pos[host[k]] - x).norm() < clearance) return true;
      const int nb = across(host[k], host[(k + 1) % 3]);
      if (nb >= 0)
        for (int w : tris_[nb])
          if ((N_.pos[w] - x).norm() < clearance) return true;
    }
    return false;
  }

  // A new node at surface point x, or -1 (surface undefined there).
  int add_node(const Vector3d& x, int near_node) {
    return N_.add(unwrapped(param_of(x, N_.params[near_node].x())), S_);
  }
  void take_back_last_node() {  // the node added last was not used
    N_.params.pop_back();
    N_.pos.pop_back();
    N_.normal.pop_back();
  }
  int push_triangle(const std::array<int, 3>& v) {
    tris_.push_back({});
    set_triangle(static_cast<int>(tris_.size()) - 1, v);
    return static_cast<int>(tris_.size()) - 1;
  }

  bool split_triangle(int host, int p) {
    const std::array<int, 3> h = tris_[host];
    if (!faces_out(h[0], h[1], p) || !faces_out(h[1], h[2], p) || !faces_out(h[2], h[0], p))
      return false;
    drop_edges(host);
    set_triangle(host, {h[0], h[1], p});
    push_triangle({h[1], h[2], p});
    push_triangle({h[2], h[0], p});
    lawson_flips({edge_key(h[0], h[1]), edge_key(h[1], h[2]), edge_key(h[2], h[0])});
    return true;
  }

  // Splits the interior edge (a, b) of triangle t at node p: two triangles become four.
  bool split_edge(int t, int a, int b, int p) {
    if (constrained(a, b)) return false;
    const int u = across(a, b);
    if (u < 0) return false;
    const int c = third(t, a, b), d = third(u, b, a);
    if (c < 0 || d < 0) return false;
    if (!faces_out(a, p, c) || !faces_out(p, b, c) || !faces_out(b, p, d) || !faces_out(p, a, d))
      return false;
    drop_edges(t);
    drop_edges(u);
    set_triangle(t, {a, p, c});
    set_triangle(u, {p, b, c});
    push_triangle({b, p, d});
    push_triangle({p, a, d});
    lawson_flips({edge_key(a, c), edge_key(c, b), edge_key(b, d), edge_key(d, a)});
    return true;
  }

  // Ruppert's encroachment: x inside the diametral sphere of a segment edge. Chew and Ruppert
  // would split that segment instead of inserting x; ours are shared with the neighbouring
  // region and stay, so x is not inserted — the triangle on the segment is then left as it
  // is (its apex is outside the diametral circle, so its angle there is below 90°).
  bool encroaches_segment(const Vector3d& x) const {
    for (const auto& [a, b] : segment_edges_)
      if ((N_.pos[a] - x).dot(N_.pos[b] - x) < 0) return true;
    return false;
  }

  // Inserts surface point x found from triangle t; x near an edge splits that edge.
  bool insert_point(int t, const Vector3d& x, double clearance) {
    if (encroaches_segment(x)) return false;
    const int host = locate(t, x);
    if (host < 0) return false;  // behind a segment edge: Chew would split it; ours stay
    const std::array<int, 3> h = tris_[host];
    if (crowds(x, h, clearance)) return false;
    const Eigen::Vector3d w = barycentric(host, x);
    int k = 0;
    for (int i = 1; i < 3; ++i)
      if (w[i] < w[k]) k = i;
    const int p = add_node(x, h[0]);
    if (p < 0) return false;
    // Close to the edge opposite vertex k: a point-in-triangle split would leave a sliver.
    const bool ok =
        w[k] < 0.05 ? split_edge(host, h[(k + 1) % 3], h[(k + 2) % 3], p) : split_triangle(host, p);
    if (!ok) take_back_last_node();
    return ok;
  }

  // Üngör's off-centre: on the bisector of the shortest edge, at the apex of the equilateral
  // triangle over it (or the circumcentre if that is nearer). It lies inside the circumcircle
  // and usually on the region's side of a segment whose circumcentre fell behind it. Returns
  // the surface point and the clearance it needs from existing nodes.
  std::optional<std::pair<Vector3d, double>> off_centre(const std::array<int, 3>& v) const {
    int k = 0;
    double shortest = 1e300;
    for (int i = 0; i < 3; ++i) {
      const double len = (N_.pos[v[i]] - N_.pos[v[(i + 1) % 3]]).norm();
      if (len < shortest) shortest = len, k = i;
    }
    const Vector3d &p = N_.pos[v[k]], &q = N_.pos[v[(k + 1) % 3]];
    const auto cc = circumcircle(N_.pos[v[0]], N_.pos[v[1]], N_.pos[v[2]]);
    if (!cc) return std::nullopt;
    const Vector3d mid = 0.5 * (p + q), to_centre = cc->first - mid;
    if (to_centre.norm() < 1e-12) return std::nullopt;
    const Vector3d x =
        mid + std::min(to_centre.norm(), shortest * std::sqrt(3.0) / 2) * to_centre.normalized();
    const Vector3d n =
        (N_.pos[v[1]] - N_.pos[v[0]]).cross(N_.pos[v[2]] - N_.pos[v[0]]).normalized();
    const auto hit = nearest_hit(x, n, shortest);
    if (!hit) return std::nullopt;
    return std::make_pair(hit->point, 0.5 * shortest);
  }

  // Inserts the surface circumcentre of triangle t if it is allowed (Chew), else the surface
  // point at the middle of its longest interior edge: a triangle whose circumcentre is outside
  // the region or behind a segment is long and thin along the border, and splitting it from
  // inside is what splitting the segment would have achieved. True if a node was inserted.
  bool try_insert(int t, double radius) {
    const std::array<int, 3> v = tris_[t];
    if (const auto centre = surface_circumcentre(N_.pos[v[0]], N_.pos[v[1]], N_.pos[v[2]]);
        centre && inside_region(param_of(*centre, N_.params[v[0]].x())) &&
        insert_point(t, *centre, 0.5 * radius)) {
      ++stats_.chose_circumcentre;
      ++stats_.steiner_points;
      return true;
    }
    if (const auto off = off_centre(v); off &&
                                        inside_region(param_of(off->first, N_.params[v[0]].x())) &&
                                        insert_point(t, off->first, off->second)) {
      ++stats_.steiner_points;
      return true;
    }
    int best = -1;
    double longest = 0;
    for (int k = 0; k < 3; ++k) {
      const int a = v[k], b = v[(k + 1) % 3];
      const double len = (N_.pos[a] - N_.pos[b]).norm();
      if (!constrained(a, b) && across(a, b) >= 0 && len > longest) longest = len, best = k;
    }
    if (best < 0) return false;
    const int a = v[best], b = v[(best + 1) % 3];
    const auto mid = S_.project(0.5 * (N_.pos[a] + N_.pos[b]));
    if (!mid) return false;
    if (crowds(mid->point, v, 0.3 * longest) || encroaches_segment(mid->point)) return false;
    const int p = add_node(mid->point, a);
    if (p < 0) return false;
    if (!split_edge(t, a, b, p)) {
      take_back_last_node();
      return false;
    }
    ++stats_.steiner_points;
    return true;
  }

  bool refine() {
    if (!build_surface_triangulation()) return false;
    first_steiner_ = static_cast<int>(N_.pos.size());
    // A budget far above what the size bound needs: area / (equilateral triangle of the unit).
    double area = 0;
    for (const auto& v : tris_)
      area += 0.5 * (N_.pos[v[1]] - N_.pos[v[0]]).cross(N_.pos[v[2]] - N_.pos[v[0]]).norm();
    const double unit = std::max(in_.unit_mm, in_.min_unit_mm);
    budget_ = in_.max_steps > 0
                  ? in_.max_steps
                  : static_cast<std::size_t>(4.0 * area / (0.433 * unit * unit)) + 100;
    // Chew's refinement, then the Steiner points relaxed (segments cannot be split, so the
    // triangles next to them are improved by moving their inner vertex instead), and once
    // more refinement for what the moves left non-ideal.
    refinement_passes();
    smooth(8);
    refinement_passes();
    smooth(4);
    stats_.rejected_circumcentres = rejected_;
    return true;
  }

  void refinement_passes() {
    for (int pass = 0; pass < 100 && inserted_ < budget_; ++pass) {
      std::vector<Candidate> bad;
      for (const auto& v : tris_)
        if (auto c = non_ideal(v)) bad.push_back(*c);
      // Largest first (Chew leaves the order open): big triangles' centres fall in the
      // interior, and the small ones they leave are often fixed on the way.
      std::sort(bad.begin(), bad.end(), [](const Candidate& x, const Candidate& y) {
        return x.radius > y.radius || (x.radius == y.radius && x.nodes < y.nodes);
      });
      std::size_t pass_inserted = 0;
      rejected_ = 0;
      for (const Candidate& c : bad) {
        if (inserted_ >= budget_) break;
        const auto it = owner_.find(directed_edge_key(c.nodes[0], c.nodes[1]));
        if (it == owner_.end() || third(it->second, c.nodes[0], c.nodes[1]) != c.nodes[2])
          continue;  // changed by an earlier insertion of this pass
        if (try_insert(it->second, c.radius)) {
          ++inserted_;
          ++pass_inserted;
        } else {
          ++rejected_;
        }
      }
      if (pass_inserted == 0) break;
    }
  }

  double star_min_angle(const std::vector<int>& star) const {
    double worst = M_PI;
    for (int t : star)
      worst =
          std::min(worst, min_angle(N_.pos[tris_[t][0]], N_.pos[tris_[t][1]], N_.pos[tris_[t][2]]));
    return worst;
  }

  // Moves each Steiner point towards the centroid of its neighbours, on the surface, when that
  // raises the smallest angle of its triangles; Lawson flips after each round.
  void smooth(int rounds) {
    for (int round = 0; round < rounds; ++round) {
      std::vector<std::vector<int>> star(N_.pos.size() - first_steiner_);
      for (std::size_t t = 0; t < tris_.size(); ++t)
        for (int v : tris_[t])
          if (v >= first_steiner_) star[v - first_steiner_].push_back(static_cast<int>(t));
      int moved = 0;
      for (std::size_t i = 0; i < star.size(); ++i) {
        if (star[i].empty()) continue;
        const int v = first_steiner_ + static_cast<int>(i);
        Vector3d centroid = Vector3d::Zero();
        int n = 0;
        for (int t : star[i])
          for (int w : tris_[t])
            if (w != v) centroid += N_.pos[w], ++n;
        centroid /= n;
        const double reach = (centroid - N_.pos[v]).norm() + in_.unit_mm;
        const auto target = nearest_hit(centroid, N_.normal[v], reach);
        if (!target) continue;
        const double before = star_min_angle(star[i]);
        const NodeStore::Saved old = N_.save(v);
        if (!N_.move(v, unwrapped(param_of(target->point, old.param.x())), S_)) continue;
        bool ok = inside_region(N_.params[v]) && star_min_angle(star[i]) > before + 1e-9 &&
                  !encroaches_segment(N_.pos[v]);
        for (int t : star[i]) ok = ok && faces_out(tris_[t][0], tris_[t][1], tris_[t][2]);
        if (ok) {
          ++moved;
        } else {
          N_.restore(v, old);
        }
      }
      lawson_flips(all_edges());
      if (moved == 0) break;
    }
  }

  std::vector<std::array<int, 3>> triangles() const {
    stats_.triangles = static_cast<int>(tris_.size());
    return tris_;
  }

  NodeStore& N_;
  const ScanSurface& S_;
  const RegionMeshInput& in_;
  RegionMeshStats& stats_;
  Cdt cdt_;
  std::unordered_map<int, Cdt::Vertex_handle> node_vertex_;
  std::vector<std::vector<Vector2d>> polygons_;     // (phi, h), unwrapped at phi_ref_
  std::vector<std::array<int, 3>> tris_;            // the surface triangulation
  std::unordered_map<std::uint64_t, int> owner_;    // directed edge -> its triangle
  std::unordered_set<std::uint64_t> constraint_;    // segment edges (undirected)
  std::vector<std::pair<int, int>> segment_edges_;  // the same, as a list
  double phi_ref_ = 0, scale_ = 1;
  // Triangles up to this multiple of the unit's circumradius are not split for size: Chew's
  // refinement leaves edges between ~1 and ~2 circumradii, so 1.3 lands the mean edge near the
  // unit (the AFT's target) on the test surfaces.
  double size_bound_factor_ = 1.3;
  int rejected_ = 0;
  int first_steiner_ = 0;  // nodes from here on are this region's Steiner points
  std::size_t budget_ = 0, inserted_ = 0;
};

}  // namespace

std::optional<std::vector<std::array<int, 3>>> delaunay_mesh_region(NodeStore& nodes,
                                                                    const ScanSurface& surface,
                                                                    const RegionMeshInput& input,
                                                                    RegionMeshStats& stats) {
  SurfaceDelaunayMesher mesher(nodes, surface, input, stats);
  return mesher.run();
}

}  // namespace scanmesh::aft::detail
