// Stitching the region meshes into one animation mesh, the final 3D Delaunay flips and
// tangential smoothing, and the quality report.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "aft_internal.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/kernel/triangle_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/mesh_topology.h"

namespace scanmesh::aft {

using detail::min_angle;
using detail::wrap_angle;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

// A valence flip may lower a pair's smallest angle to 20 deg (the max-min flips after the
// smoothing take back what does not pay); a smoothing move that makes the star rounder may
// lower its smallest angle to 30 deg, the mark of a good triangle in the quality report.
constexpr double kValenceFlipFloor = 20.0 * M_PI / 180;
constexpr double kSmoothingAngleFloor = 30.0 * M_PI / 180;
// |normal . radial direction| below which a point counts as on a depth-jump wall (on_wall); the
// crossings the post-processing made were all at points below 0.11.
constexpr double kWallRadialness = 0.2;
// Valence flips only where the quad's two triangles, before and after, are within ~20 deg.
const double kValenceFlipFlatness = std::cos(20.0 * M_PI / 180);

// Distance of the midpoint of the chord x-y from the surface (projected from the nodes' mean
// (phi, h)): what a flip to the diagonal x-y would cost in closeness to the surface. (The
// max-min-angle flips do not ask: with "no further than 0.5 mm or the old diagonal" the sample
// head's mesh-to-surface distance fell from 2.58 to 2.46 mm, but 3.2 % of its triangles were
// below 30 deg instead of 2.4 %.)
double chord_gap(const detail::NodeStore& store, const ScanSurface& surface, int x, int y) {
  const Vector3d mid = 0.5 * (store.pos[x] + store.pos[y]);
  const auto pr = surface.project(mid, detail::param_midpoint(store.params[x], store.params[y]));
  return pr ? pr->distance : std::numeric_limits<double>::infinity();
}

// A point on a depth-jump wall of the cylindrical scan (an ear's rim, under the chin): its normal
// is nearly tangential to the cylinder through it, so r(phi, h) is steep there and the (phi, h)
// parameter map squeezes the wall into a thin band.
bool on_wall(const Vector3d& p, const Vector3d& normal) {
  const double rho = std::hypot(p.x(), p.y());
  if (rho <= 0) return true;
  return std::fabs(normal.x() * p.x() + normal.y() * p.y()) < kWallRadialness * rho;
}

// The 3D crossing test of the post-processing's changes on depth-jump walls (on_wall): there a
// flip or a move that passes the local tests (angles, normals) can still cross triangles a ring
// or two away. The triangles are filed by cell at the first question (most regions have no
// wall), and every change after it is filed again (changed()). A caller that puts T or P back
// to an older state calls forget(), since that state may predate the filing.
class WallCrossingGuard {
 public:
  WallCrossingGuard(const std::vector<std::array<int, 3>>& T, const std::vector<Vector3d>& P)
      : T_(T), P_(P) {}
  //! Does triangle f (replacing T's `self` and `also_self`, or -1) cross another triangle of T?
  bool crosses(const std::array<int, 3>& f, int self, int also_self = -1) {
    if (!cells_) {
      cells_.emplace(detail::TriangleCells::cell_size_for(T_, P_));
      for (std::size_t t = 0; t < T_.size(); ++t) cells_->insert(static_cast<int>(t), T_[t], P_);
    }
    return cells_->crosses_any(f, self, T_, P_, also_self);
  }
  //! Triangle t changed (its corners, or their positions).
  void changed(int t) {
    if (cells_) cells_->insert(t, T_[t], P_);
  }
  //! T and P were replaced wholesale: file them afresh at the next question.
  void forget() { cells_.reset(); }

 private:
  const std::vector<std::array<int, 3>>& T_;
  const std::vector<Vector3d>& P_;
  std::optional<detail::TriangleCells> cells_;
};

// The flip passes work on the kernel's mesh over T's triangles; T itself is what the crossing
// guard and the callers read, so every flip is copied back into it.
class FlipPass {
 public:
  FlipPass(std::vector<std::array<int, 3>>& T, const std::vector<Vector3d>& P)
      : T_(T), mesh_(P, T, "animation mesh flips") {}
  const kernel::TriangleMesh& mesh() const { return mesh_; }
  //! The quad of edge `key` if a flip may change it: not a constraint, two faces, and the
  //! other diagonal not an edge already.
  std::optional<kernel::EdgeQuad> flippable(
      std::uint64_t key, const std::unordered_set<std::uint64_t>& constraint) const {
    if (constraint.count(key)) return std::nullopt;
    const auto q = mesh_.quad(edge_key_first(key), edge_key_second(key));
    if (!q || mesh_.edge_face_count(q->a, q->b) > 0) return std::nullopt;
    return q;
  }
  void flip(const kernel::EdgeQuad& q) {
    mesh_.flip(q);
    // The new faces start at the corners the animation meshes' flips have always started them
    // from (put_first says why).
    mesh_.put_first(q.f1, q.a);
    mesh_.put_first(q.f2, q.b);
    T_[q.f1] = mesh_.tri[q.f1];
    T_[q.f2] = mesh_.tri[q.f2];
  }

 private:
  std::vector<std::array<int, 3>>& T_;
  kernel::TriangleMesh mesh_;
};

// The triangle (x, y, z) faces the side its corners' normals point to.
bool faces_out(const std::vector<Vector3d>& P, const std::vector<Vector3d>& normal, int x, int y,
               int z) {
  const Vector3d n = (P[y] - P[x]).cross(P[z] - P[x]);
  const Vector3d m = normal[x] + normal[y] + normal[z];
  return n.dot(m) > 0.05 * n.norm() * m.norm();
}

// The smaller minimum angle of the quad's two triangles before and after its flip.
double min_angle_before(const std::vector<Vector3d>& P, const kernel::EdgeQuad& q) {
  return std::min(min_angle(P[q.v], P[q.w], P[q.a]), min_angle(P[q.w], P[q.v], P[q.b]));
}
double min_angle_after(const std::vector<Vector3d>& P, const kernel::EdgeQuad& q) {
  return std::min(min_angle(P[q.a], P[q.v], P[q.b]), min_angle(P[q.b], P[q.w], P[q.a]));
}

// Edge flips that raise the smaller of the two triangles' minimum angles (max-min in 3D),
// never across a constraint, never producing a triangle that faces away from the surface.
int delaunay_flips(std::vector<std::array<int, 3>>& T, const std::vector<Vector3d>& P,
                   const std::vector<Vector3d>& normal,
                   const std::unordered_set<std::uint64_t>& constraint, WallCrossingGuard& guard) {
  int flips = 0;
  // (The edge map was rebuilt from T for every pass; a flip's outcome does not depend on the
  // order of the two triangles, so keeping it up to date gives the same flips.)
  FlipPass pass_mesh(T, P);
  // The first pass visits every edge; later passes only the edges whose test can now give
  // another answer: the edges of the quads flipped in the pass before, and edges that were
  // refused because their flipped diagonal r-s already existed, once that r-s is flipped away.
  // (The passes re-tested every edge, 0.45 s of 43,000 triangles at a quarter of the sample
  // units.) Not the old order exactly: an edge touched by a flip later in the same pass is
  // re-tested in the next pass, where the full passes re-tested it in the same one; on the
  // sample head and at half and a quarter of its units the meshes have the same triangle counts
  // and angle figures. Key order in every pass, so the result is deterministic.
  std::unordered_map<std::uint64_t, std::vector<std::uint64_t>> blocked_by;
  std::vector<std::uint64_t> keys, dirty;
  keys = pass_mesh.mesh().edges();
  for (int pass = 0; pass < 30; ++pass) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    dirty.clear();
    int pass_flips = 0;
    for (const std::uint64_t key : keys) {
      if (constraint.count(key)) continue;
      const auto f = pass_mesh.mesh().quad(edge_key_first(key), edge_key_second(key));
      if (!f) continue;
      // The quad's corners under the names of the docs: edge a-b, opposite corners r and s.
      const auto [t1, t2, a, b, r, s] = *f;
      if (pass_mesh.mesh().edge_face_count(r, s) > 0) {
        blocked_by[edge_key(r, s)].push_back(key);
        continue;
      }
      if (min_angle_after(P, *f) <= min_angle_before(P, *f) + 1e-6) continue;
      if (!faces_out(P, normal, r, a, s) || !faces_out(P, normal, s, b, r)) continue;
      // On walls a flip that faces out can still cross a triangle beyond the quad (3 crossing
      // pairs at an ear's rim at 0.18 of the sample units).
      if (on_wall(P[a], normal[a]) || on_wall(P[b], normal[b]) || on_wall(P[r], normal[r]) ||
          on_wall(P[s], normal[s])) {
        if (guard.crosses({r, a, s}, t1, t2) || guard.crosses({s, b, r}, t1, t2)) continue;
      }
      pass_mesh.flip(*f);
      guard.changed(t1);
      guard.changed(t2);
      for (const std::uint64_t k :
           {edge_key(r, s), edge_key(a, s), edge_key(s, b), edge_key(b, r), edge_key(r, a)})
        dirty.push_back(k);
      if (const auto bl = blocked_by.find(key); bl != blocked_by.end()) {
        dirty.insert(dirty.end(), bl->second.begin(), bl->second.end());
        blocked_by.erase(bl);
      }
      ++pass_flips;
    }
    flips += pass_flips;
    if (pass_flips == 0) break;
    keys.swap(dirty);
  }
  return flips;
}

// The ideal valence of every vertex: 6 inside the mesh, 1 + round(angle sum / 60 deg) on its
// border (4 at a straight border, 3 at a right-angled corner).
std::vector<int> ideal_valences(const std::vector<std::array<int, 3>>& T,
                                const std::vector<Vector3d>& P, const kernel::TriangleMesh& mesh) {
  std::vector<double> angle_sum(P.size(), 0);
  for (const auto& t : T)
    for (int k = 0; k < 3; ++k) {
      const Vector3d u = P[t[(k + 1) % 3]] - P[t[k]], w = P[t[(k + 2) % 3]] - P[t[k]];
      angle_sum[t[k]] += std::acos(std::clamp(u.dot(w) / (u.norm() * w.norm()), -1.0, 1.0));
    }
  std::vector<char> on_border(P.size(), 0);
  for (const std::uint64_t key : mesh.edges()) {
    const int x = edge_key_first(key), y = edge_key_second(key);
    if (mesh.edge_face_count(x, y) == 1) on_border[x] = on_border[y] = 1;
  }
  std::vector<int> ideal(P.size(), 6);
  for (std::size_t v = 0; v < P.size(); ++v)
    if (on_border[v]) ideal[v] = static_cast<int>(std::lround(angle_sum[v] / (M_PI / 3))) + 1;
  return ideal;
}

// Edge flips towards regular valences, as isotropic remeshers do (Botsch & Kobbelt): a flip is
// taken if it lowers the summed squared deviation of the four corners from their ideal valence
// (ideal_valences; at a segment node in its region's job 4, not 6). The AFT's layers leave ~35 %
// irregular Steiner points and the max-min-angle flips cannot see valence; with the smoothing's
// quality rule below this raised the mean radius ratio at a quarter of the sample units from 0.946
// to 0.960 and lowered the triangles below 30 deg from 0.63 to 0.56 %. A flip may lower the pair's
// smallest angle, but not below `floor_rad` (or the smallest angle before it); the max-min flips
// after the smoothing restore the angles where the valence gain was not worth it.
int valence_flips(std::vector<std::array<int, 3>>& T, const detail::NodeStore& store,
                  const ScanSurface& surface, const std::unordered_set<std::uint64_t>& constraint,
                  double floor_rad, std::vector<char>& flipped_corners, WallCrossingGuard& guard) {
  const std::vector<Vector3d>& P = store.pos;
  flipped_corners.assign(P.size(), 0);
  FlipPass pass_mesh(T, P);
  const std::vector<int> ideal = ideal_valences(T, P, pass_mesh.mesh());
  // Squared deviation of v's valence, changed by d, from its ideal.
  const auto dev = [&](int v, int d) {
    const int x = pass_mesh.mesh().valence(v) + d - ideal[v];
    return x * x;
  };
  const auto unit_normal = [&](int x, int y, int z) {
    return (P[y] - P[x]).cross(P[z] - P[x]).normalized();
  };
  // A few full passes in key order (deterministic); each flip lowers the total deviation, so
  // the passes end; five were enough on the sample head at its units and at a quarter of them.
  int flips = 0;
  for (int pass = 0; pass < 5; ++pass) {
    const std::vector<std::uint64_t> keys = pass_mesh.mesh().edges();  // sorted
    int pass_flips = 0;
    for (const std::uint64_t key : keys) {
      const auto f = pass_mesh.flippable(key, constraint);
      if (!f) continue;
      const auto [t1, t2, a, b, r, s] = *f;  // edge a-b, opposite corners r and s
      if (dev(a, -1) + dev(b, -1) + dev(r, 1) + dev(s, 1) >=
          dev(a, 0) + dev(b, 0) + dev(r, 0) + dev(s, 0))
        continue;
      if (min_angle_after(P, *f) < std::min(min_angle_before(P, *f), floor_rad)) continue;
      if (!faces_out(P, store.normal, r, a, s) || !faces_out(P, store.normal, s, b, r)) continue;
      // Only nearly flat quads: across a crease a valence flip can fold the surface (it made
      // 3 crossing triangle pairs on the sample head at the ear rims without this test), and
      // there the edge is where the shape needs it, not where the valences would like it.
      if (unit_normal(a, b, r).dot(unit_normal(b, a, s)) < kValenceFlipFlatness ||
          unit_normal(r, a, s).dot(unit_normal(s, b, r)) < kValenceFlipFlatness)
        continue;
      // No flip that takes the mesh further from the surface: the new diagonal's midpoint must
      // lie no further from it than the old one's (without this test the sample head's
      // mesh-to-surface Hausdorff distance grew from 2.5 to 3.4 mm, at the ear's rim).
      if (chord_gap(store, surface, r, s) > chord_gap(store, surface, a, b)) continue;
      if (on_wall(P[a], store.normal[a]) || on_wall(P[b], store.normal[b]) ||
          on_wall(P[r], store.normal[r]) || on_wall(P[s], store.normal[s])) {
        if (guard.crosses({r, a, s}, t1, t2) || guard.crosses({s, b, r}, t1, t2)) continue;
      }
      pass_mesh.flip(*f);
      guard.changed(t1);
      guard.changed(t2);
      for (const int v : {a, b, r, s}) flipped_corners[v] = 1;
      ++pass_flips;
    }
    flips += pass_flips;
    if (!pass_flips) break;
  }
  return flips;
}

// Intersecting triangle pairs of one region's (or the stitched) triangles over the node store
// that involve a triangle with a corner flagged in `near` (the valence flips' quad corners).
std::size_t count_crossings_near(const std::vector<std::array<int, 3>>& tris,
                                 const std::vector<Vector3d>& pos, const std::vector<char>& near) {
  const Mesh m{.positions = pos, .triangles = tris};
  std::vector<char> involved(tris.size(), 0);
  const auto flagged = [&](int v) { return v < static_cast<int>(near.size()) && near[v]; };
  for (std::size_t t = 0; t < tris.size(); ++t)
    involved[t] = flagged(tris[t][0]) || flagged(tris[t][1]) || flagged(tris[t][2]);
  return count_intersecting_faces(m, nullptr, &involved);
}

// Gauss-Seidel sweeps moving each Steiner point to the projection of its neighbours' centroid.
// The projection starts from the point's own (phi, h), next to the answer. (One linear step
// through the surface's Jacobian instead, as the repair's search takes, was cheaper but left
// more small angles at a quarter of the sample units: 0.14 % of the triangles below 20 deg
// instead of 0.09 %; the centroid moves are up to half an edge, the search's steps a quarter
// and less.) A move is kept if no incident triangle turns away from the point's normal and
// either the smallest incident angle grows or the star's summed mean ratio (triangle_quality.h)
// grows while its smallest angle stays at or above min(before, 30 deg). (The angle rule alone
// refused most moves that only made the star rounder: mean radius ratio 0.946 at a quarter of
// the sample units; with the mean-ratio rule 0.952, 0.965 with the valence flips.)
void smooth_steiner_points(const std::vector<std::array<int, 3>>& tris, detail::NodeStore& store,
                           const ScanSurface& surface, std::size_t boundary_nodes, int iterations,
                           WallCrossingGuard& guard) {
  std::vector<std::vector<int>> vt(store.pos.size());
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int v : tris[t]) vt[v].push_back(static_cast<int>(t));
  const auto star_min = [&](std::size_t v) {
    double m = 1e9;
    for (int t : vt[v])
      m = std::min(m,
                   min_angle(store.pos[tris[t][0]], store.pos[tris[t][1]], store.pos[tris[t][2]]));
    return m;
  };
  const auto star_quality = [&](std::size_t v) {
    double sum = 0;
    for (int t : vt[v])
      sum += mean_ratio(store.pos[tris[t][0]], store.pos[tris[t][1]], store.pos[tris[t][2]]);
    return sum;
  };
  // Is v's star rounder (summed mean ratio) at its new position than at old_pos? Only asked
  // when the smallest angle did not grow, so most moves skip the 2 x valence evaluations.
  const auto rounder = [&](std::size_t v, const Vector3d& old_pos) {
    const Vector3d new_pos = store.pos[v];
    const double q_new = star_quality(v);
    store.pos[v] = old_pos;
    const double q_old = star_quality(v);
    store.pos[v] = new_pos;
    return q_new > q_old + 1e-12;
  };
  // Moves on a depth-jump wall are tested for crossings in 3D: there the centroid's projection
  // can carry a point a few millimetres along the wall, and its star then crossed triangles a
  // ring or two away that the normal test below cannot see (13 crossing pairs in the chin's
  // region at 0.18 of the sample units, every one with a corner whose normal is within 6 deg
  // of tangential to the cylinder). Elsewhere the test is skipped: it would cost more than the
  // smoothing.
  const auto star_on_wall = [&](std::size_t v) {
    for (int t : vt[v])
      for (int w : tris[t])
        if (on_wall(store.pos[w], store.normal[w])) return true;
    return false;
  };
  // A point that stayed put stays put again while no point of its star has moved since: its
  // evaluation would repeat exactly (same star, same start). Skipping those is exact.
  std::vector<long> moved_at(store.pos.size(), -1), stayed_at(store.pos.size(), -1);
  long step = 0;
  const auto star_moved_since = [&](std::size_t v, long since) {
    for (int t : vt[v])
      for (int w : tris[t])
        if (moved_at[w] > since) return true;
    return false;
  };
  for (int it = 0; it < iterations; ++it)
    for (std::size_t v = boundary_nodes; v < store.pos.size(); ++v) {
      if (vt[v].empty()) continue;
      ++step;
      if (stayed_at[v] >= 0 && !star_moved_since(v, stayed_at[v])) continue;
      stayed_at[v] = step;  // until the move below is kept
      Vector3d c = Vector3d::Zero();
      int n = 0;
      for (int t : vt[v])
        for (int w : tris[t])
          if (w != static_cast<int>(v)) {
            c += store.pos[w];
            ++n;
          }
      c /= n;
      const detail::NodeStore::Saved old = store.save(static_cast<int>(v));
      const double before = star_min(v);
      const auto pr = surface.project(c, old.param);
      if (!pr) continue;
      const Vector2d param(pr->phi, pr->h);
      if (!store.move(static_cast<int>(v), param, surface)) continue;
      bool ok = true;
      double after = 1e9;
      for (int t : vt[v]) {
        const Vector3d &a = store.pos[tris[t][0]], &b = store.pos[tris[t][1]],
                       &d = store.pos[tris[t][2]];
        const Vector3d nn = (b - a).cross(d - a);
        after = std::min(after, min_angle(a, b, d));
        if (nn.dot(store.normal[v]) <= 0.3 * nn.norm()) {
          ok = false;
          break;
        }
      }
      ok = ok && (after > before ||
                  (after >= std::min(before, kSmoothingAngleFloor) && rounder(v, old.pos)));
      if (ok && star_on_wall(v)) {
        for (int t : vt[v])
          if (guard.crosses(tris[t], t)) {
            ok = false;
            break;
          }
      }
      if (!ok) {
        store.restore(static_cast<int>(v), old);
      } else {
        moved_at[v] = step;
        stayed_at[v] = -1;
        for (int t : vt[v]) guard.changed(t);
      }
    }
}

// What a region's own post-processing cannot see, counted on the stitched mesh: pairs of
// triangles of different regions that cross (more than sharing a corner or an edge), and edges
// with more than two triangles (a flip or collapse made an edge between two segment nodes that
// another region has too).
struct StitchDefects {
  std::size_t crossings = 0, overfull_edges = 0;  // crossings: pairs between two regions
  std::vector<int> regions_crossing_themselves;   // regions with a crossing pair of their own
};
StitchDefects stitch_defects(const std::vector<std::array<int, 3>>& tris,
                             const std::vector<int>& labels, const std::vector<Vector3d>& pos) {
  const Mesh mesh{.positions = pos, .triangles = tris};
  StitchDefects d;
  d.overfull_edges = topology_stats(mesh).nonmanifold_edges;
  for (const auto& [f, g] : intersecting_face_pairs(mesh)) {
    if (labels[f] != labels[g])
      ++d.crossings;
    else
      d.regions_crossing_themselves.push_back(labels[f]);
  }
  auto& own = d.regions_crossing_themselves;
  std::sort(own.begin(), own.end());
  own.erase(std::unique(own.begin(), own.end()), own.end());
  return d;
}

// Limit (docs/animation-meshes.md, "Limits"): the regions' unit sizes decide the mesh's size,
// and a unit far below the scan's resolution (a region at 0.05 mm on a 0.45 mm grid, allowed by
// lowering min_unit_mm in the same file) ran for minutes and past 1 GB. Each region's surface
// area (its (phi, h) area times the radius at its label point) over an equilateral triangle of
// side unit_mm estimates its triangles; more than this in all is refused before any work.
constexpr double kMaxEstimatedTriangles = 5e5;

void check_triangle_budget(const RegionGraph& g, const ScanSurface& surface) {
  double total = 0, largest = 0;
  std::string largest_name;
  double largest_unit = 0;
  for (const Region& r : g.regions) {
    if (r.opening || !(r.unit_mm > 0)) continue;
    const auto radius = surface.radius_value(r.label_point.x(), r.label_point.y());
    const double area_mm2 = std::abs(r.area) * (radius ? *radius : 0.0);
    const double triangles = area_mm2 / (std::sqrt(3.0) / 4.0 * r.unit_mm * r.unit_mm);
    total += triangles;
    if (triangles > largest) largest = triangles, largest_name = r.name, largest_unit = r.unit_mm;
  }
  if (total <= kMaxEstimatedTriangles) return;
  std::ostringstream os;
  os.precision(3);
  os << "the regions' unit sizes ask for about " << total << " triangles (region '" << largest_name
     << "' alone " << largest << " at unit_mm " << largest_unit << "), more than the "
     << kMaxEstimatedTriangles << " the animation mesher takes: raise unit_mm";
  throw InvalidInputError(os.str());
}

std::size_t crossings_within(const std::vector<std::array<int, 3>>& tris,
                             const std::vector<Vector3d>& pos) {
  return count_intersecting_faces(Mesh{.positions = pos, .triangles = tris});
}

using Clock = std::chrono::steady_clock;

// Every stage's time of `more` added to `sum`.
void add(AnimationMesh::StageSeconds& sum, const AnimationMesh::StageSeconds& more) {
  sum.segments += more.segments;
  sum.regions += more.regions;
  sum.flips += more.flips;
  sum.smoothing += more.smoothing;
  sum.repair += more.repair;
  sum.check += more.check;
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The segment nodes lifted onto the surface: the first entries of every region's store and of
// the stitched one.
detail::NodeStore segment_node_store(const SegmentNodes& seg, const ScanSurface& surface) {
  detail::NodeStore store;
  for (std::size_t i = 0; i < seg.params.size(); ++i)
    if (store.add(seg.params[i], surface) < 0)
      throw InvalidInputError("segment node " + std::to_string(i) + " is off the scan surface");
  return store;
}

// One job per meshed region. The regions share only the segment nodes (fixed, the first
// boundary_nodes entries of the store), so each is meshed on its own copy of them, in
// parallel; the Steiner points are then appended region by region in region order, which
// gives the same node numbering, and the same mesh, as meshing the regions one after another.
struct RegionJob {
  int region;
  detail::RegionMeshInput in;
  detail::NodeStore nodes;
  RegionMeshStats stats;
  std::vector<std::array<int, 3>> tris;
  int flips = 0, valence_flip_retries = 0;
  detail::RepairStats repair;
  // The region as the mesher left it, for the serial fallback (postprocess_stitched_if_needed).
  detail::NodeStore nodes_meshed;
  std::vector<std::array<int, 3>> tris_meshed;
  AnimationMesh::StageSeconds thread_seconds;
};

// The mesher's input for region r: its settings, its boundary polygons and its front.
detail::RegionMeshInput region_mesh_input(const RegionGraph& g, const SegmentNodes& seg,
                                          const RegionSettings& settings, std::size_t r) {
  const Region& reg = g.regions[r];
  detail::RegionMeshInput in;
  in.unit_mm = reg.unit_mm > 0 ? reg.unit_mm : settings.default_unit_mm;
  in.strategy = settings.strategy;
  in.chordal_tolerance_mm = settings.chordal_tolerance_mm;
  in.min_unit_mm = settings.min_unit_mm;
  in.seed = settings.seed + 1000003ull * r;
  in.max_steps = static_cast<std::size_t>(settings.max_front_steps);
  std::vector<int> cycles{reg.outer};
  cycles.insert(cycles.end(), reg.inner.begin(), reg.inner.end());
  // Each cycle gives the polygon of its boundary nodes (the chords the front starts from, not
  // the curves: a chord cutting a curved opening's corner must not count as leaving) and its
  // chain edges in the cycle's direction, where the region's front starts.
  for (int c : cycles) {
    std::vector<Vector2d>& poly = in.polygons.emplace_back();
    for (const HalfEdgeRef& he : g.cycles[c].edges) {
      std::vector<int> chain = seg.chains[he.segment];
      if (!he.forward) std::reverse(chain.begin(), chain.end());
      for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
        Vector2d p = seg.params[chain[k]];
        if (!poly.empty()) p.x() = poly.back().x() + wrap_angle(p.x() - poly.back().x());
        poly.push_back(p);
        in.front.push_back({chain[k], chain[k + 1]});
      }
    }
  }
  return in;
}

// A job for every region that is not an opening, in region order.
std::vector<RegionJob> region_jobs(const RegionGraph& g, const SegmentNodes& seg,
                                   const RegionSettings& settings) {
  std::vector<RegionJob> jobs;
  for (std::size_t r = 0; r < g.regions.size(); ++r) {
    if (g.regions[r].opening) continue;
    jobs.push_back({.region = static_cast<int>(r), .in = region_mesh_input(g, seg, settings, r)});
  }
  return jobs;
}

// Constraint edges: every segment chain. Their ends are segment nodes, which have the same
// index in every region's store and in the stitched one.
std::unordered_set<std::uint64_t> segment_constraint_edges(const SegmentNodes& seg) {
  std::unordered_set<std::uint64_t> constraint;
  for (const auto& chain : seg.chains)
    for (std::size_t k = 0; k + 1 < chain.size(); ++k)
      constraint.insert(edge_key(chain[k], chain[k + 1]));
  return constraint;
}

// Largest fronts first, so that a big region does not start last.
std::vector<int> largest_fronts_first(const std::vector<RegionJob>& jobs) {
  std::vector<int> order(jobs.size());
  for (std::size_t k = 0; k < jobs.size(); ++k) order[k] = static_cast<int>(k);
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return jobs[x].in.front.size() > jobs[y].in.front.size(); });
  return order;
}

// The regions' triangles over one node store, each labelled with its region.
struct StitchedMesh {
  detail::NodeStore nodes;
  std::vector<std::array<int, 3>> tris;
  std::vector<int> labels;
};

// What a post-processing run (RegionMesher::postprocess) did, and its time per stage.
struct PostResult {
  int flips = 0;
  int valence_flip_retries = 0;
  detail::RepairStats repair;
  AnimationMesh::StageSeconds seconds;
};

// What the regions' meshing, their post-processing and the stitching share: the segment nodes
// and the constraint edges between them. (Called from the parallel jobs: const throughout.)
struct RegionMesher {
  const RegionGraph& g;
  const ScanSurface& surface;
  const RegionSettings& settings;
  const detail::NodeStore& store;  // the segment nodes alone
  std::size_t boundary_nodes;      // store's size: every store's segment nodes come first
  const std::unordered_set<std::uint64_t>& constraint;

  // Small-angle repair (a little above 20 deg so that later rounding cannot drop below it).
  detail::RepairStats repair(std::vector<std::array<int, 3>>& tris, std::vector<int>& labels,
                             detail::NodeStore& nodes) const {
    return detail::repair_small_angles(tris, labels, nodes, surface, constraint, boundary_nodes,
                                       settings.repair_goal_deg * M_PI / 180, 20.0 * M_PI / 180,
                                       settings.repair_rounds, settings.deviation_goal_mm);
  }

  // The stages after the first max-min flips: the valence flips (if asked; their quad corners
  // go to flipped_corners), the smoothing, the max-min flips again and the repair, timed into
  // `out`. Returns the valence and the max-min flips.
  std::pair<int, int> smooth_flip_and_repair(bool with_valence_flips,
                                             std::vector<std::array<int, 3>>& tris,
                                             std::vector<int>& labels, detail::NodeStore& nodes,
                                             WallCrossingGuard& guard,
                                             std::vector<char>& flipped_corners,
                                             PostResult& out) const {
    auto t1 = Clock::now();
    flipped_corners.clear();
    const int valence = with_valence_flips
                            ? valence_flips(tris, nodes, surface, constraint, kValenceFlipFloor,
                                            flipped_corners, guard)
                            : 0;
    smooth_steiner_points(tris, nodes, surface, boundary_nodes, settings.smooth_iterations, guard);
    out.seconds.smoothing += seconds_since(t1);
    t1 = Clock::now();
    const int delaunay = delaunay_flips(tris, nodes.pos, nodes.normal, constraint, guard);
    out.seconds.flips += seconds_since(t1);
    t1 = Clock::now();
    out.repair = repair(tris, labels, nodes);
    out.seconds.repair += seconds_since(t1);
    return std::pair{valence, delaunay};
  }

  // Flips, tangential smoothing of the Steiner points (towards the neighbours' centroid, on the
  // surface, kept only if the smallest incident angle grows), flips again, and the small-angle
  // repair: of one region in its job, or of the stitched mesh in the fallback
  // (postprocess_stitched_if_needed).
  PostResult postprocess(std::vector<std::array<int, 3>>& tris, std::vector<int>& labels,
                         detail::NodeStore& nodes) const {
    PostResult out;
    auto t0 = Clock::now();
    // One filing of the triangles for the wall tests of all the stages below (tris and nodes
    // stay the same objects; the retry without valence flips puts them back and forgets it).
    WallCrossingGuard guard(tris, nodes.pos);
    out.flips = delaunay_flips(tris, nodes.pos, nodes.normal, constraint, guard);
    out.seconds.flips = seconds_since(t0);
    // Kept for a second try without valence flips (below).
    std::vector<std::array<int, 3>> tris_flipped;
    std::vector<int> labels_flipped;
    detail::NodeStore nodes_flipped;
    if (settings.valence_flips) {
      tris_flipped = tris;
      labels_flipped = labels;
      nodes_flipped = nodes;
    }
    std::vector<char> flipped_corners;  // the valence flips' quad corners
    auto [valence, later_flips] = smooth_flip_and_repair(settings.valence_flips, tris, labels,
                                                         nodes, guard, flipped_corners, out);
    // The valence flips' tests are local; where a thin part of the surface (an ear's rim) lies
    // close to the other side of itself, a flip there and the moves after it crossed triangles
    // of that other side (2 crossing pairs at half the sample units). So the triangles at the
    // flipped quads' corners are checked against the region's (which the smoothing, flips and
    // repair alone never made cross) and the region is done again without valence flips if one
    // crosses. (Checking every triangle of the region cost 5 % of the run at a quarter of the
    // sample units.)
    if (valence > 0 && count_crossings_near(tris, nodes.pos, flipped_corners) > 0) {
      tris = std::move(tris_flipped);
      labels = std::move(labels_flipped);
      nodes = std::move(nodes_flipped);
      guard.forget();
      std::tie(valence, later_flips) =
          smooth_flip_and_repair(false, tris, labels, nodes, guard, flipped_corners, out);
      ++out.valence_flip_retries;
    }
    later_flips += valence;
    out.flips += later_flips;
    return out;
  }

  // Per region, none of these stages crosses a region border: flips never flip a constraint
  // edge (every border is one), and only Steiner points move, whose stars lie in their region.
  // The job's numbering is the stitched one shifted, so the smoothing's Gauss-Seidel order and
  // the flips' key order are kept. What a region does not see is the others' triangles: the
  // repair tests a changed triangle for crossings against its own region only, and a flip or
  // collapse cannot know that the edge it makes between two segment nodes exists in another
  // region. Both are checked on the stitched mesh (stitch_defects,
  // postprocess_stitched_if_needed).
  void postprocess_region(RegionJob& job) const {
    job.nodes_meshed = job.nodes;
    job.tris_meshed = job.tris;
    std::vector<int> labels(job.tris.size(), job.region);
    const PostResult r = postprocess(job.tris, labels, job.nodes);
    job.flips = r.flips;
    job.valence_flip_retries = r.valence_flip_retries;
    job.repair = r.repair;
    add(job.thread_seconds, r.seconds);  // (it holds only the meshing's time so far)
  }

  // One region meshed (and post-processed, unless that runs on the stitched mesh) from scratch.
  void mesh_region(RegionJob& job) const {
    const auto job_start = Clock::now();
    job.nodes = store;
    job.stats = RegionMeshStats{};
    job.stats.region = job.region;
    std::optional<std::vector<std::array<int, 3>>> region_tris;
    if (g.regions[job.region].mesher == "delaunay") {
      region_tris = detail::delaunay_mesh_region(job.nodes, surface, job.in, job.stats);
      if (region_tris) job.stats.mesher = "delaunay";
    }
    if (!region_tris) region_tris = detail::aft_mesh_region(job.nodes, surface, job.in, job.stats);
    job.tris = std::move(*region_tris);
    job.thread_seconds.regions += seconds_since(job_start);
    if (settings.parallel_postprocessing) {
      postprocess_region(job);
    } else {
      job.nodes_meshed = job.nodes;
      job.tris_meshed = job.tris;
    }
  }

  // Stitching: the Steiner points appended region by region (as the mesher left each region,
  // or as its job's post-processing did).
  StitchedMesh stitch(const std::vector<RegionJob>& jobs, bool as_meshed) const {
    StitchedMesh out;
    out.nodes = store;
    for (const RegionJob& job : jobs) {
      const detail::NodeStore& jn = as_meshed ? job.nodes_meshed : job.nodes;
      const int offset = static_cast<int>(out.nodes.pos.size() - boundary_nodes);
      for (std::size_t v = boundary_nodes; v < jn.pos.size(); ++v) {
        out.nodes.params.push_back(jn.params[v]);
        out.nodes.pos.push_back(jn.pos[v]);
        out.nodes.normal.push_back(jn.normal[v]);
      }
      for (auto t : as_meshed ? job.tris_meshed : job.tris) {
        for (int& v : t)
          if (v >= static_cast<int>(boundary_nodes)) v += offset;
        out.tris.push_back(t);
        out.labels.push_back(job.region);
      }
    }
    return out;
  }
};

// Every job meshed, largest fronts first, on all threads; the first failed job's (in job order)
// exception is rethrown once all have run.
void mesh_regions_in_parallel(std::vector<RegionJob>& jobs, const RegionMesher& mesher) {
  const std::vector<int> order = largest_fronts_first(jobs);
  std::vector<std::exception_ptr> errors(jobs.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t k = 0; k < order.size(); ++k) {
    RegionJob& job = jobs[order[k]];
    try {
      mesher.mesh_region(job);
    } catch (...) {
      errors[order[k]] = std::current_exception();
    }
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

// The job meshed again with the other front orders; the best attempt is kept, with the time
// of every attempt.
void remesh_with_other_front_orders(RegionJob& job, const RegionMesher& mesher) {
  // An attempt is better with fewer unclosed front edges (a hole is worse than a crossing),
  // then fewer crossings.
  const auto badness = [&](const RegionJob& j) {
    return std::pair{j.stats.unmeshed_front_edges, crossings_within(j.tris, j.nodes.pos)};
  };
  RegionJob best = job;
  auto best_badness = badness(job);
  AnimationMesh::StageSeconds spent = job.thread_seconds;
  std::vector<std::pair<EdgeStrategy, std::uint64_t>> orders;
  for (const EdgeStrategy s : {EdgeStrategy::Shortest, EdgeStrategy::Longest, EdgeStrategy::Random})
    if (s != job.in.strategy) orders.push_back({s, job.in.seed});
  orders.push_back({EdgeStrategy::Random, job.in.seed + 1});
  orders.push_back({EdgeStrategy::Random, job.in.seed + 2});
  for (const auto& [strategy, seed] : orders) {
    if (best_badness == std::pair{0, std::size_t{0}}) break;
    job.in.strategy = strategy;
    job.in.seed = seed;
    job.thread_seconds = {};
    mesher.mesh_region(job);
    add(spent, job.thread_seconds);
    if (const auto b = badness(job); b < best_badness) {
      best = job;
      best_badness = b;
    }
  }
  job = std::move(best);
  job.thread_seconds = spent;  // every attempt's time
}

// Crossing triangles inside one region: the front's visibility tests run in (phi, h), and at
// a depth-jump wall (an ear's rim) the flat 3D triangles' footprints can overlap where their
// parameter triangles do not (3 pairs at a quarter of the sample units with segment_spacing:
// finer; none at the defaults). Such a region, and one whose front did not close, is meshed
// again with the other front orders (GET-NEXT-EDGE), which build a different mesh there, and
// the first without crossings and holes is kept (else the least bad). If any region needed it,
// the regions are stitched again and `defects` counted again.
void remesh_defective_regions(std::vector<RegionJob>& jobs, const RegionMesher& mesher,
                              StitchedMesh& stitched, StitchDefects& defects,
                              std::vector<int>& regions_remeshed) {
  const auto needs_remeshing = [&](const RegionJob& job) {
    return job.stats.unmeshed_front_edges > 0 ||
           std::binary_search(defects.regions_crossing_themselves.begin(),
                              defects.regions_crossing_themselves.end(), job.region);
  };
  if (!std::any_of(jobs.begin(), jobs.end(), needs_remeshing)) return;
  for (RegionJob& job : jobs) {
    if (!needs_remeshing(job)) continue;
    // The surface Delaunay mesher has no front order to change.
    if (job.stats.mesher == "delaunay") continue;
    regions_remeshed.push_back(job.region);
    remesh_with_other_front_orders(job, mesher);
  }
  stitched = {};  // freed before the new one is built
  stitched = mesher.stitch(jobs, false);
  defects = stitch_defects(stitched.tris, stitched.labels, stitched.nodes.pos);
}

// The regions' statistics and thread times summed into am.
void add_region_stats(const std::vector<RegionJob>& jobs, AnimationMesh& am) {
  for (const RegionJob& job : jobs) {
    am.region_stats.push_back(job.stats);
    am.flips += job.flips;
    am.valence_flip_retries += job.valence_flip_retries;
    for (int k = 0; k < 5; ++k) am.repair_operations[k] += job.repair.operations[k];
    am.repair_left_below_20 += job.repair.left_below_goal;
    am.repair_forced_below_20 += job.repair.forced_below_goal;
    am.repair_left_above_deviation_goal += job.repair.left_above_deviation_goal;
    add(am.thread_seconds, job.thread_seconds);
  }
}

// The regions did not see each other (RegionMesher::postprocess_region). If the stitched mesh
// has an edge with more than two triangles, or more crossings between regions than the meshers
// left, the flips, smoothing and repair are done again on the stitched mesh as the meshers left
// it, where every edge and every changed triangle is tested against the whole mesh. (Neither
// has happened on the sample head at any unit size tried.) Also where the settings ask for the
// post-processing on the stitched mesh. The result replaces `stitched` and am's figures.
void postprocess_stitched_if_needed(const std::vector<RegionJob>& jobs, const RegionMesher& mesher,
                                    const StitchDefects& defects, StitchedMesh& stitched,
                                    AnimationMesh& am) {
  const RegionSettings& settings = mesher.settings;
  if (!settings.parallel_postprocessing || defects.crossings > 0 || defects.overfull_edges > 0) {
    StitchedMesh meshed = mesher.stitch(jobs, true);
    if (!settings.parallel_postprocessing || defects.overfull_edges > 0 ||
        defects.crossings >
            stitch_defects(meshed.tris, meshed.labels, meshed.nodes.pos).crossings) {
      const PostResult r = mesher.postprocess(meshed.tris, meshed.labels, meshed.nodes);
      am.flips = r.flips;
      am.valence_flip_retries = r.valence_flip_retries;
      am.repair_operations = r.repair.operations;
      am.repair_left_below_20 = r.repair.left_below_goal;
      am.repair_forced_below_20 = r.repair.forced_below_goal;
      am.repair_left_above_deviation_goal = r.repair.left_above_deviation_goal;
      am.serial_postprocessing = true;
      add(am.seconds, r.seconds);  // (no post-processing time in it so far)
      stitched = std::move(meshed);
    }
  }
}

// Compact: drop nodes no triangle uses (segments bordering nothing meshed). The used nodes and
// the triangles go to am.mesh; returns every stitched node's index there (-1: dropped).
std::vector<int> add_used_nodes_and_triangles(const StitchedMesh& stitched,
                                              std::size_t boundary_nodes, AnimationMesh& am) {
  const detail::NodeStore& store_all = stitched.nodes;
  const std::vector<std::array<int, 3>>& tris = stitched.tris;
  std::vector<int> used(store_all.pos.size(), 0);
  for (const auto& t : tris)
    for (int v : t) used[v] = 1;
  // Nodes of opening/seam chains stay even if unused? No: only used nodes are mesh vertices.
  std::vector<int> remap(store_all.pos.size(), -1);
  for (std::size_t v = 0; v < store_all.pos.size(); ++v)
    if (used[v]) {
      remap[v] = static_cast<int>(am.mesh.positions.size());
      am.mesh.positions.push_back(store_all.pos[v]);
      am.params.push_back(store_all.params[v]);
      am.steiner.push_back(v >= boundary_nodes);
    }
  for (std::size_t t = 0; t < tris.size(); ++t) {
    am.mesh.triangles.push_back({remap[tris[t][0]], remap[tris[t][1]], remap[tris[t][2]]});
    am.mesh.face_labels.push_back(stitched.labels[t]);
  }
  return remap;
}

// Every segment's chain in the mesh's numbering (-1 for a dropped node); the chains whose nodes
// are all in the mesh give its line edges.
void add_segment_chains(const RegionGraph& g, const SegmentNodes& seg,
                        const std::vector<int>& remap, AnimationMesh& am) {
  for (std::size_t s = 0; s < seg.chains.size(); ++s) {
    std::vector<int> chain;
    bool complete = true;
    for (int v : seg.chains[s]) {
      chain.push_back(remap[v]);
      complete &= remap[v] >= 0;
    }
    am.segment_chains.push_back(chain);
    if (!complete) continue;
    for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
      am.line_edges.push_back({chain[k], chain[k + 1]});
      am.line_edge_line.push_back(g.segments[s].line);
    }
  }
}

// Seams: each seam line's node list in line order (segments are in line order already).
void add_seams(const RegionGraph& g, const LineSet& lines, AnimationMesh& am) {
  for (std::size_t s = 0; s < g.segments.size(); ++s) {
    const AnimationLine& line = lines.lines[g.segments[s].line];
    if (line.kind != LineKind::Seam) continue;
    auto& list = am.seams[line.id];
    for (int v : am.segment_chains[s])
      if (list.empty() || list.back() != v) list.push_back(v);
  }
}

}  // namespace

AnimationMesh build_animation_mesh(const RegionGraph& g, const LineSet& lines,
                                   const ScanSurface& surface, const RegionSettings& settings) {
  check_triangle_budget(g, surface);
  auto stage_start = Clock::now();
  AnimationMesh am;
  const SegmentNodes seg = initialise_segments(g, lines, surface, settings);
  const detail::NodeStore store = segment_node_store(seg, surface);
  const std::size_t boundary_nodes = store.params.size();
  am.seconds.segments = seconds_since(stage_start);

  stage_start = Clock::now();
  std::vector<RegionJob> jobs = region_jobs(g, seg, settings);
  const std::unordered_set<std::uint64_t> constraint = segment_constraint_edges(seg);
  const RegionMesher mesher{g, surface, settings, store, boundary_nodes, constraint};
  mesh_regions_in_parallel(jobs, mesher);
  StitchedMesh stitched = mesher.stitch(jobs, false);
  am.seconds.regions = seconds_since(stage_start);

  stage_start = Clock::now();
  StitchDefects defects = stitch_defects(stitched.tris, stitched.labels, stitched.nodes.pos);
  remesh_defective_regions(jobs, mesher, stitched, defects, am.regions_remeshed);
  add_region_stats(jobs, am);
  postprocess_stitched_if_needed(jobs, mesher, defects, stitched, am);
  am.seconds.check = seconds_since(stage_start);
  for (RegionJob& job : jobs) job = {};

  const std::vector<int> remap = add_used_nodes_and_triangles(stitched, boundary_nodes, am);
  add_segment_chains(g, seg, remap, am);
  add_seams(g, lines, am);
  am.mesh.compute_vertex_normals();
  return am;
}

std::string AnimationMeshQuality::to_text() const {
  std::ostringstream os;
  os.precision(4);
  os << "min angle " << min_angle_deg << " deg (" << min_angle_non_exempt_deg
     << " deg away from sharp line junctions, " << small_angle_exempt
     << " triangles exempt), max angle " << max_angle_deg << " deg\n";
  os << "min angle >= 30 deg: " << 100 * fraction_min_angle_ge_30
     << " %, >= 20 deg: " << 100 * fraction_min_angle_ge_20 << " %\n";
  os << "radius ratio 2 r_in / R_circ: mean " << mean_radius_ratio << ", min " << min_radius_ratio
     << "\n";
  os << "Hausdorff to the scan surface: mesh->surface " << hausdorff_mesh_to_surface_mm
     << " mm, surface->mesh " << hausdorff_surface_to_mesh_mm << " mm; max vertex offset "
     << max_vertex_offset_mm << " mm";
  if (vertices_off_surface > 0) os << ", " << vertices_off_surface << " vertices off the surface";
  os << "\n";
  os << "valence:";
  for (const auto& [v, n] : valence_histogram) os << " " << v << ":" << n;
  os << "\ntriangles per region:";
  for (std::size_t r = 0; r < triangles_per_region.size(); ++r)
    if (triangles_per_region[r]) os << " " << r << ":" << triangles_per_region[r];
  os << "\n";
  return os.str();
}

AnimationMeshQuality evaluate_quality(const AnimationMesh& am, const ScanSurface& surface,
                                      int samples, const RegionGraph* regions) {
  AnimationMeshQuality q;
  const auto& P = am.mesh.positions;
  const auto& T = am.mesh.triangles;
  std::unordered_set<std::uint64_t> line_edge;
  for (const auto& e : am.line_edges) line_edge.insert(edge_key(e[0], e[1]));
  q.min_angle_deg = 180;
  q.min_angle_non_exempt_deg = 180;
  q.min_radius_ratio = 1;
  int ge30 = 0, ge20 = 0;
  std::vector<int> valence(P.size(), 0);
  std::unordered_set<std::uint64_t> edges;
  for (std::size_t t = 0; t < T.size(); ++t) {
    const auto& f = T[t];
    const std::array<double, 3> ang = detail::corner_angles(P, f);
    const int kmin = detail::smallest_corner(ang);
    const double mn = ang[kmin] * 180 / M_PI,
                 mx = *std::max_element(ang.begin(), ang.end()) * 180 / M_PI;
    q.min_angle_deg = std::min(q.min_angle_deg, mn);
    q.max_angle_deg = std::max(q.max_angle_deg, mx);
    const bool exempt = mn < 20 && detail::corner_between(f, kmin, line_edge);
    if (exempt)
      ++q.small_angle_exempt;
    else
      q.min_angle_non_exempt_deg = std::min(q.min_angle_non_exempt_deg, mn);
    ge30 += mn >= 30;
    ge20 += mn >= 20;
    q.min_angle_histogram[std::min(11, static_cast<int>(mn / 5))]++;
    const double rho = radius_ratio(P[f[0]], P[f[1]], P[f[2]]);
    q.mean_radius_ratio += rho;
    q.min_radius_ratio = std::min(q.min_radius_ratio, rho);
    q.radius_ratio_histogram[std::clamp(static_cast<int>(rho * 10), 0, 9)]++;
    for (int k = 0; k < 3; ++k) edges.insert(edge_key(f[k], f[(k + 1) % 3]));
    const int label = t < am.mesh.face_labels.size() ? am.mesh.face_labels[t] : 0;
    if (label >= static_cast<int>(q.triangles_per_region.size()))
      q.triangles_per_region.resize(label + 1);
    q.triangles_per_region[label]++;
  }
  for (const auto k : edges) {
    valence[edge_key_first(k)]++;
    valence[edge_key_second(k)]++;
  }
  for (int v : valence)
    if (v) q.valence_histogram[v]++;
  if (!T.empty()) {
    q.mean_radius_ratio /= T.size();
    q.fraction_min_angle_ge_30 = static_cast<double>(ge30) / T.size();
    q.fraction_min_angle_ge_20 = static_cast<double>(ge20) / T.size();
  }
  // Projected from the point itself, not from the vertex's own (phi, h): an independent check.
  // A vertex that cannot be projected (no surface around it) is counted, not skipped.
  for (const Vector3d& p : P) {
    if (const auto pr = surface.project(p))
      q.max_vertex_offset_mm = std::max(q.max_vertex_offset_mm, pr->distance);
    else
      ++q.vertices_off_surface;
  }
  // Two-way sampled Hausdorff with exact distances to triangle sets (surface_distance.cpp).
  const detail::TwoWayDistance d = detail::sampled_hausdorff(am, surface, samples, regions);
  q.hausdorff_mesh_to_surface_mm = d.mesh_to_surface_mm;
  q.hausdorff_surface_to_mesh_mm = d.surface_to_mesh_mm;
  return q;
}

}  // namespace scanmesh::aft
