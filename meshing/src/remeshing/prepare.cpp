// Scan clean-up before remeshing: tiny components removed, small holes closed by a refined
// patch (hole_filling.cpp).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <numbers>
#include <cstdint>
#include <unordered_map>

#include "../kernel/cell_lists.h"
#include "../kernel/segment.h"
#include "../kernel/vertex_components.h"
#include "hole_filling.h"
#include "scanmesh/meshing/kernel/triangle_mesh.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/remeshing/remesh.h"

namespace scanmesh::remeshing {

namespace {

using Vec3 = Eigen::Vector3d;

// The faces with keep[f] set, their vertices renumbered in the order of first use, with their
// labels (0 where `labels` is empty).
Mesh kept_faces(const std::vector<Vec3>& pos, const std::vector<std::array<int, 3>>& tri,
                const std::vector<char>& keep, const std::vector<int>& labels) {
  Mesh out;
  std::vector<int> map(pos.size(), -1);
  for (std::size_t f = 0; f < tri.size(); ++f) {
    if (!keep[f]) continue;
    std::array<int, 3> t{};
    for (int i = 0; i < 3; ++i) {
      int& m = map[tri[f][i]];
      if (m < 0) {
        m = static_cast<int>(out.positions.size());
        out.positions.push_back(pos[tri[f][i]]);
      }
      t[i] = m;
    }
    out.triangles.push_back(t);
    out.face_labels.push_back(labels.empty() ? 0 : labels[f]);
  }
  return out;
}

// Face soup with per-vertex face lists for local repairs; removed faces are marked dead.
class Surface {
 public:
  explicit Surface(const Mesh& in)
      : pos(in.positions),
        tri(in.triangles),
        alive(in.triangles.size(), 1),
        vf(in.positions.size()) {
    label = in.has_face_labels() ? in.face_labels : std::vector<int>(tri.size(), 0);
    for (std::size_t f = 0; f < tri.size(); ++f)
      for (int c : tri[f]) vf[c].push_back(static_cast<int>(f));
  }
  static bool has(const std::array<int, 3>& t, int v) {
    return t[0] == v || t[1] == v || t[2] == v;
  }
  int edge_count(int a, int b) const {
    int n = 0;
    for (int f : vf[a]) n += alive[f] && has(tri[f], b);
    return n;
  }
  std::vector<int> edge_faces(int a, int b) const {
    std::vector<int> out;
    for (int f : vf[a])
      if (alive[f] && has(tri[f], b)) out.push_back(f);
    return out;
  }
  bool on_boundary(int v) const {
    for (int f : vf[v])
      if (alive[f])
        for (int c : tri[f])
          if (c != v && edge_count(v, c) == 1) return true;
    return false;
  }
  std::vector<int> neighbours(int v) const {
    std::vector<int> out;
    for (int f : vf[v])
      if (alive[f])
        for (int c : tri[f])
          if (c != v) out.push_back(c);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  void kill(int f) {
    if (alive[f]) killed.push_back(f);
    alive[f] = 0;
  }
  // The live faces sharing a corner with a face killed at or after killed[since] (each once,
  // ascending): where a removal can have made a new ear, veil or pinch.
  std::vector<int> faces_near_killed(std::size_t since) const {
    std::vector<int> out;
    for (std::size_t i = since; i < killed.size(); ++i)
      for (int c : tri[killed[i]])
        for (int g : vf[c])
          if (alive[g]) out.push_back(g);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  // The live faces with a border edge, ascending, brought up to date from the kill log (a
  // removal changes the edges of its neighbours only). Tips and necks read the border from
  // these instead of every face, every round.
  const std::vector<int>& border_faces() {
    auto has_border_edge = [&](int f) {
      const auto& t = tri[f];
      for (int i = 0; i < 3; ++i)
        if (edge_count(t[i], t[(i + 1) % 3]) == 1) return true;
      return false;
    };
    if (border_faces_seen_ == 0 && border_flag_.empty()) {
      border_flag_.assign(tri.size(), 0);
      for (int f = 0; f < static_cast<int>(tri.size()); ++f)
        border_flag_[f] = alive[f] && has_border_edge(f);
    } else {
      for (std::size_t i = border_faces_seen_; i < killed.size(); ++i) border_flag_[killed[i]] = 0;
      for (int g : faces_near_killed(border_faces_seen_)) border_flag_[g] = has_border_edge(g);
    }
    border_faces_seen_ = killed.size();
    border_list_.clear();
    for (int f = 0; f < static_cast<int>(tri.size()); ++f)
      if (border_flag_[f]) border_list_.push_back(f);
    return border_list_;
  }
  // The border as directed edges (as in their face: the surface lies to their left) and, per
  // vertex, the next and previous border vertex (-1 off the border).
  struct BorderLinks {
    std::vector<int> next, prev;
    std::vector<std::array<int, 2>> edges;
  };
  BorderLinks border_links() {
    BorderLinks b{std::vector<int>(pos.size(), -1), std::vector<int>(pos.size(), -1), {}};
    for (const int f : border_faces()) {
      const auto& t = tri[f];
      for (int i = 0; i < 3; ++i)
        if (edge_count(t[i], t[(i + 1) % 3]) == 1) {
          b.next[t[i]] = t[(i + 1) % 3];
          b.prev[t[(i + 1) % 3]] = t[i];
          b.edges.push_back({t[i], t[(i + 1) % 3]});
        }
    }
    return b;
  }
  // Sum of the live faces' (p1 - p0) x (p2 - p0) at v: the area-weighted normal, not normalised.
  Vec3 normal_at(int v) const {
    Vec3 n = Vec3::Zero();
    for (int g : vf[v])
      if (alive[g]) {
        const auto& t = tri[g];
        n += (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
      }
    return n;
  }
  // Removes every live face at the given vertices; returns how many.
  std::size_t kill_faces_at(const std::vector<int>& vertices) {
    std::size_t removed = 0;
    for (int v : vertices)
      for (int g : vf[v])
        if (alive[g]) {
          kill(g);
          ++removed;
        }
    return removed;
  }
  std::vector<int> corners_of_killed(std::size_t since) const {
    std::vector<int> out;
    for (std::size_t i = since; i < killed.size(); ++i)
      for (int c : tri[killed[i]]) out.push_back(c);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  // The smallest corner angle of f; `short_i` gets its corner (the short edge is opposite it),
  // `max_angle` and `max_i` the largest angle and its corner.
  double min_angle(int f, int* short_i = nullptr, double* max_angle = nullptr,
                   int* max_i = nullptr) const {
    const auto& t = tri[f];
    double mn = 10, mx = 0;
    for (int i = 0; i < 3; ++i) {
      const Vec3 e1 = pos[t[(i + 1) % 3]] - pos[t[i]], e2 = pos[t[(i + 2) % 3]] - pos[t[i]];
      const double a = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      if (a < mn) {
        mn = a;
        if (short_i) *short_i = i;
      }
      if (a > mx && max_i) *max_i = i;
      mx = std::max(mx, a);
    }
    if (max_angle) *max_angle = mx;
    return mn;
  }
  Mesh to_mesh() const { return kept_faces(pos, tri, alive, label); }

  std::vector<Vec3> pos;
  std::vector<std::array<int, 3>> tri;
  std::vector<char> alive;
  std::vector<std::vector<int>> vf;
  std::vector<int> label;
  std::vector<int> killed;  // faces in the order they were removed

 private:
  std::vector<char> border_flag_;
  std::vector<int> border_list_;
  std::size_t border_faces_seen_ = 0;
};

void repair_needles(Surface& s, double max_angle_rad, PrepareStats& st) {
  const int nf = static_cast<int>(s.tri.size());
  for (int f = 0; f < nf; ++f) {
    if (!s.alive[f]) continue;
    const auto t = s.tri[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
        !((s.pos[t[1]] - s.pos[t[0]]).cross(s.pos[t[2]] - s.pos[t[0]]).norm() > 0)) {
      s.kill(f);
      ++st.degenerate_removed;
      continue;
    }
    int i = 0, ci = 0;
    double amax = 0;
    if (s.min_angle(f, &i, &amax, &ci) >= max_angle_rad) continue;
    if (amax > 2 * std::numbers::pi / 3) {
      // Cap: the longest edge is opposite the largest angle, corner c (one angle > 120 deg).
      const int c = t[ci], a = t[(ci + 1) % 3], b = t[(ci + 2) % 3];  // f = (c, a, b)
      const auto ef = s.edge_faces(a, b);
      if (ef.size() == 1) {
        s.kill(f);
        ++st.caps_removed;
        continue;
      }
      if (ef.size() != 2) continue;
      const int g = ef[0] == f ? ef[1] : ef[0];
      const auto u = s.tri[g];
      const int d = u[0] != a && u[0] != b ? u[0] : (u[1] != a && u[1] != b ? u[1] : u[2]);
      if (d == c || s.edge_count(c, d) > 0) continue;
      // f = (c, a, b) has a -> b; g has b -> a: g = (b, a, d) up to rotation. New (c, a, d),
      // (d, b, c).
      const int gi = u[0] == b ? 0 : (u[1] == b ? 1 : 2);
      if (u[(gi + 1) % 3] != a) continue;  // inconsistent orientation: leave it
      const double before = std::min(s.min_angle(f), s.min_angle(g));
      s.tri[f] = {c, a, d};
      s.tri[g] = {d, b, c};
      if (std::min(s.min_angle(f), s.min_angle(g)) <= before) {
        s.tri[f] = t;
        s.tri[g] = u;
        continue;
      }
      std::erase(s.vf[a], g);
      std::erase(s.vf[b], f);
      s.vf[c].push_back(g);
      s.vf[d].push_back(f);
      ++st.caps_flipped;
      continue;
    }
    // Needle: weld the short edge (a, b) opposite corner i, keeping a boundary end in place.
    int a = t[(i + 1) % 3], b = t[(i + 2) % 3];
    const bool ba = s.on_boundary(a), bb = s.on_boundary(b);
    if (ba && bb) continue;
    if (bb) std::swap(a, b);  // a survives
    // Link condition: the common neighbours of a and b are the opposite corners of edge (a, b).
    const auto ef = s.edge_faces(a, b);
    std::vector<int> opp;
    for (int e : ef)
      for (int c : s.tri[e])
        if (c != a && c != b) opp.push_back(c);
    const auto na = s.neighbours(a), nb = s.neighbours(b);
    bool ok = ef.size() <= 2;
    for (int x : nb)
      if (x != a && std::binary_search(na.begin(), na.end(), x) &&
          std::find(opp.begin(), opp.end(), x) == opp.end())
        ok = false;
    if (!ok) continue;
    if (!ba && !bb) s.pos[a] = 0.5 * (s.pos[a] + s.pos[b]);
    for (int e : ef) s.kill(e);
    for (int e : s.vf[b]) {
      if (!s.alive[e]) continue;
      for (int& c : s.tri[e])
        if (c == b) c = a;
      s.vf[a].push_back(e);
    }
    s.vf[b].clear();
    ++st.needles_welded;
  }
}

// Sharp convex tips of the border at scale `reach`: the border is followed `reach` mm back and
// forward from each boundary vertex; where the surface's angle between the two chords is below
// `max_angle` the vertex's faces are removed. Returns the number of faces removed.
std::size_t remove_tips(Surface& s, double reach, double max_angle) {
  const int nv = static_cast<int>(s.pos.size());
  const Surface::BorderLinks border = s.border_links();
  const std::vector<int>&next = border.next, &prev = border.prev;
  auto walk = [&](int v, const std::vector<int>& step) {
    int cur = v;
    double arc = 0;
    for (int k = 0; k < 1000 && arc < reach; ++k) {
      const int n = step[cur];
      if (n < 0 || n == v) break;
      arc += (s.pos[n] - s.pos[cur]).norm();
      cur = n;
    }
    return cur;
  };
  std::vector<int> tips;
  for (int v = 0; v < nv; ++v) {
    if (next[v] < 0 || prev[v] < 0) continue;
    const int f = walk(v, next), b = walk(v, prev);
    if (f == v || b == v || f == b) continue;
    const Vec3 n = s.normal_at(v);
    const Vec3 db = s.pos[b] - s.pos[v], df = s.pos[f] - s.pos[v];
    const double alpha = std::atan2(db.cross(df).norm(), db.dot(df));
    // Faces lie to the left of the directed border (b -> v -> f): a left turn is convex.
    const bool convex = (s.pos[v] - s.pos[b]).cross(df).dot(n) > 0;
    if (convex && alpha < max_angle) tips.push_back(v);
  }
  return s.kill_faces_at(tips);
}

// Necks: where the surface between two parts of its border is narrower than `max_width` (the
// parts not within `reach` of each other along the border: there it would be a notch or tip of
// one border, which remove_tips judges). No triangle of the output fits across such a neck (9-12
// deg slivers with all three corners on the border, on the demo head's ear), so the faces at
// its border vertices are removed; the caller repeats this until no neck is left, and the ear
// removal eats what remains of the strand. A slit (a narrow hole) is left alone: the other
// border must lie on the surface's side of the vertex. Returns the number of faces removed.
std::size_t remove_necks(Surface& s, double max_width, double reach) {
  const int nv = static_cast<int>(s.pos.size());
  const Surface::BorderLinks links = s.border_links();
  const std::vector<int>&next = links.next, &prev = links.prev;
  const std::vector<std::array<int, 2>>& border = links.edges;
  if (border.empty() || !(max_width > 0)) return 0;
  // Border edges in a hash grid: each edge is entered in the cells of points along it, half a
  // cell apart, so a point within max_width <= cell of the edge has such a point within 1.25
  // cells, at most two cells away on each axis. The cell grows with the border's mean edge so
  // that the points number at most 32 per edge (bounded work on edges far longer than L).
  double length = 0;
  for (const auto& e : border) length += (s.pos[e[1]] - s.pos[e[0]]).norm();
  const double cell = std::max(max_width, length / (32.0 * static_cast<double>(border.size())));
  kernel::CellLists grid;
  for (int e = 0; e < static_cast<int>(border.size()); ++e) {
    const Vec3 &p = s.pos[border[e][0]], &q = s.pos[border[e][1]];
    const int steps = static_cast<int>(std::ceil((q - p).norm() / (0.5 * cell)));
    for (int k = 0; k <= steps; ++k) {
      auto& list = grid[kernel::cell_key(p + (steps ? double(k) / steps : 0.0) * (q - p), cell)];
      if (list.empty() || list.back() != e) list.push_back(e);
    }
  }
  auto along_border = [&](int from, int to) {
    for (const std::vector<int>* step : {&next, &prev}) {
      double arc = 0;
      for (int cur = from, k = 0; k < 1000 && arc <= reach; ++k) {
        const int n = (*step)[cur];
        if (n < 0 || n == from) break;
        arc += (s.pos[n] - s.pos[cur]).norm();
        if (n == to) return arc <= reach;
        cur = n;
      }
    }
    return false;
  };
  std::vector<int> necks;
  for (int c = 0; c < nv; ++c) {
    if (next[c] < 0 || prev[c] < 0) continue;
    // Faces lie left of the directed border: n x t points into the surface.
    const Vec3 inward = s.normal_at(c).cross(s.pos[next[c]] - s.pos[prev[c]]);
    const Vec3& p = s.pos[c];
    const auto k = kernel::cell_of(p, cell);
    bool neck = false;
    for (std::int64_t x = k[0] - 2; x <= k[0] + 2 && !neck; ++x)
      for (std::int64_t y = k[1] - 2; y <= k[1] + 2 && !neck; ++y)
        for (std::int64_t z = k[2] - 2; z <= k[2] + 2 && !neck; ++z) {
          const std::vector<int>* list = grid.find(kernel::pack_cell(x, y, z));
          if (!list) continue;
          for (int e : *list) {
            const int a = border[e][0], b = border[e][1];
            if (a == c || b == c) continue;
            const double u = kernel::closest_segment_parameter(p, s.pos[a], s.pos[b]);
            const Vec3 across = s.pos[a] + u * (s.pos[b] - s.pos[a]) - p;
            if (across.norm() >= max_width || across.dot(inward) <= 0) continue;
            if (along_border(c, a) || along_border(c, b)) continue;
            neck = true;
            break;
          }
        }
    if (neck) necks.push_back(c);
  }
  return s.kill_faces_at(necks);
}

// Removes every live face among `candidates` for which `peel(f)` holds, and after each removal
// looks again at the live faces around its corners (a removal exposes the next face of a strip
// or an ear). First in, first out; returns the number removed.
template <class Peel>
std::size_t peel_faces(Surface& s, const std::vector<int>& candidates, Peel&& peel) {
  std::deque<int> queue(candidates.begin(), candidates.end());
  std::size_t removed = 0;
  while (!queue.empty()) {
    const int f = queue.front();
    queue.pop_front();
    if (!s.alive[f] || !peel(f)) continue;
    s.kill(f);
    ++removed;
    for (int c : s.tri[f])
      for (int g : s.vf[c])
        if (s.alive[g]) queue.push_back(g);
  }
  return removed;
}

// Veils: faces along the border that are thinner than `max_height` over their border edge and
// at least four times longer than thick. A range scan's grid mesh spans a depth jump one row
// high with such faces (5.8 x 0.45 mm on the demo head's ear); the output, its edges ~4 x
// max_height long, can only follow them with needles. Removed face by face, each exposing the
// next one of the strip. A regular border row (0.45 x 1.1 mm cells) is not thin in this sense.
std::size_t remove_veils(Surface& s, double max_height, const std::vector<int>& candidates) {
  return peel_faces(s, candidates, [&](int f) {
    const auto& t = s.tri[f];
    bool thin = false;
    for (int i = 0; i < 3 && !thin; ++i) {
      const int a = t[i], b = t[(i + 1) % 3], c = t[(i + 2) % 3];
      if (s.edge_count(a, b) != 1) continue;
      const Vec3 ab = s.pos[b] - s.pos[a];
      const double length = ab.norm();
      if (!(length > 0)) continue;
      const double height = ab.cross(s.pos[c] - s.pos[a]).norm() / length;
      thin = height < max_height && 4 * height < length;
    }
    return thin;
  });
}

void remove_spikes(Surface& s, double tip_reach, double tip_angle, PrepareStats& st) {
  // Repeated until nothing changes. A vertex can become a pinch, and a face an ear or a veil,
  // only where a face was removed since the last look: after the first round only those are
  // looked at again (the 40 rounds of the demo head, a handful of faces each, were full passes;
  // every step is a closure, so the result is the same).
  std::vector<int> all_faces, all_vertices(s.pos.size());
  for (int f = 0; f < static_cast<int>(s.tri.size()); ++f)
    if (s.alive[f]) all_faces.push_back(f);
  for (int v = 0; v < static_cast<int>(s.pos.size()); ++v) all_vertices[v] = v;
  std::size_t pinch_seen = 0, ear_seen = 0, veil_seen = 0;
  for (int round = 0; round < 100; ++round) {
    // Pinch vertices: keep the largest fan (faces connected across edges at the vertex).
    std::size_t pinched = 0;
    const std::vector<int> pinch_candidates =
        round == 0 ? all_vertices : s.corners_of_killed(pinch_seen);
    pinch_seen = s.killed.size();
    for (int v : pinch_candidates) {
      std::vector<int> fs;
      for (int f : s.vf[v])
        if (s.alive[f]) fs.push_back(f);
      std::sort(fs.begin(), fs.end());
      for (int f : kernel::faces_off_largest_wedge(s.tri, fs, v)) {
        s.kill(f);
        ++st.pinch_faces_removed;
        ++pinched;
      }
    }
    // Ears: faces with two or three boundary edges, until none is left.
    const std::vector<int> ear_candidates = round == 0 ? all_faces : s.faces_near_killed(ear_seen);
    const std::size_t eaten = peel_faces(s, ear_candidates, [&](int f) {
      const auto& t = s.tri[f];
      int boundary = 0;
      for (int i = 0; i < 3; ++i) boundary += s.edge_count(t[i], t[(i + 1) % 3]) == 1;
      return boundary >= 2;
    });
    ear_seen = s.killed.size();
    st.spike_faces_removed += eaten;
    const std::size_t tipped = tip_reach > 0 ? remove_tips(s, tip_reach, tip_angle) : 0;
    st.tip_faces_removed += tipped;
    // A triangle across a neck of width w with its base on one side (at least the collapse
    // bound 0.8 L long) has an angle of at most atan(2 w / 0.8 L): under 32 deg for w = L / 4.
    std::size_t opened = 0;
    if (tip_reach > 0) {
      opened += remove_necks(s, 0.25 * tip_reach, tip_reach);
      const std::vector<int> veil_candidates =
          round == 0 ? all_faces : s.faces_near_killed(veil_seen);
      veil_seen = s.killed.size();
      opened += remove_veils(s, 0.25 * tip_reach, veil_candidates);
    }
    st.neck_faces_removed += opened;
    if (pinched == 0 && tipped == 0 && opened == 0) break;
  }
}

double triangle_area(const Mesh& m, const std::array<int, 3>& t) {
  return 0.5 * (m.positions[t[1]] - m.positions[t[0]])
                   .cross(m.positions[t[2]] - m.positions[t[0]])
                   .norm();
}

}  // namespace

double uniform_edge_length(const Mesh& mesh, int vertices) {
  return std::sqrt(surface_area(mesh) / (std::sqrt(3.0) / 2 * std::max(vertices, 1)));
}

bool looks_like_scan(const TopologyStats& ts) {
  return ts.boundary_loops > kScanLoops || ts.components > kScanComponents ||
         ts.border_ears > kScanEars;
}

bool looks_like_scan(const Mesh& mesh) { return looks_like_scan(topology_stats(mesh)); }

PrepareOptions scan_prepare_options(const Mesh& mesh, int target_vertices) {
  const double edge = uniform_edge_length(mesh, target_vertices);
  return {.min_component_area = 10 * edge * edge,
          .max_hole_perimeter = 10 * edge,
          .needle_angle_deg = 5,
          .remove_spikes = true,
          .tip_reach_mm = edge,
          .tip_angle_deg = 120};
}

Mesh prepare_input(const Mesh& original, const PrepareOptions& o, PrepareStats* stats) {
  PrepareStats st;
  Mesh repaired;
  if (o.needle_angle_deg > 0 || o.remove_spikes) {
    Surface s(original);
    if (o.needle_angle_deg > 0)
      for (int pass = 0; pass < 3; ++pass)
        repair_needles(s, o.needle_angle_deg * std::numbers::pi / 180, st);
    if (o.remove_spikes)
      remove_spikes(s, o.tip_reach_mm, o.tip_angle_deg * std::numbers::pi / 180, st);
    repaired = s.to_mesh();
  }
  const Mesh& in = (o.needle_angle_deg > 0 || o.remove_spikes) ? repaired : original;
  const int nv = static_cast<int>(in.positions.size());
  const int nf = static_cast<int>(in.triangles.size());
  std::vector<char> keep(nf, 1);
  // Always: a face whose corners are those of an earlier face (a copy, or an STL's repeated
  // facet) is dropped. Copies stack non-manifold edges that the remesher keeps as seams, and
  // ten copies of one triangle kept its polish busy for half a minute.
  const std::vector<char> repeats = faces_repeating_earlier_geometry(in);
  for (int f = 0; f < nf; ++f)
    if (repeats[f]) keep[f] = 0, ++st.repeated_faces_removed;
  if (o.min_component_faces > 0 || o.min_component_area > 0) {
    // Components by shared vertices (union-find).
    kernel::VertexComponents components(nv);
    for (int f = 0; f < nf; ++f)
      if (keep[f]) components.join(in.triangles[f]);
    std::unordered_map<int, int> size;
    std::unordered_map<int, double> area;
    for (int f = 0; f < nf; ++f) {
      if (!keep[f]) continue;
      const int r = components.root(in.triangles[f][0]);
      ++size[r];
      area[r] += triangle_area(in, in.triangles[f]);
    }
    std::unordered_map<int, char> counted;
    for (int f = 0; f < nf; ++f) {
      if (!keep[f]) continue;
      const int r = components.root(in.triangles[f][0]);
      if (size[r] < o.min_component_faces || area[r] < o.min_component_area) {
        keep[f] = 0;
        ++st.faces_removed;
        if (!counted[r]) {
          counted[r] = 1;
          ++st.components_removed;
        }
      }
    }
  }
  Mesh out = kept_faces(in.positions, in.triangles, keep, in.face_labels);
  if (o.max_hole_edges > 0 || o.max_hole_perimeter > 0) {
    const int longest_walk =
        std::max(o.max_hole_edges, o.max_hole_perimeter > 0 ? kMaxHolePatchEdges : 0);
    // A loop is closed when it is short in edges or in length.
    auto small_hole = [&](const std::vector<int>& loop) {
      if (static_cast<int>(loop.size()) <= o.max_hole_edges) return true;
      double perimeter = 0;
      for (std::size_t i = 0; i < loop.size(); ++i)
        perimeter += (out.positions[loop[(i + 1) % loop.size()]] - out.positions[loop[i]]).norm();
      return perimeter <= o.max_hole_perimeter;
    };
    // Directed boundary edges a -> b (as in their face) with the face label.
    std::map<std::pair<int, int>, int> count;
    for (const auto& t : out.triangles)
      for (int i = 0; i < 3; ++i) {
        const int a = t[i], b = t[(i + 1) % 3];
        ++count[{std::min(a, b), std::max(a, b)}];
      }
    std::unordered_map<int, std::vector<std::pair<int, int>>> out_edges;  // a -> (b, label)
    for (std::size_t f = 0; f < out.triangles.size(); ++f) {
      const auto& t = out.triangles[f];
      for (int i = 0; i < 3; ++i) {
        const int a = t[i], b = t[(i + 1) % 3];
        if (count[{std::min(a, b), std::max(a, b)}] == 1)
          out_edges[a].push_back({b, out.face_labels[f]});
      }
    }
    std::vector<int> starts;
    for (const auto& [a, e] : out_edges) starts.push_back(a);
    std::sort(starts.begin(), starts.end());
    std::unordered_map<int, char> used;
    for (int a0 : starts) {
      if (used[a0] || out_edges[a0].size() != 1) continue;
      std::vector<int> loop = {a0};
      int lab = out_edges[a0][0].second;
      int cur = out_edges[a0][0].first;
      bool ok = true;
      while (cur != a0) {
        auto it = out_edges.find(cur);
        if (it == out_edges.end() || it->second.size() != 1 || used[cur] ||
            static_cast<int>(loop.size()) > longest_walk) {
          ok = false;
          break;
        }
        loop.push_back(cur);
        cur = it->second[0].first;
      }
      for (int v : loop) used[v] = 1;
      if (!ok || loop.size() < 3 || !small_hole(loop)) continue;
      std::vector<Eigen::Vector3d> corners;
      for (int v : loop) corners.push_back(out.positions[v]);
      // Loop vertices already joined by an edge outside the hole (an edge with a face).
      auto joined = [&](int i, int j) {
        const auto it = count.find({std::min(loop[i], loop[j]), std::max(loop[i], loop[j])});
        return it != count.end() && it->second > 0;
      };
      const detail::HolePatch patch = detail::fill_hole(corners, joined);
      const int base = static_cast<int>(out.positions.size());
      out.positions.insert(out.positions.end(), patch.new_points.begin(), patch.new_points.end());
      const int n_loop = static_cast<int>(loop.size());
      auto vertex = [&](int k) { return k < n_loop ? loop[k] : base + (k - n_loop); };
      for (const auto& t : patch.triangles) {
        out.triangles.push_back({vertex(t[0]), vertex(t[1]), vertex(t[2])});
        out.face_labels.push_back(lab);
        ++st.faces_added;
      }
      ++st.holes_filled;
    }
  }
  if (stats) *stats = st;
  return out;
}

}  // namespace scanmesh::remeshing
