// The local small-angle repair after the advancing front (docs/animation-meshes.md,
// "Small angles"): every triangle whose minimum angle is below the goal is attacked by a few
// composite local operations — optimise its Steiner points on the surface, flip one of its
// edges, collapse a short edge into its neighbour, split its longest edge — each followed by
// optimising the Steiner points it touched. The candidate that best improves the sorted angle
// list of the neighbourhood is kept. Constraint (segment) edges are never flipped, split or
// collapsed and segment nodes never move, so every animation line stays a chain of mesh edges
// and every region keeps its boundary; a Steiner point only moves on the surface (projected and
// re-lifted through (phi, h)), so it stays on the scan surface. With a deviation goal the same
// operations also attack triangles further than that from the surface (docs/animation-meshes.md,
// "Deviation goal").
#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <unordered_set>
#include <variant>

#include "aft_internal.h"
#include "scanmesh/meshing/kernel/triangle_mesh.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::aft::detail {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

// A Steiner point whose incident triangles all have at least this minimum angle is left where
// it is: the repair's goal is 20 deg, and moving such a point only trades good angles.
const double kSettledAngle = 30.0 * M_PI / 180;

// A triangle's corner points, bit for bit: the key of the repair's per-triangle caches.
struct Corners {
  std::array<Vector3d, 3> p;
  bool operator==(const Corners& o) const {
    return std::memcmp(p.data(), o.p.data(), sizeof p) == 0;
  }
};
struct CornersHash {
  std::size_t operator()(const Corners& c) const {
    std::uint64_t h = 0x9E3779B97F4A7C15ull, bits;
    for (const Vector3d& v : c.p)
      for (int k = 0; k < 3; ++k) {
        std::memcpy(&bits, &v[k], sizeof bits);
        h = (h ^ bits) * 0xBF58476D1CE4E5B9ull;
        h ^= h >> 31;
      }
    return h;
  }
};
class Repair {
 public:
  Repair(std::vector<std::array<int, 3>>& T, std::vector<int>& labels, NodeStore& store,
         const ScanSurface& surface, const std::unordered_set<std::uint64_t>& constraint,
         std::size_t boundary_nodes, double deviation_goal)
      : T_(T),
        L_(labels),
        S_(store),
        surf_(surface),
        C_(constraint),
        fixed_(boundary_nodes),
        deviation_goal_(deviation_goal),
        m_(store.pos, T, "small-angle repair"),
        grid_(TriangleCells::cell_size_for(T, store.pos)) {
    m_.label = labels;
    for (std::size_t t = 0; t < m_.tri.size(); ++t) insert(static_cast<int>(t));
  }

  double tri_min(int t) const {
    const auto& f = m_.tri[t];
    return min_angle(S_.pos[f[0]], S_.pos[f[1]], S_.pos[f[2]]);
  }

  // The triangle needs work: its smallest angle is below the goal (not fixed by the input), or
  // it lies further from the surface than the deviation goal.
  bool wanted(int t, double goal) const {
    if (tri_min(t) < goal && !forced(t)) return true;
    return excess(t) > 0 && !beyond_reach_.count(corners(t));
  }
  Corners corners(int t) const {
    const auto& f = m_.tri[t];
    return {{S_.pos[f[0]], S_.pos[f[1]], S_.pos[f[2]]}};
  }

  // How far the triangle lies beyond the deviation goal (mm; 0 within it or without a goal).
  // Its samples are those of the quality report's Hausdorff distance (the points of the
  // triangle's 4 x 4 barycentric lattice other than the corners), each projected onto the
  // surface from its interpolated (phi, h). Cached by the corner points, as the candidates
  // re-score the same neighbourhood triangles.
  double excess(int t) const {
    if (deviation_goal_ <= 0 || !m_.face_alive[t]) return 0;
    const auto& f = m_.tri[t];
    const Vector3d &a = S_.pos[f[0]], &b = S_.pos[f[1]], &c = S_.pos[f[2]];
    // A smooth patch deviates from its flat triangle by about the circumradius times the
    // tilt of the corner normals against the face's; triangles well within the goal by that
    // estimate are not sampled (at a quarter of the sample units 95 % of them).
    const Vector3d cross = (b - a).cross(c - a);
    const double twice_area = cross.norm();
    if (twice_area <= 0) return 0;
    const Vector3d n = cross / twice_area;
    const double circumradius = (b - c).norm() * (c - a).norm() * (a - b).norm() / (2 * twice_area);
    double tilt = 0;
    for (int v : f) tilt = std::max(tilt, n.cross(S_.normal[v]).norm());
    if (circumradius * tilt <= 0.5 * deviation_goal_) return 0;
    const Corners key{{a, b, c}};
    if (const auto it = deviation_.find(key); it != deviation_.end()) return it->second;
    const Vector2d pa = S_.params[f[0]];
    const auto param = [&](int v) {
      const Vector2d& p = S_.params[v];
      return Vector2d(pa.x() + wrap_angle(p.x() - pa.x()), p.y());
    };
    const Vector2d pb = param(f[1]), pc = param(f[2]);
    constexpr int kLattice = 4;
    double worst = 0;
    for (int i = 0; i <= kLattice; ++i)
      for (int j = 0; i + j <= kLattice; ++j) {
        if (i == kLattice || j == kLattice || i + j == 0) continue;  // the corners
        const double u = double(i) / kLattice, v = double(j) / kLattice, w = 1 - u - v;
        const Vector3d x = w * a + u * b + v * c;
        worst = std::max(worst, sample_distance(x, w * pa + u * pb + v * pc));
      }
    const double e = std::max(0.0, worst - deviation_goal_);
    deviation_.emplace(key, e);
    return e;
  }

  // Distance of x from the surface where it exceeds the deviation goal, else at most the goal.
  // Three bounds, cheapest first: the surface point on x's radial ray (one evaluation), the
  // local projection from `param` (a surface point too), and the exact distance to the grid
  // triangulation searched within the goal, then within the projection's distance (at most
  // goal + 3 mm: beyond it all candidates are equally bad). The projection alone stops in far
  // local minima at the ears' rims, 3-7 mm above the true distance.
  double sample_distance(const Vector3d& x, const Vector2d& param) const {
    const double goal = deviation_goal_;
    const Vector3d cyl = ScanSurface::to_cylindrical(x);
    if (const auto r = surf_.radius_value(cyl.x(), cyl.y()); r && std::fabs(*r - cyl.z()) <= goal)
      return std::fabs(*r - cyl.z());
    const auto pr = surf_.project(x, param);
    const double d = pr ? pr->distance : std::numeric_limits<double>::infinity();
    if (d <= goal) return d;
    if (grid_distance_(x, goal) < goal) return std::min(d, goal);
    return grid_distance_(x, std::min(d, goal + 3.0));
  }

  // True if the smallest angle of t sits between two constraint edges: the input fixes it.
  bool forced(int t) const {
    const auto& f = m_.tri[t];
    return corner_between(f, smallest_corner(corner_angles(S_.pos, f)), C_);
  }

  RepairStats run(double goal, double report, int rounds) {
    RepairStats st;
    for (int round = 0; round < rounds; ++round) {
      bool changed = false;
      for (std::size_t t = 0; t < m_.tri.size(); ++t) {
        if (!m_.face_alive[t] || !wanted(static_cast<int>(t), goal)) continue;
        if (improve(static_cast<int>(t), goal, st)) changed = true;
      }
      if (!changed) break;
    }
    // The live triangles, in index order, back to the caller.
    T_.clear();
    L_.clear();
    for (std::size_t t = 0; t < m_.tri.size(); ++t) {
      if (!m_.face_alive[t]) continue;
      T_.push_back(m_.tri[t]);
      L_.push_back(m_.label[t]);
      const double m = tri_min(static_cast<int>(t));
      if (m < report) (forced(static_cast<int>(t)) ? st.forced_below_goal : st.left_below_goal)++;
      if (excess(static_cast<int>(t)) > 0) ++st.left_above_deviation_goal;
    }
    return st;
  }

 private:
  // A candidate's changes, undone in reverse by rollback(): the kernel's operations, the
  // Steiner points' moves and the triangles' filings in grid_.
  using Operation = std::variant<kernel::EdgeQuad, kernel::EdgeSplit, kernel::EdgeCollapse>;
  struct Journal {
    std::vector<Operation> operations;
    struct Moved {
      int v;
      NodeStore::Saved old;
    };
    std::vector<Moved> moved;
    TriangleCells::Undo cells;  // the candidate's filings in grid_
    std::size_t n_tris = 0, n_verts = 0;
    // Emptied, keeping the arrays' memory for the next candidate.
    void clear() {
      operations.clear();
      moved.clear();
      cells.clear();
      n_tris = n_verts = 0;
    }
  };

  // Calls visit(t) for each triangle an operation changed, added or removed (no list built:
  // the candidates' scores ask for them thousands of times).
  template <class Visit>
  static void for_each_triangle(const Operation& op, Visit&& visit) {
    if (const auto* q = std::get_if<kernel::EdgeQuad>(&op)) {
      visit(q->f1);
      visit(q->f2);
    } else if (const auto* sp = std::get_if<kernel::EdgeSplit>(&op)) {
      for (int t : sp->changed) visit(t);
      for (int t : sp->added) visit(t);
    } else {
      const auto& c = std::get<kernel::EdgeCollapse>(op);
      for (int t : c.moved) visit(t);
      for (int t : c.removed) visit(t);
    }
  }
  void undo(const Operation& op) {
    std::visit([&](const auto& o) { m_.undo(o); }, op);
  }
  // Records an operation the mesh just made and files its changed triangles in grid_.
  void record(Operation op) {
    journal_.operations.push_back(std::move(op));  // first: undone by rollback() come what may
    for_each_triangle(journal_.operations.back(), [&](int t) { insert(t); });
  }

  // The triangles by 3D cell (grid_), for the intersection test of changed ones; a candidate's
  // filings are taken back with it.
  void insert(int t) {
    if (m_.face_alive[t]) grid_.insert(t, m_.tri[t], S_.pos, &journal_.cells);
  }
  // Pairs of intersecting triangles involving the triangles changed since begin().
  int new_intersections() const {
    std::vector<int> changed;
    for (const Operation& op : journal_.operations)
      for_each_triangle(op, [&](int t) {
        if (m_.face_alive[t]) changed.push_back(t);
      });
    for (const auto& m : journal_.moved)
      for (int t : m_.vfaces[m.v]) changed.push_back(t);
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    int hits = 0;
    // A cell may list a triangle once per filing; any_near's stamps meet it once per query.
    for (int c : changed)
      grid_.any_near(m_.tri[c], c, m_.tri.size(), S_.pos, [&](int u) {
        if (m_.face_alive[u] && triangles_intersect(S_.pos, m_.tri[c], m_.tri[u])) ++hits;
        return false;
      });
    return hits;
  }

  int add_vertex(const Vector3d& near_point, double near_phi) {
    const auto pr = surf_.project(near_point);
    if (!pr) return -1;
    const int v = S_.add(param_of(pr->point, near_phi), surf_);
    if (v >= 0) m_.add_vertex(S_.pos[v]);
    return v;
  }
  // Moves Steiner point v to (phi, h), journalled; false if the surface is undefined there.
  bool move_vertex(int v, const Vector2d& param) {
    const Journal::Moved old{v, S_.save(v)};
    if (!S_.move(v, param, surf_)) return false;
    journal_.moved.push_back(old);
    for (int t : m_.vfaces[v]) insert(t);
    return true;
  }
  void begin() {
    journal_.clear();
    journal_.n_tris = m_.tri.size();
    journal_.n_verts = S_.pos.size();
  }
  void rollback() {
    auto& touched = touched_;  // corners of the triangles the operations changed or removed
    touched.clear();
    for (auto it = journal_.operations.rbegin(); it != journal_.operations.rend(); ++it) {
      for_each_triangle(
          *it, [&](int t) { touched.insert(touched.end(), m_.tri[t].begin(), m_.tri[t].end()); });
      undo(*it);
    }
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (auto it = journal_.moved.rbegin(); it != journal_.moved.rend(); ++it)
      S_.restore(it->v, it->old);
    grid_.take_back(journal_.cells);
    m_.truncate(journal_.n_tris, journal_.n_verts);
    S_.params.resize(journal_.n_verts);
    S_.pos.resize(journal_.n_verts);
    S_.normal.resize(journal_.n_verts);
    // The undone operations restore the triangles but not the order of their corners' lists:
    // sorted, those lists do not keep whatever order the refused operations left (a list that
    // a kept operation had appended to comes back sorted all the same).
    for (int v : touched)
      if (v < static_cast<int>(m_.vfaces.size())) m_.sort_faces(v);
    journal_.clear();
  }

  // The triangle is counter-clockwise in the (phi, h) plane. The surface is a graph over it,
  // so a valid mesh is a planar triangulation there; 3D normals are no guide at creases such as
  // the chin line, where the vertex normals of one triangle differ by more than 90 deg.
  // The converse fails where the surface is nearly horizontal (the crown, under the chin, the
  // rims of the ears): h hardly changes across a triangle there and r changes fast, so the
  // parameter map is ill-conditioned and a well-shaped triangle that lies flat on the surface
  // can be turned over in (phi, h) (at a quarter of the sample units the mesher and the
  // smoothing leave ~400 such triangles, 98 % of them with a normal within 25 deg of the
  // surface's). Counting them as folds made the repair spend its candidates on unfolding sound
  // triangles. So a triangle turned over in (phi, h) still faces out if its normal agrees with
  // the surface normal under its centroid, by the smoothing's margin.
  bool faces_out(int t) const {
    if (ccw_in_parameters(t)) return true;
    const auto& f = m_.tri[t];
    return agrees_with_surface(S_.pos[f[0]], S_.pos[f[1]], S_.pos[f[2]]);
  }
  // The normal of triangle (a, b, c) against the surface normal under its centroid. The
  // scores of a bad triangle's candidates re-test the same turned-over triangles of its
  // neighbourhood, so the answers are kept by the corner points (bit for bit: the same points
  // give the same answer).
  bool agrees_with_surface(const Vector3d& a, const Vector3d& b, const Vector3d& c) const {
    const Corners key{{a, b, c}};
    if (const auto it = agrees_.find(key); it != agrees_.end()) return it->second;
    const Vector3d n = (b - a).cross(c - a);
    const auto pr = surf_.project((a + b + c) / 3);
    const auto under = pr ? surf_.point_normal(pr->phi, pr->h) : std::nullopt;
    const bool agrees = under && n.dot(under->normal) > 0.3 * n.norm();
    agrees_.emplace(key, agrees);
    return agrees;
  }
  bool ccw_in_parameters(int t) const {
    const auto& f = m_.tri[t];
    const Vector2d& a = S_.params[f[0]];
    auto rel = [&](int v) {
      const Vector2d& p = S_.params[v];
      return Vector2d(wrap_angle(p.x() - a.x()), p.y() - a.y());
    };
    const double rho = std::max(1e-6, std::hypot(S_.pos[f[0]].x(), S_.pos[f[0]].y()));
    const Vector2d b = rel(f[1]), c = rel(f[2]);
    return rho * (b.x() * c.y() - b.y() * c.x()) > 0;
  }

  // The star of Steiner point v, projected on its tangent plane, winds once round it: the
  // fan does not fold over itself (a fold can keep every triangle facing outwards).
  bool simple_star(int v) const {
    const Vector3d& n = S_.normal[v];
    const Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    double sum = 0;
    for (int t : m_.vfaces[v]) {
      const auto& f = m_.tri[t];
      int k = 0;
      while (f[k] != v) ++k;
      const Vector3d a = S_.pos[f[(k + 1) % 3]] - S_.pos[v], b = S_.pos[f[(k + 2) % 3]] - S_.pos[v];
      const double ax = a.dot(t1), ay = a.dot(t2), bx = b.dot(t1), by = b.dot(t2);
      sum += std::atan2(ax * by - ay * bx, ax * bx + ay * by);
    }
    return std::fabs(sum - 2 * M_PI) < 1e-3;
  }

  bool has_edge(int p, int q) const { return m_.edge_face_count(p, q) > 0; }
  std::vector<int> neighbours(int v) const {
    const kernel::NeighbourList nb = m_.neighbours(v);
    std::vector<int> r(nb.begin(), nb.end());
    std::sort(r.begin(), r.end());
    return r;
  }
  bool steiner(int v) const { return v >= static_cast<int>(fixed_); }

  // Edge p-q of two triangles (p, q, r) and (q, p, s) of one region becomes r-s.
  bool flip(int p, int q) {
    if (C_.count(edge_key(p, q))) return false;
    const auto quad = m_.oriented_quad(p, q);
    if (!quad || m_.label[quad->f1] != m_.label[quad->f2] || has_edge(quad->a, quad->b))
      return false;
    m_.flip(*quad);
    record(*quad);
    return true;
  }

  // Steiner point q merges into p (p keeps its place).
  bool collapse(int q, int p) {
    if (!steiner(q)) return false;
    // Two faces with different third corners (quad); a doubled face pair is not collapsed.
    const auto quad = m_.quad(p, q);
    if (!quad) return false;
    const std::array<int, 2> ts{quad->f1, quad->f2};
    const auto np = m_.neighbours(p), nq = m_.neighbours(q);
    if (!m_.link_condition(q, p, ts, nq, np)) return false;
    record(m_.collapse(q, p));
    return true;
  }

  // A new surface point on edge p-q (not a constraint), both triangles split in two.
  int split(int p, int q) {
    if (C_.count(edge_key(p, q))) return -1;
    if (m_.edge_face_count(p, q) != 2) return -1;
    const int m = add_vertex(0.5 * (S_.pos[p] + S_.pos[q]), S_.params[p].x());
    if (m < 0) return -1;
    record(m_.split(p, q, m));
    return m;
  }

  // Smallest incident angle, minus pi per incident triangle facing away from the surface.
  double vertex_min(int v) const { return vertex_min_above(v, -1e9); }
  // The same where it exceeds `floor`; otherwise some value <= floor. (The fold penalty only
  // lowers the value, so a trial point is decided after the first triangle at or below the
  // floor, before the costlier fold tests; the search's decisions are those of vertex_min.)
  // Likewise the folds are counted only until the value is at or below the floor: the fold
  // tests of turned-over triangles project onto the surface, ~half of the pattern search's time.
  double vertex_min_above(int v, double floor) const {
    double m = 1e9;
    for (int t : m_.vfaces[v]) {
      m = std::min(m, tri_min(t));
      if (m <= floor) return m;
    }
    int folded = !simple_star(v);
    for (int t : m_.vfaces[v]) {
      if (m - M_PI * folded <= floor) break;
      folded += !faces_out(t);
    }
    return m - M_PI * folded;
  }

  // Pattern search on the tangent plane maximising the smallest incident angle. The trial
  // steps are taken in (phi, h), mapped from the tangent plane through the surface's Jacobian
  // at the current point, so that a trial point costs one surface evaluation; projecting each
  // 3D trial point back onto the surface (a Gauss-Newton iteration per trial) made this search
  // most of the repair's time. The two differ by step^2 x curvature, below the search's
  // resolution.
  void optimise(int v) {
    if (!steiner(v) || m_.vfaces[v].empty()) return;
    double cur = vertex_min(v);
    if (cur >= kSettledAngle) return;
    // The 15 candidates of a bad triangle optimise overlapping vertex sets, mostly around stars
    // the candidate left as they were; a search from a star state that already gave no move
    // gives none again (the search is a function of that state), so it is skipped.
    const std::uint64_t state = star_state(v);
    if (stuck_states_.count(state)) return;
    bool moved = false;
    double len = 0;
    const auto nb = neighbours(v);
    for (int w : nb) len += (S_.pos[w] - S_.pos[v]).norm();
    len /= std::max<std::size_t>(1, nb.size());
    const Vector3d n = S_.normal[v];
    const Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    double step = 0.25 * len;
    for (int it = 0; it < 12 && step > 0.02 * len && cur < kSettledAngle; ++it) {
      const NodeStore::Saved start = S_.save(v);
      const Vector2d p0 = start.param;
      const auto here = surf_.point_normal(p0.x(), p0.y());
      if (!here) return;
      const Eigen::Matrix<double, 2, 3> to_param = tangent_to_parameters(*here);
      double best = cur;
      Vector2d best_p = p0;
      for (int d = 0; d < 8; ++d) {
        const double a = d * M_PI / 4;
        const Vector2d p = p0 + to_param * (step * (std::cos(a) * t1 + std::sin(a) * t2));
        if (!S_.move(v, p, surf_)) continue;
        const double m = vertex_min_above(v, best + 1e-9);
        if (m > best + 1e-9) {
          best = m;
          best_p = p;
        }
        S_.restore(v, start);
      }
      if (best > cur + 1e-9 && move_vertex(v, best_p)) {
        cur = best;
        moved = true;
      } else {
        step *= 0.5;
      }
    }
    if (!moved) stuck_states_.insert(state);
  }

  // A hash of everything optimise(v) reads: v's parameters, point and normal, and every
  // triangle of its star with its corners' parameters and points (summed per triangle, so the
  // order of the star list does not matter).
  std::uint64_t star_state(int v) const {
    const auto mix = [](std::uint64_t h, double x) {
      std::uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      h ^= bits + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
      return h * 0xBF58476D1CE4E5B9ull;
    };
    const auto vertex = [&](std::uint64_t h, int w) {
      h = mix(h, static_cast<double>(w));
      h = mix(mix(h, S_.params[w].x()), S_.params[w].y());
      return mix(mix(mix(h, S_.pos[w].x()), S_.pos[w].y()), S_.pos[w].z());
    };
    std::uint64_t h = vertex(0x1234567ull, v);
    h = mix(mix(mix(h, S_.normal[v].x()), S_.normal[v].y()), S_.normal[v].z());
    std::uint64_t star = 0;
    for (int t : m_.vfaces[v]) {
      std::uint64_t ht = 0x51ED27ull;
      for (int w : m_.tri[t]) ht = vertex(ht, w);
      star += ht;
    }
    return mix(h, static_cast<double>(star >> 11)) ^ star;
  }

  void optimise_all(const std::vector<int>& vs) {
    for (int pass = 0; pass < 2; ++pass)
      for (int v : vs)
        if (v < static_cast<int>(S_.pos.size())) optimise(v);
  }

  // The neighbourhood whose triangles an operation on t can change, and its score: the
  // ascending list of triangle minimum angles capped at the goal (lexicographically larger is
  // better); empty if any triangle faces away from the surface.
  std::vector<int> region_of(int t) const {
    std::vector<int> vs(m_.tri[t].begin(), m_.tri[t].end());
    for (int ring = 0; ring < 2; ++ring) {
      std::vector<int> next = vs;
      for (int v : vs)
        for (int w : neighbours(v)) next.push_back(w);
      std::sort(next.begin(), next.end());
      next.erase(std::unique(next.begin(), next.end()), next.end());
      vs = next;
    }
    return vs;
  }
  struct Score {
    int folded = 0;         // triangles facing away from the surface normals
    std::vector<double> s;  // ascending minimum angles, capped
    double longest = 0;     // longest side of the triangles (mm)
    double excess = 0;      // largest excess over the deviation goal (mm)
  };
  // `bar`: the best score so far; a candidate that loses to it on folds or on the smallest
  // angle loses whatever its deviation, so its triangles are not sampled (infinite excess).
  Score score(const std::vector<int>& vs, double cap, const Score* bar = nullptr) const {
    std::vector<int> ts;
    for (int v : vs)
      if (v < static_cast<int>(m_.vfaces.size()))
        for (int t : m_.vfaces[v]) ts.push_back(t);
    for (std::size_t v = journal_.n_verts; v < m_.vfaces.size(); ++v)
      for (int t : m_.vfaces[v]) ts.push_back(t);
    std::sort(ts.begin(), ts.end());
    ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
    Score sc;
    sc.folded += new_intersections();
    for (int t : ts) {
      if (!faces_out(t)) ++sc.folded;
      sc.s.push_back(std::min(cap, tri_min(t)));
      if (m_.face_alive[t])
        for (int k = 0; k < 3; ++k)
          sc.longest =
              std::max(sc.longest, (S_.pos[m_.tri[t][k]] - S_.pos[m_.tri[t][(k + 1) % 3]]).norm());
    }
    std::sort(sc.s.begin(), sc.s.end());
    if (!scoring_deviation_) return sc;
    // (In better()'s order: more folds, or as many and a smaller smallest angle.)
    if (bar && (sc.folded > bar->folded || (sc.folded == bar->folded && !sc.s.empty() &&
                                            !bar->s.empty() && sc.s[0] < bar->s[0] - 1e-7))) {
      sc.excess = std::numeric_limits<double>::infinity();
      return sc;
    }
    for (int t : ts) sc.excess = std::max(sc.excess, excess(t));
    return sc;
  }
  // Fewer folds; then the smallest angle (capped); then less excess deviation (scored only in
  // the repair of a triangle off the surface, else 0); then the rest of the angle list. So a
  // deviation repair never lowers the neighbourhood's smallest angle below min(its value,
  // the cap) unless it removes a fold.
  static bool better(const Score& a, const Score& b) {
    if (a.folded != b.folded) return a.folded < b.folded;
    if (!a.s.empty() && !b.s.empty()) {
      if (a.s[0] > b.s[0] + 1e-7) return true;
      if (a.s[0] < b.s[0] - 1e-7) return false;
    }
    if (a.excess < b.excess - 1e-6) return true;
    if (a.excess > b.excess + 1e-6) return false;
    for (std::size_t i = 0; i < std::min(a.s.size(), b.s.size()); ++i) {
      if (a.s[i] > b.s[i] + 1e-7) return true;
      if (a.s[i] < b.s[i] - 1e-7) return false;
    }
    return false;
  }

  // Candidate k on triangle f; false if it does not apply.
  bool apply(const std::array<int, 3>& f, int k) {
    const int kind = k / 3, i = k % 3;
    const int p = f[i], q = f[(i + 1) % 3];
    switch (kind) {
      case 0: {  // optimise the triangle's own Steiner points (i = 0) or its whole 1-ring (1)
        if (i == 2) return false;
        std::vector<int> vs(f.begin(), f.end());
        if (i == 1)
          for (int v : f)
            for (int w : neighbours(v)) vs.push_back(w);
        std::sort(vs.begin(), vs.end());
        vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
        optimise_all(vs);
        return true;
      }
      case 1: {  // flip side i
        std::vector<int> quad;
        for (int t : m_.edge_faces(p, q))
          for (int w : m_.tri[t]) quad.push_back(w);
        if (!flip(p, q)) return false;
        optimise_all(quad);
        return true;
      }
      case 2:
      case 3: {  // collapse side i, into p (kind 2) or into q (kind 3)
        const int from = kind == 2 ? q : p, to = kind == 2 ? p : q;
        if (!collapse(from, to)) return false;
        std::vector<int> vs = neighbours(to);
        vs.push_back(to);
        optimise_all(vs);
        return true;
      }
      case 4: {  // split side i, flip around the new point, optimise
        const int m = split(p, q);
        if (m < 0) return false;
        for (int pass = 0; pass < 2; ++pass)
          for (int t : std::vector<int>(m_.vfaces[m].begin(), m_.vfaces[m].end())) {
            if (!m_.face_alive[t]) continue;
            const auto& ft = m_.tri[t];
            int j = 0;
            while (ft[j] != m) ++j;
            const int a = ft[(j + 1) % 3], b = ft[(j + 2) % 3];
            const auto before = score({a, b, m}, 10);
            if (!flip(a, b)) continue;
            if (!better(score({a, b, m}, 10), before)) {  // undo just this flip
              undo(journal_.operations.back());
              journal_.operations.pop_back();
            }
          }
        std::vector<int> vs = neighbours(m);
        vs.push_back(m);
        optimise_all(vs);
        return true;
      }
    }
    return false;
  }

  bool improve(int t, double goal, RepairStats& st) {
    const std::array<int, 3> f = m_.tri[t];
    const std::vector<int> region = region_of(t);
    // Deviations are scored only in the repair of a triangle off the surface: sampling every
    // candidate's neighbourhood in the angle repairs too cost as much as the repair itself.
    scoring_deviation_ = excess(t) > 0;
    begin();
    // Off the surface, the angles count up to 30 deg (not just to the goal): with the goal's
    // cap of 20.5 deg the flips and splits that bring the sample head within 1.88 mm turned
    // 2.42 % of its triangles below 30 deg into 2.55 %; with 30 deg, 2.10 % (same distance;
    // 35 deg left it at 2.38 mm).
    const double cap = scoring_deviation_ ? std::max(goal, kSettledAngle) : goal;
    const Score base = score(region, cap);
    int best_k = -1;
    Score best = base;
    for (int k = 0; k < 15; ++k) {
      // Off the surface a collapse only makes the triangles around the kept end larger. On
      // the sample head skipping the collapses there left the distance at 1.88 mm and took
      // the build from 0.26-0.32 to 0.18-0.21 s.
      const bool collapse = k / 3 == 2 || k / 3 == 3;
      if (scoring_deviation_ && collapse) continue;
      begin();
      if (apply(f, k)) {
        const auto s = score(region, cap, &best);
        // A collapse may not lengthen the neighbourhood's longest side: at the ears'
        // depth-jump walls collapses built 22-24 mm sides in 10 mm regions, 3.4 mm off the
        // surface, to win a few degrees (docs/animation-meshes.md, "Depth jumps").
        if ((!collapse || s.longest <= base.longest) && better(s, best)) {
          best = s;
          best_k = k;
        }
      }
      rollback();
      // Every triangle of the neighbourhood at the goal and none folded: no later candidate
      // can be better (the scores are capped at the goal), so stop searching.
      if (best_k >= 0 && best.folded == 0 && best.excess == 0 && !best.s.empty() &&
          best.s.front() >= goal - 1e-7)
        break;
    }
    if (best_k < 0) {
      // No candidate brings it closer: it is not tried again unless a neighbour's change
      // moves one of its corners (the 44 failures of the sample head's 81 deviation repairs
      // were otherwise re-tried every round).
      if (scoring_deviation_) beyond_reach_.insert(corners(t));
      return false;
    }
    begin();
    apply(f, best_k);
    journal_.clear();
    ++st.operations[best_k / 3];
    return true;
  }

  std::vector<std::array<int, 3>>& T_;
  std::vector<int>& L_;
  NodeStore& S_;
  const ScanSurface& surf_;
  const std::unordered_set<std::uint64_t>& C_;
  std::size_t fixed_;
  Journal journal_;
  std::vector<int> touched_;  // rollback()'s corners, kept for its memory
  std::unordered_set<std::uint64_t> stuck_states_;  // optimise: star states that gave no move
  double deviation_goal_;                           // mm; 0: no deviation goal
  // The triangles, their labels and adjacency. Positions live in S_: m_.pos is the start's
  // copy, never updated, so m_'s geometric queries (face_normal, to_mesh) are not used here.
  kernel::TriangleMesh m_;
  TriangleCells grid_;                              // triangles by 3D cell, for new_intersections
  GridSurfaceDistance grid_distance_{surf_};
  bool scoring_deviation_ = false;  // improve() works on a triangle beyond the deviation goal
  mutable std::unordered_map<Corners, bool, CornersHash> agrees_;       // agrees_with_surface
  mutable std::unordered_map<Corners, double, CornersHash> deviation_;  // excess
  std::unordered_set<Corners, CornersHash> beyond_reach_;  // off the surface, no candidate helped
};

}  // namespace

RepairStats repair_small_angles(std::vector<std::array<int, 3>>& triangles,
                                std::vector<int>& labels, NodeStore& nodes,
                                const ScanSurface& surface,
                                const std::unordered_set<std::uint64_t>& constraint,
                                std::size_t boundary_nodes, double goal_rad, double report_rad,
                                int rounds, double deviation_goal_mm) {
  Repair r(triangles, labels, nodes, surface, constraint, boundary_nodes, deviation_goal_mm);
  return r.run(goal_rad, report_rad, rounds);
}

}  // namespace scanmesh::aft::detail
