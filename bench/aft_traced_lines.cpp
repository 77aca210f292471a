// bench_aft's animation lines traced on the grid band (aft_traced_lines.h).
#include "aft_traced_lines.h"

#include <CGAL/Polygon_mesh_processing/remesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <queue>
#include <set>
#include <tuple>
#include <utility>

namespace scanmesh::bench_aft {

namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

// CGAL 5.5's relax_constraints lets the tangential relaxation move the vertices of constrained
// polylines (and of the band's and holes' borders) to 1/4 - 1/2 - 1/4 of their neighbours on
// the chord, with no projection back onto the line or the surface. Measured here (same run,
// same count): with it 1.51 % < 30 deg, mean q 0.942, Hausdorff 3.39 / 12.50 mm; without
// 2.88 %, 0.933, 2.35 / 14.82 mm. Off: the lines should stay where they are drawn, and the
// mesh->surface distance is the other goal.
constexpr bool kRelaxConstraints = false;

// ---- The animation lines as simple polylines of grid-mesh edges (the fair constrained input).
// Pixels: x = phi column, y = h row, a grid vertex at its cell centre. The grid is periodic in
// phi, so a pixel x and x + n_phi are the same point; the segments' x is unwrapped.

struct LinePoint {
  double distance_px = std::numeric_limits<double>::infinity();
  Eigen::Vector2d pixel;  // on the polyline, in its own (unwrapped) x
  double arc_px = 0;      // its arc length from the polyline's start
};

LinePoint closest_on_polyline(const std::vector<Eigen::Vector2d>& line, const Eigen::Vector2d& p,
                              int n_phi) {
  LinePoint best;
  for (int k = -1; k <= 1; ++k) {
    const Eigen::Vector2d q = p + Eigen::Vector2d(k * n_phi, 0);
    double arc = 0;
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
      const Eigen::Vector2d a = line[i], d = line[i + 1] - line[i];
      const double t =
          d.squaredNorm() > 0 ? std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      const double dist = (a + t * d - q).norm();
      if (dist < best.distance_px) best = {dist, a + t * d, arc + t * d.norm()};
      arc += d.norm();
    }
  }
  return best;
}

double wrapped_pixel_distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, int n_phi) {
  const double dx = std::fmod(std::abs(b.x() - a.x()), static_cast<double>(n_phi));
  return std::hypot(std::min(dx, n_phi - dx), b.y() - a.y());
}

// The grid band with the lines traced on it: "e:line" / "v:line" are the CGAL constraint maps,
// "v:node" the region-graph node a vertex stands for (-1 for none).
struct LinedBand {
  SM mesh;
  std::vector<std::pair<int, int>> chains;  // the traced polylines' end nodes (-1: at a hole)
  std::size_t segments = 0, partial_segments = 0, edges = 0, constrained_vertices = 0;
  std::size_t unsnapped_nodes = 0, untraced_segments = 0, unmoved_vertices = 0;
};

class LineTracer {
 public:
  LineTracer(SM& band, const std::vector<Eigen::Vector2d>& pixel, int n_phi)
      : band_(band), pixel_(pixel), n_phi_(n_phi), taken_(band.number_of_vertices(), 0) {}

  // The free vertex nearest to `p`; nullopt if none lies within max_px (a hole).
  std::optional<SM::Vertex_index> snap(const Eigen::Vector2d& p, double max_px) const {
    std::optional<SM::Vertex_index> best;
    double best_d = max_px;
    for (auto v : band_.vertices()) {
      const double d = wrapped_pixel_distance(pixel_[v], p, n_phi_);
      if (!taken_[v] && d <= best_d) best_d = d, best = v;
    }
    return best;
  }

  void take(SM::Vertex_index v) { taken_[v] = 1; }

  // The cheapest path from `from` to `to` along `line`; empty if there is none in its corridor.
  std::vector<SM::Vertex_index> trace(SM::Vertex_index from, SM::Vertex_index to,
                                      const std::vector<Eigen::Vector2d>& line,
                                      const SM::Property_map<SM::Edge_index, bool>& on_line) const {
    const Search s = search(from, to, line, on_line);
    return std::isfinite(s.cost[to]) ? s.path(from, to) : std::vector<SM::Vertex_index>{};
  }

  // Where the line crosses a hole of the band (the grid mesh skips depth jumps: chin, nose,
  // mouth corners), no edge path reaches its far end. This is the cheapest path from `from` to
  // the hole's border, to the border vertex furthest along `line`; empty if none is reached.
  std::vector<SM::Vertex_index> trace_to_hole(
      SM::Vertex_index from, const std::vector<Eigen::Vector2d>& line,
      const SM::Property_map<SM::Edge_index, bool>& on_line) const {
    const Search s = search(from, std::nullopt, line, on_line);
    std::optional<SM::Vertex_index> end;
    double furthest = 0;
    for (auto v : band_.vertices())
      if (v != from && std::isfinite(s.cost[v]) && band_.is_border(v)) {
        const double along = closest_on_polyline(line, pixel_[v], n_phi_).arc_px;
        if (along > furthest) furthest = along, end = v;
      }
    return end ? s.path(from, *end) : std::vector<SM::Vertex_index>{};
  }

 private:
  struct Search {
    std::vector<double> cost;
    std::vector<SM::Vertex_index> prev;
    std::vector<SM::Vertex_index> path(SM::Vertex_index from, SM::Vertex_index to) const {
      std::vector<SM::Vertex_index> out;
      for (SM::Vertex_index v = to; v != from; v = prev[v]) out.push_back(v);
      out.push_back(from);
      std::reverse(out.begin(), out.end());
      return out;
    }
  };

  // Dijkstra on the band's edges, cost = pixel length + a steep penalty for leaving `line`,
  // within a corridor around it. Vertices of earlier paths are off limits (so paths meet only
  // at junctions), and so is every existing line edge.
  Search search(SM::Vertex_index from, std::optional<SM::Vertex_index> to,
                const std::vector<Eigen::Vector2d>& line,
                const SM::Property_map<SM::Edge_index, bool>& on_line) const {
    constexpr double kCorridorPx = 3, kPenaltyPerPx2 = 10;
    const std::size_t n = band_.number_of_vertices();
    Search s{std::vector<double>(n, std::numeric_limits<double>::infinity()),
             std::vector<SM::Vertex_index>(n)};
    std::vector<double> offset(n, -1);
    using Item = std::pair<double, SM::Vertex_index>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    s.cost[from] = 0;
    queue.push({0, from});
    while (!queue.empty()) {
      const auto [c, v] = queue.top();
      queue.pop();
      if (v == to) break;
      if (c > s.cost[v]) continue;
      for (auto h : halfedges_around_target(band_.halfedge(v), band_)) {
        const SM::Vertex_index w = band_.source(h);
        if ((taken_[w] && w != to) || on_line[band_.edge(h)]) continue;
        if (offset[w] < 0) offset[w] = penalised_offset(w, line);
        if (offset[w] > kCorridorPx) continue;
        const double cw = c + wrapped_pixel_distance(pixel_[v], pixel_[w], n_phi_) +
                          kPenaltyPerPx2 * offset[w] * offset[w];
        if (cw < s.cost[w]) s.cost[w] = cw, s.prev[w] = v, queue.push({cw, w});
      }
    }
    return s;
  }

  // A line lying on the band's border (the neck and crown lines) is traced along the border:
  // one row inside it would leave a strip of slivers between two constrained polylines that
  // CGAL can neither flip nor collapse. So border vertices count half a pixel closer.
  double penalised_offset(SM::Vertex_index v, const std::vector<Eigen::Vector2d>& line) const {
    const double d = closest_on_polyline(line, pixel_[v], n_phi_).distance_px;
    return band_.is_border(v) ? std::max(0.0, d - 0.5) : d;
  }

  SM& band_;
  const std::vector<Eigen::Vector2d>& pixel_;
  int n_phi_;
  std::vector<char> taken_;
};

// Moves v to p unless that turns one of its triangles over (normal against the old one).
bool move_if_no_flip(SM& m, SM::Vertex_index v, const Eigen::Vector3d& p) {
  auto normals = [&] {
    std::vector<K::Vector_3> out;
    for (auto f : faces_around_target(m.halfedge(v), m)) {
      if (f == SM::null_face()) continue;
      std::array<K::Point_3, 3> c;
      int k = 0;
      for (auto u : vertices_around_face(m.halfedge(f), m)) c[k++] = m.point(u);
      out.push_back(CGAL::cross_product(c[1] - c[0], c[2] - c[0]));
    }
    return out;
  };
  const auto before = normals();
  const K::Point_3 old = m.point(v);
  m.point(v) = K::Point_3(p.x(), p.y(), p.z());
  const auto after = normals();
  for (std::size_t i = 0; i < before.size(); ++i)
    if (before[i] * after[i] <= 0) {
      m.point(v) = old;
      return false;
    }
  return true;
}

// The segment's polyline in pixels, split in two at half its length for a loop (one node), so
// that each half is a path between two different vertices.
std::vector<std::vector<Eigen::Vector2d>> segment_legs(const aft::Segment& s,
                                                       const ScanSurface& surface) {
  std::vector<Eigen::Vector2d> px;
  for (const auto& p : s.pts) px.push_back(aft::param_to_pixel(surface, p));
  if (s.node0 != s.node1) return {px};
  double total = 0;
  for (std::size_t i = 0; i + 1 < px.size(); ++i) total += (px[i + 1] - px[i]).norm();
  std::vector<Eigen::Vector2d> first{px[0]};
  double run = 0;
  std::size_t i = 0;
  for (; i + 1 < px.size() && run + (px[i + 1] - px[i]).norm() < total / 2; ++i) {
    run += (px[i + 1] - px[i]).norm();
    first.push_back(px[i + 1]);
  }
  const Eigen::Vector2d mid =
      px[i] + (total / 2 - run) / (px[i + 1] - px[i]).norm() * (px[i + 1] - px[i]);
  first.push_back(mid);
  std::vector<Eigen::Vector2d> second{mid};
  second.insert(second.end(), px.begin() + static_cast<long>(i) + 1, px.end());
  return {first, second};
}

struct Leg {
  std::vector<SM::Vertex_index> path;
  std::vector<Eigen::Vector2d> line;
};

// A segment on the band: its legs, and the chains of line edges they should leave in the
// remeshed band as pairs of graph nodes (-1: the end is on the border of a hole).
struct TracedSegment {
  std::vector<Leg> legs;
  std::vector<std::pair<int, int>> chains;
  bool partial = false;  // crosses a hole: traced from both ends up to it
};

void take_interior(LineTracer& tracer, const std::vector<SM::Vertex_index>& path) {
  for (std::size_t i = 1; i + 1 < path.size(); ++i) tracer.take(path[i]);
}

// A loop (node0 == node1) in two legs via its half-way vertex; empty if that fails.
TracedSegment trace_loop(LineTracer& tracer, const aft::Segment& s, SM::Vertex_index node,
                         const SM::Property_map<SM::Edge_index, bool>& on_line,
                         const ScanSurface& surface) {
  const auto lines = segment_legs(s, surface);
  const auto via = tracer.snap(lines[0].back(), 1.5);
  if (!via) return {};
  tracer.take(*via);
  TracedSegment out;
  for (const auto& [a, b, line] :
       {std::tuple(node, *via, lines[0]), std::tuple(*via, node, lines[1])}) {
    Leg leg{tracer.trace(a, b, line, on_line), line};
    if (leg.path.empty()) return {};
    take_interior(tracer, leg.path);
    out.legs.push_back(std::move(leg));
  }
  out.chains.emplace_back(s.node0, s.node1);
  return out;
}

// One segment between two nodes; across a hole, the two pieces from its ends up to the hole.
TracedSegment trace_segment(LineTracer& tracer, const aft::Segment& s,
                            const std::vector<std::optional<SM::Vertex_index>>& node_vertex,
                            const SM::Property_map<SM::Edge_index, bool>& on_line,
                            const ScanSurface& surface) {
  if (s.node0 == s.node1) return trace_loop(tracer, s, *node_vertex[s.node0], on_line, surface);
  const std::vector<Eigen::Vector2d> line = segment_legs(s, surface).front();
  TracedSegment out;
  Leg whole{tracer.trace(*node_vertex[s.node0], *node_vertex[s.node1], line, on_line), line};
  if (!whole.path.empty()) {
    take_interior(tracer, whole.path);
    out.legs.push_back(std::move(whole));
    out.chains.emplace_back(std::minmax(s.node0, s.node1));
    return out;
  }
  out.partial = true;
  const std::vector<Eigen::Vector2d> reversed(line.rbegin(), line.rend());
  for (const auto& [node, piece] : {std::pair(s.node0, line), std::pair(s.node1, reversed)}) {
    Leg leg{tracer.trace_to_hole(*node_vertex[node], piece, on_line), piece};
    if (leg.path.size() < 2) continue;
    tracer.take(leg.path.back());
    take_interior(tracer, leg.path);
    out.legs.push_back(std::move(leg));
    out.chains.emplace_back(-1, node);
  }
  return out;
}

std::optional<Eigen::Vector3d> surface_point_at_pixel(const ScanSurface& surface,
                                                      const Eigen::Vector2d& px) {
  const Eigen::Vector2d p = aft::pixel_to_param(surface, px);
  return surface.position(p.x(), p.y());
}

// Puts the leg's interior vertices exactly onto its line (the closest point in (phi, h), lifted
// to the surface); returns how many had to stay (the move would flip a triangle, or the surface
// is not defined there).
std::size_t move_onto_line(SM& m, const Leg& leg, const std::vector<Eigen::Vector2d>& pixel,
                           const ScanSurface& surface) {
  std::size_t unmoved = 0;
  for (std::size_t i = 1; i + 1 < leg.path.size(); ++i) {
    const SM::Vertex_index v = leg.path[i];
    const LinePoint c = closest_on_polyline(leg.line, pixel[v], surface.n_phi());
    const auto p = surface_point_at_pixel(surface, c.pixel);
    if (!p || !move_if_no_flip(m, v, *p)) ++unmoved;
  }
  return unmoved;
}

std::size_t line_degree(const SM& m, SM::Vertex_index v,
                        const SM::Property_map<SM::Edge_index, bool>& on_line) {
  std::size_t n = 0;
  for (auto h : halfedges_around_target(m.halfedge(v), m)) n += on_line[m.edge(h)];
  return n;
}

LinedBand trace_lines(const SM& band, const std::vector<Eigen::Vector2d>& pixel,
                      const aft::RegionGraph& g, const ScanSurface& surface) {
  LinedBand out{band};
  SM& m = out.mesh;
  auto on_line = m.add_property_map<SM::Edge_index, bool>("e:line", false).first;
  auto fixed = m.add_property_map<SM::Vertex_index, bool>("v:line", false).first;
  auto node_of = m.add_property_map<SM::Vertex_index, int>("v:node", -1).first;
  LineTracer tracer(m, pixel, surface.n_phi());
  // Junctions and line ends first: segments sharing a node share its vertex, which then sits
  // exactly on the node.
  std::vector<std::optional<SM::Vertex_index>> node_vertex(g.nodes.size());
  for (std::size_t i = 0; i < g.nodes.size(); ++i) {
    const Eigen::Vector2d px = aft::param_to_pixel(surface, g.nodes[i]);
    node_vertex[i] = tracer.snap(px, 1.5);
    if (!node_vertex[i]) {
      ++out.unsnapped_nodes;
      continue;
    }
    tracer.take(*node_vertex[i]);
    node_of[*node_vertex[i]] = static_cast<int>(i);
    const auto p = surface_point_at_pixel(surface, px);
    if (!p || !move_if_no_flip(m, *node_vertex[i], *p)) ++out.unmoved_vertices;
  }
  for (const aft::Segment& s : g.segments) {
    if (!node_vertex[s.node0] || !node_vertex[s.node1]) {
      ++out.untraced_segments;
      continue;
    }
    const TracedSegment traced = trace_segment(tracer, s, node_vertex, on_line, surface);
    out.untraced_segments += traced.legs.empty();
    out.partial_segments += traced.partial && !traced.legs.empty();
    out.segments += !traced.legs.empty();
    for (const Leg& leg : traced.legs) {
      out.unmoved_vertices += move_onto_line(m, leg, pixel, surface);
      for (std::size_t i = 0; i + 1 < leg.path.size(); ++i)
        on_line[m.edge(m.halfedge(leg.path[i], leg.path[i + 1]))] = true;
      out.edges += leg.path.size() - 1;
    }
    out.chains.insert(out.chains.end(), traced.chains.begin(), traced.chains.end());
  }
  // Where != 2 line edges meet (junctions, line ends) CGAL must keep the vertex; the nodes of
  // degree 2 (a loop's node, a corner where two lines end) are kept as well.
  for (auto v : m.vertices()) {
    const std::size_t d = line_degree(m, v, on_line);
    fixed[v] = d > 0 && (d != 2 || node_of[v] >= 0);
    out.constrained_vertices += fixed[v];
  }
  return out;
}

// isotropic_remeshing of a copy of the lined band: the lines' edges constrained but not
// protected, so CGAL splits and collapses along them; their junctions and ends fixed.
SM remesh_along_lines(const SM& lined, double edge, double* seconds) {
  SM m = lined;
  auto on_line = m.property_map<SM::Edge_index, bool>("e:line").first;
  auto fixed = m.property_map<SM::Vertex_index, bool>("v:line").first;
  const auto t0 = std::chrono::steady_clock::now();
  PMP::isotropic_remeshing(faces(m), edge, m,
                           CGAL::parameters::number_of_iterations(3)
                               .edge_is_constrained_map(on_line)
                               .vertex_is_constrained_map(fixed)
                               .protect_constraints(false)
                               .relax_constraints(kRelaxConstraints));
  *seconds = seconds_since(t0);
  m.collect_garbage();
  return m;
}

// What CGAL made of the lines: the line edges it kept (the map follows splits and collapses),
// the chains they form between fixed vertices, how many of these join the same two nodes as a
// traced segment, and how far the chains' vertices are from the nearest line in (phi, h).
struct ChainCheck {
  std::size_t edges = 0, chains = 0, matched = 0, broken = 0;
  double max_offset_px = 0, mean_offset_px = 0;  // mean over edge ends
};

ChainCheck check_line_chains(const SM& m, const LinedBand& in,
                             const std::vector<std::vector<Eigen::Vector2d>>& lines_px,
                             const ScanSurface& surface) {
  auto on_line = m.property_map<SM::Edge_index, bool>("e:line").first;
  auto node_of = m.property_map<SM::Vertex_index, int>("v:node").first;
  ChainCheck out;
  auto is_end = [&](SM::Vertex_index v) {
    return node_of[v] >= 0 || line_degree(m, v, on_line) != 2;
  };
  std::multiset<std::pair<int, int>> expected(in.chains.begin(), in.chains.end());
  std::vector<char> seen(m.number_of_edges(), 0);
  for (auto h0 : m.halfedges()) {
    if (!on_line[m.edge(h0)] || seen[m.edge(h0)] || !is_end(m.source(h0))) continue;
    SM::Halfedge_index h = h0;
    seen[m.edge(h)] = 1;
    while (!is_end(m.target(h))) {
      SM::Halfedge_index next = h;
      for (auto g : halfedges_around_source(m.target(h), m))
        if (on_line[m.edge(g)] && m.edge(g) != m.edge(h)) next = g;
      h = next;
      seen[m.edge(h)] = 1;
    }
    ++out.chains;
    const auto ends = std::minmax(node_of[m.source(h0)], node_of[m.target(h)]);
    if (const auto it = expected.find(ends); it != expected.end()) {
      expected.erase(it);
      ++out.matched;
    }
  }
  for (auto e : m.edges()) {
    out.edges += on_line[e];
    out.broken += on_line[e] && !seen[e];  // on a closed chain without a fixed vertex
    if (!on_line[e]) continue;
    for (int k = 0; k < 2; ++k) {
      const auto& p = m.point(m.vertex(e, k));
      const Eigen::Vector3d cyl = ScanSurface::to_cylindrical({p.x(), p.y(), p.z()});
      const Eigen::Vector2d px = aft::param_to_pixel(surface, {cyl.x(), cyl.y()});
      double offset = std::numeric_limits<double>::infinity();
      for (const auto& line : lines_px)
        offset = std::min(offset, closest_on_polyline(line, px, surface.n_phi()).distance_px);
      out.max_offset_px = std::max(out.max_offset_px, offset);
      out.mean_offset_px += offset;
    }
  }
  if (out.edges) out.mean_offset_px /= 2.0 * static_cast<double>(out.edges);
  return out;
}

std::vector<std::vector<Eigen::Vector2d>> segment_pixels(const aft::RegionGraph& g,
                                                         const ScanSurface& surface) {
  std::vector<std::vector<Eigen::Vector2d>> out;
  for (const aft::Segment& s : g.segments) {
    out.emplace_back();
    for (const auto& p : s.pts) out.back().push_back(aft::param_to_pixel(surface, p));
  }
  return out;
}

}  // namespace

// The "lines constrained, same count" row: the lines traced on the band, CGAL's target edge tuned
// from the unconstrained same-count run (edge, count) in three rounds to the AFT's count.
void print_lines_constrained(const SM& band, const std::vector<Eigen::Vector2d>& pixel,
                             const aft::RegionGraph& g, const ScanSurface& surface, double edge,
                             std::size_t count, std::size_t target_count) {
  const LinedBand lined = trace_lines(band, pixel, g, surface);
  double seconds = 0;
  SM m;
  for (int round = 0; round < 3; ++round) {
    edge *= std::sqrt(static_cast<double>(count) / static_cast<double>(target_count));
    m = remesh_along_lines(lined.mesh, edge, &seconds);
    count = m.number_of_vertices();
  }
  const ChainCheck check = check_line_chains(m, lined, segment_pixels(g, surface), surface);
  const aft::AnimationMesh cl = to_animation_mesh(m);
  print(Row{"CGAL, lines constrained, same count", seconds, cl.mesh.positions.size(),
            cl.mesh.triangles.size(), aft::evaluate_quality(cl, surface, 4, &g)});
  std::printf(
      "  lines: %zu of %zu segments traced (%zu only up to a hole of the band from both ends) as "
      "%zu polylines, %zu edges, %zu fixed vertices; %zu nodes not snapped, %zu vertices left off "
      "their line; target edge %.2f mm\n",
      lined.segments, g.segments.size(), lined.partial_segments, lined.chains.size(), lined.edges,
      lined.constrained_vertices, lined.unsnapped_nodes, lined.unmoved_vertices, edge);
  std::printf(
      "  after CGAL: %zu constrained edges in %zu chains, %zu of %zu polylines kept as a chain "
      "between the same ends, %zu edges off these chains; their vertices %.3f px (mean), %.3f px "
      "(max) from a line\n",
      check.edges, check.chains, check.matched, lined.chains.size(), check.broken,
      check.mean_offset_px, check.max_offset_px);
}

// Each band vertex's pixel: its grid cell's centre.
std::vector<Eigen::Vector2d> band_pixels(const SM& band,
                                         const std::map<SM::Vertex_index, int>& back,
                                         const GridMesh& gm, int n_phi) {
  std::vector<Eigen::Vector2d> out(band.number_of_vertices());
  for (const auto& [v, i] : back) {
    const std::size_t cell = gm.vertex_cell[i];
    out[v] = {static_cast<double>(cell % n_phi) + 0.5, static_cast<double>(cell / n_phi) + 0.5};
  }
  return out;
}

}  // namespace scanmesh::bench_aft
