// The spring network of seed 003 §4.2-4.4 (eq. 8, 11-16, 17-23, 24-25). The iteration order
// follows the digest's §5.2 proposal; every gap decision is marked "Gap:" and collected in
// docs/particles.md.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/triangle_quality.h"
#include "scanmesh/meshing/edge_key.h"
#include "scanmesh/meshing/kernel/triangle_mesh.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/particles/particles.h"

#include "../kernel/vertex_components.h"

namespace scanmesh::particles {

using Eigen::Vector3d;

namespace {

// Decision 44: untangling moves after which a particle stops following its springs.
constexpr int kUntanglesBeforeSettling = 3;

struct Spring {
  double rest = 1.0;
  double old_length = 0.0;  // |r|_alt of eq. (16)
  int mark_iter = -1000;    // Rule 3: set in step k, protects during steps k and k+1
  bool topo = false;        // §4.4 Step 1: persistent, never split
  bool special = false;     // §4.4 Step 2: reduced rest length, never split
};

// What a particle carries besides its position and faces (which the kernel's mesh holds).
struct Particle {
  std::uint64_t id = 0;
  bool boundary = false;  // on an open border (scan mode): slides along it (decision 19)
  bool defined = false;   // F could be evaluated at p this step
  // Decision 44 (scan mode, relax() past the flip freeze): untangling moves so far, the
  // previous step's undamped move, and the factor on the move (halved when it turns back).
  int untangled = 0;
  Vector3d last_move = Vector3d::Zero();
  double damping = 1.0;
  void reset_calming() {
    untangled = 0;
    last_move.setZero();
    damping = 1.0;
  }
  ImplicitValue f;
};

// Throws InvalidInputError for options no mesher can work with.
void validate_options(const ParticleOptions& o) {
  if (!(o.edge_length > 0.0) || !(o.rho > 0.0) || !(o.time_step_factor > 0.0) || !(o.d_min > 0.0) ||
      !(o.d_max > 2.0 * o.d_min) || !(o.spring_stiffening >= 0.0) || !(o.moving_epsilon >= 0.0) ||
      !(o.theta >= 0.0 && o.theta <= 1.0) || !(o.lambda >= 0.0 && o.lambda < 1.0) ||
      !(o.special_factor > 0.0 && o.special_factor <= 1.0) || !(o.max_step > 0.0) ||
      !(o.subdivision_accept >= 0.0 && o.subdivision_accept <= 1.0) || o.subdivision_trials < 0 ||
      o.max_spread_particles < 0)
    throw InvalidInputError(
        "particles: impossible options (need edge_length, rho > 0, d_max > 2 d_min, theta in "
        "[0,1], lambda in [0,1), special_factor in (0,1], subdivision_accept in [0,1], "
        "subdivision_trials and max_spread_particles >= 0)");
}

}  // namespace

struct SpringNetwork::Impl {
  ParticleOptions o;
  kernel::TriangleMesh mesh;        // positions, faces and adjacency
  std::vector<Particle> particles;  // per vertex of `mesh`
  std::unordered_map<std::uint64_t, Spring> springs;
  std::uint64_t next_id = 0;
  int iter = 0;

  double R() const { return o.edge_length; }
  const Vector3d& P(int v) const { return mesh.pos[v]; }
  double length(int a, int b) const { return (P(a) - P(b)).norm(); }

  int add_vertex(const Vector3d& p) {
    Particle q;
    q.id = next_id++;
    particles.push_back(std::move(q));
    return mesh.add_vertex(p);
  }
  int add_face(int a, int b, int c) { return mesh.add_face(a, b, c, 0); }
  void kill_face(int f) { mesh.remove_face(f); }
  void kill_vertex(int v) { mesh.remove_vertex(v); }
  std::size_t dead_faces() const { return mesh.tri.size() - mesh.face_count(); }
  // Faces containing both a and b (a vector: the rules reorder them).
  std::vector<int> edge_faces(int a, int b) const { return mesh.edge_faces(a, b); }
  int opposite(int f, int a, int b) const { return mesh.opposite(f, a, b); }
  // Sorted: the rules visit neighbours in index order.
  std::vector<int> neighbors(int a) const {
    std::vector<int> r = mesh.neighbours(a);
    std::sort(r.begin(), r.end());
    return r;
  }
  int valence(int a) const { return mesh.valence(a); }
  Vector3d face_normal(const std::array<int, 3>& t) const {
    return (P(t[1]) - P(t[0])).cross(P(t[2]) - P(t[0]));
  }
  Spring& spring(int a, int b) { return springs.at(edge_key(a, b)); }
  Spring make_spring(int a, int b, double rest) const {
    Spring s;
    s.rest = rest;
    s.old_length = length(a, b);
    return s;
  }
  void mark(int a, int b) {
    const auto it = springs.find(edge_key(a, b));
    if (it != springs.end()) it->second.mark_iter = iter;
  }
  bool marked(const Spring& s) const { return s.mark_iter >= iter - 1; }

  // Rebuilds the spring map from the faces, keeping the data of springs that still exist.
  void rebuild_springs() {
    std::unordered_map<std::uint64_t, Spring> next;
    next.reserve(springs.size() + 16);
    for (std::size_t f = 0; f < mesh.tri.size(); ++f) {
      if (!mesh.face_alive[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const int a = mesh.tri[f][k], b = mesh.tri[f][(k + 1) % 3];
        const std::uint64_t key = edge_key(a, b);
        if (next.count(key)) continue;
        const auto it = springs.find(key);
        next.emplace(key, it != springs.end() ? it->second : make_spring(a, b, R()));
      }
    }
    springs = std::move(next);
    keys_valid_ = false;
  }

  // Drops dead vertices and faces (indices change; ids do not).
  void compact() {
    const std::vector<int> vmap = mesh.compact();
    std::vector<Particle> kept;
    kept.reserve(mesh.pos.size());
    for (std::size_t i = 0; i < particles.size(); ++i)
      if (vmap[i] >= 0) kept.push_back(std::move(particles[i]));
    std::unordered_map<std::uint64_t, Spring> ns;
    ns.reserve(springs.size());
    for (const auto& [k, s] : springs) {
      const int a = vmap[edge_key_first(k)], b = vmap[edge_key_second(k)];
      if (a >= 0 && b >= 0) ns.emplace(edge_key(a, b), s);
    }
    particles = std::move(kept);
    springs = std::move(ns);
    keys_valid_ = false;
    lost_steps_.clear();  // indices changed; the counters start again
  }

  void evaluate_all(const ImplicitSurface& s) {
#pragma omp parallel for schedule(static) if (particles.size() > 20000)
    for (std::size_t i = 0; i < particles.size(); ++i) {
      Particle& v = particles[i];
      if (!mesh.vertex_alive[i]) continue;
      const auto f = s.evaluate(mesh.pos[i]);
      v.defined = f.has_value();
      if (f) v.f = *f;
    }
  }

  // True if moving particle v to q turns none of its triangles over that are not turned now.
  // "Turned" is the test untangle_turned_faces() undoes: the face normal against the sum of
  // its corners' gradients (n, v's gradient, where a corner's F is undefined). With a weaker
  // test here (v's gradient alone) a particle near a tight bend was let into a position the
  // untangling then took back, and the springs pushed it there again: a cycle of ~15 steps
  // that kept relax() from converging on scans (docs/particles.md, decision 41).
  bool keeps_orientation(int v, const Vector3d& q, const Vector3d& n) const {
    for (int f : mesh.vfaces[v]) {
      const auto& t = mesh.tri[f];
      const Vector3d g = corner_gradients(t).value_or(n);
      std::array<Vector3d, 3> x{P(t[0]), P(t[1]), P(t[2])};
      if ((x[1] - x[0]).cross(x[2] - x[0]).dot(g) <= 0.0) continue;  // already turned
      for (int k = 0; k < 3; ++k)
        if (t[k] == v) x[k] = q;
      if ((x[1] - x[0]).cross(x[2] - x[0]).dot(g) <= 0.0) return false;
    }
    return true;
  }
  // The sum of the corners' gradients of face t; none where F is undefined at a corner.
  std::optional<Vector3d> corner_gradients(const std::array<int, 3>& t) const {
    Vector3d g = Vector3d::Zero();
    for (int v : t) {
      if (!particles[v].defined) return std::nullopt;
      g += particles[v].f.gradient;
    }
    return g;
  }

  // ---- Rule 1: midpoint collapse with the link condition ---------------------------------
  bool try_collapse(int a, int b) {
    const auto ef = edge_faces(a, b);
    // Gap (decisions 19, 35): border particles are not merged with interior ones; a border
    // edge (one face, both ends on the border) may collapse along the border.
    const bool border_edge = ef.size() == 1 && particles[a].boundary && particles[b].boundary;
    if (!border_edge && (particles[a].boundary || particles[b].boundary)) return false;
    if (ef.size() != 2 && !border_edge) return false;
    const int c = opposite(ef[0], a, b), d = border_edge ? -1 : opposite(ef[1], a, b);
    if (c == d) return false;
    // Link condition (not in the report, needed for a manifold result): the common neighbours
    // of a and b are exactly the two opposite vertices (the one, for a border edge).
    const auto na = neighbors(a), nb = neighbors(b);
    if (!mesh.link_condition(a, b, ef, na, nb)) return false;
    if (valence(c) <= 3 || (d >= 0 && valence(d) <= 3)) return false;
    if (na.size() + nb.size() - 2 - ef.size() < 3) return false;  // merged valence
    // A border particle that swallowed its border neighbours again and again would collect a
    // huge fan (and the time step shrinks with the largest valence): cap it at 6 (target 4).
    if (border_edge && na.size() + nb.size() - 3 > 6) return false;
    const Vector3d m = 0.5 * (P(a) + P(b));
    // No face around a or b may flip or degenerate when its corner moves to m.
    for (int v : {a, b})
      for (int f : mesh.vfaces[v]) {
        if (std::find(ef.begin(), ef.end(), f) != ef.end()) continue;
        auto t = mesh.tri[f];
        const Vector3d before = face_normal(t);
        for (int& x : t)
          if (x == a || x == b) x = -1;
        std::array<Vector3d, 3> q;
        for (int k = 0; k < 3; ++k) q[k] = t[k] < 0 ? m : P(t[k]);
        const Vector3d after = (q[1] - q[0]).cross(q[2] - q[0]);
        if (after.dot(before) <= 0.2 * before.norm() * after.norm()) return false;
        if (triangle_min_angle(q[0], q[1], q[2]) < 5.0 * std::numbers::pi / 180.0) return false;
      }
    mesh.collapse(b, a);
    springs.erase(edge_key(a, b));
    keys_valid_ = false;
    for (int x : nb) {
      if (x == a) continue;
      const auto it = springs.find(edge_key(b, x));
      if (it == springs.end()) continue;
      const Spring s = it->second;
      springs.erase(it);
      if (x != c && x != d) springs[edge_key(a, x)] = s;
    }
    mesh.pos[a] = m;
    particles[a].id = next_id++;  // a merged particle is a new particle (docs/particles.md)
    particles[a].reset_calming();
    if (static_cast<std::size_t>(a) < lost_steps_.size()) lost_steps_[a] = 0;
    kill_vertex(b);
    for (int x : neighbors(a)) mark(a, x);
    return true;
  }

  // ---- Rule 2: 2 -> 4 split at the midpoint ---------------------------------------------
  static constexpr int kMaxSplitValence = 12;
  bool try_split(int a, int b, const ImplicitSurface& surface) {
    const auto quad = mesh.oriented_quad(a, b);
    // Gap: border edges are not split (scan mode), nor an edge whose faces are a doubled pair.
    if (!quad) return false;
    const int c = quad->a, d = quad->b;
    // Decision 42: in relax() (static surfaces, scan mode; §4.4 off) a split adds a spring at c
    // and at d only up to kMaxSplitValence springs. The time step is 1 / (rho x largest
    // valence), so one particle whose fan kept growing slowed the whole network down (the
    // 512 x 512 head: a particle waiting in a hole of the data reached 820 springs, the step
    // fell to 1/820). An animation's neck needs such fans while it constricts (§4.4 on).
    if (!o.topology_change &&
        (fast_valence(c) >= kMaxSplitValence || fast_valence(d) >= kMaxSplitValence))
      return false;
    const double rest = spring(a, b).rest;
    Vector3d mid = 0.5 * (P(a) + P(b));
    // Gap: the new particle is Newton-projected at once (the report lets eq. 8 do it).
    if (const auto q = project_to_surface(surface, mid, 3);
        q && (*q - mid).norm() < 0.5 * length(a, b))
      mid = *q;
    kill_face(quad->f1);
    kill_face(quad->f2);
    const int m = add_vertex(mid);
    particles[m].f = particles[a].f;
    particles[m].defined = false;
    add_face(a, m, c);
    add_face(m, b, c);
    add_face(b, m, d);
    add_face(m, a, d);
    springs.erase(edge_key(a, b));
    keys_valid_ = false;
    for (int x : {a, b, c, d}) springs[edge_key(m, x)] = make_spring(m, x, rest);
    for (int x : {a, b, c, d}) mark(m, x);
    mark(a, c), mark(b, c), mark(a, d), mark(b, d);
    return true;
  }

  // ---- Edge flip towards valence 6 (not in the report; switchable) -----------------------
  // kGlide: skip the valence criterion (a dislocation glide step, remove_dislocations());
  // kDelaunay: also allow a crease (the caller checked the Delaunay criterion on a coarse
  // mesh, whose neighbouring faces may meet at more than 60 degrees).
  enum FlipMode { kValence, kGlide, kDelaunay };
  bool try_flip(int a, int b, FlipMode mode = kValence) {
    const auto quad = mesh.oriented_quad(a, b);
    if (!quad || springs.count(edge_key(quad->a, quad->b))) return false;
    const int c = quad->a, d = quad->b;
    auto target = [&](int v) { return particles[v].boundary ? 4 : 6; };
    const int va = fast_valence(a), vb = fast_valence(b), vc = fast_valence(c),
              vd = fast_valence(d);
    if (va <= 3 || vb <= 3) return false;
    auto sq = [](int x) { return x * x; };
    const int before =
        sq(va - target(a)) + sq(vb - target(b)) + sq(vc - target(c)) + sq(vd - target(d));
    const int after = sq(va - 1 - target(a)) + sq(vb - 1 - target(b)) + sq(vc + 1 - target(c)) +
                      sq(vd + 1 - target(d));
    if (after >= before && mode == kValence) return false;
    const std::array<int, 3> t0{a, d, c}, t1{b, c, d};
    const Vector3d n0 = face_normal(t0), n1 = face_normal(t1);
    const Vector3d old_n =
        face_normal(mesh.tri[quad->f1]).normalized() + face_normal(mesh.tri[quad->f2]).normalized();
    if (mode != kDelaunay && n0.dot(n1) < 0.5 * n0.norm() * n1.norm()) return false;  // crease
    if (n0.dot(old_n) <= 0.0 || n1.dot(old_n) <= 0.0) return false;
    const double min_new =
        std::min(triangle_min_angle(P(a), P(d), P(c)), triangle_min_angle(P(b), P(c), P(d)));
    const double min_old =
        std::min(triangle_min_angle(P(a), P(b), P(c)), triangle_min_angle(P(b), P(a), P(d)));
    if (min_new < std::min(min_old, 10.0 * std::numbers::pi / 180.0)) return false;
    const double rest =
        0.25 * (spring(a, c).rest + spring(b, c).rest + spring(a, d).rest + spring(b, d).rest);
    mesh.flip(*quad);             // (a, b, c), (b, a, d) as tested
    mesh.put_first(quad->f1, a);  // t0, started where the network's flips always started it
    mesh.put_first(quad->f2, b);  // t1 (put_first says why)
    springs.erase(edge_key(a, b));
    keys_valid_ = false;
    springs[edge_key(c, d)] = make_spring(c, d, rest);
    mark(c, d), mark(a, c), mark(b, c), mark(a, d), mark(b, d);
    return true;
  }

  // ---- Dislocation removal (an addition; docs/particles.md, decision 33) -----------------
  // An adjacent valence-7/valence-5 pair is a lattice dislocation: no flip that lowers the
  // sum of squared valence deviations exists around it, so the greedy flips of decision 12
  // leave it, and its spokes carry the largest strains of the mesh. A "glide" flip of the
  // edge (seven, w), w the 6-valent common neighbour of the pair on one side, moves the pair
  // one lattice step (7,5,6,6 -> 6,6,5,7) at no valence cost. Each pair is glided up to
  // `max_glide` steps in each of its two directions; as soon as the moving 7 or 5 can be
  // cancelled by an improving flip (it met a defect of opposite sign, e.g. an isolated 5) the
  // path is kept, otherwise it is undone. Returns the number of cancelled pairs.
  bool improving_flip_around(int x) {
    if (!mesh.vertex_alive[x]) return false;
    for (int y : neighbors(x))
      if (try_flip(x, y)) return true;
    return false;
  }
  int remove_dislocations(int max_glide) {
    int removed = 0;
    auto interior = [&](int v, int val) {
      return mesh.vertex_alive[v] && !particles[v].boundary && fast_valence(v) == val;
    };
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const int v = static_cast<int>(i);
      if (!interior(v, 7)) continue;
      bool done = false;
      for (int c : neighbors(v)) {
        if (done || !interior(v, 7)) break;
        if (!interior(c, 5)) continue;
        const auto ef = edge_faces(v, c);
        if (ef.size() != 2) continue;
        const std::array<int, 2> sides{opposite(ef[0], v, c), opposite(ef[1], v, c)};
        for (int side = 0; side < 2 && !done; ++side) {
          int seven = v, five = c, w = sides[side];
          std::vector<std::pair<int, int>> undo;
          for (int k = 0; k < max_glide; ++k) {
            if (!interior(w, 6)) break;
            const auto e2 = edge_faces(seven, w);
            if (e2.size() != 2) break;
            int d = opposite(e2[0], seven, w);
            if (d == five) d = opposite(e2[1], seven, w);
            if (!interior(d, 6) || !try_flip(seven, w, kGlide)) break;
            undo.emplace_back(five, d);  // now d is 7 and w is 5
            if (improving_flip_around(d) || improving_flip_around(w)) {
              done = true;
              break;
            }
            const auto e3 = edge_faces(d, w);
            if (e3.size() != 2) break;
            int x = opposite(e3[0], d, w);
            if (x == five) x = opposite(e3[1], d, w);
            seven = d;
            five = w;
            w = x;
          }
          if (done) break;
          for (auto it = undo.rbegin(); it != undo.rend(); ++it)
            try_flip(it->first, it->second, kGlide);
        }
      }
      removed += done ? 1 : 0;
    }
    return removed;
  }

  // ---- Turned border triangles (scan mode; an addition, docs/particles.md, decision 38) ---
  // Where the range surface ends (grid holes, occlusion borders) a triangle at a border can
  // end up turned over against the surface normal: its border particles slide along their
  // border chord and cannot untangle it. Such a triangle is dropped (the border moves
  // inwards) when it touches the border: with the whole fan of a border corner whose fan's
  // rim is interior but for its two border neighbours, when it has no border edge and there
  // is such a corner; otherwise alone, with whatever smaller wedge one of its corners is left
  // with (decision 43), so the mesh stays a manifold (a particle left with no face goes too).
  // Interior folds are left to the untangling. Returns the number of triangles dropped.
  int drop_turned_border_faces(const ImplicitSurface& surface) {
    int dropped = 0;
    for (int round = 0; round < 8; ++round) {
      int this_round = 0;
      for (std::size_t f = 0; f < mesh.tri.size(); ++f) {
        if (!mesh.face_alive[f] || !turned_over(mesh.tri[f], surface)) continue;
        const auto t = mesh.tri[f];
        int border_edges = 0;
        for (int k = 0; k < 3; ++k)
          border_edges += edge_faces(t[k], t[(k + 1) % 3]).size() == 1 ? 1 : 0;
        if (border_edges == 0) {
          const auto fan_corner = std::find_if(t.begin(), t.end(), [&](int v) {
            return particles[v].boundary && fan_rim_is_interior(v);
          });
          if (fan_corner != t.end()) {
            const std::vector<int> fan = mesh.vfaces[*fan_corner];
            drop_faces(fan);
            this_round += static_cast<int>(fan.size());
            continue;
          }
          if (std::none_of(t.begin(), t.end(), [&](int v) { return particles[v].boundary; }))
            continue;  // interior folds are not touched
        }
        const std::size_t before = dead_faces();
        drop_faces({static_cast<int>(f)});
        separate_wedges({t.begin(), t.end()});
        this_round += static_cast<int>(dead_faces() - before);
      }
      if (this_round == 0) break;
      dropped += this_round;
    }
    if (dropped > 0) rebuild_springs();
    return dropped;
  }
  // Removes faces; their particles become border particles, or go if no face is left.
  void drop_faces(const std::vector<int>& doomed) {
    for (int f : doomed) {
      const auto t = mesh.tri[f];
      kill_face(f);
      for (int v : t) {
        particles[v].boundary = true;
        if (mesh.vfaces[v].empty() && mesh.vertex_alive[v]) kill_vertex(v);
      }
    }
  }
  // True if every neighbour of border particle v is interior except its two border
  // neighbours (v has exactly two border edges).
  bool fan_rim_is_interior(int v) const {
    int border_neighbours = 0;
    for (int w : neighbors(v)) {
      const bool border_edge = edge_faces(v, w).size() == 1;
      border_neighbours += border_edge ? 1 : 0;
      if (!border_edge && particles[w].boundary) return false;
    }
    return border_neighbours == 2;
  }
  // True if the triangle's normal points against F's gradient at its centroid (where F is
  // defined there).
  bool turned_over(const std::array<int, 3>& t, const ImplicitSurface& surface) const {
    const auto f = surface.evaluate((P(t[0]) + P(t[1]) + P(t[2])) / 3.0);
    return f && face_normal(t).dot(f->gradient) <= 0.0;
  }

  // ---- Evenly spread coarse particles (an addition; docs/particles.md, decision 37) -------
  // A coarse mesh of a few dozen particles fixes where a subdivided fine mesh has its valence
  // defects (subdivision adds none). Coarsening leaves whatever connectivity its collapses
  // made (e.g. three valence-4 particles on a 12-particle sphere) and springs keep it.
  // All-pairs Coulomb repulsion on the surface (the Thomson problem) spreads the particles
  // evenly, and Delaunay flips give them the matching connectivity (on a sphere with 12
  // particles: the icosahedron). Charges repel only within their own component; border
  // particles stay where they are.
  void spread_particles(const ImplicitSurface& surface, int iterations) {
    const std::vector<std::vector<int>> groups = particles_by_component();
    std::vector<int> alive;
    for (const auto& g : groups) alive.insert(alive.end(), g.begin(), g.end());
    std::vector<Vector3d> force(particles.size());
    for (int it = 0; it < iterations; ++it) {
      evaluate_all(surface);
      for (int a : alive) force[a].setZero();
      for (const auto& g : groups)
        for (std::size_t i = 0; i < g.size(); ++i)
          for (std::size_t j = i + 1; j < g.size(); ++j) {
            const Vector3d d = P(g[i]) - P(g[j]);
            const double r2 = std::max(d.squaredNorm(), 1e-24);
            const Vector3d f = d / (r2 * std::sqrt(r2));
            force[g[i]] += f;
            force[g[j]] -= f;
          }
      double largest = 0.0;
      for (int a : alive) {
        if (particles[a].boundary || !particles[a].defined ||
            particles[a].f.gradient.squaredNorm() == 0.0) {
          force[a].setZero();
          continue;
        }
        const Vector3d n = particles[a].f.gradient.normalized();
        force[a] -= force[a].dot(n) * n;
        largest = std::max(largest, force[a].norm());
      }
      if (largest == 0.0) break;
      // The largest move shrinks from 0.1 R to 0 (a simple annealed gradient descent).
      const double step = 0.1 * R() * (1.0 - static_cast<double>(it) / iterations) / largest;
      for (int a : alive) {
        if (force[a].squaredNorm() == 0.0) continue;
        const auto q = project_to_surface(surface, P(a) + step * force[a], 8);
        if (q && keeps_orientation(a, *q, particles[a].f.gradient)) mesh.pos[a] = *q;
      }
      delaunay_flips();
    }
  }
  // The alive particles grouped by connected component (through faces), in index order.
  std::vector<std::vector<int>> particles_by_component() const {
    kernel::VertexComponents components(particles.size());
    for (std::size_t f = 0; f < mesh.tri.size(); ++f)
      if (mesh.face_alive[f]) components.join(mesh.tri[f]);
    std::vector<int> group_of(particles.size(), -1);
    std::vector<std::vector<int>> groups;
    for (std::size_t i = 0; i < particles.size(); ++i) {
      if (!mesh.vertex_alive[i]) continue;
      int& g = group_of[components.root(static_cast<int>(i))];
      if (g < 0) g = static_cast<int>(groups.size()), groups.emplace_back();
      groups[g].push_back(static_cast<int>(i));
    }
    return groups;
  }
  // Flips every edge whose two opposite angles (in 3D) sum to more than pi, until none.
  int delaunay_flips() {
    auto angle_at = [&](int c, int a, int b) {
      const Vector3d u = P(a) - P(c), w = P(b) - P(c);
      return std::atan2(u.cross(w).norm(), u.dot(w));
    };
    int total = 0;
    for (int round = 0; round < 20; ++round) {
      int flipped = 0;
      const std::vector<std::uint64_t> keys = sorted_keys();
      for (std::uint64_t k : keys) {
        const auto it = springs.find(k);
        if (it == springs.end() || it->second.topo) continue;
        const int a = edge_key_first(k), b = edge_key_second(k);
        const auto ef = edge_faces(a, b);
        if (ef.size() != 2) continue;
        const int c = opposite(ef[0], a, b), d = opposite(ef[1], a, b);
        // Both ways must agree (a quad that is folded over looks non-Delaunay either way and
        // would flip back and forth).
        if (angle_at(c, a, b) + angle_at(d, a, b) > std::numbers::pi + 1e-9 &&
            angle_at(a, c, d) + angle_at(b, c, d) < std::numbers::pi - 1e-9 &&
            try_flip(a, b, kDelaunay))
          ++flipped;
      }
      total += flipped;
      if (flipped == 0) break;
    }
    return total;
  }

  // ---- Density correction (an addition; docs/particles.md) -------------------------------
  // Rules 1-2 react only to single over-compressed or over-stretched springs. With a fixed
  // particle count the network can settle uniformly compressed or stretched (all springs at
  // 0.9 R, say), which no local rule sees. Then the mean stretch s = mean(|r| / R_e) tells how
  // many particles are missing or superfluous (count ~ 1 / s^2); collapse the shortest or
  // split the longest springs until that count is reached.
  int rebalance(double mean_stretch, const ImplicitSurface& surface) {
    const double change = static_cast<double>(alive_count()) * (mean_stretch * mean_stretch - 1.0);
    return change_count(static_cast<int>(std::lround(change)), surface);
  }
  // Adds (`delta` > 0: splits of the longest springs) or removes (collapses of the shortest)
  // up to |delta| particles; returns how many changes were made.
  int change_count(int delta, const ImplicitSurface& surface) {
    std::vector<std::pair<double, std::uint64_t>> order;
    for (const auto& [k, sp] : springs)
      order.emplace_back(length(edge_key_first(k), edge_key_second(k)) / sp.rest, k);
    std::sort(order.begin(), order.end());
    if (delta > 0) std::reverse(order.begin(), order.end());
    const int wanted = std::abs(delta);
    int done = 0;
    for (const auto& [ratio, k] : order) {
      if (done >= wanted) break;
      const auto it = springs.find(k);
      if (it == springs.end() || marked(it->second) || it->second.topo || it->second.special)
        continue;
      const int a = edge_key_first(k), b = edge_key_second(k);
      if (delta < 0 ? try_collapse(a, b) : try_split(a, b, surface)) ++done;
    }
    return done;
  }
  std::size_t alive_count() const { return static_cast<std::size_t>(mesh.vertex_count()); }
  double mean_stretch() const {
    double sum = 0.0;
    for (const auto& [k, sp] : springs)
      sum += length(edge_key_first(k), edge_key_second(k)) / sp.rest;
    return springs.empty() ? 1.0 : sum / static_cast<double>(springs.size());
  }

  // ---- §4.3: curvature-adaptive rest lengths, eq. (17)-(23) -------------------------------
  void adapt_rest_lengths() {
    double sum = 0.0;
    std::size_t count = 0;
    std::vector<std::pair<Spring*, double>> cosines;
    cosines.reserve(springs.size());
    for (auto& [k, s] : springs) {
      const Particle &va = particles[edge_key_first(k)], &vb = particles[edge_key_second(k)];
      if (!va.defined || !vb.defined) continue;
      const double na = va.f.gradient.norm(), nb = vb.f.gradient.norm();
      if (!(na > 0.0 && nb > 0.0)) continue;
      const double c = std::clamp(va.f.gradient.dot(vb.f.gradient) / (na * nb), -1.0, 1.0);
      cosines.emplace_back(&s, c);
      if (!s.special && !s.topo) sum += c, ++count;
    }
    if (count == 0) return;
    const double cos_beta = sum / static_cast<double>(count);  // the mean over all springs
    const double lo = R() * (1.0 - o.lambda), hi = R() * (1.0 + o.lambda);
    for (auto [s, cos_alpha] : cosines) {
      if (s->special || s->topo) continue;
      const double l = s->old_length;  // Gap: l is the current length |r| (stored this step)
      const double denom = std::max(1.0 - cos_alpha, 1e-12);  // flat spring: clamp decides
      const double delta = l * (std::sqrt((1.0 - cos_beta) / denom) - 1.0);  // eq. (21)
      s->rest = std::clamp(l + o.theta * delta, lo, hi);                     // (22), (23)
    }
    // Gap decision 31: eq. (21) sets every spring on its own, so neighbouring springs can get
    // very different rest lengths and the triangles between them turn skinny. Smooth: each
    // particle takes the mean rest length of its springs, each spring the mean of its two
    // particles'.
    if (!o.adaptive_smoothing) return;
    std::vector<double> vsum(particles.size(), 0.0);
    std::vector<int> vcount(particles.size(), 0);
    for (const auto& [k, s] : springs) {
      if (s.special || s.topo) continue;
      for (int v : {edge_key_first(k), edge_key_second(k)}) vsum[v] += s.rest, ++vcount[v];
    }
    for (auto& [k, s] : springs) {
      if (s.special || s.topo) continue;
      const int a = edge_key_first(k), b = edge_key_second(k);
      s.rest = 0.5 * (vsum[a] / vcount[a] + vsum[b] / vcount[b]);
    }
  }

  // ---- §4.4 Step 1 and 2 ------------------------------------------------------------------
  int mark_gap_springs(const ImplicitSurface& surface) {
    int marked_now = 0;
    const double cos_eps = std::cos(o.gap_angle_deg * std::numbers::pi / 180.0);
    for (auto& [k, s] : springs) {
      if (s.topo) continue;
      const int a = edge_key_first(k), b = edge_key_second(k);
      const Particle &va = particles[a], &vb = particles[b];
      if (!va.defined || !vb.defined) continue;
      const Vector3d ga = va.f.gradient, gb = vb.f.gradient;
      const Vector3d r = P(a) - P(b);
      const double rl = r.norm();
      if (!(rl > 0.0)) continue;
      const bool diverging = ga.dot(gb) < 0.0;
      double cos_gamma = 0.0;
      if (ga.norm() > 0.0) cos_gamma = std::max(cos_gamma, std::abs(ga.dot(r)) / (ga.norm() * rl));
      if (gb.norm() > 0.0) cos_gamma = std::max(cos_gamma, std::abs(gb.dot(r)) / (gb.norm() * rl));
      if (!diverging && cos_gamma <= cos_eps) continue;
      const auto fm = surface.evaluate(0.5 * (P(a) + P(b)));
      if (!fm || !(fm->value > 0.0)) continue;  // eq. (24): the midpoint lies outside
      s.topo = true;
      ++marked_now;
    }
    if (marked_now == 0 && !any_topo_) return 0;
    any_topo_ = true;
    // Step 2: the third edge of a triangle with exactly two marked edges becomes special.
    for (std::size_t f = 0; f < mesh.tri.size(); ++f) {
      if (!mesh.face_alive[f]) continue;
      const auto& t = mesh.tri[f];
      int n = 0, third = -1;
      for (int k = 0; k < 3; ++k) {
        if (springs.at(edge_key(t[k], t[(k + 1) % 3])).topo)
          ++n;
        else
          third = k;
      }
      if (n != 2) continue;
      Spring& s = springs.at(edge_key(t[third], t[(third + 1) % 3]));
      s.special = true;
    }
    return marked_now;
  }
  bool any_topo_ = false;
  bool has_border_ = false;  // scan mode: the start mesh had borders (decision 43)
  // Scan mode, relax() past the flip freeze (decision 44): moves that turn back are damped
  // and particles the untangling keeps taking back settle; past twice the flip freeze no
  // Rule 1-2 split or collapse either (the density correction at convergence still runs).
  bool calming_ = false;
  bool rules_frozen_ = false;
  // Sorted spring keys (deterministic processing order), rebuilt only after the spring set
  // changed: sorting every step was a quarter of the run time.
  std::vector<std::uint64_t> keys_;
  bool keys_valid_ = false;
  bool last_changed_ = true;  // the previous step changed the mesh (flip pass due)
  const std::vector<std::uint64_t>& sorted_keys() {
    if (!keys_valid_ || keys_.size() != springs.size()) {
      keys_.clear();
      keys_.reserve(springs.size());
      for (const auto& [k, s] : springs) keys_.push_back(k);
      std::sort(keys_.begin(), keys_.end());
      keys_valid_ = true;
    }
    return keys_;
  }
  int fallback_cuts_ = 0;
  bool converged = false;  // the last relax() met its convergence test
  int candidate_steps_ = 0;
  // Per particle: consecutive steps farther than R from F = 0 (in scan mode also: with F
  // undefined; decisions 25 and 43).
  std::vector<int> lost_steps_;

  int fast_valence(int v) const {
    return static_cast<int>(mesh.vfaces[v].size()) + (particles[v].boundary ? 1 : 0);
  }

  // ---- Remeshing polish (an addition; docs/particles.md) ---------------------------------
  // Tangential relaxation: every free particle moves towards the area-weighted centroid of
  // its triangles' centroids (one Lloyd-like step), within the tangent plane, and is then
  // Newton-projected onto F = 0.
  void smooth(const ImplicitSurface& surface, double weight) {
    std::vector<Vector3d> next(particles.size());
#pragma omp parallel for schedule(static) if (particles.size() > 20000)
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const Vector3d& p = mesh.pos[i];
      next[i] = p;
      if (!mesh.vertex_alive[i] || particles[i].boundary || mesh.vfaces[i].empty()) continue;
      Vector3d c = Vector3d::Zero(), n = Vector3d::Zero();
      double area = 0.0;
      for (int f : mesh.vfaces[i]) {
        const auto& t = mesh.tri[f];
        const Vector3d nf = face_normal(t);
        const double a = nf.norm();
        c += a * (P(t[0]) + P(t[1]) + P(t[2])) / 3.0;
        n += nf;
        area += a;
      }
      if (!(area > 0.0)) continue;
      c /= area;
      const auto f = surface.evaluate(p);
      if (f && f->gradient.squaredNorm() > 1e-20) n = f->gradient;
      n.normalize();
      Vector3d d = c - p;
      d -= n.dot(d) * n;
      Vector3d q = p + weight * d;
      if (const auto pr = project_to_surface(surface, q, 4, 1e-10 * R());
          pr && (*pr - q).norm() < 0.5 * R())
        q = *pr;
      next[i] = q;
    }
    for (std::size_t i = 0; i < particles.size(); ++i) mesh.pos[i] = next[i];
  }

  // A face turned against the surface: its normal points against the sum of its corners'
  // gradients (evaluated this step; the same test as keeps_orientation, without evaluating F).
  bool turned_at_corners(const std::array<int, 3>& t) const {
    const auto g = corner_gradients(t);
    return g && face_normal(t).dot(*g) < 0.0;
  }
  int turned_faces_around(int v) const {
    int n = 0;
    for (int f : mesh.vfaces[v]) n += turned_at_corners(mesh.tri[f]) ? 1 : 0;
    return n;
  }

  // Gap decision 39: a face turned over (the cut's closing fans across a neck, a face the
  // move guard could not protect because the gradient turns within it) stays turned: springs
  // act along edges and do not see orientation. Each corner of a turned face moves to the
  // centroid of its one-ring (Newton-projected) when that turns fewer faces around it over;
  // a few rounds, as the untangling of a folded mesh by Laplacian steps.
  int untangle_turned_faces(const ImplicitSurface& surface) {
    int moved = 0;
    for (int round = 0; round < 4; ++round) {
      std::vector<int> corners;
      for (std::size_t f = 0; f < mesh.tri.size(); ++f)
        if (mesh.face_alive[f] && turned_at_corners(mesh.tri[f]))
          for (int v : mesh.tri[f])
            if (!particles[v].boundary) corners.push_back(v);
      if (corners.empty()) break;
      std::sort(corners.begin(), corners.end());
      corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
      int moved_now = 0;
      for (int v : corners) {
        const auto ring = neighbors(v);
        if (ring.empty()) continue;
        Vector3d c = Vector3d::Zero();
        for (int x : ring) c += P(x);
        c /= static_cast<double>(ring.size());
        if (const auto q = project_to_surface(surface, c, 4, 1e-10 * R());
            q && (*q - c).norm() < 0.5 * R())
          c = *q;
        const int before = turned_faces_around(v);
        const Vector3d old = mesh.pos[v];
        mesh.pos[v] = c;
        if (turned_faces_around(v) < before) {
          ++moved_now;
          if (calming_) ++particles[v].untangled;
        } else {
          mesh.pos[v] = old;
        }
      }
      moved += moved_now;
      if (moved_now == 0) break;
    }
    return moved;
  }

  // Collapse only if no spring at the merged particle would become longer than `limit`.
  bool collapse_keeps_short(int a, int b, double limit) const {
    const Vector3d m = 0.5 * (P(a) + P(b));
    for (int v : {a, b})
      for (int f : mesh.vfaces[v])
        for (int x : mesh.tri[f])
          if (x != a && x != b && (P(x) - m).norm() > limit) return false;
    return true;
  }

  // One round of isotropic remeshing towards the rest lengths: split springs longer than
  // 4/3 R_e, collapse those shorter than 4/5 R_e, flip towards valence 6, relax tangentially.
  int remesh_round(const ImplicitSurface& surface) {
    int changes = 0;
    // Each pass over a copy of the keys as they were before it (its operations change them).
    std::vector<std::uint64_t> keys = sorted_keys();
    for (std::uint64_t k : keys) {
      const auto it = springs.find(k);
      if (it == springs.end() || it->second.topo || it->second.special) continue;
      const int a = edge_key_first(k), b = edge_key_second(k);
      if (length(a, b) > 4.0 / 3.0 * it->second.rest && try_split(a, b, surface)) ++changes;
    }
    keys = sorted_keys();
    for (std::uint64_t k : keys) {
      const auto it = springs.find(k);
      if (it == springs.end() || it->second.topo || it->second.special) continue;
      const int a = edge_key_first(k), b = edge_key_second(k);
      const double rest = it->second.rest;
      if (length(a, b) < 0.8 * rest && collapse_keeps_short(a, b, 4.0 / 3.0 * rest) &&
          try_collapse(a, b))
        ++changes;
    }
    keys = sorted_keys();
    for (std::uint64_t k : keys) {
      const auto it = springs.find(k);
      if (it == springs.end() || it->second.topo) continue;
      if (try_flip(edge_key_first(k), edge_key_second(k))) ++changes;
    }
    smooth(surface, 1.0);
    return changes;
  }

  // ---- §4.4 Step 3: ring detection (eq. 25) and the cut with two closing fans ------------
  int cut_rings(const ImplicitSurface& surface) {
    std::unordered_map<std::uint64_t, bool> qualifies;
    auto qual = [&](int a, int b) {
      const std::uint64_t k = edge_key(a, b);
      if (const auto it = qualifies.find(k); it != qualifies.end()) return it->second;
      bool q = false;
      const Particle &va = particles[a], &vb = particles[b];
      if (va.defined && vb.defined) {
        const double na = va.f.gradient.norm(), nb = vb.f.gradient.norm();
        if (na > 0.0 && nb > 0.0 && va.f.gradient.dot(vb.f.gradient) / (na * nb) < o.epsilon2) {
          const auto fm = surface.evaluate(0.5 * (P(a) + P(b)));
          q = fm && fm->value > o.epsilon1 * R() * fm->gradient.norm() && fm->value > 0.0;
        }
      }
      qualifies.emplace(k, q);
      return q;
    };
    // Candidates: triangles with exactly two qualifying edges (eq. 25.1-3).
    std::unordered_map<int, std::array<int, 3>> cand;  // face -> qualifying flags
    for (std::size_t f = 0; f < mesh.tri.size(); ++f) {
      if (!mesh.face_alive[f]) continue;
      const auto& t = mesh.tri[f];
      std::array<int, 3> q{};
      int n = 0;
      for (int k = 0; k < 3; ++k) n += (q[k] = qual(t[k], t[(k + 1) % 3]) ? 1 : 0);
      if (n == 2) cand.emplace(static_cast<int>(f), q);
    }
    if (cand.empty()) {
      candidate_steps_ = 0;
      return 0;
    }
    ++candidate_steps_;
    std::vector<int> order;
    for (const auto& [f, q] : cand) order.push_back(f);
    std::sort(order.begin(), order.end());
    std::unordered_set<int> visited;
    int cuts = 0;
    for (int start : order) {
      if (visited.count(start) || !mesh.face_alive[start]) continue;
      // Walk the dual cycle through qualifying shared edges (eq. 25.1, closed by 25.4).
      std::vector<int> ring;
      bool closed = false, broken = false;
      int prev = -1, cur = start;
      while (true) {
        visited.insert(cur);
        ring.push_back(cur);
        const auto& t = mesh.tri[cur];
        const auto& q = cand.at(cur);
        std::vector<int> nbr;
        for (int k = 0; k < 3; ++k) {
          if (!q[k]) continue;
          const auto ef = edge_faces(t[k], t[(k + 1) % 3]);
          if (ef.size() != 2) {
            broken = true;
            break;
          }
          const int other = ef[0] == cur ? ef[1] : ef[0];
          if (!cand.count(other)) {
            broken = true;
            break;
          }
          nbr.push_back(other);
        }
        if (broken || nbr.size() != 2 || nbr[0] == nbr[1]) {
          broken = true;
          break;
        }
        const int next = prev < 0 ? std::min(nbr[0], nbr[1]) : (nbr[0] == prev ? nbr[1] : nbr[0]);
        if (next == start) {
          closed = true;
          break;
        }
        if (visited.count(next)) {
          broken = true;
          break;
        }
        prev = cur;
        cur = next;
      }
      if (broken || !closed || ring.size() < 3) continue;
      bool alive = true;
      for (int f : ring) alive = alive && mesh.face_alive[f];
      if (!alive) continue;
      if (cut_ring(ring, cand, surface)) {
        ++cuts;
        continue;
      }
      // Gap: the ring is clean (eq. 25) but its third edges do not form two simple loops
      // (e.g. two ring triangles share a third edge where the ring wraps round a particle).
      // Cut it all the same: remove the ring and close every hole it leaves by a fan, finding
      // the holes from the border half-edges (pinched vertices widened, decision 27).
      for (int f : ring) kill_face(f);
      for (int f : ring)
        for (int v : mesh.tri[f])
          if (mesh.vertex_alive[v] && mesh.vfaces[v].empty()) kill_vertex(v);
      close_new_holes(surface);
      ++cuts;
    }
    if (cuts) {
      rebuild_springs();
      clear_gap_marks();
      return cuts;
    }
    // Patience: constriction (Step 2) usually turns the first ragged band of candidates into a
    // clean ring within a few steps; only a band that persists is removed wholesale.
    if (candidate_steps_ <= o.ring_patience) return 0;
    candidate_steps_ = 0;
    fallback_cuts_ += 1;
    // Gap: no clean ring (e.g. a twisted band of spanning triangles whose constricted feet
    // could not be collapsed further). Every candidate triangle spans the gap (its qualifying
    // edges join end points with gradients >= 90 deg apart through the outside), so remove
    // them all and close the holes with fans.
    bool all_spanning = true;
    for (const auto& [f, q] : cand) all_spanning = all_spanning && mesh.face_alive[f];
    if (!all_spanning) return 0;
    for (int f : order) kill_face(f);
    for (std::size_t i = 0; i < particles.size(); ++i)
      if (mesh.vertex_alive[i] && mesh.vfaces[i].empty()) kill_vertex(static_cast<int>(i));
    close_new_holes(surface);
    clear_gap_marks();
    return 1;
  }

  // Gap decision 40: the marks of Steps 1-2 describe the neck that was just cut. Kept, the
  // special springs left on the rims of the closing fans held their shrunken rest length
  // (special_factor R) and could not be split, so each new cap kept a crumpled patch of tiny
  // triangles that folded over (dihedral angles up to 177 deg) a few frames later. After a
  // cut every mark is dropped with its reduced rest length; Step 1 marks again, in the next
  // step, whatever still spans a gap.
  void clear_gap_marks() {
    for (auto& [k, s] : springs) {
      if (s.special) s.rest = R();
      s.special = false;
      s.topo = false;
    }
    any_topo_ = false;
    candidate_steps_ = 0;
  }

  // Closes every hole that is not an original border by a fan to a new particle at its
  // centroid (Newton-projected). A hole whose border is not a simple loop stays open.
  void close_new_holes(const ImplicitSurface& surface) {
    std::unordered_map<int, std::vector<int>> next;  // x -> y of border half-edges x -> y
    // A vertex where two hole borders touch (two outgoing border half-edges) would make the
    // fan non-manifold: remove it with its triangles, widening the hole (at most 8 rounds).
    for (int round = 0; round < 8; ++round) {
      next.clear();
      // Border half-edges: a face has x -> y and no face has y -> x.
      std::unordered_set<std::uint64_t> half;
      for (std::size_t f = 0; f < mesh.tri.size(); ++f)
        if (mesh.face_alive[f])
          for (int k = 0; k < 3; ++k)
            half.insert(directed_edge_key(mesh.tri[f][k], mesh.tri[f][(k + 1) % 3]));
      for (std::uint64_t h : half) {
        const int x = edge_key_first(h), y = edge_key_second(h);
        if (half.count(directed_edge_key(y, x))) continue;
        if (particles[x].boundary && particles[y].boundary) continue;  // an original border (scan)
        next[x].push_back(y);
      }
      std::vector<int> pinched;
      for (const auto& [x, ys] : next)
        if (ys.size() > 1 && !particles[x].boundary) pinched.push_back(x);
      if (pinched.empty()) break;
      std::sort(pinched.begin(), pinched.end());
      for (int v : pinched) {
        const std::vector<int> around = mesh.vfaces[v];
        for (int f : around)
          if (mesh.face_alive[f]) kill_face(f);
        kill_vertex(v);
      }
      for (std::size_t i = 0; i < particles.size(); ++i)
        if (mesh.vertex_alive[i] && mesh.vfaces[i].empty()) kill_vertex(static_cast<int>(i));
    }
    std::vector<int> starts;
    for (const auto& [x, ys] : next) starts.push_back(x);
    std::sort(starts.begin(), starts.end());
    std::unordered_set<int> used;
    for (int x0 : starts) {
      if (used.count(x0)) continue;
      std::vector<int> loop;
      int x = x0;
      bool simple = true;
      while (true) {
        const auto it = next.find(x);
        if (it == next.end() || it->second.size() != 1 || used.count(x)) {
          simple = false;
          break;
        }
        used.insert(x);
        loop.push_back(x);
        x = it->second.front();
        if (x == x0) break;
      }
      if (!simple || loop.size() < 3) continue;  // left open (reported by the mesh checks)
      Vector3d c = Vector3d::Zero();
      for (int v : loop) c += P(v);
      c /= static_cast<double>(loop.size());
      if (const auto q = project_to_surface(surface, c, 5); q && (*q - c).norm() < 2.0 * R())
        c = *q;
      const int centre = add_vertex(c);
      for (std::size_t k = 0; k < loop.size(); ++k)
        add_face(loop[(k + 1) % loop.size()], loop[k], centre);
    }
    for (std::size_t i = 0; i < particles.size(); ++i)
      if (mesh.vertex_alive[i] && mesh.vfaces[i].empty()) kill_vertex(static_cast<int>(i));
    rebuild_springs();
  }

  // §4.4 names a second sub-problem, "removing triangles whose vertices no longer lie on the
  // surface", without an algorithm. Gap: a particle farther than R from F = 0 (first-order
  // distance |F|/|grad F|; a vanishing gradient with F > 0 means it sits in the empty gap
  // between separated parts) is removed with its triangles, and every hole this opens is
  // closed by a fan to a new particle at the hole's centroid, as in the ring cut.
  int remove_lost_particles(const ImplicitSurface& surface) {
    // Patience as for the ring (§4.4 Step 3 usually removes such particles with its ring):
    // only a particle that stays lost is removed here.
    const std::vector<int> lost = lost_for_longer_than_patience([&](const Particle& v) {
      if (v.boundary || !v.defined) return false;
      const double g = v.f.gradient.norm();
      return g < 1e-10 ? v.f.value > 0.0 : std::abs(v.f.value) > R() * g;
    });
    if (lost.empty()) return 0;
    for (int v : lost) {
      const std::vector<int> around = mesh.vfaces[v];
      for (int f : around)
        if (mesh.face_alive[f]) kill_face(f);
    }
    for (int v : lost) kill_vertex(v);
    close_new_holes(surface);
    return static_cast<int>(lost.size());
  }

  // Scan mode (a mesh with borders, decision 43): where the range surface has a hole or a
  // step the grid cannot represent (the underside of the nose: r jumps 17 mm between two rows),
  // F is undefined or its zero set is far from the particles that the start mesh put across
  // the gap. Such particles can never settle, and the springs of their neighbours, pulled
  // across the gap, split again and again. A particle that stays lost (F undefined, or farther
  // than R from F = 0 to first order) for more than `ring_patience` steps is removed with its
  // triangles, and the hole stays open: it is a border of the data, not of the object.
  int open_holes_at_lost_particles() {
    const std::vector<int> lost = lost_for_longer_than_patience(
        [&](const Particle& v) { return !v.defined || farther_than_R(v.f); });
    if (lost.empty()) return 0;
    std::vector<int> doomed;
    for (int v : lost) doomed.insert(doomed.end(), mesh.vfaces[v].begin(), mesh.vfaces[v].end());
    std::sort(doomed.begin(), doomed.end());
    doomed.erase(std::unique(doomed.begin(), doomed.end()), doomed.end());
    std::vector<int> rim;
    for (int f : doomed) rim.insert(rim.end(), mesh.tri[f].begin(), mesh.tri[f].end());
    drop_faces(doomed);
    for (int v : lost)
      if (mesh.vertex_alive[v]) kill_vertex(v);
    separate_wedges(std::move(rim));
    rebuild_springs();
    return static_cast<int>(lost.size());
  }
  // Counts, per alive particle, the consecutive steps `lost_now` holds; returns the particles
  // it has held for more than `ring_patience` steps.
  template <class Lost>
  std::vector<int> lost_for_longer_than_patience(Lost&& lost_now) {
    std::vector<int> lost;
    lost_steps_.resize(particles.size(), 0);
    for (std::size_t i = 0; i < particles.size(); ++i) {
      if (!mesh.vertex_alive[i]) continue;
      lost_steps_[i] = lost_now(particles[i]) ? lost_steps_[i] + 1 : 0;
      if (lost_steps_[i] > o.ring_patience) lost.push_back(static_cast<int>(i));
    }
    return lost;
  }
  // First-order distance |F| / |grad F| beyond R (a vanishing gradient counts as far).
  bool farther_than_R(const ImplicitValue& f) const {
    const double g = f.gradient.norm();
    return g < 1e-10 || std::abs(f.value) > R() * g;
  }
  // A particle of `touched` whose triangles form several wedges (joined only at the particle:
  // a bow-tie left where faces were dropped) keeps its largest wedge; the others' faces are
  // dropped, and their corners are checked in turn (dropping faces can make new bow-ties).
  void separate_wedges(std::vector<int> touched) {
    while (!touched.empty()) {
      const int v = touched.back();
      touched.pop_back();
      if (!mesh.vertex_alive[v] || mesh.vfaces[v].size() < 2) continue;
      const std::vector<int> doomed = kernel::faces_off_largest_wedge(mesh.tri, mesh.vfaces[v], v);
      for (int f : doomed) touched.insert(touched.end(), mesh.tri[f].begin(), mesh.tri[f].end());
      drop_faces(doomed);
    }
  }
  // Every particle keeps only its largest wedge of faces.
  void make_vertex_manifold() {
    const std::size_t before = dead_faces();
    std::vector<int> all;
    for (std::size_t i = 0; i < particles.size(); ++i)
      if (mesh.vertex_alive[i]) all.push_back(static_cast<int>(i));
    separate_wedges(std::move(all));
    if (dead_faces() != before) rebuild_springs();
  }
  bool cut_ring(const std::vector<int>& ring,
                const std::unordered_map<int, std::array<int, 3>>& cand,
                const ImplicitSurface& surface) {
    const std::unordered_set<int> in_ring(ring.begin(), ring.end());
    // The third (non-qualifying) edge of each ring triangle borders the hole after the cut.
    struct Border {
      int x, y;  // direction in the triangle outside the ring
    };
    std::vector<Border> border;
    for (int f : ring) {
      const auto& t = mesh.tri[f];
      const auto& q = cand.at(f);
      for (int k = 0; k < 3; ++k) {
        if (q[k]) continue;
        const int u = t[k], v = t[(k + 1) % 3];
        const auto ef = edge_faces(u, v);
        if (ef.size() != 2) return false;
        const int other = ef[0] == f ? ef[1] : ef[0];
        if (in_ring.count(other)) return false;
        border.push_back(mesh.traverses(other, u, v) ? Border{u, v} : Border{v, u});
      }
    }
    // Group the border edges into loops: exactly two, each simple with >= 3 edges.
    std::unordered_map<int, std::vector<int>> incident;
    for (std::size_t e = 0; e < border.size(); ++e) {
      incident[border[e].x].push_back(static_cast<int>(e));
      incident[border[e].y].push_back(static_cast<int>(e));
    }
    for (const auto& [v, es] : incident)
      if (es.size() != 2) return false;
    std::vector<int> loop_of(border.size(), -1);
    int loops = 0;
    for (std::size_t e0 = 0; e0 < border.size(); ++e0) {
      if (loop_of[e0] >= 0) continue;
      std::vector<int> stack{static_cast<int>(e0)};
      loop_of[e0] = loops;
      while (!stack.empty()) {
        const int e = stack.back();
        stack.pop_back();
        for (int v : {border[e].x, border[e].y})
          for (int e2 : incident[v])
            if (loop_of[e2] < 0) loop_of[e2] = loops, stack.push_back(e2);
      }
      ++loops;
    }
    if (loops != 2) return false;
    std::array<int, 2> loop_size{0, 0};
    std::array<Vector3d, 2> centroid{Vector3d::Zero(), Vector3d::Zero()};
    for (std::size_t e = 0; e < border.size(); ++e) {
      ++loop_size[loop_of[e]];
      centroid[loop_of[e]] += P(border[e].x);  // each loop vertex is the tail of one edge
    }
    if (loop_size[0] < 3 || loop_size[1] < 3) return false;
    // Cut: drop the ring, insert one particle per side "in the middle of the hole" (Gap: at
    // the loop centroid, Newton-projected, not at the cut midpoints in the gap) and close
    // each hole with a fan (Bild 4d).
    std::unordered_set<int> ring_vertices;
    for (int f : ring)
      for (int v : mesh.tri[f]) ring_vertices.insert(v);
    for (int f : ring) kill_face(f);
    std::array<int, 2> centre{};
    for (int l = 0; l < 2; ++l) {
      Vector3d c = centroid[l] / loop_size[l];
      if (const auto q = project_to_surface(surface, c, 5); q && (*q - c).norm() < 2.0 * R())
        c = *q;
      centre[l] = add_vertex(c);
    }
    for (std::size_t e = 0; e < border.size(); ++e)
      add_face(border[e].y, border[e].x, centre[loop_of[e]]);
    for (int v : ring_vertices)
      if (mesh.vertex_alive[v] && mesh.vfaces[v].empty()) kill_vertex(v);
    return true;
  }

  // ---- One step() of the network, in its order (defined next to SpringNetwork::step) ------
  struct StepCandidates {
    std::vector<std::uint64_t> special_short;    // §4.4 Step 2
    std::vector<std::uint64_t> rule_candidates;  // Rules 1-2
  };
  void start_step(const ImplicitSurface& surface);
  double stable_time_step() const;
  void mark_topology_change(const ImplicitSurface& surface, StepReport& rep);
  std::vector<Vector3d> spring_forces() const;
  std::unordered_map<int, Vector3d> border_slide_directions() const;
  void move_particles(const std::vector<Vector3d>& force,
                      const std::unordered_map<int, Vector3d>& border_dir, double dt,
                      double surface_time_step, StepReport& rep);
  Vector3d driving_force(std::size_t i, const std::vector<Vector3d>& force,
                         const std::unordered_map<int, Vector3d>& border_dir) const;
  void keep_triangles_unturned(int i, const Vector3d& g, double g2, Vector3d& move) const;
  static void damp_reversing_move(Particle& v, Vector3d& move);
  StepCandidates step_candidates() const;
  void collapse_short_special_springs(const std::vector<std::uint64_t>& special_short,
                                      StepReport& rep);
  void collapse_or_split_springs(const std::vector<std::uint64_t>& rule_candidates,
                                 const ImplicitSurface& surface, StepReport& rep);
  void flip_unmarked_springs(StepReport& rep);
  void remove_valence_three_particles(StepReport& rep);
  void cut_qualifying_rings(const ImplicitSurface& surface, StepReport& rep);
  void drop_lost_particles(const ImplicitSurface& surface, StepReport& rep);
  void store_old_lengths();
};

SpringNetwork::SpringNetwork(const Mesh& start, const ParticleOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.o = options;
  validate_options(options);
  start.validate();
  for (const auto& p : start.positions) m.add_vertex(p);
  for (const auto& t : start.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw InvalidInputError("particles: degenerate start triangle");
    m.add_face(t[0], t[1], t[2]);
  }
  // Every edge: at most two faces, traversed in opposite directions.
  std::unordered_map<std::uint64_t, int> count;
  for (const auto& t : start.triangles)
    for (int k = 0; k < 3; ++k) ++count[directed_edge_key(t[k], t[(k + 1) % 3])];
  for (const auto& [k, n] : count) {
    const int a = edge_key_first(k), b = edge_key_second(k);
    if (n > 1) throw InvalidInputError("particles: start mesh is not consistently oriented");
    if (!count.count(directed_edge_key(b, a)))
      m.particles[a].boundary = m.particles[b].boundary = true;
  }
  for (std::size_t v = 0; v < m.particles.size(); ++v) {
    if (m.mesh.vfaces[v].empty()) m.kill_vertex(static_cast<int>(v));
    m.has_border_ = m.has_border_ || (m.mesh.vertex_alive[v] && m.particles[v].boundary);
  }
  m.rebuild_springs();
}

SpringNetwork::~SpringNetwork() = default;
SpringNetwork::SpringNetwork(SpringNetwork&&) noexcept = default;
SpringNetwork& SpringNetwork::operator=(SpringNetwork&&) noexcept = default;

// ---- SpringNetwork::step and its parts, in the order step() runs them ---------------------

// Counts the step, compacts storage that is more than half dead and evaluates F everywhere.
void SpringNetwork::Impl::start_step(const ImplicitSurface& surface) {
  ++iter;
  const std::size_t dead_vertices = mesh.pos.size() - static_cast<std::size_t>(mesh.vertex_count());
  if (dead_faces() > mesh.tri.size() / 2 || dead_vertices > mesh.pos.size() / 2) compact();
  evaluate_all(surface);
}

// Time step: the explicit Euler step stays non-oscillating for the stiffest local mode of
// eq. (12) (stiffness ~ rho * valence), so dt = factor / (rho * max valence).
double SpringNetwork::Impl::stable_time_step() const {
  std::size_t max_valence = 6;
  for (std::size_t v = 0; v < mesh.pos.size(); ++v)
    if (mesh.vertex_alive[v]) max_valence = std::max(max_valence, mesh.vfaces[v].size());
  return o.time_step_factor / (o.rho * static_cast<double>(max_valence));
}

// §4.4 Steps 1-2: marks the springs across a gap of F (with their special springs), then
// constricts the special springs.
void SpringNetwork::Impl::mark_topology_change(const ImplicitSurface& surface, StepReport& rep) {
  rep.new_topology_marks = mark_gap_springs(surface);
  // Step 2: special springs shrink gradually towards special_factor * R_e (the report
  // gives no rate; a sudden drop would make eq. 12 explode).
  for (auto& [k, s] : springs)
    if (s.special) s.rest = std::max(o.special_factor * R(), 0.7 * s.rest);
}

// Eq. (12)-(13): P_i = sum_j r_ij rho (R_e - |r_ij|) / R_e over the one-ring.
std::vector<Vector3d> SpringNetwork::Impl::spring_forces() const {
  std::vector<Vector3d> force(particles.size(), Vector3d::Zero());
  for (const auto& [k, s] : springs) {
    const int a = edge_key_first(k), b = edge_key_second(k);
    const Vector3d r = P(a) - P(b);
    const double l = r.norm();
    // Eq. (12) with an optional stiffening for moderate strains (an addition,
    // docs/particles.md): S = rho x (1 + min(k x^2, 1/3)), x = (R_e - |r|) / R_e. It spreads the
    // strain around valence defects more evenly; the cap keeps the tangent stiffness <= 2x
    // eq. (12)'s, within the explicit Euler bound of the time step.
    const double x = (s.rest - l) / s.rest;
    const double sij = o.rho * x * (1.0 + std::min(o.spring_stiffening * x * x, 1.0 / 3.0));
    force[a] += sij * r;
    force[b] -= sij * r;
  }
  return force;
}

// Border particles (scan mode) slide along their border: the spring force is reduced to its
// component along the chord of the two border neighbours (decision 19).
std::unordered_map<int, Vector3d> SpringNetwork::Impl::border_slide_directions() const {
  std::unordered_map<int, Vector3d> border_dir;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (!mesh.vertex_alive[i] || !particles[i].boundary) continue;
    std::vector<int> ends;
    for (int x : neighbors(static_cast<int>(i)))
      if (edge_faces(static_cast<int>(i), x).size() == 1) ends.push_back(x);
    if (ends.size() != 2) continue;
    const Vector3d d = P(ends[1]) - P(ends[0]);
    if (d.norm() > 0.0) border_dir.emplace(static_cast<int>(i), d.normalized());
  }
  return border_dir;
}

// Eq. (8) and (11): constraint velocity with feedback phi; phi * dt = 1 (one Newton step).
void SpringNetwork::Impl::move_particles(const std::vector<Vector3d>& force,
                                         const std::unordered_map<int, Vector3d>& border_dir,
                                         double dt, double surface_time_step, StepReport& rep) {
  const double cap = o.max_step * R();
  for (std::size_t i = 0; i < particles.size(); ++i) {
    Particle& v = particles[i];
    // Gap: a particle where F is undefined waits (in scan mode, for ring_patience steps;
    // then it is removed, decision 43).
    if (!mesh.vertex_alive[i] || !v.defined) continue;
    const Vector3d g = v.f.gradient;
    const double g2 = g.squaredNorm();
    const Vector3d p_target = driving_force(i, force, border_dir);
    Vector3d move = dt * p_target;
    if (g2 > 1e-20) {
      rep.max_constraint = std::max(rep.max_constraint, std::abs(v.f.value) / std::sqrt(g2));
      const Vector3d tangential = dt * (p_target - g.dot(p_target) / g2 * g);
      rep.max_tangential_move = std::max(rep.max_tangential_move, tangential.norm());
      move = tangential - (v.f.dvalue_dt * surface_time_step + v.f.value) / g2 * g;
    }
    const double len = move.norm();
    if (len > cap) move *= cap / len;
    keep_triangles_unturned(static_cast<int>(i), g, g2, move);
    if (calming_) damp_reversing_move(v, move);
    mesh.pos[i] += move;
  }
}

// The spring force on particle i that drives its move: along the border chord for a border
// particle, none for a settled one.
Vector3d SpringNetwork::Impl::driving_force(
    std::size_t i, const std::vector<Vector3d>& force,
    const std::unordered_map<int, Vector3d>& border_dir) const {
  const Particle& v = particles[i];
  // Decision 44: in calming, a particle the untangling had to move back again and again
  // (a rough surface whose gradient turns within a spring's length: the springs push it
  // into a turned position, the untangling takes it out) keeps only the constraint part.
  const bool settled = calming_ && v.untangled >= kUntanglesBeforeSettling;
  Vector3d p_target = v.boundary || settled ? Vector3d::Zero() : force[i];
  if (v.boundary)
    if (const auto it = border_dir.find(static_cast<int>(i)); it != border_dir.end())
      p_target = force[i].dot(it->second) * it->second;
  return p_target;
}

// Gap decisions 35 and 39: a move may not turn one of the particle's triangles over
// (normal against the outward gradient). At a border (scan mode) the border is free on
// one side, so nothing else stops a particle next to it from crossing a border edge; in
// the interior, the explicit Euler step plus the constraint's projection turned a few
// triangles over where the surface moves fast (the caps of two blobs pulled apart:
// 16-34 crossing face pairs per frame), and nothing turned them back.
void SpringNetwork::Impl::keep_triangles_unturned(int i, const Vector3d& g, double g2,
                                                  Vector3d& move) const {
  if (g2 > 1e-20 && !keeps_orientation(i, P(i) + move, g)) {
    Vector3d tangential = move - g.dot(move) / g2 * g;
    const Vector3d normal_part = move - tangential;
    move = Vector3d::Zero();
    for (int h = 0; h < 4; ++h, tangential *= 0.5)
      if (keeps_orientation(i, P(i) + normal_part + tangential, g)) {
        move = normal_part + tangential;
        break;
      }
  }
}

// Decision 44: a move that turns back on the previous one (a 2-cycle of the Newton step
// between two bumps of a rough surface) is damped, more each time it happens again.
void SpringNetwork::Impl::damp_reversing_move(Particle& v, Vector3d& move) {
  const bool reverses = move.dot(v.last_move) < -0.5 * move.norm() * v.last_move.norm();
  v.damping = reverses ? std::max(v.damping * 0.5, 1.0 / 64) : std::min(1.0, v.damping * 1.25);
  v.last_move = move;
  move *= v.damping;
}

// Candidates of Step 2 and Rules 1-2 from one sequential pass over the springs (a spring
// whose length an operation of this step changes is marked by it, so nothing is missed
// that Rule 3 would not block anyway), processed in key order.
SpringNetwork::Impl::StepCandidates SpringNetwork::Impl::step_candidates() const {
  std::vector<std::uint64_t> special_short, rule_candidates;
  for (const auto& [k, s] : springs) {
    const double l = length(edge_key_first(k), edge_key_second(k));
    if (s.special && l < o.special_min_length * R()) special_short.push_back(k);
    if (l < o.d_min * s.rest || (l > o.d_max * s.rest && !s.topo && !s.special))
      rule_candidates.push_back(k);
  }
  std::sort(special_short.begin(), special_short.end());
  std::sort(rule_candidates.begin(), rule_candidates.end());
  return {std::move(special_short), std::move(rule_candidates)};
}

// §4.4 Step 2: special springs that became short are removed (collapsed, Rule 1).
void SpringNetwork::Impl::collapse_short_special_springs(
    const std::vector<std::uint64_t>& special_short, StepReport& rep) {
  for (std::uint64_t k : special_short) {
    const auto it = springs.find(k);
    if (it == springs.end() || !it->second.special) continue;
    const int a = edge_key_first(k), b = edge_key_second(k);
    if (!mesh.vertex_alive[a] || !mesh.vertex_alive[b]) continue;
    if (length(a, b) < o.special_min_length * R() && try_collapse(a, b)) ++rep.special_collapses;
  }
}

// Rules 1-4: collapse (14) / split (15) settled (16), unmarked (Rule 3) springs.
void SpringNetwork::Impl::collapse_or_split_springs(
    const std::vector<std::uint64_t>& rule_candidates, const ImplicitSurface& surface,
    StepReport& rep) {
  for (std::uint64_t k : rule_candidates) {
    const auto it = springs.find(k);
    if (it == springs.end()) continue;
    const Spring s = it->second;
    const int a = edge_key_first(k), b = edge_key_second(k);
    if (marked(s)) continue;
    const double l = length(a, b);
    if (std::abs(s.old_length - l) > o.moving_epsilon * s.rest) continue;  // still moving
    if (l < o.d_min * s.rest) {
      if (try_collapse(a, b)) ++rep.collapses;
    } else if (l > o.d_max * s.rest && !s.topo && !s.special) {
      if (try_split(a, b, surface)) ++rep.splits;
    }
  }
}

// One valence-improving flip pass over the unmarked, non-topological springs in key order.
void SpringNetwork::Impl::flip_unmarked_springs(StepReport& rep) {
  const std::vector<std::uint64_t> keys = sorted_keys();
  for (std::uint64_t k : keys) {
    const auto it = springs.find(k);
    if (it == springs.end() || marked(it->second) || it->second.topo) continue;
    if (try_flip(edge_key_first(k), edge_key_second(k))) ++rep.flips;
  }
}

// Valence-3 particles cannot be repaired by flips (a flip never lowers the valence of a
// vertex below 4 here); remove them by collapsing their shortest spring.
void SpringNetwork::Impl::remove_valence_three_particles(StepReport& rep) {
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const int v = static_cast<int>(i);
    if (!mesh.vertex_alive[i] || particles[i].boundary || mesh.vfaces[i].size() != 3) continue;
    auto ring = neighbors(v);
    std::sort(ring.begin(), ring.end(), [&](int x, int y) { return length(v, x) < length(v, y); });
    for (int x : ring) {
      if (marked(spring(v, x))) continue;
      if (try_collapse(v, x)) {
        ++rep.collapses;
        break;
      }
    }
  }
}

// §4.4 Step 3 on freshly evaluated particles; a fallback cut (a persisting band removed
// wholesale) is reported apart from the clean ring cuts.
void SpringNetwork::Impl::cut_qualifying_rings(const ImplicitSurface& surface, StepReport& rep) {
  evaluate_all(surface);
  const int before = fallback_cuts_;
  const int c = cut_rings(surface);
  if (fallback_cuts_ > before)
    rep.fallback_cuts += c;
  else
    rep.cuts += c;
}

// Particles that stay lost: removed and their holes closed by fans (topology change, decision
// 25), or, in scan mode, removed and their holes left open (decision 43).
void SpringNetwork::Impl::drop_lost_particles(const ImplicitSurface& surface, StepReport& rep) {
  if (o.topology_change && any_topo_ && remove_lost_particles(surface) > 0) ++rep.fallback_cuts;
  if (!o.topology_change && has_border_ && open_holes_at_lost_particles() > 0) ++rep.fallback_cuts;
}

// |r|_alt of eq. (16) for the next step's "still moving" test.
void SpringNetwork::Impl::store_old_lengths() {
  for (auto& [k, s] : springs) s.old_length = length(edge_key_first(k), edge_key_second(k));
}

StepReport SpringNetwork::step(const ImplicitSurface& surface, double surface_time_step) {
  Impl& m = *impl_;
  const ParticleOptions& o = m.o;
  StepReport rep;
  m.start_step(surface);
  const double dt = m.stable_time_step();
  rep.time_step = dt;

  if (o.adaptive) m.adapt_rest_lengths();
  if (o.topology_change) m.mark_topology_change(surface, rep);

  const std::vector<Vector3d> force = m.spring_forces();
  const std::unordered_map<int, Vector3d> border_dir = m.border_slide_directions();
  m.move_particles(force, border_dir, dt, surface_time_step, rep);

  m.untangle_turned_faces(surface);

  Impl::StepCandidates candidates = m.step_candidates();
  if (o.topology_change) m.collapse_short_special_springs(candidates.special_short, rep);

  if (m.rules_frozen_) candidates.rule_candidates.clear();
  m.collapse_or_split_springs(candidates.rule_candidates, surface, rep);

  // Flips depend on valences (and, weakly, on angles): a pass after a step that changed
  // nothing is repeated only every 10th step.
  if (o.flips && (m.last_changed_ || rep.changed() || m.iter % 10 == 0))
    m.flip_unmarked_springs(rep);

  if (o.flips) m.remove_valence_three_particles(rep);
  if (o.topology_change && m.any_topo_) m.cut_qualifying_rings(surface, rep);

  m.drop_lost_particles(surface, rep);
  if (rep.cuts + rep.fallback_cuts > 0) {
    m.evaluate_all(surface);
    m.untangle_turned_faces(surface);
  }

  m.store_old_lengths();
  m.last_changed_ = rep.changed();
  return rep;
}

int SpringNetwork::relax(const ImplicitSurface& surface, std::size_t target_vertices) {
  Impl& m = *impl_;
  int quiet = 0, n = 0, rounds = 0, glide_rounds = 0;
  m.converged = false;
  // A surface frozen in time cannot tear: §4.4 answers a surface that splits while it moves.
  // On a static surface its tests fire at concave creases instead (a union of objects:
  // neighbouring particles on two objects have gradients > 90 deg apart across the crease)
  // and keep collapsing there, so relax() runs without topology change (restored after).
  const bool topology_change = m.o.topology_change;
  const bool flips = m.o.flips;
  m.o.topology_change = false;
  for (Particle& v : m.particles) v.reset_calming();
  m.lost_steps_.clear();
  // Isotropic remeshing rounds first (an addition, docs/particles.md): they bring the start
  // mesh near the spring equilibrium in a few sweeps, which explicit Euler needs hundreds of
  // steps for. Stop early once a round changes nothing.
  for (int k = 0; k < m.o.remesh_rounds; ++k)
    if (m.remesh_round(surface) == 0 && k >= 2) break;
  // Converged: 10 steps without a mesh change in which no particle moved farther than
  // 10 x tolerance x R in total. The net displacement (not the per-step move) is measured so a
  // particle on a crease of F (C0, e.g. a union), whose gradient and hence tangent plane
  // alternate between the two sides, settles into a 2-cycle that counts as converged.
  std::vector<Vector3d> window;
  for (; n < m.o.max_iterations; ++n) {
    if (quiet == 0) {
      window.resize(m.particles.size());
      for (std::size_t i = 0; i < m.particles.size(); ++i) window[i] = m.mesh.pos[i];
    }
    // Freeze the flips after `flip_freeze` steps (decision 34): on scans the flips and the
    // collapses of Rule 1 kept undoing each other somewhere (never converged in 3,000 steps).
    // Scan mode also calms what still cycles from then on, and stops Rules 1-2 at twice that
    // (decision 44).
    if (m.o.flip_freeze > 0 && n == m.o.flip_freeze) {
      m.o.flips = false;
      m.calming_ = m.has_border_;
    }
    if (m.o.flip_freeze > 0 && n == 2 * m.o.flip_freeze) m.rules_frozen_ = m.has_border_;
    if (m.o.progress && n % 10 == 0) m.o.progress(n, m.o.max_iterations);
    const StepReport r = step(surface);
    if (r.changed() || m.particles.size() != window.size()) {
      quiet = 0;
      continue;
    }
    if (++quiet < 10) continue;
    double moved = 0.0;
    for (std::size_t i = 0; i < m.particles.size(); ++i)
      if (m.mesh.vertex_alive[i]) moved = std::max(moved, (m.mesh.pos[i] - window[i]).norm());
    if (moved >= 10.0 * m.o.convergence_tolerance * m.o.edge_length) {
      quiet = 0;
      continue;
    }
    // Converged: cancel dislocations (decision 33), then correct a uniform compression or
    // stretch (at most 8 rounds each), else stop.
    if (m.o.flips && glide_rounds < 8 && m.remove_dislocations(m.o.max_glide) > 0) {
      ++glide_rounds;
      quiet = 0;
      continue;
    }
    // The subdivided start asks for a count (a coarse particle becomes about n^2 fine ones;
    // decision 37); otherwise the mean stretch decides.
    const long missing = target_vertices > 0 ? static_cast<long>(target_vertices) -
                                                   static_cast<long>(m.alive_count())
                                             : 0;
    const double s = m.mean_stretch();
    const bool correct =
        target_vertices > 0 ? missing != 0 : std::abs(s - 1.0) > m.o.density_tolerance;
    if (correct && rounds < 8 &&
        (target_vertices > 0 ? m.change_count(static_cast<int>(missing), surface)
                             : m.rebalance(s, surface)) > 0) {
      ++rounds;
      quiet = 0;
      continue;
    }
    ++n;
    m.converged = true;
    break;
  }
  m.o.topology_change = topology_change;
  m.o.flips = flips;
  m.calming_ = false;
  m.rules_frozen_ = false;
  project(surface);
  // Scan mode (a mesh with borders): no triangle may stay turned over at a border, and no
  // particle may join two wedges of faces (a bow-tie at a border: 3 on the 128 x 128 head;
  // where they come from is not traced; decision 43).
  if (m.has_border_) {
    m.drop_turned_border_faces(surface);
    m.make_vertex_manifold();
  }
  return n;
}

void SpringNetwork::spread_evenly(const ImplicitSurface& surface, int iterations) {
  impl_->spread_particles(surface, iterations);
  project(surface);
}

void SpringNetwork::project(const ImplicitSurface& surface) {
  Impl& m = *impl_;
#pragma omp parallel for schedule(static) if (m.particles.size() > 20000)
  for (std::size_t i = 0; i < m.particles.size(); ++i) {
    if (!m.mesh.vertex_alive[i]) continue;
    Vector3d& p = m.mesh.pos[i];
    if (const auto q = project_to_surface(surface, p, 20, 1e-13);
        q && (*q - p).norm() < m.o.edge_length)
      p = *q;
  }
  for (auto& [k, s] : m.springs) s.old_length = m.length(edge_key_first(k), edge_key_second(k));
}

Mesh SpringNetwork::mesh() const {
  Mesh out = impl_->mesh.to_mesh();
  out.face_labels.clear();  // the network has no regions
  return out;
}

std::vector<std::uint64_t> SpringNetwork::vertex_ids() const {
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < impl_->particles.size(); ++i)
    if (impl_->mesh.vertex_alive[i]) ids.push_back(impl_->particles[i].id);
  return ids;
}

std::size_t SpringNetwork::vertex_count() const { return impl_->alive_count(); }

int SpringNetwork::iteration() const { return impl_->iter; }
bool SpringNetwork::converged() const { return impl_->converged; }

namespace {

// The options of a coarse level, which is subdivided and relaxed again: it need not settle as
// tightly, and the progress display follows the final level.
ParticleOptions coarse_level(const ParticleOptions& options, double edge_length) {
  ParticleOptions coarse = options;
  coarse.edge_length = edge_length;
  coarse.max_iterations = std::min(options.max_iterations, 600);
  coarse.convergence_tolerance = std::max(options.convergence_tolerance, 1e-2);
  coarse.progress = nullptr;
  return coarse;
}

// 1:4 subdivision; the edge midpoints are Newton-projected onto the surface. Every new
// vertex has valence 6, so the valence defects of the coarse mesh are all the fine mesh has.
Mesh subdivide(const Mesh& m, const ImplicitSurface& surface) {
  Mesh out;
  out.positions = m.positions;
  std::unordered_map<std::uint64_t, int> mid;
  auto midpoint = [&](int a, int b) {
    const std::uint64_t k = edge_key(a, b);
    if (const auto it = mid.find(k); it != mid.end()) return it->second;
    Vector3d p = 0.5 * (m.positions[a] + m.positions[b]);
    const double len = (m.positions[a] - m.positions[b]).norm();
    if (const auto q = project_to_surface(surface, p, 8); q && (*q - p).norm() < 0.5 * len) p = *q;
    out.positions.push_back(p);
    const int v = static_cast<int>(out.positions.size()) - 1;
    mid.emplace(k, v);
    return v;
  };
  for (const auto& t : m.triangles) {
    const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
    out.triangles.push_back({t[0], ab, ca});
    out.triangles.push_back({ab, t[1], bc});
    out.triangles.push_back({ca, bc, t[2]});
    out.triangles.push_back({ab, bc, ca});
  }
  return out;
}

// Particles a closed mesh of near-equilateral triangles with edge `edge` needs on `area`:
// F = 2 (V - chi) triangles of sqrt(3)/4 edge^2 each.
double particles_for_area(double area, double edge, long long chi) {
  return area / (std::sqrt(3.0) / 2.0 * edge * edge) + static_cast<double>(chi);
}

// Closed like the reference: no border or non-manifold edge, the same Euler characteristic
// and as many components.
bool closed_like(const TopologyStats& s, const TopologyStats& reference) {
  return s.boundary_edges == 0 && s.nonmanifold_edges == 0 &&
         s.euler_characteristic == reference.euler_characteristic &&
         s.components == reference.components;
}

// The network's mesh, when it converged closed like the reference.
std::optional<Mesh> mesh_if_closed_like(const SpringNetwork& net, const TopologyStats& reference) {
  if (!net.converged()) return std::nullopt;
  Mesh mesh = net.mesh();
  if (!closed_like(topology_stats(mesh), reference)) return std::nullopt;
  return mesh;
}

// Every edge length of a closed mesh (each edge twice, once per face).
template <class F>
void for_each_edge_length(const Mesh& m, F&& f) {
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) f((m.positions[t[k]] - m.positions[t[(k + 1) % 3]]).norm());
}

// The layered start: marching tetrahedra at 2^k R relaxed and subdivided 1:4 level by level.
SpringNetwork layered_network(const ImplicitSurface& surface, const ParticleOptions& options,
                              const Mesh& fine, int* iterations) {
  // Gap decision: the multilevel start needs a closed mesh; surfaces with borders (scans)
  // start from the fine marching-tetrahedra mesh.
  const double R = options.edge_length;
  // Multilevel start (docs/particles.md): the coarsest level 2^k R whose marching-tetrahedra
  // mesh has the fine one's topology (closed, same components and Euler characteristic) and
  // enough vertices is relaxed, then subdivided 1:4 and relaxed again at half the length.
  const TopologyStats fine_stats = topology_stats(fine);
  int level = 0;
  Mesh start = fine;
  if (fine_stats.boundary_edges == 0)
    for (int k = options.max_levels; k >= 1; --k) {
      const Mesh coarse = marching_tetrahedra(surface, options.start_spacing * R * (1 << k));
      if (coarse.triangles.empty()) continue;
      if (!closed_like(topology_stats(coarse), fine_stats) ||
          coarse.vertex_count() < 150u * fine_stats.components)
        continue;
      level = k;
      start = coarse;
      break;
    }
  int total = 0;
  for (; level > 0; --level) {
    ParticleOptions coarse = coarse_level(options, R * (1 << level));
    coarse.adaptive = false;
    SpringNetwork net(start, coarse);
    total += net.relax(surface);
    const Mesh relaxed = net.mesh();
    if (!net.converged() || !closed_like(topology_stats(relaxed), fine_stats)) {
      start = fine;  // the coarse level did not settle: start again from the fine mesh
      break;
    }
    start = subdivide(relaxed, surface);
    // The subdivided edges are chords of the coarse arcs' halves, a little longer than half
    // the coarse rest length on a curved surface; with a fixed vertex count that stretch would
    // stay. Correct the coarse rest length once by the measured stretch and relax again.
    const double half = 0.5 * coarse.edge_length;
    double sum = 0.0;
    std::size_t count = 0;
    for_each_edge_length(start, [&](double l) { sum += l, ++count; });
    const double stretch = sum / static_cast<double>(std::max<std::size_t>(count, 1)) / half;
    if (std::abs(stretch - 1.0) > 0.01) {
      coarse.edge_length /= stretch;
      // Here the density is the point: correct the coarse count to 1 % (a coarse particle
      // added now becomes 4^level fine ones without new valence defects at the fine level).
      coarse.density_tolerance = std::min(options.density_tolerance, 0.01);
      SpringNetwork again(relaxed, coarse);
      total += again.relax(surface);
      if (const auto mesh = mesh_if_closed_like(again, fine_stats)) start = subdivide(*mesh, surface);
    }
  }
  SpringNetwork net(start, options);
  total += net.relax(surface);
  *iterations += total;
  return net;
}

// 1:n subdivision: every triangle becomes n^2 triangles on the barycentric grid, points
// Newton-projected onto the surface. Only the coarse mesh's vertices keep their valence;
// every new vertex has valence 6.
Mesh subdivide_n(const Mesh& m, int n, const ImplicitSurface& surface) {
  Mesh out;
  out.positions = m.positions;
  auto add_point = [&](const Vector3d& p, double reach) {
    Vector3d q = p;
    if (const auto s = project_to_surface(surface, p, 8); s && (*s - p).norm() < reach) q = *s;
    out.positions.push_back(q);
    return static_cast<int>(out.positions.size()) - 1;
  };
  // Edge points are shared: key (edge, index counted from the lower end).
  std::unordered_map<std::uint64_t, std::vector<int>> edge_points;
  auto edge_point = [&](int a, int b, int i) {
    if (i == 0) return a;
    if (i == n) return b;
    const int lo = std::min(a, b), hi = std::max(a, b), from_lo = a == lo ? i : n - i;
    auto& pts = edge_points[edge_key(lo, hi)];
    if (pts.empty()) {
      const Vector3d p = m.positions[lo], q = m.positions[hi];
      for (int k = 1; k < n; ++k)
        pts.push_back(add_point(p + (q - p) * (static_cast<double>(k) / n), 0.5 * (q - p).norm()));
    }
    return pts[from_lo - 1];
  };
  std::vector<int> id((n + 1) * (n + 1));
  for (const auto& t : m.triangles) {
    const Vector3d a = m.positions[t[0]], ab = m.positions[t[1]] - a, ac = m.positions[t[2]] - a;
    const double reach = 0.5 * std::max({ab.norm(), ac.norm(), (ac - ab).norm()});
    // Grid point (i, j) = a + i/n ab + j/n ac, i + j <= n.
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j)
        id[i * (n + 1) + j] = j == 0       ? edge_point(t[0], t[1], i)
                              : i == 0     ? edge_point(t[0], t[2], j)
                              : i + j == n ? edge_point(t[1], t[2], j)
                                           : add_point(a + ab * (static_cast<double>(i) / n) +
                                                           ac * (static_cast<double>(j) / n),
                                                       reach);
    auto at = [&](int i, int j) { return id[i * (n + 1) + j]; };
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        out.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j + 1 < n) out.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  }
  return out;
}

// Edge lengths against R: (fraction within +-15 %, largest |l / R - 1|).
std::pair<double, double> edge_uniformity(const Mesh& m, double R) {
  std::size_t within = 0, count = 0;
  double worst = 0.0;
  for_each_edge_length(m, [&](double l) {
    const double x = std::abs(l / R - 1.0);
    within += x <= 0.15 ? 1 : 0;
    worst = std::max(worst, x);
    ++count;
  });
  return {count ? static_cast<double>(within) / static_cast<double>(count) : 0.0, worst};
}

// How far the edges of a 1:n subdivision of `coarse` would stray from R at best: the coarse
// mesh's shortest and longest edge relative to its mean, times the stretch the fine particle
// count leaves (`wanted` particles were asked for).
double handed_down_spread(const Mesh& coarse, int n, double wanted, long long chi) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0, sum = 0.0;
  std::size_t count = 0;
  for_each_edge_length(
      coarse, [&](double l) { lo = std::min(lo, l), hi = std::max(hi, l), sum += l, ++count; });
  const double mean = sum / static_cast<double>(std::max<std::size_t>(count, 1));
  const double fine_count =
      static_cast<double>(n * n) * (static_cast<double>(coarse.vertex_count()) - chi);
  const double stretch = std::sqrt((wanted - static_cast<double>(chi)) / fine_count);
  return std::max(hi / mean * stretch - 1.0, 1.0 - lo / mean * stretch);
}

// A coarse mesh for the subdivided start, to be refined 1:n.
struct CoarseCandidate {
  double score = 0.0;  // handed_down_spread(): smaller is better
  int n = 0;
  Mesh mesh;
};

// The subdivided start (docs/particles.md, decision 37): coarse meshes with V_c particles,
// spread evenly, where V_c and n are chosen so that their 1:n subdivision has the particle
// count R needs: V - chi = n^2 (V_c - chi). For every n from 2 to max_subdivision with
// 12 <= V_c <= max_spread_particles per component, the two counts next to V_c; best first.
// Empty if none keeps the topology.
std::vector<CoarseCandidate> coarse_candidates(const ImplicitSurface& surface,
                                               const ParticleOptions& options, const Mesh& fine,
                                               int* iterations) {
  const TopologyStats fine_stats = topology_stats(fine);
  const int components = static_cast<int>(fine_stats.components);
  const long long chi = fine_stats.euler_characteristic;
  const double R = options.edge_length;
  const double per_component = 12.0 * components;
  std::vector<CoarseCandidate> out;
  // The candidates are coarsened from the marching-tetrahedra mesh at twice the spacing when
  // it has the fine one's topology (relaxing the fine mesh to 2 R cost most of this search).
  Mesh source = marching_tetrahedra(surface, options.start_spacing * 2.0 * R);
  if (source.triangles.empty() || !closed_like(topology_stats(source), fine_stats)) source = fine;
  {
    SpringNetwork seed(source, coarse_level(options, 2.0 * R));
    *iterations += seed.relax(surface);
    auto mesh = mesh_if_closed_like(seed, fine_stats);
    if (!mesh) return out;
    source = std::move(*mesh);
  }
  // The area from the seed subdivided once and projected (the marching-tetrahedra mesh's
  // chords miss ~1 % on a sphere at R / radius = 0.2; this is within ~0.1 %).
  const double wanted = particles_for_area(surface_area(subdivide(source, surface)), R, chi);
  for (int n = 2; n <= options.max_subdivision; ++n) {
    const double coarse_count =
        (wanted - static_cast<double>(chi)) / (n * n) + static_cast<double>(chi);
    if (std::ceil(coarse_count) < per_component) break;
    if (coarse_count > options.max_spread_particles * components) continue;
    for (const double count : {std::floor(coarse_count), std::ceil(coarse_count)}) {
      if (count < per_component) continue;
      SpringNetwork net(
          source,
          coarse_level(options, R * n * std::sqrt((wanted - chi) / (n * n * (count - chi)))));
      *iterations += net.relax(surface, static_cast<std::size_t>(count));
      net.spread_evenly(surface, 200);
      *iterations += net.relax(surface, static_cast<std::size_t>(count));
      auto mesh = mesh_if_closed_like(net, fine_stats);
      if (!mesh) continue;
      const double score = handed_down_spread(*mesh, n, wanted, chi);
      out.push_back({score, n, std::move(*mesh)});
    }
  }
  std::sort(out.begin(), out.end(),
            [](const CoarseCandidate& a, const CoarseCandidate& b) { return a.score < b.score; });
  return out;
}

}  // namespace

SpringNetwork relaxed_network(const ImplicitSurface& surface, const ParticleOptions& options,
                              int* iterations) {
  validate_options(options);
  const Mesh fine = marching_tetrahedra(surface, options.start_spacing * options.edge_length);
  if (fine.triangles.empty())
    throw InvalidInputError("particles: the surface has no zero crossing inside its bounds");
  int total = 0;
  const TopologyStats fine_stats = topology_stats(fine);
  const bool closed = fine_stats.boundary_edges == 0 && fine_stats.nonmanifold_edges == 0;
  // Decision 37: with uniform rest lengths a closed surface also gets the subdivided start
  // (the best-scored coarse candidates, subdivided and relaxed, until one has every edge
  // within +-15 % of R); the layered start runs only if none has `subdivision_accept` of
  // them. The best mesh by edge-length uniformity wins.
  const auto uniformity = [&](const SpringNetwork& net) {
    return edge_uniformity(net.mesh(), options.edge_length);
  };
  std::optional<SpringNetwork> best;
  std::pair<double, double> best_uniformity{-1.0, 0.0};
  const auto keep_if_better = [&](SpringNetwork&& net) {
    const auto u = uniformity(net);
    if (u.first > best_uniformity.first ||
        (u.first == best_uniformity.first && u.second < best_uniformity.second))
      best_uniformity = u, best = std::move(net);
  };
  const int components = static_cast<int>(fine_stats.components);
  // Spheres (genus 0) only: a coarse mesh of a dozen particles cannot follow a torus' hole
  // (its subdivision did not converge in 3,000 steps).
  const bool spheres = fine_stats.euler_characteristic == 2LL * components;
  if (closed && spheres && !options.adaptive && options.max_subdivision >= 2 &&
      options.subdivision_trials > 0) {
    const auto candidates = coarse_candidates(surface, options, fine, &total);
    for (std::size_t i = 0;
         i < candidates.size() && static_cast<int>(i) < options.subdivision_trials &&
         best_uniformity.first < 1.0;
         ++i) {
      ParticleOptions last = options;
      // Subdivision gave the count (chosen with its stretch in view); split/collapse rounds
      // and the density correction would only add valence defects.
      last.remesh_rounds = 0;
      last.density_tolerance = 1.0;
      // A candidate that does not settle soon is a poor one (the layered start follows).
      last.max_iterations = std::min(options.max_iterations, 500);
      SpringNetwork net(subdivide_n(candidates[i].mesh, candidates[i].n, surface), last);
      total += net.relax(surface);
      if (mesh_if_closed_like(net, fine_stats)) keep_if_better(std::move(net));
    }
  }
  if (!best || best_uniformity.first < options.subdivision_accept) {
    SpringNetwork layered = layered_network(surface, options, fine, &total);
    if (!best || layered.converged()) keep_if_better(std::move(layered));
  }
  if (iterations) *iterations = total;
  return std::move(*best);
}

ParticleMeshResult particle_mesh(const ImplicitSurface& surface, const ParticleOptions& options) {
  ParticleMeshResult r;
  const SpringNetwork net = relaxed_network(surface, options, &r.iterations);
  r.mesh = net.mesh();
  r.vertex_ids = net.vertex_ids();
  r.converged = net.converged();
  return r;
}

}  // namespace scanmesh::particles
