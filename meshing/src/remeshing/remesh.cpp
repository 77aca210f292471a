// Seed 001 remesher: link to the input, local operations with E_dist / E_glatt checks and undo,
// skeleton rules and density control, the schemes. docs/remeshing.md.
#include "scanmesh/meshing/remeshing/remesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <numbers>
#include <queue>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::remeshing {

RemeshScheme parse_remesh_scheme(const std::string& name) {
  if (name == "regularize") return RemeshScheme::Regularize;
  if (name == "lloyd") return RemeshScheme::Lloyd;
  throw InvalidInputError("unknown remesh scheme '" + name + "' (expected regularize or lloyd)");
}

std::string to_string(RemeshScheme s) {
  return s == RemeshScheme::Regularize ? "regularize" : "lloyd";
}

namespace {

using Vec3 = Eigen::Vector3d;

// The length rules of the adapt rounds (§3.4), in target lengths h: edges longer than
// kSplitAbove are split, edges shorter than kCollapseBelow collapsed.
constexpr double kSplitAbove = 4.0 / 3.0;
constexpr double kCollapseBelow = 0.8;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5);
// returns the barycentric coordinates.
Vec3 closest_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

// Sets a pointer member back to null when the scope that pointed it somewhere ends, on every
// exit (the drive's stamp journal, the drive rounds' flip record).
// (A constructor, not an aggregate: clang 14 deduces T from constructors only.)
template <class T>
struct ClearOnExit {
  explicit ClearOnExit(T*& p) : pointer(p) {}
  ~ClearOnExit() { pointer = nullptr; }
  T*& pointer;
};

struct VState {
  VertexKind kind = VertexKind::Free;
  int seg = -1;        // skeleton: segment of the input skeleton
  double s = 0;        // skeleton: arc length on the segment
  int inp = -1;        // branch: input vertex
  int iface = -1;      // free: input face of the projection
  Vec3 bary{1, 0, 0};  // free: barycentric coordinates in iface
  double sq = 1;       // sqrt(Psi) at the vertex
  Vec3 normal = Vec3::Zero();  // free: the input's normal there (face_ok asks ~20 times a move)
};

class Remesher {
 public:
  Remesher(const Mesh& input, const RemeshOptions& o)
      : o_(o), input_(input), m0_(input, "remesh") {}

  RemeshResult run();

 private:
  // ---- the phases of run(), in order ----
  void check_options() const;
  void set_up();             // input, skeleton, density, defect zone; M := M0
  void copy_input_states();  // M's vertex states from M0 and its skeleton
  void adapt_phase();        // count and density: split / collapse / flip / relax rounds
  void area_phase();         // §3.4: area-based moves and Delaunay flips at the exact count
  void regularize_phase();   // valence regularisation (or the Voronoi rounds of --scheme lloyd)
  void smooth_phase();       // angle-based smoothing, angle polish, crossing repair
  RemeshResult result();     // the output mesh with its per-vertex kinds and statistics

  // ---- setup ----
  void build_input();
  // ---- where the input cuts itself ----
  // Input faces within `reach` (along the input's edges) of an input face that cuts another
  // input face. The input is no surface there: its normals fold over, so E_glatt / E_dist
  // refuse every operation and the local-intersection test every move that keeps the input's
  // own crossing (mannequin-devil: 0.03 deg needles left as they came). Inside the zone the
  // operations are checked only for degenerate faces, as CGAL's remeshing checks them
  // everywhere; elsewhere nothing changes. `crossing` holds the input's intersecting pairs.
  void mark_defect_zone(const std::vector<std::array<int, 2>>& crossing, double reach);
  bool in_defect_zone(int v) const {
    if (zone_face_.empty()) return false;
    const VState& st = vs_[v];
    if (st.kind == VertexKind::Free) return st.iface >= 0 && zone_face_[st.iface] != 0;
    return st.kind == VertexKind::Branch && zone_vertex_[st.inp] != 0;
  }
  bool face_in_defect_zone(int f) const {
    const auto& t = m_.tri[f];
    return in_defect_zone(t[0]) || in_defect_zone(t[1]) || in_defect_zone(t[2]);
  }
  // ---- link to the input ----
  Vec3 input_point(int f, const Vec3& b) const {
    const auto& t = m0_.tri[f];
    return b[0] * m0_.pos[t[0]] + b[1] * m0_.pos[t[1]] + b[2] * m0_.pos[t[2]];
  }
  // Walks over faces of the same patch toward the closest point to x (local minimum).
  void project(const Vec3& x, int& face, Vec3& bary) const;
  int input_face_on_patch_at_edge(int a, int b, int patch) const;
  int input_face_on_patch_at_vertex(int u, int patch) const;
  Vec3 corner_normal(int v, int patch) const;
  Vec3 free_normal(const VState& st) const {  // zero for other kinds
    if (st.kind != VertexKind::Free || st.iface < 0) return Vec3::Zero();
    const auto& c = cn_[st.iface];
    return (st.bary[0] * c[0] + st.bary[1] * c[1] + st.bary[2] * c[2]).normalized();
  }
  double sq_of(const VState& st) const;
  Vec3 position_of(const VState& st) const;
  // Parameter of vertex x on segment seg, near `near_s` (a branch vertex may sit at either end).
  double param_on(int x, int seg, double near_s) const;
  int start_face(int v, int patch) const;

  // ---- mesh helpers ----
  int add_vertex(const VState& st) {
    const int v = m_.add_vertex(position_of(st));
    vs_.push_back(st);
    vs_.back().sq = sq_of(st);
    vs_.back().normal = free_normal(st);
    return v;
  }
  void set_state(int v, const VState& st) {
    vs_[v] = st;
    vs_[v].sq = sq_of(st);
    vs_[v].normal = free_normal(st);
    m_.pos[v] = position_of(st);
  }
  // A skeleton edge joins two skeleton or branch vertices: a free end answers without the
  // hash look-up (the sweeps ask for every edge, tens of times).
  bool is_skel(int v, int w) const {
    if (vs_[v].kind == VertexKind::Free || vs_[w].kind == VertexKind::Free) return false;
    return sedge_.count(edge_key(v, w)) != 0;
  }
  double target(int v, int w) const { return scale_ * 0.5 * (vs_[v].sq + vs_[w].sq); }
  bool face_ok(int f) const;
  bool faces_ok(std::span<const int> fs) const {
    for (int f : fs)
      if (!face_ok(f)) return false;
    return !embed_check_ || locally_embedded(fs);
  }
  // No changed face intersects a live face at one of its corners: prevents
  // folds and local self-intersections instead of repairing them afterwards.
  bool locally_embedded(std::span<const int> fs) const;
  // A face near a changed one, with what the pair tests need of it.
  struct NearFace {
    int face;
    std::array<int, 3> corners;
    Vec3 lo, hi, normal;  // box; (p1 - p0) x (p2 - p0)
    double length;        // |normal|
    bool in_zone;         // a corner in the input's defect zone
  };
  // True when faces t and u, which share `shared` corners, provably do not intersect.
  bool cannot_meet(const NearFace& t, const NearFace& u, int shared) const;
  std::vector<int> fan(int v, int f) const;  // faces of v's side containing f
  int side_valence(int v, int f) const { return static_cast<int>(fan(v, f).size()) - 1; }
  int deviation(int v, int f) const;  // valence minus optimum (0 for branch)
  bool ordered_ring(int v, std::vector<int>& ring) const;
  Vec3 vertex_normal(int v) const;

  // ---- operations (return true when applied) ----
  bool collapse(int v, int w);  // removes v
  int split(int v, int w);      // returns the new vertex or -1
  bool flip(int v, int w, bool check = true);
  int flip_delta(int v, int w) const;  // change of R (3.22) by flipping, 1000 if impossible
  // True when no edge (c, z), z in `ring` (c's neighbours), has flip_delta < 0, known from the
  // valences alone; false when it cannot tell.
  bool no_valence_flip_at(int c, const NeighbourList& ring) const;
  bool drive(int b, int w, int side);
  std::array<int, 2> last_flip_{-1, -1};        // the edge the last flip made
  std::array<int, 2> last_flip_faces_{-1, -1};  // and its two faces
  // While set, every flip made appends (edge removed, edge made): the drive rounds keep their
  // edge list up to date from it instead of listing every edge again.
  std::vector<std::array<std::uint64_t, 2>>* flip_record_ = nullptr;
  // `sorted` (all edges, sorted) after the recorded flips.
  static std::vector<std::uint64_t> edges_after_flips(
      const std::vector<std::uint64_t>& sorted,
      const std::vector<std::array<std::uint64_t, 2>>& flips);
  bool try_state(int v, const VState& ns);  // move v to ns if its star stays valid
  bool move_to(int v, const Vec3& x);       // free vertex, 3D target (projected)
  bool move_skeleton(int v, double s_new);  // skeleton vertex, 1D
  bool flip_improves_valence(int v, int w) const;
  bool flip_improves_angle(int v, int w) const;

  // ---- phases ----
  void split_long();
  void collapse_short();
  int flip_pass(bool delaunay);
  int flip_queue();  // simple-edge flips, worst valence deviation first
  // What the last finished flip sweep of a kind left: every edge's answer as of clock `at`
  // under these bounds (not valid: the sweep stopped at its pass limit).
  struct FlipSweepMemory {
    bool valid = false;
    std::uint64_t at = 0;
    double cos_glatt = 0, cos_dist = 0;
  };
  FlipSweepMemory valence_sweep_, angle_sweep_;
  // Edges of the faces at vertices stamped after `at`, sorted.
  std::vector<std::uint64_t> edges_near_changes_since(std::uint64_t at) const;
  // Edges of the faces at these vertices, sorted, each once.
  std::vector<std::uint64_t> face_edges_at(const std::vector<int>& vertices) const;
  template <class Consider>
  int incremental_first_sweep(const std::vector<std::uint64_t>& dirty, Consider& consider,
                              std::vector<int>& touched);
  int simple_flips() { return o_.regularize_queue ? flip_queue() : flip_pass(false); }
  // Where a free vertex is moved by one relaxation pass.
  enum class Relax {
    StarCentroid,     // density-weighted centroid of the star's triangles (§3.4 area moves)
    AngleBased,       // Zhou-Shimada angle-based smoothing (§3.5)
    VoronoiCentroid,  // centroid of the vertex's Voronoi cell in its star (Lloyd, §3.6)
  };
  void relax_pass(Relax how);
  // ---- what a relaxation pass may skip ----
  // A vertex's relaxed target depends on its position and state and on those of its ring; the
  // outcome of a move there, on the faces at its ring too. note_change(v) stamps v and its ring
  // after anything changed at v (a move, a face at v changed, or a face list reordered by an
  // undone operation). A vertex found settled, or whose move was refused, is skipped by the
  // next passes until a stamp around it is newer than that finding: it would compute the same
  // target and get the same answer, so the output is the same as without skipping.
  //
  // The flip sweeps ask less: only whether anything but the order of a face list changed
  // (Change::Altered, stamped into altered_at_ as well). An undone flip or split leaves the
  // same faces and positions (Change::Reordered); an undone collapse may round a position anew
  // and counts as altered.
  enum class Finding : std::uint8_t { None, Settled, Refused };
  enum class Change { Altered, Reordered };
  void note_change(int v, Change change = Change::Altered) {
    if (changed_at_.size() < m_.pos.size()) {
      changed_at_.resize(m_.pos.size(), 0);
      altered_at_.resize(m_.pos.size(), 0);
    }
    ++clock_;
    auto stamp = [&](int x) {
      changed_at_[x] = clock_;
      if (change != Change::Altered) return;
      if (altered_journal_) altered_journal_->push_back({x, altered_at_[x]});
      altered_at_[x] = clock_;
    };
    stamp(v);
    for (int f : m_.vfaces[v])
      for (int x : m_.tri[f]) stamp(x);
  }
  bool finding_holds(int v) const;
  void remember(int v, Finding f);
  Vec3 voronoi_centroid(int v, const std::vector<int>& ring) const;
  void skeleton_relax_pass();
  // The two skeleton neighbours a, b of skeleton vertex v and their parameters sa < s(v) < sb
  // on v's segment; false when v is not strictly between two (a segment end).
  bool skeleton_bounds(int v, int& a, int& b, double& sa, double& sb) const;
  // `passes` x (free vertices: centroidal or angle-based move, skeleton vertices: 1D move).
  void relax_rounds(int passes, Relax how) {
    for (int k = 0; k < passes; ++k) {
      relax_pass(how);
      skeleton_relax_pass();
    }
  }
  void skeleton_density_control();
  // Which edges adjust_count changes first.
  enum class CountOrder { Length, ValenceFirst };
  void adjust_count(CountOrder order = CountOrder::Length);
  // The change of R (3.22) by collapsing v into w / splitting (v, w); kNotJudged where the
  // simple count does not apply (skeleton ends, seams).
  static constexpr int kNotJudged = 1000;
  int collapse_valence_change(int v, int w) const;
  int split_valence_change(int v, int w) const;
  // The regularised count adjustment may leave edges up to this many target lengths at the
  // survivor (1.6 kept the >= 30 deg share of the corpus and the demo head where the split
  // bound 4/3 let the count adjustment fall back to length order more often; measured).
  static constexpr double kLongAfterCollapse = 1.6;
  // (4.5) splits no skeleton edge shorter than the collapse bound (0.8 target lengths).
  bool too_short_to_split(int v, int w) const {
    return (m_.pos[v] - m_.pos[w]).norm() < kCollapseBelow * target(v, w);
  }
  // Whether collapse(v, w) would leave an edge longer than `bound` target lengths at w: among
  // v's edges alone (collapse_short, bound 4/3) or also w's own (the count adjustment).
  enum class CollapseEnds { RemovedOnly, Both };
  bool collapse_makes_long_edge(int v, int w, double bound, CollapseEnds ends) const;
  // Valence flips of the edges at u's ring vertices; with Spokes::Excluded not the ring's
  // edges to u itself (regularize's order after its splits).
  enum class Spokes { Included, Excluded };
  void flips_around(int u, Spokes spokes = Spokes::Included);
  void regularize();
  // Simple flips, then up to `rounds` sweeps of §3.8 drive edges; the vertex count stays.
  void drive_dipoles(int rounds = 10);
  std::vector<int> intersecting_faces() const;
  void repair_intersections();
  // ---- angle polish (after the smoothing; not in the seed) ----
  double face_min_angle(int f) const;  // radians
  double star_min_angle(int v) const;
  bool raise_star_min_angle(int v);          // pattern search on the surface / the segment
  bool flip_raises_min_angle(int v, int w);  // applied when it does, at a bounded valence cost
  void polish_angles();
  std::vector<int> faces_below(double limit) const;  // live faces, min angle under limit
  //! Up to `rounds` rounds of star moves and angle flips over the faces with a min angle below
  //! `limit` (rad); returns how many are left.
  std::size_t polish_below(double limit, int rounds);
  void report(const std::string& phase, double f) const {
    if (o_.progress) o_.progress(phase, f);
  }

  RemeshOptions o_;
  const Mesh& input_;
  TriangleMesh m0_;
  FeatureSkeleton sk_;
  std::vector<double> psi0_, sq0_;
  std::vector<std::array<Vec3, 3>> cn_;  // per input face: per-patch corner normals
  std::vector<Vec3> fn0_;
  // Per input face: a ball holding it (centroid, farthest corner). The projection walk skips
  // a face whose ball lies farther from x than the best foot found so far.
  std::vector<std::pair<Vec3, double>> face_ball_;
  bool farther_than(int f, const Vec3& x, double best_squared) const {
    const auto& [centre, radius] = face_ball_[f];
    const double to_centre = (x - centre).norm();
    // Slack for rounding: skipping must never drop a face the exact test would take.
    const double gap = to_centre - radius - 1e-9 * (to_centre + radius);
    return gap > 0 && gap * gap > best_squared;
  }
  TriangleMesh m_;
  std::vector<VState> vs_;
  std::vector<int> patch_;
  std::unordered_map<std::uint64_t, int> sedge_;  // skeleton edges of M -> segment
  std::vector<int> seg_edges_;                    // M edges per segment
  double scale_ = 1;
  double cos_dist_ = 0, cos_glatt_ = 0;
  // locally_embedded is checked from the vertex-count phase on: in the adapt phase the mesh is
  // still the dense input, where it doubled the run time and refused nothing (measured).
  bool embed_check_ = false;
  mutable std::vector<NearFace> near_;   // locally_embedded's scratch
  std::uint64_t clock_ = 0;                // counts note_change calls
  std::vector<std::uint64_t> changed_at_;  // per vertex: clock of the last change at or next to it
  std::vector<std::uint64_t> altered_at_;  // the same for Change::Altered alone
  // While a drive is tried: the altered_at_ stamps it overwrote, to put back when it is undone
  // (its flips and their undoing leave the mesh as it was).
  std::vector<std::pair<int, std::uint64_t>>* altered_journal_ = nullptr;
  struct Verdict {
    Finding finding = Finding::None;
    std::uint64_t at = 0;  // clock when found
    std::uint64_t settings = 0;
  };
  std::vector<Verdict> verdicts_;  // per vertex
  // Findings hold only under the settings they were made with (mode, scale, bounds): a
  // relaxation pass with other settings starts a new generation.
  std::uint64_t settings_generation_ = 0;
  std::tuple<int, double, double, double, bool> last_settings_{-1, 0, 0, 0, false};
  mutable std::vector<std::pair<int, int>> ring_scratch_;  // ordered_ring's
  mutable std::vector<unsigned> walk_mark_;  // per input face: the walk of project() that met it
  mutable unsigned walk_stamp_ = 0;
  mutable std::vector<int> face_mark_;   // per face: its place in near_, or -1
  std::vector<char> zone_face_, zone_vertex_;  // per input face / vertex; empty: no zone
  double uniform_edge_ = 0;                    // of a uniform mesh with the target count
  RemeshStats st_;
};

void Remesher::build_input() {
  // Mean edge length of a uniform mesh with the requested vertex count: F ~ 2 V faces of
  // area sqrt(3)/4 h^2. The scale of the kink rule and of the curvature fit.
  const double uniform_edge = uniform_edge_length(input_, o_.target_vertices);
  uniform_edge_ = uniform_edge;
  SkeletonOptions so = o_.skeleton;
  if (so.kink_reach_mm <= 0) so.kink_reach_mm = uniform_edge;
  sk_ = build_feature_skeleton(m0_, o_.features, so);
  DensityOptions density = o_.density;
  if (density.curvature_radius < 0) density.curvature_radius = uniform_edge;
  psi0_ = compute_density(m0_, density);
  if (density.gamma != 0 || !density.user.empty())
    limit_gradation(m0_, psi0_, o_.target_vertices, density.gradation);
  sq0_.resize(psi0_.size());
  for (std::size_t i = 0; i < psi0_.size(); ++i) sq0_[i] = std::sqrt(psi0_[i]);
  const int nf = static_cast<int>(m0_.tri.size());
  fn0_.resize(nf);
  for (int f = 0; f < nf; ++f) fn0_[f] = m0_.face_normal(f);
  face_ball_.resize(nf);
  for (int f = 0; f < nf; ++f) {
    const auto& t = m0_.tri[f];
    const Vec3 c = (m0_.pos[t[0]] + m0_.pos[t[1]] + m0_.pos[t[2]]) / 3.0;
    double r = 0;
    for (int i : t) r = std::max(r, (m0_.pos[i] - c).norm());
    face_ball_[f] = {c, r};
  }
  // Angle-weighted vertex normals per (vertex, patch): a skeleton vertex has one per side.
  cn_.assign(nf, {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
  for (int v = 0; v < static_cast<int>(m0_.pos.size()); ++v) {
    const auto& fs = m0_.vfaces[v];
    std::vector<std::pair<int, Vec3>> acc;
    for (int f : fs) {
      const auto& t = m0_.tri[f];
      const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      const Vec3 e1 = (m0_.pos[t[(i + 1) % 3]] - m0_.pos[v]).normalized();
      const Vec3 e2 = (m0_.pos[t[(i + 2) % 3]] - m0_.pos[v]).normalized();
      const double ang = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
      const int p = sk_.face_patch[f];
      auto it = std::find_if(acc.begin(), acc.end(), [&](const auto& a) { return a.first == p; });
      if (it == acc.end())
        acc.push_back({p, ang * fn0_[f]});
      else
        it->second += ang * fn0_[f];
    }
    for (int f : fs) {
      const auto& t = m0_.tri[f];
      const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      const int p = sk_.face_patch[f];
      for (const auto& a : acc)
        if (a.first == p) cn_[f][i] = a.second.norm() > 0 ? Vec3(a.second.normalized()) : fn0_[f];
    }
  }
}

void Remesher::mark_defect_zone(const std::vector<std::array<int, 2>>& crossing, double reach) {
  st_.input_intersecting_faces = 0;
  if (crossing.empty()) return;
  const int nv = static_cast<int>(m0_.pos.size());
  // Distance along the input's edges from the crossing faces' corners (Dijkstra, cut at reach).
  std::vector<double> dist(nv, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  std::vector<char> crossing_face(m0_.tri.size(), 0);
  for (const auto& pair : crossing)
    for (int f : pair) crossing_face[f] = 1;
  for (std::size_t f = 0; f < crossing_face.size(); ++f) {
    if (!crossing_face[f]) continue;
    ++st_.input_intersecting_faces;
    for (int c : m0_.tri[f])
      if (dist[c] > 0) dist[c] = 0, queue.push({0.0, c});
  }
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    for (int w : m0_.neighbours(v)) {
      const double dw = d + (m0_.pos[w] - m0_.pos[v]).norm();
      if (dw <= reach && dw < dist[w]) dist[w] = dw, queue.push({dw, w});
    }
  }
  zone_vertex_.assign(nv, 0);
  for (int v = 0; v < nv; ++v) zone_vertex_[v] = dist[v] <= reach;
  zone_face_.assign(m0_.tri.size(), 0);
  for (std::size_t f = 0; f < m0_.tri.size(); ++f) {
    const auto& t = m0_.tri[f];
    zone_face_[f] = zone_vertex_[t[0]] || zone_vertex_[t[1]] || zone_vertex_[t[2]];
    st_.input_defect_zone_faces += zone_face_[f];
  }
}

void Remesher::project(const Vec3& x, int& face, Vec3& bary) const {
  // Each input face is evaluated once per walk: a face met again (around a second corner, or
  // in a later step) cannot beat the best found since, so skipping it changes nothing.
  if (walk_mark_.size() < m0_.tri.size()) walk_mark_.resize(m0_.tri.size(), 0);
  if (++walk_stamp_ == 0) {  // wrapped: forget every old mark
    std::fill(walk_mark_.begin(), walk_mark_.end(), 0);
    walk_stamp_ = 1;
  }
  const int patch = sk_.face_patch[face];
  auto eval = [&](int f, Vec3& b) {
    const auto& t = m0_.tri[f];
    b = closest_barycentric(x, m0_.pos[t[0]], m0_.pos[t[1]], m0_.pos[t[2]]);
    return (input_point(f, b) - x).squaredNorm();
  };
  Vec3 b;
  double best = eval(face, b);
  walk_mark_[face] = walk_stamp_;
  bary = b;
  for (int step = 0; step < 10000; ++step) {
    int next = -1;
    Vec3 nb;
    for (int c : m0_.tri[face])
      for (int g : m0_.vfaces[c]) {
        if (walk_mark_[g] == walk_stamp_ || sk_.face_patch[g] != patch) continue;
        walk_mark_[g] = walk_stamp_;
        if (farther_than(g, x, best)) continue;
        const double d = eval(g, b);
        if (d < best * (1 - 1e-12) - 1e-18) {
          best = d;
          next = g;
          nb = b;
        }
      }
    if (next < 0) return;
    face = next;
    bary = nb;
  }
}

int Remesher::input_face_on_patch_at_edge(int a, int b, int patch) const {
  for (int f : m0_.vfaces[a]) {
    const auto& t = m0_.tri[f];
    if ((t[0] == b || t[1] == b || t[2] == b) && sk_.face_patch[f] == patch) return f;
  }
  return -1;
}

int Remesher::input_face_on_patch_at_vertex(int u, int patch) const {
  for (int f : m0_.vfaces[u])
    if (sk_.face_patch[f] == patch) return f;
  return -1;
}

Vec3 Remesher::corner_normal(int v, int patch) const {
  const VState& st = vs_[v];
  auto at = [&](int f, int u) {
    const auto& t = m0_.tri[f];
    return cn_[f][t[0] == u ? 0 : (t[1] == u ? 1 : 2)];
  };
  if (st.kind == VertexKind::Free) return st.normal;
  if (st.kind == VertexKind::Branch) {
    const int f = input_face_on_patch_at_vertex(st.inp, patch);
    return f >= 0 ? at(f, st.inp) : Vec3::Zero();
  }
  int e = 0;
  double t = 0;
  sk_.point(m0_.pos, st.seg, st.s, &e, &t);
  const auto& sg = sk_.segments[st.seg];
  const int a = sg.vertices[e], b = sg.vertices[e + 1];
  const int f = input_face_on_patch_at_edge(a, b, patch);
  if (f < 0) return Vec3::Zero();
  return ((1 - t) * at(f, a) + t * at(f, b)).normalized();
}

double Remesher::sq_of(const VState& st) const {
  if (st.kind == VertexKind::Free) {
    const auto& t = m0_.tri[st.iface];
    return st.bary[0] * sq0_[t[0]] + st.bary[1] * sq0_[t[1]] + st.bary[2] * sq0_[t[2]];
  }
  if (st.kind == VertexKind::Branch) return sq0_[st.inp];
  int e = 0;
  double t = 0;
  sk_.point(m0_.pos, st.seg, st.s, &e, &t);
  const auto& sg = sk_.segments[st.seg];
  return (1 - t) * sq0_[sg.vertices[e]] + t * sq0_[sg.vertices[e + 1]];
}

Vec3 Remesher::position_of(const VState& st) const {
  if (st.kind == VertexKind::Free) return input_point(st.iface, st.bary);
  if (st.kind == VertexKind::Branch) return m0_.pos[st.inp];
  return sk_.point(m0_.pos, st.seg, st.s);
}

double Remesher::param_on(int x, int seg, double near_s) const {
  const VState& st = vs_[x];
  if (st.kind == VertexKind::Skeleton) return st.s;
  const auto& sg = sk_.segments[seg];
  const bool at_start = sg.vertices.front() == st.inp, at_end = sg.vertices.back() == st.inp;
  if (at_start && at_end) return near_s < 0.5 * sg.length() ? 0.0 : sg.length();
  return at_start ? 0.0 : sg.length();
}

int Remesher::start_face(int v, int patch) const {
  const VState& st = vs_[v];
  if (st.kind == VertexKind::Free) return st.iface;
  if (st.kind == VertexKind::Branch) return input_face_on_patch_at_vertex(st.inp, patch);
  int e = 0;
  sk_.point(m0_.pos, st.seg, st.s, &e);
  const auto& sg = sk_.segments[st.seg];
  return input_face_on_patch_at_edge(sg.vertices[e], sg.vertices[e + 1], patch);
}

bool Remesher::face_ok(int f) const {
  const auto& t = m_.tri[f];
  const Vec3 n = (m_.pos[t[1]] - m_.pos[t[0]]).cross(m_.pos[t[2]] - m_.pos[t[0]]);
  const double len = n.norm();
  const double l2 = (m_.pos[t[1]] - m_.pos[t[0]]).squaredNorm() +
                    (m_.pos[t[2]] - m_.pos[t[1]]).squaredNorm() +
                    (m_.pos[t[0]] - m_.pos[t[2]]).squaredNorm();
  if (!(len > 1e-6 * l2)) return false;  // degenerate (sliver with min angle < ~1e-4 rad)
  if (face_in_defect_zone(f)) return true;  // the input has no usable normals there
  const Vec3 nf = n / len;
  Vec3 cn[3];
  for (int i = 0; i < 3; ++i) {
    cn[i] = corner_normal(t[i], patch_[f]);
    if (nf.dot(cn[i]) <= cos_glatt_) return false;  // E_glatt (3.5)
  }
  for (int i = 0; i < 3; ++i)
    if (cn[i].dot(cn[(i + 1) % 3]) <= cos_dist_) return false;  // E_dist (3.4)
  return true;
}

bool Remesher::locally_embedded(std::span<const int> fs) const {
  // Each changed face against each live face sharing a corner with it, every pair once. The
  // faces around are gathered first, each with its box and normal: a face is met from up to
  // three changed faces, and two changed faces from both sides (~70 pairs per vertex move; the
  // check was ~18 % of a remesh when every pair recomputed both).
  if (face_mark_.size() < m_.tri.size()) face_mark_.resize(m_.tri.size(), -1);
  near_.clear();
  auto gather = [&](int h) {
    if (face_mark_[h] >= 0) return;
    face_mark_[h] = static_cast<int>(near_.size());
    NearFace nf;
    nf.face = h;
    nf.corners = m_.tri[h];
    const Vec3 &p0 = m_.pos[nf.corners[0]], &p1 = m_.pos[nf.corners[1]],
               &p2 = m_.pos[nf.corners[2]];
    nf.lo = p0.cwiseMin(p1).cwiseMin(p2);
    nf.hi = p0.cwiseMax(p1).cwiseMax(p2);
    nf.normal = (p1 - p0).cross(p2 - p0);
    nf.length = nf.normal.norm();
    nf.in_zone = face_in_defect_zone(h);
    near_.push_back(nf);
  };
  for (int f : fs) gather(f);  // the changed faces first: near_[0, k)
  const std::size_t k = near_.size();
  for (std::size_t i = 0; i < k; ++i)
    for (const int c : std::array<int, 3>(near_[i].corners))  // a copy: gather grows near_
      for (int h : m_.vfaces[c])
        if (m_.face_alive[h]) gather(h);
  bool embedded = true;
  for (std::size_t i = 0; i < k && embedded; ++i) {
    const NearFace& a = near_[i];
    for (std::size_t j = 0; j < near_.size() && embedded; ++j) {
      if (j < k && j <= i) continue;  // itself, or a changed pair met from the other side
      const NearFace& b = near_[j];
      int shared = 0;
      for (int c : a.corners) shared += c == b.corners[0] || c == b.corners[1] || c == b.corners[2];
      if (shared == 0) continue;
      if (a.in_zone || b.in_zone) continue;  // the input itself crosses there
      if ((b.lo.array() > a.hi.array()).any() || (b.hi.array() < a.lo.array()).any()) continue;
      if (cannot_meet(a, b, shared)) continue;
      // Two changed faces were tested in both orders before (the test is exact only up to
      // rounding, and not symmetric in it).
      embedded = !triangles_intersect(m_.pos, a.corners, b.corners) &&
                 !(j < k && triangles_intersect(m_.pos, b.corners, a.corners));
    }
  }
  for (const NearFace& nf : near_) face_mark_[nf.face] = -1;
  return embedded;
}

bool Remesher::cannot_meet(const NearFace& t, const NearFace& u, int shared) const {
  // Exact shortcuts for the faces of a star, which share corners with the changed face (most
  // of the pairs locally_embedded tests; the full test was ~half of a remesh's time):
  // - a common edge: non-coplanar faces meet only on it, and |cos| < 0.99 is far from coplanar;
  // - a common corner: if the other two corners of one face lie strictly on one side of the
  //   other's plane, the faces touch that plane (and so each other) only at the corner.
  // - no common corner: the corners of one face strictly on one side of the other's plane.
  if (shared == 3) return false;
  if (!(t.length > 0 && u.length > 0)) return false;
  if (shared == 2) return std::abs(t.normal.dot(u.normal)) < 0.99 * t.length * u.length;
  auto strictly_one_side = [&](const NearFace& a, const NearFace& b) {
    // The corners of b that are not corners of a, against a's plane (unit normal n / ln).
    const double tol = 1e-9 * std::sqrt(a.length);
    int above = 0, below = 0, others = 0;
    for (int c : b.corners)
      if (c != a.corners[0] && c != a.corners[1] && c != a.corners[2]) {
        const double s = a.normal.dot(m_.pos[c] - m_.pos[a.corners[0]]) / a.length;
        ++others;
        above += s > tol;
        below += s < -tol;
      }
    return others > 0 && (above == others || below == others);
  };
  return strictly_one_side(t, u) || strictly_one_side(u, t);
}

std::vector<int> Remesher::fan(int v, int f0) const {
  std::vector<int> out = {f0};
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto& t = m_.tri[out[i]];
    for (int c : t) {
      if (c == v || is_skel(v, c)) continue;
      for (int g : m_.vfaces[v]) {
        if (std::find(out.begin(), out.end(), g) != out.end()) continue;
        const auto& u = m_.tri[g];
        if (u[0] == c || u[1] == c || u[2] == c) out.push_back(g);
      }
    }
  }
  return out;
}

int Remesher::deviation(int v, int f) const {
  switch (vs_[v].kind) {
    case VertexKind::Free:
      return m_.valence(v) - 6;
    case VertexKind::Skeleton:
      return side_valence(v, f) - 2;  // d^_p - 2, i.e. (2 d^_p + 2 - 6) / 2 (4.3)
    default:
      return 0;
  }
}

bool Remesher::ordered_ring(int v, std::vector<int>& ring) const {
  ring.clear();
  const auto& fs = m_.vfaces[v];
  if (fs.size() < 3) return false;
  // next[a] = b for each face (v, a, b) in counter-clockwise order.
  std::vector<std::pair<int, int>>& nx = ring_scratch_;
  nx.clear();
  for (int f : fs) {
    const auto& t = m_.tri[f];
    const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    nx.push_back({t[(i + 1) % 3], t[(i + 2) % 3]});
  }
  int cur = nx[0].first;
  for (std::size_t k = 0; k < nx.size(); ++k) {
    ring.push_back(cur);
    auto it = std::find_if(nx.begin(), nx.end(), [&](const auto& p) { return p.first == cur; });
    if (it == nx.end()) return false;
    cur = it->second;
  }
  return cur == ring[0];
}

Vec3 Remesher::vertex_normal(int v) const {
  Vec3 n = Vec3::Zero();
  for (int f : m_.vfaces[v]) {
    const auto& t = m_.tri[f];
    n += (m_.pos[t[1]] - m_.pos[t[0]]).cross(m_.pos[t[2]] - m_.pos[t[0]]);
  }
  return n.norm() > 0 ? Vec3(n.normalized()) : Vec3::Zero();
}

// ---------------------------------------------------------------- operations

bool Remesher::collapse(int v, int w) {
  const VState& sv = vs_[v];
  if (sv.kind == VertexKind::Branch) return ++st_.rejected_topology, false;
  const bool skel = is_skel(v, w);
  int seg = -1;
  if (skel) {
    seg = sedge_.at(edge_key(v, w));
    if (sv.kind != VertexKind::Skeleton || sv.seg != seg) return ++st_.rejected_topology, false;
    const auto& sg = sk_.segments[seg];
    const bool loop = sg.vertices.front() == sg.vertices.back();
    if (seg_edges_[seg] <= (loop ? 3 : 1)) return ++st_.rejected_topology, false;
  } else if (sv.kind != VertexKind::Free) {
    return ++st_.rejected_topology, false;
  }
  const auto ef = m_.edge_faces(v, w);
  if (ef.empty()) return false;
  const auto nv = m_.neighbours(v), nw = m_.neighbours(w);
  if (!m_.link_condition(v, w, ef, nv, nw)) return ++st_.rejected_topology, false;
  for (int f : ef) {
    const int a = m_.opposite(f, v, w);
    if (vs_[a].kind == VertexKind::Free && m_.valence(a) <= 3)
      return ++st_.rejected_topology, false;
  }
  if (vs_[w].kind == VertexKind::Free && nv.size() + nw.size() < 8)
    return ++st_.rejected_topology, false;
  // New state of w: midpoint between two free or two skeleton vertices, else w stays.
  const VState old_w = vs_[w];
  VState nw_state = old_w;
  if (sv.kind == VertexKind::Free && old_w.kind == VertexKind::Free) {
    project(0.5 * (m_.pos[v] + m_.pos[w]), nw_state.iface, nw_state.bary);
  } else if (skel && old_w.kind == VertexKind::Skeleton) {
    nw_state.s = 0.5 * (sv.s + old_w.s);
  }
  const kernel::EdgeCollapse collapsed = m_.collapse(v, w);
  const Vec3 old_pos_v = m_.pos[v];
  set_state(w, nw_state);
  if (!faces_ok(m_.vfaces[w])) {
    m_.undo(collapsed);
    set_state(w, old_w);
    m_.pos[v] = old_pos_v;
    ++st_.rejected_error;
    note_change(v);  // their face lists are in another order now, w's position rounded anew
    note_change(w);
    return false;
  }
  // Skeleton bookkeeping.
  if (skel) {
    sedge_.erase(edge_key(v, w));
    for (int x : nv)
      if (x != w) {
        auto it = sedge_.find(edge_key(v, x));
        if (it != sedge_.end()) {
          sedge_.erase(it);
          sedge_[edge_key(w, x)] = seg;
        }
      }
    --seg_edges_[seg];
  }
  m_.remove_vertex(v);
  note_change(w);
  ++st_.collapses;
  return true;
}

int Remesher::split(int v, int w) {
  const auto ef = m_.edge_faces(v, w);
  if (ef.empty()) return -1;
  const bool skel = is_skel(v, w);
  VState su;
  if (skel) {
    const int seg = sedge_.at(edge_key(v, w));
    su.kind = VertexKind::Skeleton;
    su.seg = seg;
    const double sv = vs_[v].kind == VertexKind::Skeleton ? vs_[v].s : -1;
    const double sw = vs_[w].kind == VertexKind::Skeleton ? vs_[w].s : -1;
    const double a = param_on(v, seg, sw >= 0 ? sw : sv);
    const double b = param_on(w, seg, sv >= 0 ? sv : sw);
    su.s = 0.5 * (a + b);
  } else {
    su.iface = start_face(v, patch_[ef[0]]);
    if (su.iface < 0) return -1;
    project(0.5 * (m_.pos[v] + m_.pos[w]), su.iface, su.bary);
  }
  const int u = add_vertex(su);
  const kernel::EdgeSplit halves = m_.split(v, w, u);
  if (patch_.size() < m_.tri.size()) patch_.resize(m_.tri.size());
  for (std::size_t i = 0; i < halves.added.size(); ++i)
    patch_[halves.added[i]] = patch_[halves.changed[i]];
  std::vector<int> check = halves.changed;
  check.insert(check.end(), halves.added.begin(), halves.added.end());
  if (!faces_ok(check)) {
    m_.undo(halves);
    m_.remove_vertex(u);
    ++st_.rejected_error;
    note_change(w, Change::Reordered);  // its face list is in another order now
    return -1;
  }
  if (skel) {
    const int seg = sedge_.at(edge_key(v, w));
    sedge_.erase(edge_key(v, w));
    sedge_[edge_key(v, u)] = seg;
    sedge_[edge_key(u, w)] = seg;
    ++seg_edges_[seg];
  }
  note_change(u);
  ++st_.splits;
  return u;
}

bool Remesher::flip(int v, int w, bool check) {
  if (is_skel(v, w)) return false;
  const auto flipped = m_.flip(v, w);
  if (!flipped) return false;
  const int a = flipped->a, b = flipped->b, f1 = flipped->f1, f2 = flipped->f2;
  last_flip_ = {a, b};
  last_flip_faces_ = {f1, f2};
  if (check && (!face_ok(f1) || !face_ok(f2))) {
    m_.undo(*flipped);
    ++st_.rejected_error;
    for (int x : {v, w, a, b}) note_change(x, Change::Reordered);  // face lists reordered
    return false;
  }
  for (int x : {v, w, a, b}) note_change(x);
  ++st_.flips;
  if (flip_record_) flip_record_->push_back({edge_key(v, w), edge_key(a, b)});
  return true;
}

bool Remesher::try_state(int v, const VState& ns) {
  // Shared by every vertex move: apply, check the star (E_dist, E_glatt, no fold or local
  // intersection), undo on failure.
  const VState old = vs_[v];
  const Vec3 old_pos = m_.pos[v];
  set_state(v, ns);
  if (!faces_ok(m_.vfaces[v])) {
    vs_[v] = old;
    m_.pos[v] = old_pos;
    ++st_.rejected_error;
    return false;
  }
  note_change(v);
  ++st_.moves;
  return true;
}

bool Remesher::move_to(int v, const Vec3& x) {
  VState ns = vs_[v];
  project(x, ns.iface, ns.bary);
  return try_state(v, ns);
}

bool Remesher::move_skeleton(int v, double s_new) {
  VState ns = vs_[v];
  ns.s = s_new;
  return try_state(v, ns);
}

bool Remesher::flip_improves_valence(int v, int w) const { return flip_delta(v, w) < 0; }

bool Remesher::no_valence_flip_at(int c, const NeighbourList& ring) const {
  // With c and its ring free (weight 1), flipping (c, z) changes R by
  // 4 - 2 (d_c + d_z) + 2 (d_a + d_b), a and b the two corners opposite the edge, all three in
  // the ring. It is negative only if d_c + d_z - d_a - d_b > 2, and that sum is at most
  // d_c + (largest d in the ring) - (two smallest d in the ring). In regular surroundings this
  // answers for all of c's spokes at once (the drive walks asked ~12 flip_delta per step).
  if (vs_[c].kind != VertexKind::Free) return false;
  int largest = -1000, smallest = 1000, second = 1000;
  for (int z : ring) {
    if (vs_[z].kind != VertexKind::Free) return false;
    const int d = m_.valence(z) - 6;
    largest = std::max(largest, d);
    if (d < smallest) {
      second = smallest;
      smallest = d;
    } else if (d < second) {
      second = d;
    }
  }
  if (second == 1000) return false;  // fewer than two neighbours: no flip to judge
  return (m_.valence(c) - 6) + largest - smallest - second <= 2;
}

int Remesher::flip_delta(int v, int w) const {
  if (is_skel(v, w)) return 1000;
  const auto ef = m_.edge_faces(v, w);
  if (ef.size() != 2) return 1000;
  const int a = m_.opposite(ef[0], v, w), b = m_.opposite(ef[1], v, w);
  if (a == b || m_.edge_face_count(a, b) > 0) return 1000;
  const int dv = deviation(v, ef[0]), dw = deviation(w, ef[0]);
  const int da = deviation(a, ef[0]), db = deviation(b, ef[1]);
  // (4.3)-weighted: a skeleton vertex's per-side deviation counts double (d_p = 2 d^_p + 2).
  auto wgt = [&](int x) { return vs_[x].kind == VertexKind::Skeleton ? 2 : 1; };
  auto term = [&](int x, int d, int change) {
    const int k = wgt(x);
    const int before = k * d, after = k * (d + change);
    return after * after - before * before;
  };
  return term(v, dv, -1) + term(w, dw, -1) + term(a, da, 1) + term(b, db, 1);
}

bool Remesher::drive(int b, int w, int side) {
  // §3.8 drive edge (b black, w white): flip the edge (w, x) of a triangle (b, w, x); the pair
  // reappears on the far side of that quad. Moved at most drive_limit steps; kept only if R
  // dropped on the way (a simple edge appeared and was flipped), otherwise undone.
  std::vector<std::array<int, 2>> log;
  std::vector<std::pair<int, std::uint64_t>> journal;
  altered_journal_ = &journal;
  const ClearOnExit stop{altered_journal_};
  int total = 0;
  for (int step = 0; step < o_.drive_limit; ++step) {
    const auto ef = m_.edge_faces(b, w);
    if (ef.size() != 2 || is_skel(b, w)) break;
    // The side whose quad moves the pair away from where it came from: smallest index first.
    int x = m_.opposite(ef[side], b, w);
    const int d = flip_delta(w, x);
    if (d >= 1000) break;
    const auto fx = m_.edge_faces(w, x);
    const int y =
        m_.opposite(fx[0], w, x) == b ? m_.opposite(fx[1], w, x) : m_.opposite(fx[0], w, x);
    if (!flip(w, x)) break;
    log.push_back(last_flip_);
    total += d;
    // Simple edges around the moved pair.
    for (int c : {x, y}) {
      const NeighbourList ring = m_.neighbours(c);
      if (no_valence_flip_at(c, ring)) continue;
      for (int z : ring) {
        const int dz = flip_delta(c, z);
        if (dz < 0 && flip(c, z)) {
          log.push_back(last_flip_);
          total += dz;
        }
      }
    }
    if (total < 0) return true;
    if (!(deviation(x, m_.vfaces[x][0]) < 0 && deviation(y, m_.vfaces[y][0]) > 0)) break;
    if (m_.edge_face_count(x, y) == 0) break;
    b = x;
    w = y;
  }
  // Undone by flipping the new edges back: the same triangles, though the two faces of each
  // flip may hold each other's; the same mesh as long as both have one patch and label (a
  // flipped edge is no skeleton edge, so they do; checked all the same).
  bool restored = true;
  for (auto it = log.rbegin(); it != log.rend(); ++it) {
    restored &= flip((*it)[0], (*it)[1], false);
    const auto [f1, f2] = last_flip_faces_;
    restored &= patch_[f1] == patch_[f2] && m_.label[f1] == m_.label[f2];
  }
  st_.flips -= 2 * log.size();
  // The mesh is as it was: the flip sweeps need not look here again for this drive.
  if (restored)
    for (auto it = journal.rbegin(); it != journal.rend(); ++it) altered_at_[it->first] = it->second;
  return false;
}

bool Remesher::flip_improves_angle(int v, int w) const {
  if (is_skel(v, w)) return false;
  const auto ef = m_.edge_faces(v, w);
  if (ef.size() != 2) return false;
  const int a = m_.opposite(ef[0], v, w), b = m_.opposite(ef[1], v, w);
  if (a == b) return false;
  auto angle = [&](int p, int q, int r) {  // at p
    const Vec3 e1 = (m_.pos[q] - m_.pos[p]).normalized(), e2 = (m_.pos[r] - m_.pos[p]).normalized();
    return std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
  };
  auto min_angle = [&](int p, int q, int r) {
    return std::min({angle(p, q, r), angle(q, r, p), angle(r, p, q)});
  };
  const double before = std::min(min_angle(v, w, a), min_angle(v, w, b));
  const double after = std::min(min_angle(a, b, v), min_angle(a, b, w));
  return after > before + 1e-9;
}

// ---------------------------------------------------------------- phases

void Remesher::split_long() {
  const auto es = m_.edges();
  std::vector<std::pair<double, std::uint64_t>> cand;
  for (auto k : es) {
    const int v = edge_key_first(k), w = edge_key_second(k);
    const double r = (m_.pos[v] - m_.pos[w]).norm() / target(v, w);
    if (r > kSplitAbove) cand.push_back({-r, k});
  }
  std::sort(cand.begin(), cand.end());
  for (const auto& [r, k] : cand) {
    const int v = edge_key_first(k), w = edge_key_second(k);
    if (!m_.vertex_alive[v] || !m_.vertex_alive[w] || m_.edge_face_count(v, w) == 0) continue;
    split(v, w);
  }
}

void Remesher::collapse_short() {
  // The first pass looks at every edge. A later pass looks only at the candidates of the pass
  // before that are still edges and at the edges around a vertex a collapse attempt touched:
  // every other edge kept its length and target, so the candidates and their order are those
  // of a full scan (collapse_short was 10 % of a remesh, mostly 20 x rebuilding the edge list).
  std::vector<std::uint64_t> keys = m_.edges();
  std::vector<int> touched;
  for (int pass = 0; pass < 20; ++pass) {
    std::vector<std::pair<double, std::uint64_t>> cand;
    for (auto k : keys) {
      const int v = edge_key_first(k), w = edge_key_second(k);
      if (pass > 0 &&
          (!m_.vertex_alive[v] || !m_.vertex_alive[w] || m_.edge_face_count(v, w) == 0))
        continue;
      const double r = (m_.pos[v] - m_.pos[w]).norm() / target(v, w);
      if (r < kCollapseBelow) cand.push_back({r, k});
    }
    if (cand.empty()) return;
    std::sort(cand.begin(), cand.end());
    std::size_t done = 0;
    touched.clear();
    for (const auto& [r, k] : cand) {
      int v = edge_key_first(k), w = edge_key_second(k);
      if (!m_.vertex_alive[v] || !m_.vertex_alive[w] || m_.edge_face_count(v, w) == 0) continue;
      if ((m_.pos[v] - m_.pos[w]).norm() >= kCollapseBelow * target(v, w)) continue;
      // Remove the less constrained end; do not create edges longer than 4/3 h.
      if (vs_[v].kind != VertexKind::Free && vs_[w].kind == VertexKind::Free) std::swap(v, w);
      if (vs_[v].kind == VertexKind::Skeleton && vs_[w].kind == VertexKind::Branch) {
      } else if (vs_[v].kind == VertexKind::Branch) {
        std::swap(v, w);
      }
      if (collapse_makes_long_edge(v, w, kSplitAbove, CollapseEnds::RemovedOnly)) continue;
      // An undone collapse restores w through its state, not bit for bit its old position.
      touched.insert(touched.end(), {v, w});
      if (collapse(v, w) || collapse(w, v)) ++done;
    }
    if (done == 0) return;
    keys.clear();
    for (const auto& [r, k] : cand) keys.push_back(k);
    for (int u : touched)
      if (m_.vertex_alive[u])
        for (int x : m_.neighbours(u)) keys.push_back(edge_key(u, x));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  }
}

std::vector<std::uint64_t> Remesher::edges_near_changes_since(std::uint64_t at) const {
  const int n = static_cast<int>(m_.pos.size());
  auto stamped = [&](int u) {
    return m_.vertex_alive[u] &&
           (u >= static_cast<int>(altered_at_.size()) || altered_at_[u] > at);
  };
  std::vector<int> dirty;
  for (int u = 0; u < n; ++u)
    if (stamped(u)) dirty.push_back(u);
  // Past a quarter of the vertices, gathering and sorting the face edges costs more than the
  // vertex-by-vertex list of all edges.
  if (4 * dirty.size() > static_cast<std::size_t>(m_.vertex_count())) return m_.edges();
  return face_edges_at(dirty);
}

std::vector<std::uint64_t> Remesher::face_edges_at(const std::vector<int>& vertices) const {
  std::vector<std::uint64_t> keys;
  for (int u : vertices)
    for (int f : m_.vfaces[u]) {
      const auto& t = m_.tri[f];
      for (int i = 0; i < 3; ++i) keys.push_back(edge_key(t[i], t[(i + 1) % 3]));
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

int Remesher::flip_pass(bool delaunay) {
  // Sweeps until no flip is wanted. A flip changes only the valences and angles of its quad,
  // so after the first sweep only the edges of the faces around the flipped quads' corners
  // can have become flippable: later sweeps visit those alone (in key order, like the first).
  //
  // The first sweep, too, skips what the last finished sweep of the same kind left unchanged:
  // an edge's answer depends only on its quad (positions, states, valences, the bounds), and
  // note_change stamps every vertex whose quad changed. It visits the edges of the faces at
  // stamped vertices and, as the full sweep would, an edge that a flip makes dirty further on
  // in key order (unless that flip created it: the full sweep's list was made before). The
  // flips are the same, in the same order; only the look at ~all edges is saved (the valence
  // sweeps after each drive round were ~10 % of a remesh at the input's own count).
  FlipSweepMemory& memory = delaunay ? angle_sweep_ : valence_sweep_;
  const bool incremental = memory.valid && memory.cos_glatt == cos_glatt_ &&
                           memory.cos_dist == cos_dist_;
  int total = 0;
  std::vector<std::uint64_t> keys = incremental ? edges_near_changes_since(memory.at) : m_.edges();
  std::vector<int> touched;
  auto consider = [&](int v, int w) {
    // Both tests answer no for an edge without exactly two faces (no separate count needed).
    if (!m_.vertex_alive[v] || !m_.vertex_alive[w]) return false;
    const bool want = delaunay ? flip_improves_angle(v, w) : flip_improves_valence(v, w);
    if (!(want && flip(v, w))) return false;
    touched.insert(touched.end(), {v, w, last_flip_[0], last_flip_[1]});
    return true;
  };
  bool converged = false;
  for (int pass = 0; pass < 10; ++pass) {
    int n = 0;
    touched.clear();
    if (pass == 0 && incremental) {
      n = incremental_first_sweep(keys, consider, touched);
    } else {
      for (auto k : keys) n += consider(edge_key_first(k), edge_key_second(k));
    }
    total += n;
    if (n == 0) {
      converged = true;
      break;
    }
    keys = face_edges_at(touched);
  }
  memory = {converged, clock_, cos_glatt_, cos_dist_};
  return total;
}

template <class Consider>
int Remesher::incremental_first_sweep(const std::vector<std::uint64_t>& dirty, Consider& consider,
                                      std::vector<int>& touched) {
  // `dirty` in key order, plus the edges a flip makes dirty ahead of the cursor.
  std::priority_queue<std::uint64_t, std::vector<std::uint64_t>, std::greater<>> ahead;
  std::unordered_set<std::uint64_t> pushed, created;
  std::size_t next = 0;
  int n = 0;
  while (next < dirty.size() || !ahead.empty()) {
    std::uint64_t k;
    if (ahead.empty() || (next < dirty.size() && dirty[next] < ahead.top())) {
      k = dirty[next++];
    } else {
      k = ahead.top();
      ahead.pop();
    }
    const std::size_t before = touched.size();
    if (!consider(edge_key_first(k), edge_key_second(k))) continue;
    ++n;
    created.insert(edge_key(touched[before + 2], touched[before + 3]));
    for (std::size_t i = before; i < touched.size(); ++i)
      for (int f : m_.vfaces[touched[i]]) {
        const auto& t = m_.tri[f];
        for (int j = 0; j < 3; ++j) {
          const std::uint64_t e = edge_key(t[j], t[(j + 1) % 3]);
          if (e > k && !created.count(e) && !std::binary_search(dirty.begin(), dirty.end(), e) &&
              pushed.insert(e).second)
            ahead.push(e);
        }
      }
  }
  return n;
}

// Moves shorter than this share of the local target edge length are not made.
constexpr double kSettledMove = 0.02;
// The final angle-based passes change no connectivity, only angles: there a move under 5 % of
// the edge is not worth its checks (the smoothing took half the time with 2 %; worst angles and
// the >= 30 deg shares stayed within 0.2 deg / 0.01 points on the corpus and the demo head,
// docs/remeshing.md).
constexpr double kSettledSmoothingMove = 0.05;

Vec3 Remesher::voronoi_centroid(int v, const std::vector<int>& ring) const {
  // Lloyd's step: the Voronoi cell of v restricted to its star is, per star triangle (v, a, b),
  // the part of the triangle nearer v than a and b (the triangle clipped by the two
  // perpendicular bisectors; exact for obtuse triangles too). Its centroid is weighted by the
  // CVT density rho = h^-4 (a 2D CVT's cells grow as rho^-1/4), h the target edge length.
  const Vec3 p = m_.pos[v];
  Vec3 moment = Vec3::Zero();
  double mass = 0;
  std::vector<Vec3> poly, clipped;
  auto clip = [&](const Vec3& toward) {
    // Keep {x : (x - mid) . (toward - p) <= 0}, mid the midpoint of p and toward.
    const Vec3 n = toward - p, mid = 0.5 * (p + toward);
    clipped.clear();
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Vec3 &x = poly[i], &y = poly[(i + 1) % poly.size()];
      const double dx = (x - mid).dot(n), dy = (y - mid).dot(n);
      if (dx <= 0) clipped.push_back(x);
      if ((dx < 0) != (dy < 0) && dx != dy) clipped.push_back(x + dx / (dx - dy) * (y - x));
    }
    poly.swap(clipped);
  };
  const std::size_t k = ring.size();
  for (std::size_t i = 0; i < k; ++i) {
    const int a = ring[i], b = ring[(i + 1) % k];
    poly = {p, m_.pos[a], m_.pos[b]};
    clip(m_.pos[a]);
    clip(m_.pos[b]);
    if (poly.size() < 3) continue;
    // Area and centroid of the convex piece by a fan from its first corner.
    Vec3 c = Vec3::Zero();
    double area = 0;
    for (std::size_t j = 1; j + 1 < poly.size(); ++j) {
      const double t = 0.5 * (poly[j] - poly[0]).cross(poly[j + 1] - poly[0]).norm();
      c += t * (poly[0] + poly[j] + poly[j + 1]) / 3.0;
      area += t;
    }
    if (!(area > 0)) continue;
    const double h = (vs_[v].sq + vs_[a].sq + vs_[b].sq) / 3.0;
    const double rho = 1.0 / (h * h * h * h);
    moment += rho * c;
    mass += rho * area;
  }
  return mass > 0 ? Vec3(moment / mass) : p;
}

bool Remesher::finding_holds(int v) const {
  if (v >= static_cast<int>(verdicts_.size())) return false;
  const Verdict& d = verdicts_[v];
  if (d.finding == Finding::None || d.settings != settings_generation_) return false;
  auto unchanged = [&](int x) {
    return x >= static_cast<int>(changed_at_.size()) || changed_at_[x] <= d.at;
  };
  if (!unchanged(v)) return false;
  if (d.finding == Finding::Settled) return true;
  // A refused move also depends on the faces at the ring's corners (locally_embedded).
  for (int x : m_.neighbours(v))
    if (!unchanged(x)) return false;
  return true;
}

void Remesher::remember(int v, Finding f) {
  if (verdicts_.size() < m_.pos.size()) verdicts_.resize(m_.pos.size());
  verdicts_[v] = {f, clock_, settings_generation_};
}

void Remesher::relax_pass(Relax how) {
  const std::tuple<int, double, double, double, bool> settings{
      static_cast<int>(how), scale_, cos_glatt_, cos_dist_, embed_check_};
  if (settings != last_settings_) {
    last_settings_ = settings;
    ++settings_generation_;
  }
  std::vector<int> ring;
  const int n = static_cast<int>(m_.pos.size());
  for (int v = 0; v < n; ++v) {
    if (!m_.vertex_alive[v] || vs_[v].kind != VertexKind::Free) continue;
    if (finding_holds(v)) continue;
    if (!ordered_ring(v, ring)) continue;
    const Vec3 p = m_.pos[v];
    const Vec3 nrm = vertex_normal(v);
    if (nrm.isZero()) continue;
    const std::size_t k = ring.size();
    Vec3 target_pt = Vec3::Zero();
    if (how == Relax::VoronoiCentroid) {
      target_pt = voronoi_centroid(v, ring);
    } else if (how == Relax::AngleBased) {
      // Zhou-Shimada (3.14)-(3.18) in the tangent plane: rotate (p - p_i) onto the bisector of
      // the corner angle at p_i, weight 1 / alpha_i^2.
      double wsum = 0;
      for (std::size_t i = 0; i < k; ++i) {
        const Vec3 pi = m_.pos[ring[i]];
        auto tang = [&](const Vec3& d) { return Vec3(d - d.dot(nrm) * nrm); };
        const Vec3 a = tang(m_.pos[ring[(i + 1) % k]] - pi).normalized();
        const Vec3 b = tang(m_.pos[ring[(i + k - 1) % k]] - pi).normalized();
        const Vec3 e = tang(p - pi);
        const double len = e.norm();
        if (len == 0) continue;
        const Vec3 en = e / len;
        const double aa = std::acos(std::clamp(en.dot(a), -1.0, 1.0));
        const double ab = std::acos(std::clamp(en.dot(b), -1.0, 1.0));
        const double alpha = aa + ab;
        Vec3 bis = a + b;
        if (bis.norm() < 1e-9) bis = en;
        bis.normalize();
        if (bis.dot(en) < 0) bis = -bis;
        const double wgt = 1.0 / std::max(alpha * alpha, 1e-6);
        target_pt += wgt * (pi + len * bis);
        wsum += wgt;
      }
      if (wsum == 0) continue;
      target_pt /= wsum;
    } else {
      // Density-weighted centroid of the star (area x Psi^-1 per face): the area-equalising /
      // centroidal move of §3.4 / §3.6 in the tangent plane.
      double wsum = 0;
      for (std::size_t i = 0; i < k; ++i) {
        const int a = ring[i], b = ring[(i + 1) % k];
        const Vec3 c = (p + m_.pos[a] + m_.pos[b]) / 3.0;
        const double area = 0.5 * (m_.pos[a] - p).cross(m_.pos[b] - p).norm();
        const double s = (vs_[v].sq + vs_[a].sq + vs_[b].sq) / 3.0;
        const double wgt = area / (s * s);
        target_pt += wgt * c;
        wsum += wgt;
      }
      if (wsum == 0) continue;
      target_pt /= wsum;
    }
    Vec3 d = target_pt - p;
    d -= d.dot(nrm) * nrm;
    // A vertex already at its relaxed place is left alone: the move's checks (projection,
    // star bounds, embedding) cost far more than finding that out, and most vertices settle
    // after a few of the ~30 passes.
    const double h = scale_ * vs_[v].sq;
    const double settled = how == Relax::AngleBased ? kSettledSmoothingMove : kSettledMove;
    if (d.squaredNorm() < settled * settled * h * h) {
      remember(v, Finding::Settled);
      continue;
    }
    if (!move_to(v, p + d)) remember(v, Finding::Refused);
  }
}

bool Remesher::skeleton_bounds(int v, int& a, int& b, double& sa, double& sb) const {
  a = b = -1;
  for (int x : m_.neighbours(v))
    if (is_skel(v, x)) (a < 0 ? a : b) = x;
  if (a < 0 || b < 0) return false;
  const int seg = vs_[v].seg;
  const double s = vs_[v].s;
  sa = param_on(a, seg, s);
  sb = param_on(b, seg, s);
  if (sa > sb) std::swap(sa, sb), std::swap(a, b);
  return sa < s && s < sb;
}

void Remesher::skeleton_relax_pass() {
  // 1D moves (§4.2): p_new between the two skeleton neighbours, split in the ratio of the target
  // lengths sqrt(Psi) (the area rule of §4.2 stated for lengths).
  const int n = static_cast<int>(m_.pos.size());
  for (int v = 0; v < n; ++v) {
    if (!m_.vertex_alive[v] || vs_[v].kind != VertexKind::Skeleton) continue;
    int a, b;
    double sa, sb;
    if (!skeleton_bounds(v, a, b, sa, sb)) continue;
    const double ha = vs_[a].sq, hb = vs_[b].sq;
    const double s_new = (hb * sa + ha * sb) / (ha + hb);
    const double lim = 0.5 * (sb - sa);
    const double s_to = std::clamp(s_new, sa + 0.05 * lim, sb - 0.05 * lim);
    if (std::abs(s_to - vs_[v].s) < kSettledMove * scale_ * vs_[v].sq) continue;  // settled
    move_skeleton(v, s_to);
  }
}

void Remesher::skeleton_density_control() {
  // (4.4) / (4.5): collapse when every side is under-connected, split when every side is
  // over-connected; the branch end of an edge is not evaluated (its d^ is undefined).
  // No split of an edge the length rule already finds too short: where no free vertex fits
  // between two borders (a strip about one output edge wide), each split leaves the vertex
  // across over-connected, and the rule split both borders in turn down to a fifth of the
  // target (needles of 5-12 deg on the demo head at 50,000-80,000 vertices; docs/remeshing.md,
  // "Skeleton splits in narrow strips").
  std::vector<std::uint64_t> keys;
  for (const auto& [k, s] : sedge_) keys.push_back(k);
  std::sort(keys.begin(), keys.end());
  for (auto k : keys) {
    int v = edge_key_first(k), w = edge_key_second(k);
    if (!m_.vertex_alive[v] || !m_.vertex_alive[w] || !is_skel(v, w)) continue;
    const auto ef = m_.edge_faces(v, w);
    bool all_collapse = true, all_split = true;
    for (int f : ef) {
      const bool sv = vs_[v].kind == VertexKind::Skeleton, sw = vs_[w].kind == VertexKind::Skeleton;
      const int dv = sv ? side_valence(v, f) : -1, dw = sw ? side_valence(w, f) : -1;
      bool c, s;
      if (sv && sw) {
        c = (dv == 1 && dw <= 2) || (dw == 1 && dv <= 2);
        s = (dv >= 3 && dw >= 2) || (dw >= 3 && dv >= 2);
      } else if (sv || sw) {
        const int d = sv ? dv : dw;
        c = d == 1;
        s = d >= 3;
      } else {
        c = s = false;
      }
      all_collapse &= c;
      all_split &= s;
    }
    if (all_collapse) {
      int rm = (vs_[v].kind == VertexKind::Skeleton &&
                (vs_[w].kind != VertexKind::Skeleton || side_valence(v, ef[0]) == 1))
                   ? v
                   : w;
      const int keep = rm == v ? w : v;
      if (collapse(rm, keep)) ++st_.skeleton_collapses;
    } else if (all_split && !too_short_to_split(v, w)) {
      const int u = split(v, w);
      if (u >= 0) {
        ++st_.skeleton_splits;
        for (int f : std::vector<int>(m_.vfaces[u]))
          for (int c : m_.tri[f])
            if (c != u && m_.face_alive[f] && flip_improves_valence(u, c)) flip(u, c);
      }
    }
  }
}

void Remesher::adjust_count(CountOrder order) {
  // Exact vertex count: collapse the relatively shortest / split the relatively longest edges.
  // With CountOrder::ValenceFirst, first the collapses (splits) of edges shorter (longer) than
  // their target that lower the valence deviation R (3.22) most, each followed by valence flips
  // around it, and no collapse that leaves an edge over kLongAfterCollapse h; the relatively
  // shortest (longest) edges only for what is left. The count adjustments after the
  // regularisation, by length alone, left 5-7 pairs behind each collapse: the share of
  // irregular free vertices rose from 9.5 to 10.6 % on the demo head and from 9.8 to 11.1 % on
  // lion-head there (measured; docs/remeshing.md, "Regularity").
  const int goal = o_.target_vertices;
  for (int round = 0; round < 50 && m_.vertex_count() != goal; ++round)
    for (const bool by_valence : {true, false}) {
      if (by_valence && order != CountOrder::ValenceFirst) continue;
      const int diff = m_.vertex_count() - goal;
      if (diff == 0) break;
      std::vector<std::tuple<int, double, std::uint64_t>> cand;  // (R change, length order, key)
      for (auto k : m_.edges()) {
        const int v = edge_key_first(k), w = edge_key_second(k);
        const double r = (m_.pos[v] - m_.pos[w]).norm() / target(v, w);
        int dr = 0;
        if (by_valence) {
          if (diff > 0 ? r >= 1.0 : r <= 1.0) continue;
          dr = diff > 0 ? collapse_valence_change(v, w) : split_valence_change(v, w);
          if (dr >= kNotJudged) continue;
        }
        cand.push_back({dr, diff > 0 ? r : -r, k});
      }
      std::sort(cand.begin(), cand.end());
      int need = std::abs(diff);
      for (const auto& [dr, r, k] : cand) {
        if (need == 0) break;
        int v = edge_key_first(k), w = edge_key_second(k);
        if (!m_.vertex_alive[v] || !m_.vertex_alive[w] || m_.edge_face_count(v, w) == 0) continue;
        if (diff < 0) {
          const int u = split(v, w);
          if (u < 0) continue;
          --need;
          if (by_valence) flips_around(u);
          continue;
        }
        if (vs_[v].kind != VertexKind::Free) std::swap(v, w);
        if (by_valence && collapse_makes_long_edge(v, w, kLongAfterCollapse, CollapseEnds::Both))
          continue;
        if (collapse(v, w)) {
          --need;
          if (by_valence) flips_around(w);
        } else if (collapse(w, v)) {
          --need;
          if (by_valence) flips_around(v);
        }
      }
    }
}

int Remesher::collapse_valence_change(int v, int w) const {
  // Both ends free and interior: w takes v's edges (valence d_v + d_w + 2 over 6), the two
  // opposite corners lose one each.
  if (vs_[v].kind != VertexKind::Free || vs_[w].kind != VertexKind::Free) return kNotJudged;
  const auto ef = m_.edge_faces(v, w);
  if (ef.size() != 2) return kNotJudged;
  const int a = m_.opposite(ef[0], v, w), b = m_.opposite(ef[1], v, w);
  const int dv = m_.valence(v) - 6, dw = m_.valence(w) - 6;
  const int da = deviation(a, ef[0]), db = deviation(b, ef[1]);
  auto sq = [](int x) { return x * x; };
  return sq(dv + dw + 2) - sq(dv) - sq(dw) + sq(da - 1) - sq(da) + sq(db - 1) - sq(db);
}

int Remesher::split_valence_change(int v, int w) const {
  // The new vertex has valence 4 (deviation -2); the two opposite corners gain one each.
  const auto ef = m_.edge_faces(v, w);
  if (ef.size() != 2 || is_skel(v, w)) return kNotJudged;
  const int a = m_.opposite(ef[0], v, w), b = m_.opposite(ef[1], v, w);
  const int da = deviation(a, ef[0]), db = deviation(b, ef[1]);
  auto sq = [](int x) { return x * x; };
  return 4 + sq(da + 1) - sq(da) + sq(db + 1) - sq(db);
}

bool Remesher::collapse_makes_long_edge(int v, int w, double bound, CollapseEnds ends) const {
  // Where collapse(v, w) leaves w: the midpoint of two vertices of one kind, else in place.
  const Vec3 mid = vs_[v].kind == vs_[w].kind ? Vec3(0.5 * (m_.pos[v] + m_.pos[w])) : m_.pos[w];
  for (int end : {v, w}) {
    if (end == w && ends == CollapseEnds::RemovedOnly) break;
    for (int x : m_.neighbours(end))
      if ((m_.pos[x] - mid).norm() > bound * target(x, w)) return true;
  }
  return false;
}

void Remesher::flips_around(int u, Spokes spokes) {
  // Valence flips of the edges at u's ring vertices: a collapse or split leaves its irregular
  // vertices there (regularize calls it after its own splits, without the spokes).
  if (!m_.vertex_alive[u]) return;
  for (int f : std::vector<int>(m_.vfaces[u]))
    if (m_.face_alive[f])
      for (int c : m_.tri[f]) {
        if (c == u) continue;
        const NeighbourList ring = m_.neighbours(c);
        if (no_valence_flip_at(c, ring)) continue;
        for (int x : ring)
          if ((spokes == Spokes::Included || x != u) && m_.edge_face_count(c, x) == 2 &&
              flip_improves_valence(c, x))
            flip(c, x);
      }
}

int Remesher::flip_queue() {
  // Vertices ordered by their weighted valence deviation, worst first; each takes the flip of
  // one of its spokes or link edges that lowers R (3.22) most (the next best when E_dist /
  // E_glatt refuses it); the four vertices of a flipped quad re-enter the queue.
  auto score = [&](int v) {
    if (!m_.vertex_alive[v] || m_.vfaces[v].empty() || vs_[v].kind == VertexKind::Branch) return 0;
    const int d = std::abs(deviation(v, m_.vfaces[v][0]));
    return vs_[v].kind == VertexKind::Skeleton ? 2 * d : d;
  };
  std::priority_queue<std::pair<int, int>> pq;  // (score, -v): ties by smallest index
  for (int v = 0; v < static_cast<int>(m_.pos.size()); ++v)
    if (const int sc = score(v); sc > 0) pq.push({sc, -v});
  int flips = 0;
  std::size_t budget = 20 * m_.pos.size();
  std::vector<std::tuple<int, int, int>> cand;
  while (!pq.empty() && budget-- > 0) {
    const auto [sc, nv] = pq.top();
    pq.pop();
    const int v = -nv;
    if (sc == 0 || score(v) != sc) continue;  // stale entry
    cand.clear();
    for (int f : m_.vfaces[v]) {
      const auto& t = m_.tri[f];
      for (int i = 0; i < 3; ++i) {
        const int a = std::min(t[i], t[(i + 1) % 3]), b = std::max(t[i], t[(i + 1) % 3]);
        if (m_.edge_face_count(a, b) != 2) continue;
        const int d = flip_delta(a, b);
        if (d < 0) cand.push_back({d, a, b});
      }
    }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    for (const auto& [d, a, b] : cand) {
      const auto ef = m_.edge_faces(a, b);
      if (ef.size() != 2) continue;
      const int x = m_.opposite(ef[0], a, b), y = m_.opposite(ef[1], a, b);
      if (!flip(a, b)) continue;
      ++flips;
      for (int u : {a, b, x, y})
        if (const int su = score(u); su > 0) pq.push({su, -u});
      break;
    }
  }
  return flips;
}

void Remesher::regularize() {
  // §3.8: simple edges (flips lowering R) first, then long / short edges (split / collapse
  // followed by flips of the new link), one local angle-smoothing step after each operation.
  simple_flips();
  const auto es = m_.edges();
  for (auto k : es) {
    const int v = edge_key_first(k), w = edge_key_second(k);
    if (!m_.vertex_alive[v] || !m_.vertex_alive[w] || is_skel(v, w)) continue;
    const auto ef = m_.edge_faces(v, w);
    if (ef.size() != 2) continue;
    if (vs_[v].kind != VertexKind::Free || vs_[w].kind != VertexKind::Free) continue;
    const int dv = m_.valence(v) - 6, dw = m_.valence(w) - 6;
    if (dv < 0 && dw < 0) {  // short edge: both black
      const int a = m_.opposite(ef[0], v, w), b = m_.opposite(ef[1], v, w);
      if (deviation(a, ef[0]) <= 0 || deviation(b, ef[1]) <= 0) continue;
      collapse(v, w);
    } else if (dv > 0 && dw > 0) {  // long edge: both white
      if (const int u = split(v, w); u >= 0) flips_around(u, Spokes::Excluded);
    }
  }
  drive_dipoles();
}

std::vector<std::uint64_t> Remesher::edges_after_flips(
    const std::vector<std::uint64_t>& sorted,
    const std::vector<std::array<std::uint64_t, 2>>& flips) {
  // Net change per edge: a flip and the flip back cancel (a failed drive undoes its flips).
  std::vector<std::pair<std::uint64_t, int>> change;
  change.reserve(2 * flips.size());
  for (const auto& [removed, made] : flips) {
    change.push_back({removed, -1});
    change.push_back({made, +1});
  }
  std::sort(change.begin(), change.end());
  std::vector<std::uint64_t> gone, added;
  for (std::size_t i = 0; i < change.size();) {
    int net = 0;
    std::size_t j = i;
    for (; j < change.size() && change[j].first == change[i].first; ++j) net += change[j].second;
    if (net < 0) gone.push_back(change[i].first);
    if (net > 0) added.push_back(change[i].first);
    i = j;
  }
  std::vector<std::uint64_t> kept;
  kept.reserve(sorted.size());
  std::set_difference(sorted.begin(), sorted.end(), gone.begin(), gone.end(),
                      std::back_inserter(kept));
  std::vector<std::uint64_t> out;
  out.reserve(kept.size() + added.size());
  std::merge(kept.begin(), kept.end(), added.begin(), added.end(), std::back_inserter(out));
  return out;
}

void Remesher::drive_dipoles(int rounds) {
  simple_flips();
  // Drive edges: black-white pairs moved until they meet another irregular vertex. Only flips
  // change the mesh here, so each round's edge list is the last one with its flips applied
  // (listing every edge again was ~4 % of a remesh at the input's count).
  std::vector<std::array<std::uint64_t, 2>> record;
  const ClearOnExit stop{flip_record_};
  std::vector<std::uint64_t> edges = m_.edges();
  for (int round = 0; round < rounds; ++round) {
    int ok = 0;
    record.clear();
    flip_record_ = &record;
    for (auto k : edges) {
      int v = edge_key_first(k), w = edge_key_second(k);
      if (!m_.vertex_alive[v] || !m_.vertex_alive[w]) continue;
      // Most edges join two free vertices that are not a black-white pair: known from the
      // cached valences, without the edge's faces.
      if (vs_[v].kind == VertexKind::Free && vs_[w].kind == VertexKind::Free &&
          (m_.valence(v) - 6) * (m_.valence(w) - 6) >= 0)
        continue;
      if (is_skel(v, w)) continue;
      const auto ef = m_.edge_faces(v, w);
      if (ef.size() != 2) continue;
      int dv = deviation(v, ef[0]), dw = deviation(w, ef[0]);
      if (dv > 0 && dw < 0) std::swap(v, w), std::swap(dv, dw);
      if (dv < 0 && dw > 0 && (drive(v, w, 0) || drive(v, w, 1))) ++ok;
    }
    simple_flips();
    flip_record_ = nullptr;
    if (ok == 0) break;
    edges = edges_after_flips(edges, record);
  }
}

std::vector<int> Remesher::intersecting_faces() const {
  // The checker's broad phase (a dense cell grid, pairs tested in parallel) on the live faces;
  // its face i is the i-th live face of m_.
  std::vector<int> live;
  for (std::size_t f = 0; f < m_.tri.size(); ++f)
    if (m_.face_alive[f]) live.push_back(static_cast<int>(f));
  std::vector<int> bad;
  for (const auto& [f, g] : intersecting_face_pairs(m_.to_mesh())) {
    bad.push_back(live[f]);
    bad.push_back(live[g]);
  }
  std::sort(bad.begin(), bad.end());
  bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
  return bad;
}

// ---------------------------------------------------------------- angle polish

double Remesher::face_min_angle(int f) const {
  const auto& t = m_.tri[f];
  return triangle_min_angle(m_.pos[t[0]], m_.pos[t[1]], m_.pos[t[2]]);
}

double Remesher::star_min_angle(int v) const {
  double lo = std::numbers::pi;
  for (int f : m_.vfaces[v]) lo = std::min(lo, face_min_angle(f));
  return lo;
}

bool Remesher::raise_star_min_angle(int v) {
  // Compass (pattern) search: the smoothing optimises a weighted mean of the star's angles,
  // which leaves single small angles next to irregular vertices and the border; here the
  // objective is the star's smallest angle itself. Candidates are projected onto the input
  // (free vertices) or taken along the segment (skeleton vertices), and kept only when
  // try_state's checks pass.
  const VertexKind kind = vs_[v].kind;
  if (kind == VertexKind::Branch || m_.vfaces[v].empty()) return false;
  double h = 0;
  const auto nb = m_.neighbours(v);
  for (int x : nb) h += (m_.pos[x] - m_.pos[v]).norm();
  h /= std::max<std::size_t>(1, nb.size());
  Vec3 t1 = Vec3::Zero(), t2 = Vec3::Zero();  // free vertices: the tangent plane
  double s_lo = 0, s_hi = 0;  // skeleton vertices: the parameter range they may take
  if (kind == VertexKind::Free) {
    const Vec3 n = vertex_normal(v);
    if (n.isZero()) return false;
    t1 = n.unitOrthogonal();
    t2 = n.cross(t1);
  } else {
    // Strictly between the two skeleton neighbours, as in the 1D relaxation.
    int a, b;
    double sa, sb;
    if (!skeleton_bounds(v, a, b, sa, sb)) return false;
    const double lim = 0.5 * (sb - sa);
    s_lo = sa + 0.05 * lim;
    s_hi = sb - 0.05 * lim;
  }
  double best = star_min_angle(v);
  bool moved = false;
  double step = 0.25 * h;
  constexpr int kDirections = 8;
  for (int iter = 0; iter < 24 && step > 0.01 * h; ++iter) {
    bool better = false;
    const int dirs = kind == VertexKind::Free ? kDirections : 2;
    for (int k = 0; k < dirs && !better; ++k) {
      VState ns = vs_[v];
      if (kind == VertexKind::Free) {
        const double a = 2 * std::numbers::pi * k / kDirections;
        project(m_.pos[v] + step * (std::cos(a) * t1 + std::sin(a) * t2), ns.iface, ns.bary);
      } else {
        ns.s = std::clamp(ns.s + (k == 0 ? step : -step), s_lo, s_hi);
      }
      const VState old = vs_[v];
      const Vec3 old_pos = m_.pos[v];
      set_state(v, ns);
      const double now = star_min_angle(v);
      vs_[v] = old;
      m_.pos[v] = old_pos;
      if (now > best + 1e-4 && try_state(v, ns)) {
        best = now;
        better = moved = true;
      }
    }
    if (!better) step *= 0.5;
  }
  return moved;
}

bool Remesher::flip_raises_min_angle(int v, int w) {
  if (is_skel(v, w)) return false;
  const auto ef = m_.edge_faces(v, w);
  if (ef.size() != 2) return false;
  if (flip_delta(v, w) > o_.polish_flip_cost) return false;
  const double before = std::min(face_min_angle(ef[0]), face_min_angle(ef[1]));
  if (!flip(v, w)) return false;
  const double after = std::min(face_min_angle(ef[0]), face_min_angle(ef[1]));
  if (after > before + 1e-4 && (!embed_check_ || locally_embedded(ef))) return true;
  flip(last_flip_[0], last_flip_[1], false);  // undo: flip the new edge back
  st_.flips -= 2;
  return false;
}

std::vector<int> Remesher::faces_below(double limit) const {
  std::vector<int> bad;
  for (int f = 0; f < static_cast<int>(m_.tri.size()); ++f)
    if (m_.face_alive[f] && face_min_angle(f) < limit) bad.push_back(f);
  return bad;
}

std::size_t Remesher::polish_below(double limit, int rounds) {
  std::vector<int> bad = faces_below(limit);
  for (int round = 0; round < rounds && !bad.empty(); ++round) {
    report("polish", static_cast<double>(round) / rounds);
    for (int f : bad) {
      if (!m_.face_alive[f] || face_min_angle(f) >= limit) continue;
      const auto t = m_.tri[f];
      for (int c : t)
        if (raise_star_min_angle(c)) ++st_.polish_moves;
      if (!m_.face_alive[f] || face_min_angle(f) >= limit) continue;
      for (int i = 0; i < 3; ++i)
        if (flip_raises_min_angle(t[i], t[(i + 1) % 3])) {
          ++st_.polish_flips;
          for (int c : last_flip_)
            if (raise_star_min_angle(c)) ++st_.polish_moves;
          break;
        }
    }
    bad = faces_below(limit);
  }
  return bad.size();
}

void Remesher::polish_angles() {
  const double limit = o_.polish_angle_deg * std::numbers::pi / 180;
  st_.polish_bad_before = faces_below(limit).size();
  st_.polish_bad_after = polish_below(limit, o_.polish_rounds);
  // The floor: a face under polish_floor_deg is worse for every use of the mesh than a normal
  // a little past E_glatt / E_dist. On creases finer than the output (a lion's mane at the
  // input's own vertex count) the bounds refuse every move that would open such a face, so
  // only for these the bounds widen to polish_floor_glatt_deg / polish_floor_dist_deg.
  const double floor = o_.polish_floor_deg * std::numbers::pi / 180;
  if (o_.polish_rounds == 0) return;
  const double keep_glatt = cos_glatt_, keep_dist = cos_dist_;
  if (floor > 0) {
    cos_glatt_ =
        std::min(cos_glatt_, std::cos(o_.polish_floor_glatt_deg * std::numbers::pi / 180));
    cos_dist_ = std::min(cos_dist_, std::cos(o_.polish_floor_dist_deg * std::numbers::pi / 180));
    polish_below(floor, o_.polish_rounds);
  }
  // Last: a needle under polish_needle_deg is worse than any normal error (a fold of the input
  // finer than the output, thinner than the widened bounds allow): for these the normal bounds
  // go; the local-intersection test and the projection onto the input stay.
  const double needle = o_.polish_needle_deg * std::numbers::pi / 180;
  if (needle > 0) {
    cos_glatt_ = cos_dist_ = -2.0;
    polish_below(needle, o_.polish_rounds);
  }
  cos_glatt_ = keep_glatt;
  cos_dist_ = keep_dist;
  st_.polish_bad_after = faces_below(limit).size();
}

void Remesher::repair_intersections() {
  // Not in the thesis (it leaves global self-intersections open). Local ones are prevented by
  // every operation (locally_embedded); what is left here are distant sheets of the input that
  // come closer than an edge length (an ear and the head, nostril walls). First rounds: faces
  // that cut another face get Delaunay flips and their free corners pulled to the centroid of
  // their star. Later rounds split their longest edge: the new vertex lies on the input, so
  // both sheets' chords follow the input more closely until they no longer meet (the input
  // itself does not cut itself). Costs a few vertices over the target (within the 1 % bound).
  constexpr int kPullRounds = 4, kSplitRounds = 8;
  // The splits stop at 1 % over the target: an input that cuts itself (mannequin-devil) cannot
  // be repaired this way, and splitting on split 91,428 edges there (8x the target, 90 s).
  const int split_cap = o_.target_vertices + o_.target_vertices / 100;
  for (int round = 0; round < kPullRounds + kSplitRounds; ++round) {
    std::vector<int> bad = intersecting_faces();
    if (round == 0) st_.intersecting_faces_before_repair = bad.size();
    // Where the input cuts itself the output follows it; splitting there cannot separate the
    // sheets (it split 91,428 edges on mannequin-devil before the 1 % cap).
    std::erase_if(bad, [&](int f) { return face_in_defect_zone(f); });
    if (bad.empty()) return;
    if (round >= kPullRounds && m_.vertex_count() >= split_cap) return;
    for (int f : bad) {
      if (!m_.face_alive[f]) continue;
      const auto t = m_.tri[f];
      if (round >= kPullRounds) {
        if (m_.vertex_count() >= split_cap) break;
        int best = 0;
        double longest = -1;
        for (int i = 0; i < 3; ++i) {
          const double l = (m_.pos[t[i]] - m_.pos[t[(i + 1) % 3]]).squaredNorm();
          if (l > longest) longest = l, best = i;
        }
        if (split(t[best], t[(best + 1) % 3]) >= 0) ++st_.repair_splits;
        continue;
      }
      for (int i = 0; i < 3; ++i)
        if (m_.face_alive[f] && flip_improves_angle(t[i], t[(i + 1) % 3]))
          flip(t[i], t[(i + 1) % 3]);
      for (int c : t) {
        if (!m_.vertex_alive[c] || vs_[c].kind != VertexKind::Free) continue;
        Vec3 centroid = Vec3::Zero();
        const auto nb = m_.neighbours(c);
        for (int x : nb) centroid += m_.pos[x];
        centroid /= static_cast<double>(nb.size());
        move_to(c, 0.5 * (m_.pos[c] + centroid));
      }
    }
  }
}

void Remesher::check_options() const {
  if (m0_.face_count() == 0) throw InvalidInputError("remesh: the input mesh has no triangles");
  if (o_.target_vertices < 4 || o_.target_vertices > 10000000)
    throw InvalidInputError("remesh: target vertex count must be in [4, 10^7]");
  if (o_.polish_rounds < 0 || !(o_.polish_angle_deg > 0 && o_.polish_angle_deg < 60) ||
      o_.polish_flip_cost < 0 || !(o_.polish_needle_deg >= 0 && o_.polish_needle_deg < 60))
    throw InvalidInputError(
        "remesh: polish rounds and flip cost must be >= 0, the polish angle in (0, 60) deg and "
        "the needle angle in [0, 60) deg");
}

void Remesher::set_up() {
  cos_dist_ = std::cos(o_.theta_dist_deg * std::numbers::pi / 180);
  cos_glatt_ = std::cos(o_.theta_glatt_deg * std::numbers::pi / 180);
  report("setup", 0);
  // The input's own crossings, found on the second core while the skeleton and the density
  // are built (the broad phase over a 300,000-face scan takes ~0.15 s).
  // The checker's work bound: faces crowding one place (a hostile input) leave no zone.
  auto crossing = std::async(std::launch::async, [this] {
    bool complete = true;
    auto pairs = intersecting_face_pairs(
        input_, nullptr, nullptr, default_candidate_pair_budget(input_.triangles.size()), &complete);
    return complete ? pairs : std::vector<std::array<int, 2>>{};
  });
  build_input();
  mark_defect_zone(crossing.get(), 2.0 * uniform_edge_);
  // Branch vertices never move or go, so more of them than the target is a certain miss: say
  // so now instead of after the whole run.
  if (sk_.branch_vertex_count() > static_cast<std::size_t>(o_.target_vertices))
    throw InvalidInputError("remesh: the input's feature skeleton (boundary loops, seams and "
                            "feature lines: " + std::to_string(sk_.segments.size()) +
                            " segments) has " + std::to_string(sk_.branch_vertex_count()) +
                            " fixed branch vertices, more than the target of " +
                            std::to_string(o_.target_vertices) +
                            "; clean the scan first (scanmesh remesh --prepare) or ask for more");
  // M := M0 with the skeleton copied.
  m_ = m0_;
  patch_ = sk_.face_patch;
  copy_input_states();
  sedge_ = sk_.edge_segment;
  seg_edges_.assign(sk_.segments.size(), 0);
  for (const auto& [k, s] : sedge_) ++seg_edges_[s];
  scale_ = density_scale(m0_, psi0_, o_.target_vertices);
  st_.input_vertices = m0_.vertex_count();
  st_.input_faces = m0_.face_count();
}

void Remesher::copy_input_states() {
  vs_.resize(m0_.pos.size());
  for (int v = 0; v < static_cast<int>(m0_.pos.size()); ++v) {
    VState& s = vs_[v];
    s.kind = sk_.kind[v];
    if (m0_.vfaces[v].empty()) continue;
    if (s.kind == VertexKind::Branch) s.inp = v;
    if (s.kind == VertexKind::Skeleton) {
      s.seg = sk_.vertex_segment[v];
      s.s = sk_.vertex_arc[v];
    }
    const int f = m0_.vfaces[v][0];
    const auto& t = m0_.tri[f];
    s.iface = f;
    s.bary = Vec3(t[0] == v, t[1] == v, t[2] == v);
    s.sq = sq_of(s);
    s.normal = free_normal(s);
  }
}

void Remesher::adapt_phase() {
  const int rounds = std::max(1, o_.adapt_iterations);
  for (int it = 0; it < rounds; ++it) {
    report("adapt", static_cast<double>(it) / rounds);
    split_long();
    collapse_short();
    skeleton_density_control();
    flip_pass(false);
    relax_rounds(2, Relax::StarCentroid);
    // Steer the scale toward the requested count.
    const double ratio = static_cast<double>(m_.vertex_count()) / o_.target_vertices;
    scale_ *= std::pow(ratio, 0.5);
  }
}

void Remesher::area_phase() {
  embed_check_ = o_.prevent_intersections;
  report("count", 0);
  adjust_count();
  // Area-based remeshing (§3.4): n_step x (n_area moves + Delaunay flips), skeleton control.
  for (int step = 0; step < o_.n_step; ++step) {
    relax_rounds(o_.n_area, Relax::StarCentroid);
    flip_pass(true);
    skeleton_density_control();
    adjust_count();
  }
}

void Remesher::regularize_phase() {
  report("regularize", 0);
  if (o_.scheme != RemeshScheme::Regularize) {
    for (int k = 0; k < 5; ++k) {
      relax_rounds(1, Relax::VoronoiCentroid);
      flip_pass(true);
      skeleton_density_control();
    }
    adjust_count();
    return;
  }
  regularize();
  // Skeleton sampling follows the regularised surroundings: (4.4)/(4.5) with valence flips
  // until it settles, then the count is restored and regularised again.
  for (int k = 0; k < 4; ++k) {
    const std::size_t before = st_.skeleton_splits + st_.skeleton_collapses;
    skeleton_density_control();
    simple_flips();
    for (int j = 0; j < 2; ++j) skeleton_relax_pass();
    if (st_.skeleton_splits + st_.skeleton_collapses == before) break;
  }
  adjust_count(CountOrder::ValenceFirst);
  regularize();
  adjust_count(CountOrder::ValenceFirst);
  // The count adjustment's collapses leave dipoles: flips and drives only. Three rounds find
  // most of what ten do (rounds of 21, 8, 7, then 3, 2, 2, 1 kept drives on the demo head).
  drive_dipoles(3);
}

void Remesher::smooth_phase() {
  for (int k = 0; k < o_.smoothing_passes; ++k) {
    report("smooth", static_cast<double>(k) / std::max(1, o_.smoothing_passes));
    relax_rounds(1, o_.scheme == RemeshScheme::Regularize ? Relax::AngleBased
                                                          : Relax::VoronoiCentroid);
  }
  polish_angles();
  repair_intersections();
}

RemeshResult Remesher::result() {
  RemeshResult r;
  std::vector<int> map;
  r.mesh = m_.to_mesh(&map);
  r.kind.resize(r.mesh.positions.size());
  r.segment.assign(r.mesh.positions.size(), -1);
  r.sides.assign(r.mesh.positions.size(), 0);
  for (std::size_t v = 0; v < map.size(); ++v) {
    if (map[v] < 0) continue;
    r.kind[map[v]] = vs_[v].kind;
    if (vs_[v].kind == VertexKind::Skeleton) {
      r.segment[map[v]] = vs_[v].seg;
      r.sides[map[v]] = sk_.segments[vs_[v].seg].sides;
    }
  }
  for (std::size_t f = 0; f < m_.tri.size(); ++f)
    if (m_.face_alive[f]) r.face_patch.push_back(patch_[f]);
  st_.output_vertices = static_cast<int>(r.mesh.positions.size());
  st_.output_faces = static_cast<int>(r.mesh.triangles.size());
  st_.skeleton_segments = sk_.segments.size();
  st_.branch_vertices = sk_.branch_vertex_count();
  st_.patches = static_cast<std::size_t>(sk_.patch_count);
  r.stats = st_;
  r.skeleton = std::move(sk_);
  r.density = std::move(psi0_);
  return r;
}

RemeshResult Remesher::run() {
  const auto t0 = std::chrono::steady_clock::now();
  auto timed = [this](void (Remesher::*phase)(), double& seconds) {
    const auto start = std::chrono::steady_clock::now();
    (this->*phase)();
    seconds = seconds_since(start);
  };
  check_options();
  timed(&Remesher::set_up, st_.seconds_setup);
  timed(&Remesher::adapt_phase, st_.seconds_adapt);
  timed(&Remesher::area_phase, st_.seconds_count);
  timed(&Remesher::regularize_phase, st_.seconds_regularize);
  timed(&Remesher::smooth_phase, st_.seconds_smooth);
  RemeshResult r = result();
  r.stats.seconds_total = seconds_since(t0);
  report("done", 1);
  return r;
}

}  // namespace

RemeshResult remesh(const Mesh& input, const RemeshOptions& options) {
  input.validate();
  Remesher r(input, options);
  return r.run();
}

void require_vertex_count(const RemeshResult& result, int target,
                          std::size_t input_boundary_loops) {
  const RemeshStats& s = result.stats;
  const int got = s.output_vertices;
  if (std::abs(got - target) <= 0.01 * target) return;
  std::ostringstream msg;
  msg << "remesh: reached " << got << " vertices, not the " << target << " asked for ("
      << std::showpos << std::lround(100.0 * (got - target) / target) << std::noshowpos
      << " %): ";
  if (2 * s.branch_vertices > static_cast<std::size_t>(target))
    msg << "the input's " << input_boundary_loops << " boundary loops and feature lines make "
        << s.skeleton_segments << " skeleton segments with " << s.branch_vertices
        << " fixed vertices, which the remesher keeps; let the scan clean-up run (prepare), "
           "close holes (fill holes) or ask for more vertices";
  else
    msg << s.rejected_error << " operations were refused by the normal bounds (E_dist / "
        << "E_glatt) and " << s.rejected_topology << " by the link condition, and "
        << s.repair_splits << " edges were split to undo self-intersections; an input that "
           "folds or cuts itself does this (see check; widening theta dist / theta glatt "
           "widens the bounds)";
  throw InvalidInputError(msg.str());
}

}  // namespace scanmesh::remeshing
