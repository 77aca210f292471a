// The advancing-front region mesher on the 3D scan surface (seed 000 §4.3.4, §5.1.1, §7.1).
//
// The front is a set of directed edges with the unmeshed region on their left; components,
// splits and merges are implicit: adding triangle (a, b, c) on front edge a->b removes a->b and,
// for each new side, either cancels its reverse (UPDATE-BOUNDARY cases a, b, d, and merges with
// other components) or adds it (case c splits a component). Every geometric test is made in the
// tangent frame at the front edge's midpoint; the new candidate R is constructed in 3D by
// rotating the ideal apex about the edge until it meets the surface.
#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <unordered_map>

#include "aft_internal.h"
#include "scanmesh/reconstruction/bisection.h"

namespace scanmesh::aft::detail {

using Eigen::Vector2d;
using Eigen::Vector3d;

int NodeStore::add(const Vector2d& param, const ScanSurface& surface) {
  const auto p = surface.point_normal(param.x(), param.y());
  if (!p) return -1;
  params.push_back(param);
  pos.push_back(p->position);
  normal.push_back(p->normal);
  return static_cast<int>(params.size()) - 1;
}

bool NodeStore::move(int i, const Vector2d& param, const ScanSurface& surface) {
  const auto p = surface.point_normal(param.x(), param.y());
  if (!p) return false;
  params[i] = param;
  pos[i] = p->position;
  normal[i] = p->normal;
  return true;
}

Vector2d param_of(const Vector3d& x, double near_phi) {
  double phi = std::atan2(x.y(), x.x());
  phi += 2 * M_PI * std::round((near_phi - phi) / (2 * M_PI));
  return {phi, x.z()};
}

namespace {

double cross2(const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Proper crossing of segments p1-p2 and q1-q2 (touching at an end point does not count).
bool segments_cross(const Vector2d& p1, const Vector2d& p2, const Vector2d& q1, const Vector2d& q2,
                    double eps) {
  const double d1 = cross2(p2 - p1, q1 - p1), d2 = cross2(p2 - p1, q2 - p1);
  const double d3 = cross2(q2 - q1, p1 - q1), d4 = cross2(q2 - q1, p2 - q1);
  return ((d1 > eps && d2 < -eps) || (d1 < -eps && d2 > eps)) &&
         ((d3 > eps && d4 < -eps) || (d3 < -eps && d4 > eps));
}

// The root of the bisection: [a, b] halved while wider than `tol` (at most 200 times), keeping
// the half whose ends differ in "F < 0", stopping early where F is undefined; the midpoint of
// the last bracket. F(a) and F(b) are given (F(a) < 0 != F(b) < 0).
//
// The answer is that of the plain bisection loop, with fewer evaluations of F: the bisection
// only needs to know on which side of the sign change each midpoint lies. So the sign change is
// first located by the Illinois variant of regula falsi (a bracket [lo, hi] a tenth of
// `tol` wide after ~5 evaluations, where the bisection takes ~17), and the bisection is then
// replayed, evaluating F only at midpoints inside [lo, hi]. The replay takes F's sign on
// [a, lo] and [hi, b] to be that of the ends, i.e. one sign change in [a, b] (a quarter of the
// finest cell, the rotation construction's sample step); were there three, it could settle on
// another of them than the plain loop. An undefined point met while locating runs the plain
// loop. The sample head's meshes at its units, / 2 and / 4 are bit-identical
// (docs/animation-meshes.md, speed work of 2 Dec 2026, third part).
template <typename F>
double bisection_root(const F& f, double a, double fa, double b, double fb, double tol) {
  const bool neg_a = fa < 0;
  double lo = a, flo = fa, hi = b, fhi = fb;
  int kept = 0;  // > 0: lo kept by the last steps, < 0: hi kept (Illinois halves its value)
  for (int it = 0; it < 12 && hi - lo > 0.1 * tol; ++it) {
    double x = (lo * fhi - hi * flo) / (fhi - flo);
    if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
    const auto fx = f(x);
    if (!fx) return bisect_sign_change(f, a, fa, b, tol);
    if ((*fx < 0) == neg_a) {
      lo = x;
      flo = *fx;
      if (kept < 0) fhi *= 0.5;
      kept = -1;
    } else {
      hi = x;
      fhi = *fx;
      if (kept > 0) flo *= 0.5;
      kept = 1;
    }
    // A zero at x: the bisection counts 0 as positive, and so does the bracket; but regula
    // falsi cannot go on from a zero end, so the rest is done by the replay.
    if (*fx == 0) break;
  }
  for (int it = 0; it < 200 && b - a > tol; ++it) {
    const double m = 0.5 * (a + b);
    if (m <= lo) {
      a = m;
    } else if (m >= hi) {
      b = m;
    } else {
      const auto fm = f(m);
      if (!fm) break;
      if ((*fm < 0) == neg_a) {
        a = lo = m;
      } else {
        b = hi = m;
      }
    }
  }
  return 0.5 * (a + b);
}

// Even-odd point-in-region test against the region's boundary polygons in (phi, h), with phi
// periodic (the point is tried at every 2 pi shift inside a polygon's phi range). Each
// polygon's edges are filed in bands of h, so that a query visits only the edges of its band:
// the parity counts exactly the edges that straddle the query's h, as the plain loop over all
// edges did (a linear scan per query was 6 % of the mesher's time at fine unit sizes).
class RegionPolygons {
 public:
  explicit RegionPolygons(const std::vector<std::vector<Vector2d>>& polys) {
    for (const auto& poly : polys) {
      if (poly.size() < 3) continue;
      Indexed ix;
      ix.poly = &poly;
      for (const Vector2d& v : poly) {
        ix.xmin = std::min(ix.xmin, v.x());
        ix.xmax = std::max(ix.xmax, v.x());
        ix.ymin = std::min(ix.ymin, v.y());
        ix.ymax = std::max(ix.ymax, v.y());
      }
      const int bands = std::max<int>(1, static_cast<int>(poly.size() / 4));
      ix.band_height = std::max(1e-12, (ix.ymax - ix.ymin) / bands);
      ix.bands.resize(bands);
      for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
        const auto [lo, hi] = std::minmax(poly[i].y(), poly[j].y());
        for (int b = band(ix, lo); b <= band(ix, hi); ++b)
          ix.bands[b].push_back({static_cast<int>(i), static_cast<int>(j)});
      }
      polys_.push_back(std::move(ix));
    }
  }
  bool contains(const Vector2d& p0) const {
    bool inside = false;
    for (const Indexed& ix : polys_) {
      if (!(p0.y() >= ix.ymin && p0.y() <= ix.ymax)) continue;  // nothing straddles (or NaN)
      const auto& poly = *ix.poly;
      const auto& edges = ix.bands[band(ix, p0.y())];
      Vector2d q = p0;
      q.x() -= 2 * M_PI * std::floor((q.x() - ix.xmin) / (2 * M_PI));
      for (; q.x() <= ix.xmax; q.x() += 2 * M_PI) {
        bool in = false;
        for (const auto& [i, j] : edges) {
          const Vector2d& a = poly[i];
          const Vector2d& b = poly[j];
          if ((a.y() > q.y()) != (b.y() > q.y())) {
            const double x = a.x() + (q.y() - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
            if (q.x() < x) in = !in;
          }
        }
        if (in) inside = !inside;
      }
    }
    return inside;
  }

 private:
  struct Indexed {
    const std::vector<Vector2d>* poly = nullptr;
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300, band_height = 1;
    std::vector<std::vector<std::pair<int, int>>> bands;
  };
  static int band(const Indexed& ix, double y) {
    const int b = static_cast<int>(std::floor((y - ix.ymin) / ix.band_height));
    return std::clamp(b, 0, static_cast<int>(ix.bands.size()) - 1);
  }
  std::vector<Indexed> polys_;
};

class Mesher {
 public:
  Mesher(NodeStore& nodes, const ScanSurface& surface, const RegionMeshInput& in,
         RegionMeshStats& stats)
      : N_(nodes),
        S_(surface),
        in_(in),
        region_(in.polygons),
        stats_(stats),
        rng_(in.seed * 0x9E3779B97F4A7C15ull + 1) {}

  std::vector<std::array<int, 3>> run() {
    double longest = in_.unit_mm;
    for (const auto& e : in_.front)
      longest = std::max(longest, (N_.pos[e[1]] - N_.pos[e[0]]).norm());
    cell_ = std::max(1e-3, 2.5 * longest);
    init_param_grid();
    for (const auto& e : in_.front) add_edge(e[0], e[1]);
    std::vector<int> deferred;
    bool relaxed = false;
    std::size_t guard = 0;
    // A bound on the steps only against a front that never closes. It must grow with the
    // region's triangles, i.e. with the square of its boundary's node count at a fixed spacing
    // (20000 + 40 n, linear, cut the ears' regions off at 0.125 of the sample units with ~30,000
    // triangles made and 127 and 208 front edges left open). 10 n^2 leaves room for a region
    // some times larger than the disc its boundary encloses (an ear) and a curvature-adaptive
    // unit below the boundary spacing.
    const std::size_t n = in_.front.size();
    const std::size_t guard_max = in_.max_steps > 0 ? in_.max_steps : 20000 + 40 * n + 10 * n * n;
    while (true) {
      if (++guard >= guard_max) {
        stats_.unmeshed_front_edges = static_cast<int>(index_.size());
        break;
      }
      int e = next_edge();
      if (e < 0) {
        // Retry the edges that failed while anything still changes; then once relaxed.
        std::vector<int> live;
        for (int d : deferred)
          if (edges_[d].alive) live.push_back(d);
        deferred.clear();
        if (live.empty()) break;
        if (!progress_) {
          if (relaxed) {
            stats_.unmeshed_front_edges = static_cast<int>(live.size());
            break;
          }
          relaxed = true;
        }
        progress_ = false;
        for (int d : live) push(d);
        continue;
      }
      if (!edges_[e].alive) continue;
      if (fails_same_again(e, relaxed)) {
        deferred.push_back(e);
        continue;
      }
      seen_.param.clear();  // (the box is set by gather; the capacity is kept)
      seen_.all_param = false;
      if (try_edge(e, relaxed)) {
        progress_ = true;
        relaxed = false;
      } else {
        remember_failure(e, relaxed);
        deferred.push_back(e);
      }
    }
    return triangles_;
  }

 private:
  struct FEdge {
    int a, b;
    bool alive;
    double length;
  };

  std::uint64_t rand64() {
    rng_ ^= rng_ >> 12;
    rng_ ^= rng_ << 25;
    rng_ ^= rng_ >> 27;
    return rng_ * 0x2545F4914F6CDD1Dull;
  }

  void add_edge(int a, int b) {
    const int id = static_cast<int>(edges_.size());
    edges_.push_back({a, b, true, (N_.pos[b] - N_.pos[a]).norm()});
    index_[directed_edge_key(a, b)] = id;
    bucket(id);
    push(id);
  }
  void kill(int id) {
    edges_[id].alive = false;
    index_.erase(directed_edge_key(edges_[id].a, edges_[id].b));
  }
  int find(int a, int b) const {
    const auto it = index_.find(directed_edge_key(a, b));
    return it == index_.end() ? -1 : it->second;
  }
  void push(int id) {
    if (in_.strategy == EdgeStrategy::Random) {
      pool_.push_back(id);
    } else {
      const double key =
          in_.strategy == EdgeStrategy::Shortest ? -edges_[id].length : edges_[id].length;
      heap_.push({key, -id});
    }
  }
  int next_edge() {
    if (in_.strategy == EdgeStrategy::Random) {
      while (!pool_.empty()) {
        const std::size_t k = rand64() % pool_.size();
        const int id = pool_[k];
        pool_[k] = pool_.back();
        pool_.pop_back();
        if (edges_[id].alive) return id;
      }
      return -1;
    }
    while (!heap_.empty()) {
      const int id = -heap_.top().second;
      heap_.pop();
      if (edges_[id].alive) return id;
    }
    return -1;
  }

  double size_at(const Vector2d& param) const {
    double u = in_.unit_mm;
    if (in_.chordal_tolerance_mm > 0) {
      if (const auto jet = S_.evaluate(param.x(), param.y())) {
        const SurfaceCurvature c = jet->curvature();
        const double k = std::max(std::fabs(c.k1), std::fabs(c.k2));
        if (k > 1e-12) u = std::min(u, std::sqrt(8.0 * in_.chordal_tolerance_mm / k));
      }
    }
    return std::max(u, std::max(in_.min_unit_mm, 0.6 * in_.unit_mm));
  }

  // Local tangent frame of the current edge.
  struct Frame {
    Vector3d M, n, t1, t2;
    Vector2d operator()(const Vector3d& p) const { return {(p - M).dot(t1), (p - M).dot(t2)}; }
  };

  struct Near {
    std::vector<int> nodes;  // front nodes near the edge (normals agreeing)
    std::vector<int> edges;  // alive front edges near the edge
  };

  // Front edges bucketed by the cell of their midpoint (lazy deletion), so the search near an
  // edge costs O(local front) instead of O(front).
  void bucket(int id) {
    const FEdge& e = edges_[id];
    max_len_ = std::max(max_len_, e.length);
    grid_[cell_key(0.5 * (N_.pos[e.a] + N_.pos[e.b]), cell_)].push_back(id);
    param_bucket(id);
  }

  // Front edges are also bucketed by the (phi, h) cells their parameter box overlaps. The
  // visibility tests run in the parameter plane, and where the surface is steep (ears, nose
  // sides) front edges that are far apart in 3D lie close together there: the 3D search ball
  // missed them, and at fine unit sizes triangles crossed them (half the sample units: 33
  // self-intersecting pairs and 70 open front edges on the head).
  void init_param_grid() {
    double rho = 0.0;
    for (const auto& e : in_.front) rho += std::hypot(N_.pos[e[0]].x(), N_.pos[e[0]].y());
    rho = std::max(1.0, rho / std::max<std::size_t>(1, in_.front.size()));
    phi_cells_ = std::clamp(static_cast<int>(std::ceil(2 * M_PI * rho / cell_)), 1, 1 << 16);
    phi_cell_ = 2 * M_PI / phi_cells_;
  }
  // Cell columns of the phi interval [lo, hi] (hi >= lo, unwrapped), wrapped; false if wider
  // than kMaxParamCells.
  static constexpr int kMaxParamCells = 64;
  bool param_columns(double lo, double hi, std::vector<int>& cols) const {
    const auto i0 = static_cast<long>(std::floor(lo / phi_cell_));
    const auto i1 = static_cast<long>(std::floor(hi / phi_cell_));
    if (i1 - i0 >= kMaxParamCells) return false;
    cols.clear();
    for (long i = i0; i <= i1; ++i)
      cols.push_back(static_cast<int>(((i % phi_cells_) + phi_cells_) % phi_cells_));
    return true;
  }
  std::int64_t param_key(int col, long row) const {
    return (static_cast<std::int64_t>(col) << 32) ^ static_cast<std::int64_t>(row & 0xffffffff);
  }
  // The (phi, h) cells of the edge a-b (columns, rows j0..j1); false for a wide edge.
  bool param_cells(int a, int b, std::vector<int>& cols, long& j0, long& j1) const {
    const Vector2d& pa = N_.params[a];
    const double pb = pa.x() + wrap_angle(N_.params[b].x() - pa.x());
    const double hb = N_.params[b].y();
    j0 = static_cast<long>(std::floor(std::min(pa.y(), hb) / cell_));
    j1 = static_cast<long>(std::floor(std::max(pa.y(), hb) / cell_));
    return param_columns(std::min(pa.x(), pb), std::max(pa.x(), pb), cols) &&
           j1 - j0 < kMaxParamCells;
  }
  void param_bucket(int id) {
    const FEdge& e = edges_[id];
    std::vector<int>& cols = param_cols_;
    long j0 = 0, j1 = 0;
    if (!param_cells(e.a, e.b, cols, j0, j1)) {
      wide_edges_.push_back(id);
      return;
    }
    for (int col : cols)
      for (long j = j0; j <= j1; ++j) param_grid_[param_key(col, j)].push_back(id);
  }
  // The alive front edges whose parameter cells overlap the box of the parameter points `pts`
  // (phi unwrapped relative to the first one), into param_found_ (an edge may repeat).
  void gather_param(const std::array<Vector2d, 3>& pts) {
    double lo = pts[0].x(), hi = lo, hlo = pts[0].y(), hhi = hlo;
    for (const Vector2d& p : pts) {
      const double x = pts[0].x() + wrap_angle(p.x() - pts[0].x());
      lo = std::min(lo, x);
      hi = std::max(hi, x);
      hlo = std::min(hlo, p.y());
      hhi = std::max(hhi, p.y());
    }
    std::vector<int>& cols = param_cols_;
    const auto j0 = static_cast<long>(std::floor(hlo / cell_));
    const auto j1 = static_cast<long>(std::floor(hhi / cell_));
    std::vector<int>& found = param_found_;
    found.clear();
    auto take = [&](int id) {
      if (edges_[id].alive) found.push_back(id);
    };
    if (param_columns(lo, hi, cols) && j1 - j0 < kMaxParamCells) {
      for (int col : cols)
        for (long j = j0; j <= j1; ++j)
          if (const std::vector<int>* list = param_grid_.find(param_key(col, j)))
            for (int id : *list) take(id);
      seen_.param.push_back({cols.front(), static_cast<int>(cols.size()), j0, j1});
    } else {
      for (const auto& list : param_grid_.lists())
        for (int id : list) take(id);
      seen_.all_param = true;
    }
    for (int id : wide_edges_) take(id);
  }

  // The front edges near the edge and their end points within `radius`, into near_ (reused:
  // ~50,000 searches at a quarter of the sample units). Edges come in cell order (the tests
  // using them are ANDs over all of them); nodes sorted, each once (the candidate list).
  const Near& gather(int self, const Frame& f, double radius) {
    Near& nr = near_;
    nr.edges.clear();
    nr.nodes.clear();
    const double r2 = radius * radius;
    const double reach = radius + 0.5 * max_len_;
    // The cells that the box f.M +- reach overlaps: an edge of the search has its midpoint
    // within `reach` of f.M. (3-4 cells per axis; the cube of +-ceil(reach / cell_) cells
    // around f.M's cell, 5 per axis, looked up twice as many, nearly all of them empty.)
    const std::array<std::int64_t, 3> lo = cell_of(f.M - Vector3d::Constant(reach), cell_),
                                      hi = cell_of(f.M + Vector3d::Constant(reach), cell_);
    std::array<std::int64_t, 3> count;
    for (int k = 0; k < 3; ++k) count[k] = hi[k] - lo[k] + 1;
    seen_.lo = lo;
    seen_.count = count;
    for (std::int64_t dx = 0; dx < count[0]; ++dx)
      for (std::int64_t dy = 0; dy < count[1]; ++dy)
        for (std::int64_t dz = 0; dz < count[2]; ++dz) {
          std::vector<int>* found = grid_.find(pack_cell(lo[0] + dx, lo[1] + dy, lo[2] + dz));
          if (!found) continue;
          auto& list = *found;
          std::size_t keep = 0;
          for (std::size_t k = 0; k < list.size(); ++k) {
            const int id = list[k];
            if (!edges_[id].alive) continue;
            list[keep++] = id;
            if (id == self) continue;
            const FEdge& e = edges_[id];
            const Vector3d& p = N_.pos[e.a];
            const Vector3d& q = N_.pos[e.b];
            const double lim = radius + e.length;
            if ((p - f.M).squaredNorm() > lim * lim && (q - f.M).squaredNorm() > lim * lim)
              continue;
            nr.edges.push_back(id);
            for (int v : {e.a, e.b})
              if ((N_.pos[v] - f.M).squaredNorm() < r2) nr.nodes.push_back(v);
          }
          list.resize(keep);
        }
    std::sort(nr.nodes.begin(), nr.nodes.end());
    nr.nodes.erase(std::unique(nr.nodes.begin(), nr.nodes.end()), nr.nodes.end());
    return nr;
  }

  // Triangle a, b, c (c left of a->b) is free: no front edge crosses it or enters a corner,
  // no front node inside, the sides are not already front edges, and it faces outwards.
  // The topological tests run in the (phi, h) parameter plane, scaled to millimetres at the
  // edge (x = rho * phi): the surface is a graph over it, so the front is a planar straight-line
  // graph there and the tests cannot be fooled by a tangent plane that folds over on strongly
  // curved parts. Shape decisions (candidates, circumcentres) stay in 3D / the tangent frame.
  struct ParamFrame {
    Vector2d origin;
    double rho;
    Vector2d operator()(const Vector2d& p) const {
      return {rho * wrap_angle(p.x() - origin.x()), p.y() - origin.y()};
    }
  };

  bool visible(int a, int b, int c, const Vector3d& cpos, const Vector2d& cparam, const Frame& f,
               const Near& near3d) {
    const ParamFrame pf{N_.params[a], std::max(1e-6, std::hypot(f.M.x(), f.M.y()))};
    auto P2 = [&](int v) { return pf(N_.params[v]); };
    const Vector2d A = P2(a), B = P2(b), C = pf(cparam);
    const double scale = (B - A).norm();
    const double eps = 1e-9 * scale * scale;
    if (cross2(B - A, C - A) <= eps) return false;
    if (!in_.polygons.empty()) {  // (polygons of < 3 nodes contain nothing)
      const Vector2d cen(pf.origin.x() + (A.x() + B.x() + C.x()) / (3 * pf.rho),
                         pf.origin.y() + (A.y() + B.y() + C.y()) / 3);
      if (!region_.contains(cen)) return false;
      if (c < 0 && !region_.contains(cparam)) return false;
    }
    const Vector3d nt = (N_.pos[b] - N_.pos[a]).cross(cpos - N_.pos[a]);
    if (!relaxed_ && nt.dot(f.n) <= 0) return false;
    if (c >= 0 && (find(a, c) >= 0 || find(c, b) >= 0)) return false;
    // A front edge that crosses the triangle or enters it at a corner.
    auto edge_blocks = [&](int id) {
      const FEdge& e = edges_[id];
      const Vector2d P = P2(e.a), Q = P2(e.b);
      const bool ta = e.a == a || e.a == b || e.a == c, tb = e.b == a || e.b == b || e.b == c;
      if (ta && tb) return false;  // a side of the triangle
      if (!ta && !tb) return segments_cross(A, C, P, Q, eps) || segments_cross(B, C, P, Q, eps);
      // One end at a corner: must not point into the triangle there, nor cross the far side.
      const int v = ta ? e.a : e.b;
      const Vector2d V = ta ? P : Q, W = ta ? Q : P;
      const Vector2d d = W - V;
      Vector2d from, to;
      if (v == a) {
        from = B - A;
        to = C - A;
      } else if (v == b) {
        from = C - B;
        to = A - B;
      } else {
        from = A - C;
        to = B - C;
      }
      if (cross2(from, d) > eps && cross2(d, to) > eps) return true;
      if (v != c && segments_cross(v == a ? B : A, C, V, W, eps)) return true;
      return v == c && segments_cross(A, B, V, W, eps);
    };
    // A front node inside or on a side: a node on a new side (e.g. the middle one of three
    // collinear boundary nodes) would be skipped by the new edge and leave a zero-area loop.
    const double tol = 1e-7 * scale * scale;
    auto node_blocks = [&](int v) {
      if (v == a || v == b || v == c) return false;
      const Vector2d P = P2(v);
      return cross2(B - A, P - A) > -tol && cross2(C - B, P - B) > -tol &&
             cross2(A - C, P - C) > -tol;
    };
    // The 3D neighbourhood, then the edges near the triangle in (phi, h) and their end points.
    // The answer is an AND over all of them, so repeats and order do not matter (no merging or
    // sorting: this runs for every candidate of every front edge).
    for (int id : near3d.edges)
      if (edge_blocks(id)) return false;
    for (int v : near3d.nodes)
      if (node_blocks(v)) return false;
    gather_param({N_.params[a], N_.params[b], cparam});
    for (int id : param_found_)
      if (edge_blocks(id) || node_blocks(edges_[id].a) || node_blocks(edges_[id].b)) return false;
    return true;
  }

  bool clear_of_front(const Vector3d& x, double u, int self, const Near& nr) const {
    for (int v : nr.nodes)
      if ((N_.pos[v] - x).norm() < 0.55 * u) return false;
    for (int id : nr.edges) {
      if (id == self) continue;
      if (point_segment_distance(x, N_.pos[edges_[id].a], N_.pos[edges_[id].b]) < 0.3 * u)
        return false;
    }
    return true;
  }

  void add_triangle(int e, int c) {
    const int a = edges_[e].a, b = edges_[e].b;
    triangles_.push_back({a, b, c});
    kill(e);
    if (const int r = find(c, a); r >= 0)
      kill(r);
    else
      add_edge(a, c);
    if (const int r = find(b, c); r >= 0)
      kill(r);
    else
      add_edge(c, b);
  }

  // F(x) = r(phi, h) - rho at a point: > 0 inside the surface, < 0 outside.
  std::optional<double> implicit_at(const Vector3d& x) const {
    const Vector3d c = ScanSurface::to_cylindrical(x);
    const auto r = S_.radius_value(c.x(), c.y());
    if (!r) return std::nullopt;
    return *r - c.z();
  }

  std::optional<Vector3d> construct_r(const Frame& f, double height) const {
    // Rotation construction: the apex on the circle about the edge (plane of t2 and n), the
    // root nearest the tangent direction on the left with cos delta >= 0.3. The circle is
    // sampled outwards from delta = 0 on both sides at the grid of ScanSurface::
    // intersect_circle (2 pi / steps, a quarter of the finest cell), and the search stops at
    // the first bracketed sign change: the same root, bit for bit, as searching the whole
    // circle with intersect_circle, without the ~1000 samples of the rest of it.
    const double step = S_.sampling_step_mm();
    std::optional<Vector3d> r;
    if (height > 0 && step > 0) {
      const long steps = std::max<long>(64, static_cast<long>(std::ceil(2 * M_PI * height / step)));
      const double dt = 2 * M_PI / static_cast<double>(steps);
      const double tol = 1e-6 / height, max_delta = std::acos(0.3);
      auto point = [&](double d) {
        return f.M + height * (std::cos(d) * f.t2 + std::sin(d) * f.n);
      };
      auto F = [&](double d) { return implicit_at(point(d)); };
      auto refine = [&](double a, double fa, double b, double fb) {
        return bisection_root(F, a, fa, b, fb, tol);
      };
      // Sample angles exactly as ScanSurface::intersect_circle does (k dt, the last one 2 pi),
      // so that the root found is bit-identical to the whole-circle search.
      auto theta_neg = [&](long k) { return k == 0 ? 2 * M_PI : (steps - k) * dt; };
      const std::optional<double> f0 = F(0);
      if (f0 && *f0 == 0.0) return point(0);
      std::optional<double> prev_pos = f0, prev_neg = F(theta_neg(0));
      const long kmax = std::min(steps / 2, static_cast<long>(std::ceil(max_delta / dt)) + 1);
      for (long k = 1; k <= kmax && !r; ++k) {
        double best = 1e300;
        const double tp = k * dt, tn = theta_neg(k);
        const std::optional<double> cp = F(tp), cn = F(tn);
        auto consider = [&](double d) {
          const double c = std::cos(d), sn = std::sin(d);
          if (c < 0.3) return;
          const double dev = std::fabs(std::atan2(sn, c));
          if (dev < best) {
            best = dev;
            r = f.M + height * (c * f.t2 + sn * f.n);
          }
        };
        if (prev_pos && cp) {
          if (*cp == 0.0)
            consider(tp);
          else if (*prev_pos != 0.0 && (*prev_pos < 0) != (*cp < 0))
            consider(refine((k - 1) * dt, *prev_pos, tp, *cp));
        }
        if (prev_neg && cn) {
          if (*cn == 0.0)
            consider(tn);
          else if (*prev_neg != 0.0 && (*prev_neg < 0) != (*cn < 0))
            consider(refine(tn, *cn, theta_neg(k - 1), *prev_neg));
        }
        prev_pos = cp;
        prev_neg = cn;
      }
    }
    if (!r) {
      if (const auto p = S_.project(f.M + height * f.t2)) r = p->point;
    }
    return r;
  }

  // A failed try_edge is a function of what it read: the front edges in the 3D cells of its
  // search (and their end points), the front edges in the (phi, h) cells of its visibility
  // queries (plus the wide ones), the longest front edge (the search's reach) and the surface.
  // The front changes only by triangles: each adds and removes front edges among its three
  // sides. So an edge retried in the same mode, with no triangle since its failure having a
  // side in those cells and the longest edge unchanged, would fail again exactly: it is not
  // tried. (The deferred edges are retried after every success, and at a quarter of the sample
  // units these repeats were 15 % of the tries and 30 % of the mesher's time, ~12 us each.)
  struct ParamQuery {
    int col0, n_cols;  // columns col0, col0 + 1, ... (mod phi_cells_)
    long j0, j1;       // rows
  };
  struct Seen {
    std::array<std::int64_t, 3> lo{}, count{};  // the 3D search's cell box
    std::vector<ParamQuery> param;
    bool all_param = false;
  };
  struct Failure {
    bool relaxed = false;
    std::size_t triangles = 0;  // triangles_.size() at the failure
    double max_len = 0;
    Seen seen;
  };
  void remember_failure(int e, bool relaxed) {
    if (failures_.size() < edges_.size()) failures_.resize(edges_.size());
    Failure& f = failures_[e];
    f.relaxed = relaxed;
    f.triangles = triangles_.size();
    f.max_len = max_len_;
    std::swap(f.seen, seen_);
  }
  bool side_in(const Seen& s, int a, int b) {
    // The cell of the edge's midpoint, as cell_key files the edge.
    const auto c = cell_of(0.5 * (N_.pos[a] + N_.pos[b]), cell_);
    bool in_box = true;
    for (int k = 0; k < 3; ++k) in_box = in_box && c[k] >= s.lo[k] && c[k] < s.lo[k] + s.count[k];
    if (in_box) return true;
    std::vector<int>& cols = side_cols_;
    long j0 = 0, j1 = 0;
    if (!param_cells(a, b, cols, j0, j1)) return true;  // a wide edge: every query sees it
    for (const ParamQuery& q : s.param) {
      if (j1 < q.j0 || j0 > q.j1) continue;
      for (int col : cols)
        if (((col - q.col0) % phi_cells_ + phi_cells_) % phi_cells_ < q.n_cols) return true;
    }
    return false;
  }
  bool fails_same_again(int e, bool relaxed) {
    if (static_cast<std::size_t>(e) >= failures_.size()) return false;
    const Failure& f = failures_[e];
    if (f.triangles == 0 || f.relaxed != relaxed || f.max_len != max_len_ || f.seen.all_param)
      return false;
    for (std::size_t t = f.triangles; t < triangles_.size(); ++t) {
      const auto& tri = triangles_[t];
      for (int k = 0; k < 3; ++k)
        if (side_in(f.seen, tri[k], tri[(k + 1) % 3])) return false;
    }
    return true;
  }

  bool try_edge(int e, bool relaxed) {
    relaxed_ = relaxed;
    const int a = edges_[e].a, b = edges_[e].b;
    const Vector3d& A = N_.pos[a];
    const Vector3d& B = N_.pos[b];
    Frame f;
    f.M = 0.5 * (A + B);
    f.n = (N_.normal[a] + N_.normal[b]).normalized();
    Vector3d ab = B - A;
    f.t1 = (ab - ab.dot(f.n) * f.n).normalized();
    f.t2 = f.n.cross(f.t1);
    const double el = ab.norm();
    const Vector2d pm = param_midpoint(N_.params[a], N_.params[b]);
    const double u = std::clamp(size_at(pm), 0.62 * el, 1.6 * el);
    const double height = std::sqrt(std::max(u * u - 0.25 * el * el, 0.01 * el * el));
    const double radius = relaxed ? 6.0 * std::max(u, el) : 2.2 * std::max(u, el);
    const Near& nr = gather(e, f, radius);
    const double half = 0.5 * (f(B) - f(A)).norm();
    // Existing candidates ordered by their circumcentre on the bisector (Delaunay rule).
    std::vector<std::pair<double, int>> cand;
    const ParamFrame pf{N_.params[a], std::max(1e-6, std::hypot(f.M.x(), f.M.y()))};
    const Vector2d pb = pf(N_.params[b]);
    for (int v : nr.nodes) {
      if (v == a || v == b) continue;
      if (cross2(pb, pf(N_.params[v])) <= 1e-9 * el * el) continue;  // not left of the edge
      if (!relaxed && N_.normal[v].dot(f.n) < 0.2) continue;
      Vector2d P = f(N_.pos[v]);
      if (P.y() <= 1e-6 * el) {
        if (!relaxed) continue;
        P.y() = 1e-6 * el;
      }
      cand.push_back({(P.squaredNorm() - half * half) / (2 * P.y()), v});
    }
    std::sort(cand.begin(), cand.end());
    int s_node = -1;
    double s_c = 0;
    const std::size_t tries = relaxed ? cand.size() : std::min<std::size_t>(cand.size(), 8);
    for (std::size_t k = 0; k < tries; ++k)
      if (visible(a, b, cand[k].second, N_.pos[cand[k].second], N_.params[cand[k].second], f, nr)) {
        s_node = cand[k].second;
        s_c = cand[k].first;
        break;
      }
    if (relaxed && s_node >= 0 && min_angle(A, B, N_.pos[s_node]) >= 0.35) {
      add_triangle(e, s_node);
      ++stats_.chose_existing;
      return true;
    }
    // The new candidate R and NEW-IS-PREFERRED (circumcentre rule with S_c as a third choice).
    const auto r = construct_r(f, height);
    enum { kR, kS, kSc } choice = kS;
    if (r) {
      const Vector2d R = f(*r);
      if (R.y() > 1e-6 * el) {
        const double r_c = (R.squaredNorm() - half * half) / (2 * R.y());
        const double r_bar = R.y();
        if (s_node < 0 || s_c >= r_bar) {
          choice = kR;
        } else if (s_c <= r_c) {
          choice = kS;
        } else {
          const double frac = (s_c - r_c) / (r_bar - r_c);  // 0 at R_c, 1 at R-bar
          choice = frac > kL2 ? kR : (frac > kL1 ? kSc : kS);
        }
      }
    }
    auto try_new = [&](const Vector3d& x) {
      const Vector2d p = param_of(x, N_.params[a].x());
      const auto sp = S_.point_normal(p.x(), p.y());
      if (!sp) return false;
      const Vector3d pos = sp->position;
      if (!relaxed && sp->normal.dot(f.n) < 0.2) return false;
      if (!clear_of_front(pos, u, e, nr) || !visible(a, b, -1, pos, p, f, nr)) return false;
      if (min_angle(A, B, pos) < 0.35) return false;  // ~20 deg: never build a sliver
      const int c = N_.add(p, S_);
      if (c < 0) return false;
      add_triangle(e, c);
      ++stats_.steiner_points;
      return true;
    };
    if (choice == kSc) {
      const Vector3d x = f.M + s_c * f.t2;
      const auto pr = S_.project(x);
      if (pr && try_new(pr->point)) {
        ++stats_.chose_circumcentre;
        return true;
      }
    }
    // An existing candidate that would make a sliver (< ~20 deg) gives way to R if R is valid.
    if (choice == kS && s_node >= 0 && r && min_angle(A, B, N_.pos[s_node]) < 0.35) choice = kR;
    if (choice == kR && r && try_new(*r)) {
      ++stats_.chose_new;
      return true;
    }
    // No usable S, or S would make a sliver: try a lower apex (the thesis's shrink by a third,
    // twice) before giving in.
    if (s_node < 0 || min_angle(A, B, N_.pos[s_node]) < 0.35) {
      for (double shrink : {2.0 / 3.0, 4.0 / 9.0}) {
        const auto r2 = construct_r(f, std::max(height * shrink, 0.45 * el));
        if (r2 && try_new(*r2)) {
          ++stats_.chose_new;
          return true;
        }
      }
    }
    if (s_node >= 0) {
      add_triangle(e, s_node);
      ++stats_.chose_existing;
      return true;
    }
    return false;
  }

  // L1, L2 of NEW-IS-PREFERRED as fractions of [R_c, R-bar] measured from R_c
  // (docs/animation-meshes.md): S_c in the upper third -> R, middle third -> S_c, lower -> S.
  static constexpr double kL1 = 1.0 / 3.0, kL2 = 2.0 / 3.0;

  NodeStore& N_;
  const ScanSurface& S_;
  const RegionMeshInput& in_;
  const RegionPolygons region_;
  RegionMeshStats& stats_;
  std::uint64_t rng_;
  std::vector<FEdge> edges_;
  std::unordered_map<std::uint64_t, int> index_;
  double cell_ = 1.0, max_len_ = 0.0;
  CellLists grid_;
  Near near_;                      // gather's result
  Seen seen_;                      // what the current try_edge read (its cells)
  std::vector<Failure> failures_;  // per edge: its last failure, for fails_same_again
  std::vector<int> side_cols_;     // side_in's scratch
  int phi_cells_ = 1;
  double phi_cell_ = 2 * M_PI;
  CellLists param_grid_;                       // (phi, h) cells
  std::vector<int> wide_edges_;                // edges over more than kMaxParamCells cells
  std::vector<int> param_cols_, param_found_;  // scratch of param_bucket / gather_param
  std::vector<int> pool_;
  std::priority_queue<std::pair<double, int>> heap_;
  std::vector<std::array<int, 3>> triangles_;
  bool progress_ = false;
  bool relaxed_ = false;
};

}  // namespace

std::vector<std::array<int, 3>> aft_mesh_region(NodeStore& nodes, const ScanSurface& surface,
                                                const RegionMeshInput& input,
                                                RegionMeshStats& stats) {
  Mesher m(nodes, surface, input, stats);
  auto tris = m.run();
  stats.triangles = static_cast<int>(tris.size());
  return tris;
}

}  // namespace scanmesh::aft::detail
