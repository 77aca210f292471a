// Region analysis: the planar graph of the animation lines on the scan cylinder. All geometry
// here is in texture pixels (x unwrapped with period n_phi); (phi, h) only at the end. The
// positive diagonal map pixel -> (phi, h) keeps orientations, so "counter-clockwise" means the
// same in both.
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>
#include <tuple>

#include "aft_internal.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/aft/regions.h"

namespace scanmesh::aft {

using detail::periodic_copy_near;
using detail::signed_area;
using Eigen::Vector2d;

namespace {

constexpr double kNodeMergePx = 1e-6;

struct Piece {
  Vector2d a, b;
  int line, index;
};

struct Event {
  double s;  // piece index + t
  int node;
};

bool point_in_polygon_plain(const std::vector<Vector2d>& poly, const Vector2d& q) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vector2d& a = poly[i];
    const Vector2d& b = poly[j];
    if ((a.y() > q.y()) != (b.y() > q.y())) {
      const double x = a.x() + (q.y() - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
      if (q.x() < x) inside = !inside;
    }
  }
  return inside;
}

// Point in a winding-0 polygon with x unwrapped whose x runs over [xmin, xmax]: tries the
// periodic copies of q in that range.
bool point_in_polygon_copies(const std::vector<Vector2d>& poly, Vector2d q, double W, double xmin,
                             double xmax) {
  if (poly.size() < 3) return false;
  q.x() -= W * std::floor((q.x() - xmin) / W);
  for (; q.x() <= xmax; q.x() += W)
    if (point_in_polygon_plain(poly, q)) return true;
  return false;
}

bool point_in_polygon(const std::vector<Vector2d>& poly, Vector2d q, double W) {
  double xmin = 1e300, xmax = -1e300;
  for (const Vector2d& p : poly) {
    xmin = std::min(xmin, p.x());
    xmax = std::max(xmax, p.x());
  }
  return point_in_polygon_copies(poly, q, W, xmin, xmax);
}

double wrap_x(double x, double W) { return x - W * std::floor(x / W); }

double wrapped_distance(const Vector2d& a, const Vector2d& b, double W) {
  double dx = std::fabs(wrap_x(a.x(), W) - wrap_x(b.x(), W));
  dx = std::min(dx, W - dx);
  return std::hypot(dx, a.y() - b.y());
}

// Index pairs (i < j, sorted) of the intervals [lo[i], hi[i]] that overlap by more than -slack:
// a sweep over the sorted lower ends, O(n log n + pairs). The callers test each pair exactly as
// the all-pairs loops did, in the same order, so the results do not change; only the pairs
// that cannot meet are no longer visited (a 40,000-point line took 35 s that way).
std::vector<std::pair<int, int>> overlapping_pairs(const std::vector<double>& lo,
                                                   const std::vector<double>& hi, double slack) {
  std::vector<int> order(lo.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lo[a] < lo[b]; });
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t a = 0; a < order.size(); ++a)
    for (std::size_t b = a + 1; b < order.size() && lo[order[b]] <= hi[order[a]] + slack; ++b)
      pairs.emplace_back(std::min(order[a], order[b]), std::max(order[a], order[b]));
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(int n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[x] != x) x = p[x] = p[p[x]];  // path halving: no recursion on long chains
    return x;
  }
  void unite(int a, int b) { p[find(a)] = find(b); }
};

}  // namespace

std::vector<Vector2d> RegionGraph::cycle_polygon(int c) const {
  std::vector<Vector2d> poly;
  const double period = 2 * M_PI;
  for (const HalfEdgeRef& he : cycles[c].edges) {
    std::vector<Vector2d> pts = segments[he.segment].pts;
    if (!he.forward) std::reverse(pts.begin(), pts.end());
    if (!poly.empty()) {
      const double shift = period * std::round((poly.back().x() - pts.front().x()) / period);
      for (Vector2d& p : pts) p.x() += shift;
    }
    for (std::size_t k = poly.empty() ? 0 : 1; k < pts.size(); ++k) poly.push_back(pts[k]);
  }
  if (poly.size() > 1) poly.pop_back();  // the closing point repeats the first (shifted)
  return poly;
}

std::optional<int> RegionGraph::region_at(const Vector2d& param) const {
  return RegionLocator(*this).region_at(param);
}

RegionLocator::RegionLocator(const RegionGraph& g) {
  for (const Region& r : g.regions) {
    outer_.push_back(make(g.cycle_polygon(r.outer)));
    holes_.emplace_back();
    for (int h : r.inner) holes_.back().push_back(make(g.cycle_polygon(h)));
    area_.push_back(std::fabs(g.cycles[r.outer].area));
  }
}

RegionLocator::Polygon RegionLocator::make(std::vector<Vector2d> pts) {
  Polygon p;
  p.xmin = p.ymin = 1e300;
  p.xmax = p.ymax = -1e300;
  for (const Vector2d& q : pts) {
    p.xmin = std::min(p.xmin, q.x());
    p.xmax = std::max(p.xmax, q.x());
    p.ymin = std::min(p.ymin, q.y());
    p.ymax = std::max(p.ymax, q.y());
  }
  p.pts = std::move(pts);
  return p;
}

// point_in_polygon with the box kept and its h range tested first.
bool RegionLocator::contains(const Polygon& poly, Vector2d q) {
  if (q.y() < poly.ymin || q.y() > poly.ymax) return false;
  return point_in_polygon_copies(poly.pts, q, 2 * M_PI, poly.xmin, poly.xmax);
}

std::optional<int> RegionLocator::region_at(const Vector2d& param) const {
  std::optional<int> best;
  double best_area = 1e300;
  for (std::size_t r = 0; r < outer_.size(); ++r) {
    if (area_[r] >= best_area || !contains(outer_[r], param)) continue;
    bool in_hole = false;
    for (const Polygon& h : holes_[r])
      if (contains(h, param)) in_hole = true;
    // A hole's polygon (its component's outside, clockwise) contains the component's inside.
    if (in_hole) continue;
    best_area = area_[r];
    best = static_cast<int>(r);
  }
  return best;
}

std::string RegionGraph::to_text() const {
  std::ostringstream os;
  int openings = 0;
  for (const Region& r : regions) openings += r.opening;
  os << nodes.size() << " nodes, " << segments.size() << " segments, " << regions.size() - openings
     << " regions, " << openings << " openings, " << dangling_ends.size()
     << " dangling line ends\n";
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const Region& g = regions[r];
    int constraint_edges = 0;
    for (int c : g.inner) constraint_edges += static_cast<int>(cycles[c].edges.size());
    os << "  " << r << " " << g.name << (g.opening ? " (opening)" : "") << ": "
       << cycles[g.outer].edges.size() << " boundary segments, " << g.inner.size()
       << " inner loops (" << constraint_edges << " segments), area " << g.area << " rad*mm, unit "
       << g.unit_mm << " mm, mesher " << g.mesher << "\n";
  }
  return os.str();
}

namespace {

// The animation lines in texture pixels, x unwrapped along each line with period W, and their
// pieces (the straight spans between consecutive points) once the open ends are snapped.
struct PixelLines {
  double W = 0;                          // texture width in pixels: the period of x
  std::vector<std::vector<Vector2d>> L;  // points per line
  std::vector<bool> closed;              // per line
  std::vector<std::vector<Piece>> P;     // pieces per line, set by split_into_pieces
};

// Graph nodes as found, before coincident ones are merged, and where each line passes them.
struct FoundNodes {
  std::vector<Vector2d> node_pos;          // pixels, x wrapped into [0, W)
  std::vector<std::vector<Event>> events;  // per line

  int add_node(Vector2d p, double W) {
    p.x() = wrap_x(p.x(), W);
    node_pos.push_back(p);
    return static_cast<int>(node_pos.size()) - 1;
  }
};

// The graph's nodes after merging.
struct MergedNodes {
  std::vector<int> node_id;       // per found node: its graph node
  std::vector<Vector2d> node_px;  // per graph node: pixels, x wrapped into [0, W)
};

// The half-edges leaving each node, sorted counter-clockwise. Half-edge he runs along segment
// he / 2, forwards when he is even.
struct HalfEdgeFans {
  std::vector<std::vector<int>> out;  // per node
  std::vector<int> pos_in;            // per half-edge: its place in its start node's list

  // The face walk: "next = previous counter-clockwise" round the end node.
  int next_of(const std::vector<Segment>& segments, int he) const;
};

int half_edge_start(const std::vector<Segment>& segments, int he) {
  const Segment& s = segments[he / 2];
  return he % 2 == 0 ? s.node0 : s.node1;
}

int HalfEdgeFans::next_of(const std::vector<Segment>& segments, int he) const {
  const int twin = he ^ 1;
  const auto& o = out[half_edge_start(segments, twin)];
  const int k = pos_in[twin];
  return o[(k - 1 + static_cast<int>(o.size())) % o.size()];
}

// The direction in which half-edge he leaves its start node (pixels).
Vector2d half_edge_direction(const std::vector<std::vector<Vector2d>>& seg_px, int he) {
  const auto& p = seg_px[he / 2];
  if (he % 2 == 0) {
    for (std::size_t i = 1; i < p.size(); ++i)
      if ((p[i] - p[0]).norm() > 1e-9) return Vector2d(p[i] - p[0]);
  } else {
    for (std::size_t i = p.size() - 1; i-- > 0;)
      if ((p[i] - p.back()).norm() > 1e-9) return Vector2d(p[i] - p.back());
  }
  return Vector2d(1, 0);
}

std::string describe_line(const LineSet& set, int l) {
  return "line '" + set.lines[l].id + "' (" + set.lines[l].source + ")";
}

// 1. Lines in unwrapped pixels (consecutive points less than half a turn apart).
PixelLines unwrap_lines(const LineSet& set, double W) {
  PixelLines lines;
  lines.W = W;
  lines.L.resize(set.lines.size());
  lines.closed.resize(set.lines.size());
  for (std::size_t l = 0; l < set.lines.size(); ++l) {
    lines.closed[l] = set.lines[l].closed;
    lines.L[l] = line_curve(set.lines[l], W);
  }
  return lines;
}

// The pieces of line l as its points stand now. A closed line's last piece goes back to the
// first point, moved by whole turns next to the last.
std::vector<Piece> pieces_of(const PixelLines& lines, std::size_t l) {
  const double W = lines.W;
  std::vector<Piece> out;
  const auto& p = lines.L[l];
  const std::size_t n = lines.closed[l] ? p.size() : p.size() - 1;
  for (std::size_t k = 0; k < n; ++k) {
    Vector2d b = p[(k + 1) % p.size()];
    if (k + 1 == p.size()) b.x() += W * std::round((p[k].x() - b.x()) / W);
    out.push_back({p[k], b, static_cast<int>(l), static_cast<int>(k)});
  }
  return out;
}

// The point of piece pc (moved by whole turns next to q) closest to q; t: its place on pc.
Vector2d closest_on(const Vector2d& q, const Piece& pc, double W, double& t) {
  Vector2d a = pc.a, b = pc.b;
  const double shift = W * std::round((q.x() - 0.5 * (a.x() + b.x())) / W);
  a.x() += shift;
  b.x() += shift;
  t = detail::closest_segment_parameter(q, a, b);
  return Vector2d(a + t * (b - a));
}

// 2. Snap open ends onto other lines.
void snap_open_ends(PixelLines& lines, double snap_px) {
  const double W = lines.W;
  auto& L = lines.L;
  const auto& closed = lines.closed;
  // The pieces in height bands of the snap distance: an end looks only at the pieces of its
  // own and the neighbouring bands, in the all-pairs loop's order (line, then piece).
  std::vector<Piece> snap_pieces;
  for (std::size_t m = 0; m < L.size(); ++m)
    for (const Piece& pc : pieces_of(lines, m)) snap_pieces.push_back(pc);
  const double band = std::max(snap_px, 0.5);
  std::map<long long, std::vector<int>> in_band;
  for (std::size_t k = 0; k < snap_pieces.size(); ++k) {
    const Piece& pc = snap_pieces[k];
    const auto b0 = static_cast<long long>(std::floor(std::min(pc.a.y(), pc.b.y()) / band));
    const auto b1 = static_cast<long long>(std::floor(std::max(pc.a.y(), pc.b.y()) / band));
    for (long long b = b0; b <= b1; ++b) in_band[b].push_back(static_cast<int>(k));
  }
  std::vector<int> near;
  for (std::size_t l = 0; l < L.size(); ++l) {
    if (closed[l]) continue;
    for (int end = 0; end < 2; ++end) {
      Vector2d& q = end == 0 ? L[l].front() : L[l].back();
      double best = snap_px;
      std::optional<Vector2d> target;
      near.clear();
      const auto qb = static_cast<long long>(std::floor(q.y() / band));
      for (long long b = qb - 1; b <= qb + 1; ++b)
        if (const auto it = in_band.find(b); it != in_band.end())
          near.insert(near.end(), it->second.begin(), it->second.end());
      std::sort(near.begin(), near.end());
      near.erase(std::unique(near.begin(), near.end()), near.end());
      for (int k : near) {
        const Piece& pc = snap_pieces[k];
        if (pc.line == static_cast<int>(l)) continue;
        {
          double t;
          const Vector2d c = closest_on(q, pc, W, t);
          // Prefer the other line's end points: joining ends should land on them exactly.
          const double d = (c - q).norm() - ((t == 0.0 || t == 1.0) ? 1e-9 : 0.0);
          if (d < best) {
            best = d;
            target = c;
          }
        }
      }
      if (target) q = *target;
    }
  }
}

// The pieces of every line, once its ends are final.
void split_into_pieces(PixelLines& lines) {
  lines.P.resize(lines.L.size());
  for (std::size_t l = 0; l < lines.L.size(); ++l) lines.P[l] = pieces_of(lines, l);
}

// Index pairs of the pieces whose height ranges overlap, in the all-pairs loop's order.
std::vector<std::pair<int, int>> crossing_candidates(const std::vector<const Piece*>& all_pieces) {
  std::vector<double> y_lo(all_pieces.size()), y_hi(all_pieces.size());
  for (std::size_t k = 0; k < all_pieces.size(); ++k) {
    y_lo[k] = std::min(all_pieces[k]->a.y(), all_pieces[k]->b.y());
    y_hi[k] = std::max(all_pieces[k]->a.y(), all_pieces[k]->b.y());
  }
  std::vector<std::pair<int, int>> candidates = overlapping_pairs(y_lo, y_hi, 1e-9);
  // The all-pairs loop's order (line, other line, piece, other piece), so that the nodes are
  // numbered as before.
  std::sort(candidates.begin(), candidates.end(), [&](const auto& x, const auto& y) {
    return std::tuple(all_pieces[x.first]->line, all_pieces[x.second]->line, x.first, x.second) <
           std::tuple(all_pieces[y.first]->line, all_pieces[y.second]->line, y.first, y.second);
  });
  return candidates;
}

// The crossings of pieces p and q0 (q0 tried at the seam shifts) as nodes and events on both
// lines. Throws for a line that crosses or runs back over itself and for overlapping lines.
void add_crossings(const LineSet& set, const PixelLines& lines, const Piece& p, const Piece& q0,
                   FoundNodes& found) {
  const double W = lines.W;
  const std::string& file = set.file;
  const std::size_t l = static_cast<std::size_t>(p.line), m = static_cast<std::size_t>(q0.line);
  const int np = static_cast<int>(lines.P[l].size());
  if (l == m) {
    if (q0.index <= p.index) return;
    const bool adjacent =
        q0.index == p.index + 1 || (lines.closed[l] && p.index == 0 && q0.index == np - 1);
    if (adjacent) return;
  }
  const Vector2d pmin = p.a.cwiseMin(p.b), pmax = p.a.cwiseMax(p.b);
  for (int k = -1; k <= 1; ++k) {
    const Piece q = periodic_copy_near(p, q0, W, k);
    const Vector2d qmin = q.a.cwiseMin(q.b), qmax = q.a.cwiseMax(q.b);
    if (qmin.x() > pmax.x() + 1e-9 || qmax.x() < pmin.x() - 1e-9 || qmin.y() > pmax.y() + 1e-9 ||
        qmax.y() < pmin.y() - 1e-9)
      continue;
    const Vector2d r = p.b - p.a, s = q.b - q.a, w = q.a - p.a;
    const double den = r.x() * s.y() - r.y() * s.x();
    const double scale = r.norm() * s.norm();
    double t, u;
    if (std::fabs(den) <= 1e-12 * scale) {
      // Parallel: only a shared end point counts; overlapping collinear pieces fail.
      const double cross = w.x() * r.y() - w.y() * r.x();
      if (std::fabs(cross) > 1e-9 * r.norm()) continue;
      const double t0 = w.dot(r) / r.squaredNorm();
      const double t1 = (q.b - p.a).dot(r) / r.squaredNorm();
      const double lo = std::max(0.0, std::min(t0, t1)), hi = std::min(1.0, std::max(t0, t1));
      if (hi < lo - 1e-12) continue;
      if (hi - lo > 1e-9) {
        if (l == m) throw FileFormatError(file, describe_line(set, l) + " runs back over itself");
        throw FileFormatError(file,
                              describe_line(set, l) + " and " + describe_line(set, m) + " overlap");
      }
      t = lo;
      u = std::fabs(t0 - t) < std::fabs(t1 - t) ? 0.0 : 1.0;
    } else {
      t = (w.x() * s.y() - w.y() * s.x()) / den;
      u = (w.x() * r.y() - w.y() * r.x()) / den;
      if (t < -1e-12 || t > 1 + 1e-12 || u < -1e-12 || u > 1 + 1e-12) continue;
      t = std::clamp(t, 0.0, 1.0);
      u = std::clamp(u, 0.0, 1.0);
    }
    if (l == m) {
      // Touching at the shared vertex of a closed line's last and first pieces is not a
      // crossing; anything else is.
      std::ostringstream os;
      const Vector2d x = file_pixel(set, p.a + t * r);
      os.precision(1);
      os << std::fixed << describe_line(set, l) << " intersects itself at pixel ("
         << wrap_x(x.x(), W) << ", " << x.y() << ")";
      throw FileFormatError(file, os.str());
    }
    const int node = found.add_node(p.a + t * r, W);
    found.events[l].push_back({p.index + t, node});
    found.events[m].push_back({q0.index + u, node});
  }
}

// 3. Intersections -> events on both lines.
void add_crossing_nodes(const LineSet& set, const PixelLines& lines, FoundNodes& found) {
  // Candidate piece pairs: those whose height ranges overlap (any crossing does; the x test
  // with the seam shifts follows), in (line, piece) order.
  std::vector<const Piece*> all_pieces;
  for (const auto& pieces : lines.P)
    for (const Piece& pc : pieces) all_pieces.push_back(&pc);
  for (const auto& [first_piece, second_piece] : crossing_candidates(all_pieces))
    add_crossings(set, lines, *all_pieces[first_piece], *all_pieces[second_piece], found);
}

// 4. Open ends are nodes too.
void add_open_end_nodes(const PixelLines& lines, FoundNodes& found) {
  for (std::size_t l = 0; l < lines.L.size(); ++l) {
    if (lines.closed[l]) continue;
    found.events[l].push_back({0.0, found.add_node(lines.L[l].front(), lines.W)});
    found.events[l].push_back(
        {static_cast<double>(lines.P[l].size()), found.add_node(lines.L[l].back(), lines.W)});
  }
}

// 5. Merge coincident nodes.
MergedNodes merge_coincident_nodes(const std::vector<Vector2d>& node_pos, double W) {
  UnionFind uf(static_cast<int>(node_pos.size()));
  {
    const double merge = kNodeMergePx * 100;
    std::vector<double> y(node_pos.size());
    for (std::size_t i = 0; i < node_pos.size(); ++i) y[i] = node_pos[i].y();
    for (const auto& [i, j] : overlapping_pairs(y, y, merge))
      if (wrapped_distance(node_pos[i], node_pos[j], W) < merge) uf.unite(i, j);
  }
  MergedNodes merged;
  std::vector<int>& node_id = merged.node_id;
  std::vector<Vector2d>& node_px = merged.node_px;
  node_id.assign(node_pos.size(), -1);
  for (std::size_t i = 0; i < node_pos.size(); ++i) {
    const int root = uf.find(static_cast<int>(i));
    if (node_id[root] < 0) {
      node_id[root] = static_cast<int>(node_px.size());
      node_px.push_back(node_pos[root]);
    }
    node_id[i] = node_id[root];
  }
  return merged;
}

// The point of line l at s = piece index + t.
Vector2d point_at(const PixelLines& lines, std::size_t l, double s) {
  const auto& P = lines.P;
  const int k = std::min(static_cast<int>(std::floor(s)), static_cast<int>(P[l].size()) - 1);
  const Piece& pc = P[l][std::max(k, 0)];
  return Vector2d(pc.a + (s - pc.index) * (pc.b - pc.a));
}

// The events of line l as graph nodes in order along it, each junction once. A closed line
// that meets nothing gets a node of its own at its first point.
std::vector<Event> junctions_along(const PixelLines& lines, std::size_t l, std::vector<Event>& ev,
                                   const std::vector<int>& node_id,
                                   std::vector<Vector2d>& node_px) {
  const double W = lines.W;
  for (Event& e : ev) e.node = node_id[e.node];
  std::sort(ev.begin(), ev.end(), [](const Event& a, const Event& b) {
    return a.s < b.s || (a.s == b.s && a.node < b.node);
  });
  std::vector<Event> uniq;
  for (const Event& e : ev)
    if (uniq.empty() || e.s - uniq.back().s > 1e-9 || e.node != uniq.back().node) uniq.push_back(e);
  const double smax = static_cast<double>(lines.P[l].size());
  if (lines.closed[l]) {
    if (uniq.size() > 1 && uniq.back().node == uniq.front().node &&
        smax - uniq.back().s + uniq.front().s < 1e-9)
      uniq.pop_back();
    if (uniq.empty()) {
      uniq.push_back({0.0, static_cast<int>(node_px.size())});
      node_px.push_back(Vector2d(wrap_x(lines.L[l][0].x(), W), lines.L[l][0].y()));
    }
  }
  return uniq;
}

// The segments of line l between consecutive junctions, with their points in pixels.
void add_segments_of_line(const PixelLines& lines, std::size_t l, const std::vector<Event>& uniq,
                          RegionGraph& g, std::vector<std::vector<Vector2d>>& seg_px) {
  const double W = lines.W;
  const auto& L = lines.L;
  const auto& P = lines.P;
  const auto& closed = lines.closed;
  const double smax = static_cast<double>(P[l].size());
  const std::size_t nseg = closed[l] ? uniq.size() : uniq.size() - 1;
  for (std::size_t k = 0; k < nseg; ++k) {
    const Event a = uniq[k];
    Event b = uniq[(k + 1) % uniq.size()];
    double sb = b.s;
    if (closed[l] && k + 1 == uniq.size()) sb += smax;
    if (sb - a.s < 1e-12) continue;
    std::vector<Vector2d> pts;
    auto at = [&](double s) {
      double off = 0;
      if (closed[l] && s >= smax) {
        s -= smax;
        off = P[l].back().b.x() - L[l][0].x();  // one trip round: the unwrapping offset
      }
      Vector2d p = point_at(lines, l, s);
      p.x() += off;
      return p;
    };
    pts.push_back(at(a.s));
    for (double v = std::floor(a.s) + 1; v < sb - 1e-12; v += 1) pts.push_back(at(v));
    pts.push_back(at(sb));
    // make continuous
    for (std::size_t i = 1; i < pts.size(); ++i)
      pts[i].x() += W * std::round((pts[i - 1].x() - pts[i].x()) / W);
    Segment seg;
    seg.line = static_cast<int>(l);
    seg.node0 = a.node;
    seg.node1 = b.node;
    g.segments.push_back(seg);
    seg_px.push_back(pts);
  }
}

// 6. Segments between consecutive events of each line.
void build_segments(const PixelLines& lines, FoundNodes& found, MergedNodes& merged, RegionGraph& g,
                    std::vector<std::vector<Vector2d>>& seg_px) {
  for (std::size_t l = 0; l < lines.L.size(); ++l) {
    const std::vector<Event> uniq =
        junctions_along(lines, l, found.events[l], merged.node_id, merged.node_px);
    add_segments_of_line(lines, l, uniq, g, seg_px);
  }
}

// 7. Half-edges sorted round each node.
HalfEdgeFans sort_half_edges_round_nodes(const std::vector<Segment>& segments,
                                         const std::vector<std::vector<Vector2d>>& seg_px,
                                         std::size_t node_count) {
  const int nh = 2 * static_cast<int>(segments.size());
  HalfEdgeFans fans;
  std::vector<std::vector<int>>& out = fans.out;
  std::vector<int>& pos_in = fans.pos_in;
  out.resize(node_count);
  for (int he = 0; he < nh; ++he) out[half_edge_start(segments, he)].push_back(he);
  pos_in.resize(nh);
  for (auto& o : out) {
    std::sort(o.begin(), o.end(), [&](int a, int b) {
      const Vector2d da = half_edge_direction(seg_px, a), db = half_edge_direction(seg_px, b);
      const double aa = std::atan2(da.y(), da.x()), ab = std::atan2(db.y(), db.x());
      return aa < ab || (aa == ab && a < b);
    });
    for (std::size_t k = 0; k < o.size(); ++k) pos_in[o[k]] = static_cast<int>(k);
  }
  return fans;
}

// Segments in (phi, h) for the graph.
void add_param_geometry(RegionGraph& g, const std::vector<std::vector<Vector2d>>& seg_px,
                        const std::vector<Vector2d>& node_px, const ScanSurface& surface) {
  for (std::size_t s = 0; s < g.segments.size(); ++s)
    for (const Vector2d& p : seg_px[s]) g.segments[s].pts.push_back(pixel_to_param(surface, p));
  for (const Vector2d& p : node_px) g.nodes.push_back(pixel_to_param(surface, p));
}

// The faces' boundary cycles with their components, windings and areas; returns the cycle of
// each half-edge.
std::vector<int> trace_boundary_cycles(RegionGraph& g, const HalfEdgeFans& fans,
                                       std::size_t node_count) {
  const int nh = 2 * static_cast<int>(g.segments.size());
  // Components.
  UnionFind comp(static_cast<int>(node_count));
  for (const Segment& s : g.segments) comp.unite(s.node0, s.node1);
  std::vector<int> cycle_of(nh, -1);
  for (int he = 0; he < nh; ++he) {
    if (cycle_of[he] >= 0) continue;
    BoundaryCycle c;
    c.component = comp.find(half_edge_start(g.segments, he));
    int cur = he;
    do {
      cycle_of[cur] = static_cast<int>(g.cycles.size());
      c.edges.push_back({cur / 2, cur % 2 == 0});
      cur = fans.next_of(g.segments, cur);
    } while (cur != he && c.edges.size() <= static_cast<std::size_t>(nh));
    g.cycles.push_back(c);
    const std::vector<Vector2d> poly = g.cycle_polygon(static_cast<int>(g.cycles.size()) - 1);
    // winding: phi advance over the closed walk
    double advance = 0;
    for (const HalfEdgeRef& e : c.edges) {
      const auto& pts = g.segments[e.segment].pts;
      advance += (e.forward ? 1 : -1) * (pts.back().x() - pts.front().x());
    }
    g.cycles.back().winding = static_cast<int>(std::lround(advance / (2 * M_PI)));
    g.cycles.back().area = g.cycles.back().winding == 0 ? signed_area(poly) : 0.0;
  }
  return cycle_of;
}

// A band round the axis between two sets of lines that each go all the way round, with no
// line joining them, is a face of the graph that no (phi, h) polygon bounds: its two boundary
// cycles wind round the axis and belong to different components. Every connected set of
// lines that goes round has two such cycles (its sides towards the crown and the neck, left
// unmeshed like everything outside the lines); a second such set makes a band. It is an error
// rather than a silent hole in the mesh: one line joining the sets cuts the band open.
void check_round_sets_are_joined(const RegionGraph& g, const LineSet& set) {
  const std::string& file = set.file;
  std::vector<int> round_components;
  std::vector<std::string> round_sets;  // per component: the lines that carry its turn
  for (const BoundaryCycle& cy : g.cycles) {
    if (cy.winding == 0 || std::find(round_components.begin(), round_components.end(),
                                     cy.component) != round_components.end())
      continue;
    round_components.push_back(cy.component);
    // Lines walked one way only: a line hanging off the loop is walked there and back.
    std::map<int, int> walked;
    for (const HalfEdgeRef& e : cy.edges) walked[e.segment] += e.forward ? 1 : -1;
    std::vector<int> carrying;
    for (const auto& [segment, net] : walked) {
      const int line = g.segments[segment].line;
      if (net != 0 && std::find(carrying.begin(), carrying.end(), line) == carrying.end())
        carrying.push_back(line);
    }
    std::string names;
    for (std::size_t k = 0; k < carrying.size(); ++k)
      names += (k ? (k + 1 == carrying.size() ? " and " : ", ") : "") +
               ("'" + set.lines[carrying[k]].id + "'");
    round_sets.push_back(carrying.size() > 1 ? "lines " + names + " (together)" : "line " + names);
  }
  if (round_components.size() > 1) {
    std::string list;
    for (std::size_t k = 0; k < round_sets.size(); ++k) list += (k ? "; " : "") + round_sets[k];
    throw FileFormatError(
        file, std::to_string(round_sets.size()) +
                  " separate sets of lines go all the way round the axis (" + list +
                  ") and no line joins them: the bands between them are not regions; draw a "
                  "line joining each pair of neighbouring sets (a seam, say) to cut the bands "
                  "open");
  }
}

// 8. Regions: counter-clockwise winding-0 cycles; returns the region of each cycle (-1 none).
std::vector<int> collect_regions(RegionGraph& g, const LineSet& set) {
  std::vector<int> region_of_cycle(g.cycles.size(), -1);
  for (std::size_t c = 0; c < g.cycles.size(); ++c) {
    const BoundaryCycle& cy = g.cycles[c];
    if (cy.winding != 0 || cy.area <= 1e-12) continue;
    Region r;
    r.outer = static_cast<int>(c);
    // An opening cut by the data border stays an opening: the border only closes it.
    bool any_opening = false, only_openings = true;
    for (const HalfEdgeRef& e : cy.edges) {
      const LineKind kind = set.lines[g.segments[e.segment].line].kind;
      any_opening |= kind == LineKind::Opening;
      only_openings &= kind == LineKind::Opening || kind == LineKind::DataBorder;
    }
    r.opening = any_opening && only_openings;
    region_of_cycle[c] = static_cast<int>(g.regions.size());
    g.regions.push_back(r);
  }
  return region_of_cycle;
}

// The other winding-0 cycles go to the smallest region of another component containing them
// (holes, free-standing internal lines).
void assign_inner_cycles(RegionGraph& g, std::vector<int>& region_of_cycle) {
  for (std::size_t c = 0; c < g.cycles.size(); ++c) {
    const BoundaryCycle& cy = g.cycles[c];
    if (region_of_cycle[c] >= 0 || cy.winding != 0) continue;
    const Vector2d q = g.nodes[half_edge_start(
        g.segments, cy.edges[0].forward ? 2 * cy.edges[0].segment : 2 * cy.edges[0].segment + 1)];
    int best = -1;
    double best_area = 1e300;
    for (std::size_t r = 0; r < g.regions.size(); ++r) {
      const BoundaryCycle& oc = g.cycles[g.regions[r].outer];
      if (oc.component == cy.component) continue;
      if (oc.area < best_area &&
          point_in_polygon(g.cycle_polygon(g.regions[r].outer), q, 2 * M_PI)) {
        best = static_cast<int>(r);
        best_area = oc.area;
      }
    }
    if (best >= 0) {
      g.regions[best].inner.push_back(static_cast<int>(c));
      region_of_cycle[c] = best;
    }
  }
}

// The region on each side of each segment.
void set_segment_sides(RegionGraph& g, const std::vector<int>& cycle_of,
                       const std::vector<int>& region_of_cycle) {
  for (std::size_t s = 0; s < g.segments.size(); ++s) {
    g.segments[s].left_region = region_of_cycle[cycle_of[2 * s]];
    g.segments[s].right_region = region_of_cycle[cycle_of[2 * s + 1]];
  }
}

// Nodes with one segment: where a line ends without meeting another.
void find_dangling_ends(RegionGraph& g, const HalfEdgeFans& fans) {
  for (std::size_t n = 0; n < fans.out.size(); ++n)
    if (fans.out[n].size() == 1) g.dangling_ends.push_back(static_cast<int>(n));
}

// The label point: of a 23 x 23 grid over the region's box, the point inside with the most
// clearance (pixels) to the outer boundary and the holes; phi in [phi0, phi0 + 2 pi).
Vector2d find_label_point(const RegionGraph& g, const Region& reg, const ScanSurface& surface,
                          double W) {
  const auto poly = g.cycle_polygon(reg.outer);
  Vector2d lo = poly[0], hi = poly[0];
  for (const Vector2d& p : poly) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::vector<std::vector<Vector2d>> holes;
  for (int c : reg.inner) holes.push_back(g.cycle_polygon(c));
  double best = -1;
  Vector2d label_point = poly[0];
  constexpr int kGrid = 24;
  for (int i = 1; i < kGrid; ++i)
    for (int j = 1; j < kGrid; ++j) {
      const Vector2d q(lo.x() + (hi.x() - lo.x()) * i / kGrid,
                       lo.y() + (hi.y() - lo.y()) * j / kGrid);
      if (!point_in_polygon(poly, q, 2 * M_PI)) continue;
      bool bad = false;
      for (const auto& h : holes)
        if (point_in_polygon(h, q, 2 * M_PI)) bad = true;
      if (bad) continue;
      // clearance in pixels to the outer boundary and holes
      double d = 1e300;
      auto clear = [&](const std::vector<Vector2d>& pl) {
        for (std::size_t k = 0; k < pl.size(); ++k) {
          const Vector2d a = param_to_pixel(surface, pl[k]);
          const Vector2d b = param_to_pixel(surface, pl[(k + 1) % pl.size()]);
          Vector2d qq = param_to_pixel(surface, q);
          qq.x() += W * std::round((0.5 * (a.x() + b.x()) - qq.x()) / W);
          d = std::min(d, detail::point_segment_distance(qq, a, b));
        }
      };
      clear(poly);
      for (const auto& h : holes) clear(h);
      if (d > best) {
        best = d;
        label_point = q;
      }
    }
  label_point.x() =
      surface.phi0() + std::fmod(label_point.x() - surface.phi0() + 8 * M_PI, 2 * M_PI);
  return label_point;
}

// Areas, names and label points.
void name_regions_and_place_labels(RegionGraph& g, const ScanSurface& surface, double W) {
  for (std::size_t r = 0; r < g.regions.size(); ++r) {
    Region& reg = g.regions[r];
    reg.name = "region-" + std::to_string(r);
    reg.area = g.cycles[reg.outer].area;
    for (int c : reg.inner) reg.area += g.cycles[c].area;  // holes are negative
    reg.label_point = find_label_point(g, reg, surface, W);
  }
}

}  // namespace

RegionGraph analyze_regions(const LineSet& set, const ScanSurface& surface, double snap_px) {
  const double W = surface.n_phi();
  // 1-2. Lines in unwrapped pixels, open ends snapped onto other lines, then cut into pieces.
  PixelLines lines = unwrap_lines(set, W);
  snap_open_ends(lines, snap_px);
  split_into_pieces(lines);
  // 3-5. Nodes: the crossings and the open ends, coincident ones merged.
  FoundNodes found;
  found.events.resize(lines.L.size());
  add_crossing_nodes(set, lines, found);
  add_open_end_nodes(lines, found);
  MergedNodes merged = merge_coincident_nodes(found.node_pos, W);
  // 6. Segments between consecutive events of each line.
  RegionGraph g;
  std::vector<std::vector<Vector2d>> seg_px;
  build_segments(lines, found, merged, g, seg_px);
  // 7. Half-edges sorted round each node; faces by "next = previous counter-clockwise".
  const HalfEdgeFans fans = sort_half_edges_round_nodes(g.segments, seg_px, merged.node_px.size());
  add_param_geometry(g, seg_px, merged.node_px, surface);
  const std::vector<int> cycle_of = trace_boundary_cycles(g, fans, merged.node_px.size());
  check_round_sets_are_joined(g, set);
  // 8. Regions: counter-clockwise winding-0 cycles; the others go to the smallest region of
  // another component containing them (holes, free-standing internal lines).
  std::vector<int> region_of_cycle = collect_regions(g, set);
  assign_inner_cycles(g, region_of_cycle);
  set_segment_sides(g, cycle_of, region_of_cycle);
  find_dangling_ends(g, fans);
  name_regions_and_place_labels(g, surface, W);
  return g;
}

}  // namespace scanmesh::aft
