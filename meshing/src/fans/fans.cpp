// Point-cloud fans, seed 002 (Preuss 2002) §3.4-3.7. Decisions on the seed's gaps are marked
// "Gap" and explained in docs/fans.md.
#include "scanmesh/meshing/fans/fans.h"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "../kernel/point_grid.h"
#include "../kernel/vertex_components.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/triangle_quality.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh {

using Eigen::Vector2d;
using Eigen::Vector3d;
using kernel::PointGrid;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;
constexpr int kNormalNeighbours = 10;    // PCA fallback and orientation graph
constexpr double kAngleEps = 1e-9;       // step 4b angular epsilon (rad)
constexpr double kCosEps = 1e-12;        // in-circle / flip tie tolerance on cosine sums
constexpr double kOpenGap = kPi - 1e-6;  // a gap at least this wide is open: no triangle
// Gap: the flips towards Delaunay may not bend the surface; two faces within this angle of
// each other count as one plane (noise on a smooth scan stays below it).
constexpr double kFlipMaxDihedralDeg = 20.0;

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

double wrap_angle(double a) {
  while (a < 0) a += kTwoPi;
  while (a >= kTwoPi) a -= kTwoPi;
  return a;
}

double cross2(const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }
double orient2(const Vector2d& a, const Vector2d& b, const Vector2d& c) {
  return cross2(b - a, c - a);
}
double cos_angle(const Vector2d& u, const Vector2d& v) {
  const double d = u.norm() * v.norm();
  return d > 0 ? u.dot(v) / d : 1.0;
}

// Strictly inside or on the boundary of triangle (a, b, c), either orientation.
bool in_triangle(const Vector2d& p, const Vector2d& a, const Vector2d& b, const Vector2d& c) {
  const double d1 = orient2(a, b, p), d2 = orient2(b, c, p), d3 = orient2(c, a, p);
  const bool neg = d1 < 0 || d2 < 0 || d3<0, pos = d1> 0 || d2 > 0 || d3 > 0;
  return !(neg && pos);
}

struct Frame {
  Vector3d b1, b2, n;
  explicit Frame(const Vector3d& normal) : n(normal) {
    // Gap (seed §3.7 step 2): b1 from the coordinate axis least aligned with n.
    Vector3d e = Vector3d::UnitX();
    const Vector3d a = n.cwiseAbs();
    if (a.y() <= a.x() && a.y() <= a.z()) e = Vector3d::UnitY();
    if (a.z() <= a.x() && a.z() <= a.y()) e = Vector3d::UnitZ();
    b1 = n.cross(e).normalized();
    b2 = n.cross(b1);
  }
  // Distance-preserving rotation into the tangent plane (seed §3.7 step 2: p' = p''|v|/|p''|).
  bool rotate(const Vector3d& v, double eps_len, Vector2d& q) const {
    q = Vector2d(b1.dot(v), b2.dot(v));
    const double len = q.norm();
    if (len < eps_len) return false;  // step 4b: the image falls on c
    q *= v.norm() / len;
    return true;
  }
  Vector2d project(const Vector3d& v) const { return {b1.dot(v), b2.dot(v)}; }
};

Vector3d pca_normal(const std::vector<Vector3d>& pts, int c,
                    const std::vector<std::pair<double, int>>& nn) {
  Vector3d mean = pts[c];
  for (const auto& [d2, j] : nn) mean += pts[j];
  mean /= static_cast<double>(nn.size() + 1);
  Eigen::Matrix3d cov = (pts[c] - mean) * (pts[c] - mean).transpose();
  for (const auto& [d2, j] : nn) cov += (pts[j] - mean) * (pts[j] - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(cov);
  return es.eigenvectors().col(0).normalized();
}

struct Context {
  const std::vector<Vector3d>& pts;
  const FanOptions& opt;
  PointGrid grid;
  double eps_len = 0;
  double d_max = 0;
  std::vector<Vector3d> normals;
  std::vector<Vector3d> pca;  // PCA normal of every point (orientation reference)
  std::vector<std::uint8_t> is_pca;
  std::vector<int> knn;  // kNormalNeighbours per point, -1 padded
  std::vector<double> spacing;
  // `g`: a grid over p.
  Context(const std::vector<Vector3d>& p, const FanOptions& o, PointGrid&& g)
      : pts(p), opt(o), grid(std::move(g)) {}
};

// `box`: the points' robust_box(), without far outliers: one stray point must not make the
// cells enormous.
double cell_edge_formula(const std::pair<Vector3d, Vector3d>& box, std::size_t points, int k) {
  const Vector3d d = box.second - box.first;
  // Scaled by the longest side, so that a box spanning 1e200 does not overflow the area to
  // infinity (an infinite cell edge made the cell index of a far point NaN).
  const double s = d.maxCoeff();
  if (!(s > 0)) throw InvalidInputError("build_fans: all points coincide");
  const Vector3d u = d / s;
  const double area = 2.0 * (u.x() * u.y() + u.y() * u.z() + u.x() * u.z());
  double l = s * std::sqrt(area * k / static_cast<double>(points));
  // A cloud on a line has no bounding-box area; fall back to the 1D spacing.
  if (!(l > 0)) l = s * k / static_cast<double>(points);
  if (!(l > 0) || !std::isfinite(l))
    throw InvalidInputError("build_fans: the points' extent gives no usable cell size");
  return l;
}

// The grid with the seed's cell edge l for k points per cell.
PointGrid cell_grid(const std::vector<Vector3d>& pts, int k) {
  const auto box = kernel::robust_box(pts);
  return PointGrid(pts, cell_edge_formula(box, pts.size(), k), box);
}

int omp_threads(const FanOptions& o) { return o.threads > 0 ? o.threads : omp_get_max_threads(); }

// §3.4: plane through the 3 nearest neighbours; PCA of 10 neighbours when those 3 are
// (near-)collinear. Then orientation by propagation over the k-NN graph (§3.4, [John '99] 2.6).
void compute_normals(Context& ctx, const std::vector<Eigen::Vector3f>* given) {
  const auto& pts = ctx.pts;
  const int n = static_cast<int>(pts.size());
  ctx.normals.assign(n, Vector3d::UnitZ());
  ctx.pca.assign(n, Vector3d::UnitZ());
  ctx.is_pca.assign(n, 0);
  ctx.knn.assign(static_cast<std::size_t>(n) * kNormalNeighbours, -1);
  ctx.spacing.assign(n, 0.0);
#pragma omp parallel num_threads(omp_threads(ctx.opt))
  {
    std::vector<std::pair<double, int>> nn;
#pragma omp for schedule(dynamic, 512)
    for (int o = 0; o < n; ++o) {
      const int c = o;  // the points are in cell order: neighbours are in cache
      ctx.grid.knn(c, kNormalNeighbours, nn);
      for (std::size_t k = 0; k < nn.size(); ++k) ctx.knn[c * kNormalNeighbours + k] = nn[k].second;
      ctx.spacing[c] = nn.empty() ? 0.0 : std::sqrt(nn[0].first);
      const Vector3d pca = nn.size() >= 2 ? pca_normal(pts, c, nn) : Vector3d::UnitZ();
      ctx.pca[c] = pca;
      bool use_pca = ctx.opt.pca_normals || nn.size() < 3;
      if (!use_pca) {
        const Vector3d& q1 = pts[nn[0].second];
        const Vector3d& q2 = pts[nn[1].second];
        const Vector3d& q3 = pts[nn[2].second];
        const Vector3d cr = (q2 - q1).cross(q3 - q1);
        const double longest =
            std::max({(q2 - q1).squaredNorm(), (q3 - q1).squaredNorm(), (q3 - q2).squaredNorm()});
        // Gap (§3.4 fallback trigger): |cross| / longest^2 < 0.2 means an angle below ~12 deg.
        // Gap: also when the 3-NN plane deviates more than 30 deg from the PCA plane of the
        // 10 nearest neighbours (noise larger than the 3-NN triangle can average out).
        if (cr.norm() < 0.2 * longest || !(longest > 0) ||
            std::abs(cr.normalized().dot(pca)) < std::cos(30.0 * kPi / 180.0))
          use_pca = true;
        else
          ctx.normals[c] = cr.normalized();
      }
      if (use_pca && nn.size() >= 2) {
        ctx.normals[c] = pca;
        ctx.is_pca[c] = 1;
      }
    }
  }
  // Orientation: breadth-first propagation, flipping a neighbour whose normal points against
  // the current one. The start point (chosen by the seed) points away from the centroid.
  Vector3d centroid = Vector3d::Zero();
  for (const auto& p : pts) centroid += p;
  centroid /= n;
  std::vector<std::uint8_t> done(n, 0);
  // Every point joins the queue once: one array, read from `head` on.
  std::vector<int> queue;
  queue.reserve(static_cast<std::size_t>(n));
  std::size_t head = 0;
  // Propagation runs on the PCA normals (smoother than 3-NN planes); each fan normal is then
  // turned to agree with its point's oriented PCA normal.
  auto& ref = ctx.pca;
  auto start = [&](int s) {
    if ((pts[s] - centroid).dot(ref[s]) < 0) ref[s] = -ref[s];
    done[s] = 1;
    queue.push_back(s);
    while (head < queue.size()) {
      const int c = queue[head++];
      for (int k = 0; k < kNormalNeighbours; ++k) {
        const int j = ctx.knn[c * kNormalNeighbours + k];
        if (j < 0 || done[j]) continue;
        if (ref[j].dot(ref[c]) < 0) ref[j] = -ref[j];
        done[j] = 1;
        queue.push_back(j);
      }
    }
  };
  if (given) {
    // The cloud's own normals know the outside; they only orient, the fans keep the estimates.
    for (int c = 0; c < n; ++c)
      if (ref[c].dot((*given)[c].cast<double>()) < 0) ref[c] = -ref[c];
  } else if (ctx.opt.orient_away_from_axis) {
    for (int c = 0; c < n; ++c)
      if (ref[c].dot(Vector3d(pts[c].x(), pts[c].y(), 0.0)) < 0) ref[c] = -ref[c];
  } else {
    start(static_cast<int>(ctx.opt.seed % static_cast<std::uint64_t>(n)));
    for (int s = 0; s < n; ++s)
      if (!done[s]) start(s);
  }
  for (int c = 0; c < n; ++c)
    if (ctx.normals[c].dot(ref[c]) < 0) ctx.normals[c] = -ctx.normals[c];
}

struct Spoke {
  int id;
  double ang;
  Vector2d q;
};

struct FanEntry {
  int id;
  bool closed_after;  // a triangle (c, this, next) exists in the fan
};

double edge_limit(const Context& ctx, int c) {
  double lim = std::numeric_limits<double>::infinity();
  if (ctx.opt.max_edge > 0) lim = ctx.opt.max_edge;
  if (ctx.opt.max_edge_factor > 0) lim = std::min(lim, ctx.opt.max_edge_factor * ctx.spacing[c]);
  return lim;
}

// Steps 1-6 and 7c for one centre c with the given normal; returns the fan in CCW order.
class FanBuilder {
 public:
  explicit FanBuilder(const Context& ctx) : ctx_(ctx) {}

  // Returns false when the fan stays open (a gap >= 180 deg) at d_max.
  bool build(int c, const Vector3d& normal, std::vector<FanEntry>& out) {
    const auto& pts = ctx_.pts;
    const Frame frame(normal);
    fan_.clear();
    circles_fresh_ = false;
    const double limit = edge_limit(ctx_, c);
    const double cos_normal = ctx_.opt.max_normal_angle_deg > 0
                                  ? std::cos(ctx_.opt.max_normal_angle_deg * kPi / 180.0)
                                  : -2.0;
    const double alpha = ctx_.opt.alpha_deg * kPi / 180.0;
    // Gap (d_start, §3.7 step 1): the distance of the 10th nearest neighbour; the fans of the
    // other points are merged later, so there are no pre-existing rim points to include.
    int last = -1;
    for (int k = kNormalNeighbours - 1; k >= 0 && last < 0; --k)
      last = ctx_.knn[c * kNormalNeighbours + k];
    double d_prev = -1.0;
    double d = last >= 0 ? (pts[last] - pts[c]).norm() * (1 + 1e-9) : ctx_.grid.cell_edge();
    // Duplicated points put every stored neighbour at distance 0; a zero radius would never
    // grow below (2 * 0 = 0) and the loop would spin forever (found by tests/hostile).
    if (!(d > 0)) d = ctx_.grid.cell_edge();
    d = std::min(d, ctx_.d_max);
    const int* first = &ctx_.knn[static_cast<std::size_t>(c) * kNormalNeighbours];
    const double r1_2 = d * d;
    int round = 0;
    while (true) {
      cand_.clear();
      if (round == 0) {
        // The stored nearest neighbours are the ball of radius d, except points tied with the
        // 10th neighbour, which the second round picks up.
        for (int k = 0; k < kNormalNeighbours; ++k) {
          if (first[k] < 0) continue;
          const double d2 = (pts[first[k]] - pts[c]).squaredNorm();
          if (d2 <= r1_2) cand_.emplace_back(d2, first[k]);
        }
      } else {
        const double dp2 = d_prev * d_prev;
        // The acceptance region only shrinks as spokes are inserted (a circle through c, a and
        // a point inside the circle of (c, a, b) stays inside that circle on the sector's side
        // of c-a), so a point the circle pre-test rejects now is rejected whenever its turn
        // comes: it is dropped here, before the sort, and the fan is the same.
        const bool prefilter = circle_pretest_active();
        // Round 1 also takes the points tied with the 10th neighbour: all but the stored ones.
        ctx_.grid.collect_shell(pts[c], round == 1 ? -1.0 : dp2, d, c, shell_);
        for (const auto& [d2, j] : shell_) {
          if (round == 1 && d2 <= r1_2 &&
              std::find(first, first + kNormalNeighbours, j) != first + kNormalNeighbours)
            continue;
          Vector2d q;
          if (prefilter && frame.rotate(pts[j] - pts[c], ctx_.eps_len, q) && surely_rejected(q))
            continue;
          cand_.emplace_back(d2, j);
        }
      }
      ++round;
      std::sort(cand_.begin(), cand_.end());  // step 1: nearest first, ties by index
      for (const auto& [d2, j] : cand_) {
        if (std::sqrt(d2) > limit) break;
        if (ctx_.normals[j].dot(normal) < cos_normal) continue;
        insert_candidate(j, pts[j] - pts[c], frame);
      }
      // Step 6: completeness. Gap (radius growth): grow only as far as a candidate could still
      // split a gap wider than alpha: a point inside the circumcircle of (c, a, b) is closer to
      // c than the circle's diameter |ab| / sin(gamma); open sectors (>= 180 deg) need d_max.
      double needed = 0.0;
      const std::size_t m = fan_.size();
      if (m < 3) needed = ctx_.d_max;
      for (std::size_t i = 0; i < m && m >= 3; ++i) {
        const Spoke& a = fan_[i];
        const Spoke& b = fan_[(i + 1) % m];
        const double gap = wrap_angle(b.ang - a.ang);
        if (gap <= alpha + 1e-9) continue;
        if (gap >= kPi) {
          needed = ctx_.d_max;
          break;
        }
        needed = std::max(needed, (a.q - b.q).norm() / std::sin(gap));
      }
      needed = std::min(needed, limit);
      if (needed <= d || d >= ctx_.d_max) break;
      d_prev = d;
      // at most doubling per round: an open sector is usually closed by the next ring
      d = std::min({ctx_.d_max, 2.0 * d, std::max(needed, 1.25 * d)});
    }
    flip_spokes();
    out.clear();
    bool open = fan_.size() < 3;
    const std::size_t m = fan_.size();
    out.reserve(m);  // one allocation per fan, not four (a million fans are built in parallel)
    for (std::size_t i = 0; i < m; ++i) {
      const Spoke& a = fan_[i];
      const Spoke& b = fan_[(i + 1) % m];
      const double gap = m < 2 ? kTwoPi : wrap_angle(b.ang - a.ang);
      bool closed = gap < kOpenGap && m >= 2;
      if (gap >= kPi) open = true;
      if (closed && (pts[a.id] - pts[b.id]).norm() > limit) closed = false;
      out.push_back({a.id, closed});
    }
    return !open;
  }

 private:
  // Steps 2-4: map, locate, check 4a-4c, insert.
  void insert_candidate(int id, const Vector3d& v, const Frame& frame) {
    Vector2d q;
    if (!frame.rotate(v, ctx_.eps_len, q)) return;  // 4b: image on c
    if (surely_rejected(q)) return;
    for (const auto& s : fan_)
      if (s.id == id) return;  // 4a
    const double ang = wrap_angle(std::atan2(q.y(), q.x()));
    const std::size_t m = fan_.size();
    std::size_t pos = 0;  // step 3: first spoke with a larger angle
    while (pos < m && fan_[pos].ang <= ang) ++pos;
    if (m >= 2) {
      const Spoke& a = fan_[(pos + m - 1) % m];
      const Spoke& b = fan_[pos % m];
      const double gamma = wrap_angle(b.ang - a.ang);
      const bool inside_tri = gamma < kPi && in_triangle(q, Vector2d::Zero(), a.q, b.q);
      // 4b: an angle too close to a neighbouring spoke is ambiguous, unless the point lies in
      // the triangle (c, a, b) (then it must be taken, seed §3.7 step 4b).
      if ((wrap_angle(ang - a.ang) < kAngleEps || wrap_angle(b.ang - ang) < kAngleEps) &&
          !inside_tri)
        return;
      // 4c (Satz 3.3.3). Gap: an open sector (>= 180 deg) accepts unconditionally.
      if (gamma < kPi && !inside_tri) {
        const double cos_psi = cos_angle(a.q - q, b.q - q);
        const double cos_gamma = cos_angle(a.q, b.q);
        // Gap: on the circle counts as outside (reject); co-circular grids stay 4-connected.
        if (!(cos_psi + cos_gamma < -kCosEps)) return;
      }
    }
    fan_.insert(fan_.begin() + static_cast<std::ptrdiff_t>(pos), Spoke{id, ang, q});
    circles_fresh_ = false;
  }

  // A cheap necessary condition for 4b/4c to accept q, without its angle (most candidates of
  // the later rounds fail 4c; atan2 and the cosines were most of the fan stage). q lies in one
  // sector (c, a, b) and is tested against that one: in a convex sector it must lie in the
  // circumcircle of (c, a, b) (a point in the triangle does too); a sector of 180 deg or more
  // accepts unconditionally, so q must lie in its angular range. The pre-test asks whether q
  // passes the test of *some* sector, which needs no angle; margins leave borderline points to
  // the exact test, so the fans are the same as without it. Fans with fewer than two spokes
  // are not filtered.
  bool surely_rejected(const Vector2d& q) {
    if (!circle_pretest_active()) return false;
    for (const SectorTest& t : sector_tests_) {
      if (t.wide) {
        // The sector from a counter-clockwise to b spans >= 180 deg (or nearly): it contains
        // the half-plane left of a and the half-plane right of b, and is their union.
        const double tol = kWedgeTolerance * q.norm();
        if (cross2(t.a, q) >= -tol * t.a_len || cross2(q, t.b) >= -tol * t.b_len) return false;
      } else if ((q - t.a).squaredNorm() <= t.r2 * (1.0 + 1e-6)) {
        return false;
      }
    }
    return true;
  }
  // False when the pre-test cannot reject anything for the current fan.
  bool circle_pretest_active() {
    if (!circles_fresh_) refresh_circles();
    return filter_;
  }
  void refresh_circles() {
    circles_fresh_ = true;
    sector_tests_.clear();
    const std::size_t m = fan_.size();
    filter_ = m >= 2;
    for (std::size_t i = 0; i < m && filter_; ++i) {
      const Vector2d& a = fan_[i].q;
      const Vector2d& b = fan_[(i + 1) % m].q;
      const double cr = cross2(a, b);  // |a| |b| sin(gap): the sector is convex when > 0
      if (!(cr > 1e-3 * a.norm() * b.norm())) {
        // 180 deg or more, or nearly straight (the circle would be huge and ill-conditioned):
        // the angular-range test, a superset of the circle test there.
        sector_tests_.push_back({true, a, b, a.norm(), b.norm(), 0.0});
        continue;
      }
      // circle through 0, a and b: 2 o.a = |a|^2, 2 o.b = |b|^2
      const Vector2d o(a.squaredNorm() * b.y() - b.squaredNorm() * a.y(),
                       b.squaredNorm() * a.x() - a.squaredNorm() * b.x());
      const Vector2d centre = o / (2.0 * cr);
      sector_tests_.push_back({false, centre, Vector2d::Zero(), 0.0, 0.0, centre.squaredNorm()});
    }
  }

  // Step 7c (Satz 3.3.6): remove spoke c-r when the two angles facing it sum to more than
  // 180 deg (the quadrilateral (c, a, r, b) is then split by a-b). Gap: passes are repeated
  // until no spoke flips (the seed makes one pass).
  void flip_spokes() {
    bool changed = true;
    while (changed && fan_.size() > 3) {
      changed = false;
      const std::size_t m = fan_.size();
      for (std::size_t j = 0; j < m; ++j) {
        const Spoke& a = fan_[(j + m - 1) % m];
        const Spoke& r = fan_[j];
        const Spoke& b = fan_[(j + 1) % m];
        const double g1 = wrap_angle(r.ang - a.ang), g2 = wrap_angle(b.ang - r.ang);
        if (g1 >= kPi || g2 >= kPi || g1 + g2 >= kPi) continue;
        const double cos_a1 = cos_angle(-a.q, r.q - a.q);
        const double cos_a2 = cos_angle(r.q - b.q, -b.q);
        if (cos_a1 + cos_a2 < -kCosEps) {
          fan_.erase(fan_.begin() + static_cast<std::ptrdiff_t>(j));
          changed = true;
          break;
        }
      }
    }
  }

  const Context& ctx_;
  std::vector<Spoke> fan_;
  std::vector<std::pair<double, int>> cand_, shell_;
  // One per sector: a circle (centre in a, squared radius r2) or a wide sector's two spokes.
  struct SectorTest {
    bool wide;
    Vector2d a, b;
    double a_len, b_len, r2;
  };
  // Relative slack of the angular-range test (a sine): rounding in the rotation into the
  // tangent plane is far smaller, so no point the exact test accepts is dropped.
  static constexpr double kWedgeTolerance = 1e-6;
  std::vector<SectorTest> sector_tests_;
  bool circles_fresh_ = false, filter_ = false;
};

// An allocator that leaves new elements unconstructed: their owner constructs them itself.
template <class T>
struct Unconstructed : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = Unconstructed<U>;
  };
  Unconstructed() = default;
  template <class U>
  Unconstructed(const Unconstructed<U>&) {}
  template <class U>
  void construct(U*) {}
};

// One face at a vertex v: the face and its two other corners in face order (v, next, prev).
// Keeping the corners here answers every edge query at v (does v -> w exist? which face?)
// without looking up the faces themselves.
struct Corner {
  int face, next, prev;
};

// The faces around one vertex. Most stars hold at most kInline faces, kept in place (no heap
// block per vertex: the growth looks at stars all the time).
class FaceStar {
 public:
  static constexpr int kInline = 9;
  const Corner* begin() const { return size_ <= kInline ? inline_.data() : more_.data(); }
  const Corner* end() const { return begin() + size_; }
  std::size_t size() const { return static_cast<std::size_t>(size_); }
  bool empty() const { return size_ == 0; }
  const Corner& operator[](std::size_t i) const { return begin()[i]; }
  void push_back(const Corner& c) {
    if (size_ < kInline) {
      inline_[size_++] = c;
      return;
    }
    if (size_ == kInline) more_.assign(inline_.begin(), inline_.end());
    more_.push_back(c);
    ++size_;
  }
  void clear() {
    size_ = 0;
    more_.clear();
  }
  void erase(int face) {  // keeps the order
    Corner* data = size_ <= kInline ? inline_.data() : more_.data();
    Corner* last = std::remove_if(data, data + size_, [face](const Corner& c) { return c.face == face; });
    const int kept = static_cast<int>(last - data);
    if (size_ > kInline) {
      more_.resize(kept);
      if (kept <= kInline) {
        std::copy(more_.begin(), more_.end(), inline_.begin());
        more_.clear();
      }
    }
    size_ = kept;
  }

 private:
  int size_ = 0;
  std::array<Corner, kInline> inline_{};
  std::vector<Corner> more_;
};

// ---------------------------------------------------------------------------------------------
// Assembly (steps 7a, 7b, 9): the fans are merged in a deterministic order into one mesh; a
// triangle is accepted only if it is new (4a), keeps every directed edge unique (so no edge gets
// a third face and orientation stays consistent, 7b) and does not overlap a triangle around its
// corners (the radar sweep's visibility condition, 7a, checked per triangle).
class Assembly {
 public:
  Assembly(const std::vector<Vector3d>& pts, double eps_area, int threads)
      : pts_(pts), others_around_(pts.size(), 0), eps_area_(eps_area) {
    // A million stars are 136 MB: constructed in parallel, so every thread faults in its share of the pages.
    star_.resize(pts.size());
    const auto n = static_cast<std::ptrdiff_t>(pts.size());
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t v = 0; v < n; ++v) ::new (static_cast<void*>(&star_[v])) FaceStar();
  }

  const std::vector<std::array<int, 3>>& faces() const { return faces_; }
  const std::vector<std::uint8_t>& alive() const { return alive_; }
  const std::vector<FaceStar, Unconstructed<FaceStar>>& star() const { return star_; }

  bool directed_edge_used(int u, int v) const { return corner_with(u, v) != nullptr; }
  bool edge_exists(int u, int v) const {
    for (const Corner& c : star_[u])
      if (c.next == v || c.prev == v) return true;
    return false;
  }
  // The bit of the side of face f that starts at its corner u.
  std::uint8_t side_bit(int f, int u) const {
    const auto& t = faces_[f];
    return static_cast<std::uint8_t>(t[0] == u ? 1 : t[1] == u ? 2 : 4);
  }
  // The corner at u of the face with the directed edge u -> v, or null.
  const Corner* corner_with(int u, int v) const {
    for (const Corner& c : star_[u])
      if (c.next == v) return &c;
    return nullptr;
  }
  // Third corner of the face with the directed edge u -> v, or -1.
  int third_vertex(int u, int v) const {
    const Corner* c = corner_with(u, v);
    return c ? c->prev : -1;
  }
  // The face with the directed edge u -> v, or -1.
  int face_with(int u, int v) const {
    const Corner* c = corner_with(u, v);
    return c ? c->face : -1;
  }
  // Calls visit(p, q) for every boundary half-edge p -> q (no face has q -> p) at vertex a,
  // face by face in star order (the edge leaving a before the edge entering it).
  template <class Visit>
  void boundary_half_edges_at(int a, Visit&& visit) const {
    for (const Corner& c : star_[a]) {
      if (!directed_edge_used(c.next, a)) visit(a, c.next);
      if (!directed_edge_used(a, c.prev)) visit(c.prev, a);
    }
  }
  // Edge-connected groups ("wedges") of the faces around v: label[i] is the group of star[v][i]
  // (the index of one of its faces); returns the number of groups (1: a manifold vertex).
  int wedge_labels(int v, std::vector<int>& label) const {
    const auto& star = star_[v];
    label.resize(star.size());
    for (std::size_t i = 0; i < star.size(); ++i) label[i] = static_cast<int>(i);
    auto find = [&](int i) {
      while (label[i] != i) i = label[i] = label[label[i]];
      return i;
    };
    int groups = static_cast<int>(star.size());
    for (std::size_t i = 0; i < star.size(); ++i)
      for (std::size_t j = i + 1; j < star.size(); ++j) {
        const Corner& a = star[i];
        const Corner& b = star[j];
        const bool shared = a.next == b.next || a.next == b.prev || a.prev == b.next ||
                            a.prev == b.prev;
        const int ri = find(static_cast<int>(i)), rj = find(static_cast<int>(j));
        if (shared && ri != rj) {
          label[ri] = rj;
          --groups;
        }
      }
    for (std::size_t i = 0; i < star.size(); ++i) label[i] = find(static_cast<int>(i));
    return groups;
  }

  bool on_boundary(int a) const {
    bool open = false;
    boundary_half_edges_at(a, [&](int, int) { open = true; });
    return open;
  }

  // Checks and adds triangle (a, b, c), counter-clockwise seen from outside. `in_3d`: the
  // overlap test is a 3D intersection test against the corners' faces instead of the planar
  // one (hole closing: on a noisy surface, projected neighbours overlap without intersecting).
  // `consensus`: all three fans agree on t; when every face around its corners is such a
  // triangle too, they lie in disjoint sectors of each corner's fan and cannot overlap, so
  // the overlap test is skipped (the old assembly added these unchecked).
  //! `slot`: a face id from reserve_faces() to fill, or -1 to append.
  bool try_add(const std::array<int, 3>& t, bool in_3d = false, bool consensus = false,
               int slot = -1) {
    const Vector3d& A = pts_[t[0]];
    const Vector3d& B = pts_[t[1]];
    const Vector3d& C = pts_[t[2]];
    const Vector3d nrm = (B - A).cross(C - A);
    const double longest =
        std::max({(B - A).squaredNorm(), (C - B).squaredNorm(), (A - C).squaredNorm()});
    if (!(nrm.norm() > eps_area_ * longest)) return false;  // degenerate
    // 4a / step 9: duplicate (in either orientation): a face at t[0] with t[1] and t[2].
    for (const Corner& c : star_[t[0]])
      if ((c.next == t[1] && c.prev == t[2]) || (c.next == t[2] && c.prev == t[1])) return false;
    for (int k = 0; k < 3; ++k)
      if (directed_edge_used(t[k], t[(k + 1) % 3])) return false;
    const bool skip = consensus && !in_3d && all_consensus_around(t);
    if (!skip && (in_3d ? intersects_star(t) : overlaps_star(t, nrm.normalized()))) return false;
    add(t, consensus, slot);
    return true;
  }

  bool all_consensus_around(const std::array<int, 3>& t) const {
    return others_around_[t[0]] == 0 && others_around_[t[1]] == 0 && others_around_[t[2]] == 0;
  }

  //! Back to no faces.
  void clear() {
    faces_.clear();
    alive_.clear();
    consensus_.clear();
    open_.clear();
    std::fill(others_around_.begin(), others_around_.end(), 0);
    for (FaceStar& s : star_) s.clear();
  }

  //! Dead face ids [first, first + count) that only add(.., slot) fills: the surface growth's
  //! blocks each fill their own range in parallel, so no face array grows meanwhile.
  int reserve_faces(std::size_t count) {
    const std::size_t first = faces_.size();
    faces_.resize(first + count, {0, 0, 0});
    alive_.resize(first + count, 0);
    consensus_.resize(first + count, 0);
    open_.resize(first + count, 0);
    return static_cast<int>(first);
  }

  void add(const std::array<int, 3>& t, bool consensus = false, int slot = -1) {
    const int f = slot < 0 ? reserve_faces(1) : slot;
    std::uint8_t open = 0;
    for (int k = 0; k < 3; ++k) {
      if (const Corner* across = corner_with(t[(k + 1) % 3], t[k]))
        open_[across->face] &= static_cast<std::uint8_t>(~side_bit(across->face, t[(k + 1) % 3]));
      else
        open |= static_cast<std::uint8_t>(1 << k);
    }
    faces_[f] = t;
    alive_[f] = 1;
    consensus_[f] = consensus ? 1 : 0;
    open_[f] = open;
    for (int k = 0; k < 3; ++k) {
      star_[t[k]].push_back({f, t[(k + 1) % 3], t[(k + 2) % 3]});
      if (!consensus) ++others_around_[t[k]];
    }
  }
  void remove(int f) {
    alive_[f] = 0;
    const auto& t = faces_[f];
    for (int v : t) {
      star_[v].erase(f);
      if (!consensus_[f]) --others_around_[v];
    }
    for (int k = 0; k < 3; ++k)
      if (const Corner* across = corner_with(t[(k + 1) % 3], t[k]))
        open_[across->face] |= side_bit(across->face, t[(k + 1) % 3]);
  }
  // Side k (corners k -> k+1) of face f has no face on its other side.
  bool side_open(int f, int k) const { return open_[f] >> k & 1; }

  bool intersects_star(const std::array<int, 3>& t) const {
    for (int v : t)
      for (const Corner& c : star_[v])
        if (triangles_intersect(pts_, t, faces_[c.face])) return true;
    return false;
  }

  // 7a: no triangle sharing a corner may overlap the new one in the new triangle's plane.
  // Separating-axis test with touching allowed (shared corners and edges lie on the axis).
  bool overlaps_star(const std::array<int, 3>& t, const Vector3d& n) const {
    const Frame fr(n);
    const Vector3d& o = pts_[t[0]];
    std::array<Vector2d, 3> a;
    for (int k = 0; k < 3; ++k) a[k] = fr.project(pts_[t[k]] - o);
    double scale = 0;
    for (int k = 0; k < 3; ++k) scale = std::max(scale, (a[k] - a[(k + 1) % 3]).squaredNorm());
    const double tol = 1e-9 * std::sqrt(scale);  // x edge length = an area tolerance
    for (int v : t)
      for (const Corner& c : star_[v]) {
        std::array<Vector2d, 3> b;
        const auto& s = faces_[c.face];
        for (int k = 0; k < 3; ++k) b[k] = fr.project(pts_[s[k]] - o);
        if (overlap2d(a, b, tol)) return true;
      }
    return false;
  }

  static bool separates(const std::array<Vector2d, 3>& p, const std::array<Vector2d, 3>& q,
                        double tol) {
    const double orient = orient2(p[0], p[1], p[2]);
    if (orient == 0) return false;
    const double s = orient > 0 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k) {
      const Vector2d& e0 = p[k];
      const Vector2d& e1 = p[(k + 1) % 3];
      const double len = (e1 - e0).norm();
      bool all_out = true;
      for (int i = 0; i < 3 && all_out; ++i)
        if (s * orient2(e0, e1, q[i]) > tol * len) all_out = false;
      if (all_out) return true;
    }
    return false;
  }
  static bool overlap2d(const std::array<Vector2d, 3>& a, const std::array<Vector2d, 3>& b,
                        double tol) {
    return !separates(a, b, tol) && !separates(b, a, tol);
  }

 private:
  const std::vector<Vector3d>& pts_;
  std::vector<std::array<int, 3>> faces_;
  std::vector<std::uint8_t> alive_;
  std::vector<std::uint8_t> consensus_;  // all three fans proposed the face
  // Per face: bit k set when its side k has no face across (kept up to date by add and remove,
  // so boundary queries need no search of the stars).
  std::vector<std::uint8_t> open_;
  // Per vertex: faces around it that are not consensus faces (kept up to date, so the
  // consensus test reads three counters instead of every face around the corners).
  std::vector<int> others_around_;
  // Constructed by the constructor itself: star_ must never grow after it (a new element would
  // stay unconstructed).
  std::vector<FaceStar, Unconstructed<FaceStar>> star_;
  double eps_area_;
};

// The sides of live faces with no face on their other side, as (face, side k: corners k -> k+1),
// in face order; faces from `first` on.
std::vector<std::pair<int, int>> open_sides(const Assembly& as, std::size_t first = 0,
                                            std::size_t end = std::numeric_limits<int>::max()) {
  std::vector<std::pair<int, int>> sides;
  for (std::size_t f = first; f < std::min(end, as.faces().size()); ++f)
    if (as.alive()[f])
      for (int k = 0; k < 3; ++k)
        if (as.side_open(static_cast<int>(f), k)) sides.emplace_back(static_cast<int>(f), k);
  return sides;
}

// Face ids reserved for one block of a parallel surface growth (first -1: none, append).
struct FaceSlots {
  int first = -1;
  std::size_t size = 0;
};

// ---------------------------------------------------------------------------------------------
// Surface growth: the fan triangles are candidates, and the mesh grows from seed triangles
// across its boundary edges, like an advancing front, best-voted candidates first. A candidate
// joins only where it keeps every vertex a single fan of faces (vertex-manifold), so bow-ties
// are never built and need no repair. Gap (seed §3.6 assembly order, docs/fans.md decision 11):
// the seed merges fans in point order; on real scans that order leaves vertices whose faces
// form several wedges wherever neighbouring fans disagree.
class SurfaceGrowth {
  // Gap: a glue joins two fronts and may make a handle; only candidates at least two fans
  // agree on may do it (with one vote, noisy regions of hippo1/2 and oni grew 1-2 spurious
  // handles each).
  static constexpr int kGlueVotes = 2;

 public:
  //! Grows over the vertices [first, end) with the candidates `mine` (indices into `cands`, in
  //! order, not yet `used`, their corners all in the range; chosen before a parallel growth
  //! starts, since its blocks write `used`). `slots`: the growth fills the faces from
  //! reserve_faces(slots.size) (one block of a parallel growth; each face uses up a candidate,
  //! so the block's candidates bound its faces); without, it appends.
  SurfaceGrowth(Assembly& as, const std::vector<Vector3d>& pts,
                const std::vector<std::array<int, 4>>& cands, std::vector<std::uint8_t>& used,
                std::vector<int> mine, int first, int end, FaceSlots slots = {},
                std::vector<int>* candidate_of = nullptr)
      : as_(as),
        pts_(pts),
        cands_(cands),
        used_(used),
        mine_(std::move(mine)),
        candidate_of_(candidate_of),
        first_(first),
        start_(static_cast<std::size_t>(end - first) + 1, 0),
        waiting_(end - first),
        next_slot_(slots.first),
        slots_end_(slots.first + static_cast<int>(slots.size)),
        first_face_(slots.first < 0 ? 0 : slots.first) {
    for (int i : mine_)
      for (int k = 0; k < 3; ++k) ++start_[cands[i][k] - first + 1];
    for (std::size_t v = 0; v + 1 < start_.size(); ++v) start_[v + 1] += start_[v];
    list_.resize(start_.back());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int i : mine_) {
      const auto& c = cands[i];
      for (int k = 0; k < 3; ++k)
        list_[fill[c[k] - first]++] = {i, c[3], {c[(k + 1) % 3], c[(k + 2) % 3]}};
    }
  }

  // Seeds: a candidate whose corners are all still free starts a new front (3 votes first,
  // then 2, then 1: on co-circular samplings such as a square grid the fans split every
  // square differently and no triangle has more than one vote); each front is grown out
  // before the next seed.
  void grow() {
    for (int votes = 3; votes >= 1; --votes)
      for (const int i : mine_) {
        const auto& c = cands_[i];
        if (used_[i] || c[3] != votes) continue;
        if (has_faces(c[0]) || has_faces(c[1]) || has_faces(c[2])) continue;
        if (!add_face(i, votes == 3)) continue;
        used_[i] = 1;
        ++seeds_;
        push_edges_of(newest_);
        drain(false);
      }
    // Fronts that met stall where a candidate's third corner is on the boundary but shares no
    // edge with the new face ("glue"): allowed now, one at a time, each followed by the normal
    // growth, which zips the two fronts together from the glued vertex.
    for (const HalfEdge& e : open_half_edges()) {
      const int before = next_face();
      const std::size_t log_before = log_.size();
      if (!attach(e, kGlueVotes, true)) continue;
      const int w = as_.faces()[before][2];
      drain(false);
      // A glue the growth could not zip from the glued vertex leaves a bow-tie: the glue and
      // what grew after it are taken back (their candidates, but the glue's, usable again).
      if (wedges_at(w) > 1) {
        for (int f = before; f < next_face(); ++f)
          if (as_.alive()[f]) as_.remove(f);
        if (next_slot_ >= 0) next_slot_ = before;  // the block's slots are reused
        for (std::size_t i = log_before + 1; i < log_.size(); ++i) used_[log_[i]] = 0;
        log_.resize(log_before);
        for (auto& q : queue_) q.clear();
        --glued_;
        ++unzipped_;
      }
    }
  }

  // After the blocks of a parallel growth: their fronts grow on across the blocks' borders
  // (where they meet, the glue step above zips them), then the usual seeds and glues.
  // Each front is grown out before the next, in face order.
  void resume() {
    for (const HalfEdge& e : open_half_edges()) {
      queue_[3].push_back(e);
      drain(false);
    }
    grow();
  }

  std::size_t seeds() const { return seeds_; }
  std::size_t glued() const { return glued_; }
  std::size_t unzipped() const { return unzipped_; }

 private:
  // A boundary half-edge u -> v and the face it was found on.
  struct HalfEdge {
    int u, v, face;
  };
  struct Option {
    int cand, w, votes;
    double flatness;  // cosine between the normals of the existing and the new face
  };

  bool has_faces(int v) const { return !as_.star()[v].empty(); }

  // The next face id add_face() gives.
  int next_face() const {
    return next_slot_ >= 0 ? next_slot_ : static_cast<int>(as_.faces().size());
  }
  bool add_face(int cand, bool consensus) {
    const auto& c = cands_[cand];
    return add_face({c[0], c[1], c[2]}, consensus, cand);
  }
  bool add_face(const std::array<int, 3>& t, bool consensus, int cand) {
    if (next_slot_ >= slots_end_ && next_slot_ >= 0)
      throw std::logic_error("surface growth: a block made more faces than it has candidates");
    const int f = next_face();
    if (!as_.try_add(t, false, consensus, next_slot_)) return false;
    newest_ = f;
    if (next_slot_ >= 0) ++next_slot_;
    if (candidate_of_) (*candidate_of_)[f] = cand;
    return true;
  }
  // The boundary half-edges of the faces from first_face_ on (a block's own slots, or every
  // face when the growth appends), in face order.
  std::vector<HalfEdge> open_half_edges() const {
    std::vector<HalfEdge> open;
    const std::size_t end =
        next_slot_ >= 0 ? static_cast<std::size_t>(slots_end_) : as_.faces().size();
    for (const auto& [f, k] : open_sides(as_, static_cast<std::size_t>(first_face_), end)) {
      const auto& t = as_.faces()[f];
      open.push_back({t[k], t[(k + 1) % 3], f});
    }
    return open;
  }

  int wedges_at(int v) const {
    std::vector<int> label;
    return as_.wedge_labels(v, label);
  }

  void drain(bool glue) {
    while (true) {
      int level = 3;
      while (level >= 1 && queue_[level].empty()) --level;
      if (level < 1) return;
      const HalfEdge e = queue_[level].front();
      queue_[level].pop_front();
      attach(e, level, glue);
    }
  }

  // Candidates on the far side of the boundary half-edge u -> v, best first.
  void options_at(const HalfEdge& e, std::vector<Option>& out) const {
    out.clear();
    const int u = e.u, v = e.v;
    int x = -1;
    const auto& t = as_.faces()[e.face];
    const int k = t[0] == u ? 0 : t[1] == u ? 1 : 2;
    // A live face with the side u -> v (a block's growth reuses the ids of faces it took back).
    if (as_.alive()[e.face] && t[k] == u && t[(k + 1) % 3] == v) {
      if (!as_.side_open(e.face, k)) return;  // no longer a boundary edge
      x = t[(k + 2) % 3];
    } else {  // the face was taken back; another may have the side now
      x = as_.third_vertex(u, v);
      if (x < 0 || as_.directed_edge_used(v, u)) return;
    }
    for (int i = start_[u - first_]; i < start_[u - first_ + 1]; ++i) {
      const Incidence& c = list_[i];
      if (c.other[0] != v && c.other[1] != v) continue;
      if (used_[c.cand]) continue;
      const int w = c.other[0] + c.other[1] - v;
      if (w == x) continue;
      out.push_back({c.cand, w, c.votes, 0.0});
    }
    // The flatness only orders options of equal votes: most edges have one option or none.
    if (out.size() < 2) return;
    const Vector3d n0 = (pts_[v] - pts_[u]).cross(pts_[x] - pts_[u]).normalized();
    for (Option& o : out)
      o.flatness = n0.dot((pts_[u] - pts_[v]).cross(pts_[o.w] - pts_[v]).normalized());
    std::sort(out.begin(), out.end(), [](const Option& a, const Option& b) {
      return a.votes != b.votes ? a.votes > b.votes : a.flatness > b.flatness;
    });
  }

  enum class Join { Free, SharesEdge, Glue, Refused };
  // How the new face (v, u, w) meets w: it keeps w a single fan of faces when w is free or
  // shares an edge with it; otherwise (a "glue") only when allowed and w is on the boundary.
  Join join_at(int u, int v, int w, bool glue) const {
    if (!has_faces(w)) return Join::Free;
    if (as_.edge_exists(v, w) || as_.edge_exists(w, u)) return Join::SharesEdge;
    return glue && as_.on_boundary(w) ? Join::Glue : Join::Refused;
  }

  // Tries the candidates of boundary half-edge u -> v with at least `level` votes; re-queues
  // the edge at the next lower level when only weaker candidates remain.
  bool attach(const HalfEdge& e, int level, bool glue) {
    const int u = e.u, v = e.v;
    options_at(e, options_);
    for (const Option& o : options_) {
      if (o.votes < level) {
        queue_[o.votes].push_back(e);
        return false;
      }
      const Join join = join_at(u, v, o.w, glue);
      if (join == Join::Refused) {
        // Only a face at w can change that: the edge waits for one.
        waiting_[o.w - first_].push_back(e);
        continue;
      }
      const bool glued = join == Join::Glue;
      if (!add_face({v, u, o.w}, o.votes == 3, o.cand)) continue;
      used_[o.cand] = 1;
      log_.push_back(o.cand);
      if (glued) ++glued_;
      push_edges_of(newest_);
      return true;
    }
    return false;
  }

  // Queues the new face's free edges, and the edges that waited for one of its corners.
  void push_edges_of(int f) {
    const auto t = as_.faces()[f];
    for (int k = 0; k < 3; ++k)
      if (as_.side_open(f, k)) queue_[3].push_back({t[k], t[(k + 1) % 3], f});
    for (int a : t) {
      auto& waiting = waiting_[a - first_];
      for (const auto& e : waiting) queue_[3].push_back(e);
      waiting.clear();
    }
  }

  Assembly& as_;
  const std::vector<Vector3d>& pts_;
  const std::vector<std::array<int, 4>>& cands_;
  std::vector<std::uint8_t>& used_;  // shared by a parallel growth's blocks: disjoint entries
  std::vector<int> mine_;            // this growth's candidates, in their order
  std::vector<int>* candidate_of_;   // when given: the candidate of each face made
  int first_;                        // its first vertex: the per-vertex arrays start there
  // A candidate as seen from one of its corners, with the other two corners in place: the
  // growth scans a vertex's candidates for every boundary edge, and reading them from the
  // candidate array was a cache miss each.
  struct Incidence {
    int cand, votes;
    std::array<int, 2> other;
  };
  std::vector<int> start_;
  std::vector<Incidence> list_;  // candidates of each vertex (CSR)
  std::array<std::deque<HalfEdge>, 4> queue_;  // boundary half-edges by votes
  std::vector<Option> options_;
  std::vector<std::vector<HalfEdge>> waiting_;  // edges stalled on a vertex
  std::vector<int> log_;  // candidates in the order they joined
  int next_slot_, slots_end_;  // a block's next reserved face and the end of its range
  int first_face_;             // a block's first slot; 0 when the growth appends
  int newest_ = -1;
  std::size_t seeds_ = 0, glued_ = 0, unzipped_ = 0;
};

// Faces around v split into edge-connected wedges; all but the largest leave v's star. Only
// what the growth's glue steps left unzipped and hole closing could not join ends here; each
// removed face is counted.
std::size_t detach_bowties(Assembly& as, int n, int threads) {
  // Read-only pass in parallel: only vertices with several wedges start the work (a manifold
  // vertex is a no-op below; one that loses faces later is pushed by that removal).
  std::vector<std::uint8_t> bowtie(n, 0);
#pragma omp parallel num_threads(threads)
  {
    std::vector<int> label;
#pragma omp for schedule(dynamic, 4096)
    for (int v = 0; v < n; ++v)
      bowtie[v] = as.star()[v].size() >= 2 && as.wedge_labels(v, label) >= 2;
  }
  std::size_t removed = 0;
  std::vector<int> work;
  for (int v = 0; v < n; ++v)
    if (bowtie[v]) work.push_back(v);
  std::vector<int> label;
  while (!work.empty()) {
    const int v = work.back();
    work.pop_back();
    std::vector<int> star;
    for (const Corner& c : as.star()[v]) star.push_back(c.face);
    if (star.size() < 2 || as.wedge_labels(v, label) < 2) continue;
    std::vector<int> size(star.size(), 0);
    for (std::size_t i = 0; i < star.size(); ++i) ++size[label[i]];
    const int keep = static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
    for (std::size_t i = 0; i < star.size(); ++i) {
      if (label[i] == keep) continue;
      const auto t = as.faces()[star[i]];
      as.remove(star[i]);
      ++removed;
      for (int x : t)
        if (x != v) work.push_back(x);
    }
  }
  return removed;
}

// Edge flips towards the Delaunay condition on the surface: an interior edge whose two opposite
// angles sum to more than 180 deg is replaced by the other diagonal of its quadrilateral when
// that raises the pair's smallest angle, the two faces are nearly coplanar (so the surface does
// not change shape) and the new faces pass the 3D intersection test. Where neighbouring fans
// were built in different tangent planes the merged mesh is not Delaunay there; CGAL's
// advancing front takes its faces from the 3D Delaunay triangulation. Returns the flips.
std::size_t flip_to_delaunay(Assembly& as, const std::vector<Vector3d>& pts, int threads) {
  const double cos_coplanar = std::cos(kFlipMaxDihedralDeg * kPi / 180.0);
  auto angle_at = [&](int o, int x, int y) {
    const Vector3d u = pts[x] - pts[o], v = pts[y] - pts[o];
    return std::atan2(u.cross(v).norm(), u.dot(v));
  };
  auto min_angle = [&](int a, int b, int c) { return triangle_min_angle(pts[a], pts[b], pts[c]); };
  auto unit_normal = [&](int a, int b, int c) {
    return (pts[b] - pts[a]).cross(pts[c] - pts[a]).normalized();
  };
  auto delaunay_across = [&](int a, int b, int c, int d) {
    if (d < 0 || d == c) return true;
    // two acute opposite angles sum to less than 180 deg: most edges end here, without atan2
    if ((pts[a] - pts[c]).dot(pts[b] - pts[c]) > 0 && (pts[b] - pts[d]).dot(pts[a] - pts[d]) > 0)
      return true;
    return angle_at(c, a, b) + angle_at(d, b, a) <= kPi + 1e-9;
  };
  // Read-only pass in parallel: only faces with a non-Delaunay edge, and faces next to a flip,
  // can flip (any other face would pass every test below unchanged). The test is symmetric in
  // the two faces, so each interior edge is tested once, from the side a < b, and marks both.
  // The edges a -> b are read from the stars of a in point order: the points are in cell
  // order, so b's star and the corners' positions are near in memory (face order was not).
  const std::size_t faces = as.faces().size();
  const auto n = static_cast<std::ptrdiff_t>(pts.size());
  std::vector<std::uint8_t> suspect(faces, 0);
  auto mark = [&](std::size_t f) { std::atomic_ref(suspect[f]).store(1, std::memory_order_relaxed); };
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4096)
  for (std::ptrdiff_t a = 0; a < n; ++a) {
    for (const Corner& corner : as.star()[a]) {
      const int b = corner.next, c = corner.prev;
      if (a > b) continue;
      const Corner* across = as.corner_with(b, static_cast<int>(a));
      if (!across || delaunay_across(static_cast<int>(a), b, c, across->prev)) continue;
      mark(static_cast<std::size_t>(corner.face));
      mark(static_cast<std::size_t>(across->face));
    }
  }
  std::size_t flips = 0;
  for (std::size_t f = 0; f < faces; ++f) {
    if (!suspect[f]) continue;
    for (int k = 0; k < 3 && as.alive()[f]; ++k) {
      const auto t = as.faces()[f];
      const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      const int d = as.third_vertex(b, a);
      if (delaunay_across(a, b, c, d)) continue;
      if (unit_normal(a, b, c).dot(unit_normal(b, a, d)) < cos_coplanar) continue;
      if (as.edge_exists(c, d)) continue;
      const double before = std::min(min_angle(a, b, c), min_angle(b, a, d));
      if (std::min(min_angle(c, a, d), min_angle(d, b, c)) <= before) continue;
      if (unit_normal(c, a, d).dot(unit_normal(d, b, c)) < cos_coplanar) continue;
      const int g = as.face_with(b, a);
      if (g < 0) continue;
      const auto tg = as.faces()[g];
      as.remove(static_cast<int>(f));
      as.remove(g);
      const std::size_t first = as.faces().size();
      if (as.try_add({c, a, d}, true) && as.try_add({d, b, c}, true)) {
        ++flips;
        for (int v : {a, b, c, d})
          for (const Corner& h : as.star()[v])
            if (static_cast<std::size_t>(h.face) < faces) suspect[h.face] = 1;
        break;  // f is gone
      }
      for (std::size_t h = first; h < as.faces().size(); ++h)
        if (as.alive()[h]) as.remove(static_cast<int>(h));
      as.add(t);
      as.add(tg);
    }
  }
  return flips;
}

// Triangulates a boundary loop as a whole, maximising its smallest angle (dynamic programming
// over the loop's sub-polygons, O(m^3) for m <= max_hole_edges): ear clipping takes the best
// ear at each step and can leave slivers at the end. Every triangle passes the assembly's
// checks with the 3D intersection test; if one does not, nothing is added (returns 0) and the
// caller falls back to ear clipping. Fill faces traverse the loop backwards.
std::size_t fill_loop_max_min_angle(Assembly& as, const std::vector<Vector3d>& pts,
                                    const std::vector<int>& loop, double max_edge) {
  const int m = static_cast<int>(loop.size());
  auto min_angle = [&](int a, int b, int c) {
    return triangle_min_angle(pts[loop[a]], pts[loop[b]], pts[loop[c]]);
  };
  // best[i][j]: the largest smallest angle of a triangulation of loop[i..j] (j > i + 1); a
  // chord that is already an edge of the mesh elsewhere is forbidden (it would get 3 faces).
  std::vector<double> best(static_cast<std::size_t>(m) * m, -1.0);
  std::vector<int> split(static_cast<std::size_t>(m) * m, -1);
  auto at = [m](int i, int j) { return static_cast<std::size_t>(i) * m + j; };
  for (int len = 2; len < m; ++len)
    for (int i = 0; i + len < m; ++i) {
      const int j = i + len;
      if (!(i == 0 && j == m - 1) && as.edge_exists(loop[i], loop[j])) continue;
      if ((pts[loop[i]] - pts[loop[j]]).norm() > max_edge) continue;
      for (int k = i + 1; k < j; ++k) {
        const double left = k == i + 1 ? kPi : best[at(i, k)];
        const double right = j == k + 1 ? kPi : best[at(k, j)];
        const double q = std::min({left, right, min_angle(i, k, j)});
        if (left >= 0 && right >= 0 && q > best[at(i, j)]) {
          best[at(i, j)] = q;
          split[at(i, j)] = k;
        }
      }
    }
  if (!(best[at(0, m - 1)] > 0)) return 0;
  std::vector<std::array<int, 3>> tris;
  std::vector<std::pair<int, int>> stack{{0, m - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[at(i, j)];
    tris.push_back({loop[j], loop[k], loop[i]});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  const std::size_t first = as.faces().size();
  for (const auto& t : tris)
    if (!as.try_add(t, true)) {
      for (std::size_t f = first; f < as.faces().size(); ++f) as.remove(static_cast<int>(f));
      return 0;
    }
  return tris.size();
}

// Closes the small holes where neighbouring fans disagreed: boundary loops of at most
// `max_edges` edges, by ear clipping in the loop's mean plane, best (largest smallest angle)
// ear first, through the same checks as the assembly.
std::size_t close_holes(Assembly& as, const std::vector<Vector3d>& pts,
                        const std::vector<Vector3d>& normals, int max_edges, double max_edge) {
  const auto& faces = as.faces();
  std::vector<std::pair<int, int>> boundary;
  for (const auto& [f, k] : open_sides(as))
    boundary.emplace_back(faces[f][k], faces[f][(k + 1) % 3]);
  std::sort(boundary.begin(), boundary.end());
  std::vector<std::uint8_t> used(boundary.size(), 0);
  auto first_out = [&](int u) {
    return static_cast<std::size_t>(
        std::lower_bound(boundary.begin(), boundary.end(),
                         std::pair<int, int>{u, std::numeric_limits<int>::min()}) -
        boundary.begin());
  };
  // Where several boundary loops touch at a vertex (a non-manifold vertex: separate wedges of
  // faces), a loop continues with the outgoing boundary half-edge that follows the incoming one
  // counter-clockwise around the vertex normal: the free sector between the two wedges.
  auto next_half_edge = [&](std::size_t h, std::size_t h0) -> std::ptrdiff_t {
    const int w = boundary[h].first, u = boundary[h].second;
    std::size_t b = first_out(u);
    std::ptrdiff_t best = -1;
    double best_angle = 10.0;
    const Frame fr(normals[u]);
    const Vector2d dw = fr.project(pts[w] - pts[u]);
    const double aw = std::atan2(dw.y(), dw.x());
    for (; b < boundary.size() && boundary[b].first == u; ++b) {
      if (used[b] && b != h0) continue;
      const Vector2d dv = fr.project(pts[boundary[b].second] - pts[u]);
      double a = std::atan2(dv.y(), dv.x()) - aw;
      while (a <= 0) a += kTwoPi;
      while (a > kTwoPi) a -= kTwoPi;
      if (a < best_angle) {
        best_angle = a;
        best = static_cast<std::ptrdiff_t>(b);
      }
    }
    return best;
  };
  std::size_t added = 0;
  for (std::size_t h0 = 0; h0 < boundary.size(); ++h0) {
    if (used[h0]) continue;
    std::vector<int> loop;
    std::size_t h = h0;
    bool ok = true;
    while (true) {
      used[h] = 1;
      loop.push_back(boundary[h].first);
      if (static_cast<int>(loop.size()) > max_edges) {
        ok = false;
        break;
      }
      const std::ptrdiff_t nh = next_half_edge(h, h0);
      if (nh < 0) {
        ok = false;
        break;
      }
      if (static_cast<std::size_t>(nh) == h0) break;
      h = static_cast<std::size_t>(nh);
    }
    if (!ok || loop.size() < 3) continue;
    if (const std::size_t n_fill = fill_loop_max_min_angle(as, pts, loop, max_edge)) {
      added += n_fill;
      continue;
    }
    // The fill faces traverse the loop backwards: ear at i is (loop[i+1], loop[i], loop[i-1]).
    while (loop.size() >= 3) {
      const std::size_t m = loop.size();
      Vector3d newell = Vector3d::Zero();  // of the reversed loop = the fill orientation
      for (std::size_t i = 0; i < m; ++i) {
        const Vector3d& p = pts[loop[(i + 1) % m]];
        const Vector3d& q = pts[loop[i]];
        newell += p.cross(q);
      }
      std::vector<std::pair<double, std::size_t>> ears;  // (-smallest angle, position)
      for (std::size_t i = 0; i < m; ++i) {
        const int a = loop[(i + 1) % m], b = loop[i], c = loop[(i + m - 1) % m];
        const Vector3d nrm = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
        if (nrm.dot(newell) <= 0) continue;  // reflex ear
        if (m > 3 && as.edge_exists(a, c)) continue;
        const Vector3d A = pts[a], B = pts[b], C = pts[c];
        auto ang = [](const Vector3d& p, const Vector3d& x, const Vector3d& y) {
          return std::acos(std::clamp((x - p).normalized().dot((y - p).normalized()), -1.0, 1.0));
        };
        // no other loop vertex inside the ear (in the ear's plane)
        bool empty = true;
        const Frame fr(nrm.normalized());
        const Vector2d a2 = fr.project(A - A), b2 = fr.project(B - A), c2 = fr.project(C - A);
        for (std::size_t j2 = 0; j2 < m && empty; ++j2) {
          const int x = loop[j2];
          if (x == a || x == b || x == c) continue;
          if (in_triangle(fr.project(pts[x] - A), a2, b2, c2)) empty = false;
        }
        if (empty) ears.emplace_back(-std::min({ang(A, B, C), ang(B, C, A), ang(C, A, B)}), i);
      }
      std::sort(ears.begin(), ears.end());
      bool clipped = false;
      for (const auto& [q, i] : ears) {
        const std::array<int, 3> t{loop[(i + 1) % m], loop[i], loop[(i + m - 1) % m]};
        if ((pts[t[0]] - pts[t[2]]).norm() > max_edge) continue;  // the user's edge limit
        if (!as.try_add(t, true)) continue;
        ++added;
        loop.erase(loop.begin() + static_cast<std::ptrdiff_t>(i));
        clipped = true;
        break;
      }
      if (!clipped) break;
      if (loop.size() == 2) break;
    }
  }
  return added;
}

// A point left outside every triangle near the mesh's rim (a spike's tip, a sparse border)
// joins the boundary half-edge u -> v of its neighbourhood that gives the triangle (v, u, p)
// with the shortest perimeter, if it intersects nothing: a free vertex keeps the mesh manifold.
bool attach_to_boundary(Assembly& as, const Context& ctx, int p) {
  const auto& pts = ctx.pts;
  std::vector<std::pair<double, std::array<int, 3>>> options;
  for (int k = 0; k < kNormalNeighbours; ++k) {
    const int j = ctx.knn[static_cast<std::size_t>(p) * kNormalNeighbours + k];
    if (j < 0) continue;
    as.boundary_half_edges_at(j, [&](int u, int v) {
      const double perimeter =
          (pts[u] - pts[v]).norm() + (pts[u] - pts[p]).norm() + (pts[v] - pts[p]).norm();
      options.push_back({perimeter, {v, u, p}});
    });
  }
  std::sort(options.begin(), options.end());
  for (const auto& [perimeter, t] : options)
    if (as.try_add(t, true)) return true;
  return false;
}

// A point that ended in no triangle lies on a triangle of its neighbourhood: split that
// triangle 1-to-3 through the point (keeps the mesh manifold and every point used).
std::size_t insert_unused(Assembly& as, const Context& ctx) {
  const auto& pts = ctx.pts;
  std::size_t inserted = 0;
  for (std::size_t p = 0; p < pts.size(); ++p) {
    if (!as.star()[p].empty()) continue;
    int best = -1;
    double best_dist = std::numeric_limits<double>::infinity();
    for (int k = 0; k < kNormalNeighbours; ++k) {
      const int j = ctx.knn[p * kNormalNeighbours + k];
      if (j < 0) continue;
      for (const Corner& corner : as.star()[j]) {
        const int f = corner.face;
        const auto& t = as.faces()[f];
        const Vector3d nrm = (pts[t[1]] - pts[t[0]]).cross(pts[t[2]] - pts[t[0]]).normalized();
        const Frame fr(nrm);
        const Vector2d x = fr.project(pts[p] - pts[t[0]]);
        const Vector2d a = Vector2d::Zero(), b = fr.project(pts[t[1]] - pts[t[0]]),
                       c = fr.project(pts[t[2]] - pts[t[0]]);
        if (!(orient2(a, b, x) > 0 && orient2(b, c, x) > 0 && orient2(c, a, x) > 0)) continue;
        const double dist = std::abs(nrm.dot(pts[p] - pts[t[0]]));
        if (dist < best_dist) {
          best_dist = dist;
          best = f;
        }
      }
    }
    if (best < 0) {
      inserted += attach_to_boundary(as, ctx, static_cast<int>(p)) ? 1 : 0;
      continue;
    }
    const auto t = as.faces()[best];
    as.remove(best);
    const int q = static_cast<int>(p);
    as.add({t[0], t[1], q});
    as.add({t[1], t[2], q});
    as.add({t[2], t[0], q});
    ++inserted;
  }
  return inserted;
}

// Each connected piece the growth built is consistently oriented in itself (every face joined
// across an edge traversed the other way); a piece is turned round when its faces disagree
// with the oriented normals of their corners on the whole.
void orient_components_by_normals(std::vector<std::array<int, 3>>& faces,
                                  const std::vector<Vector3d>& pts,
                                  const std::vector<Vector3d>& normals, int threads) {
  kernel::VertexComponents components(pts.size());
  for (const auto& t : faces) components.join(t);
  // Each face's vote in parallel, summed in face order (the same sums as one loop).
  std::vector<double> vote(faces.size());
  const auto nf = static_cast<std::ptrdiff_t>(faces.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t f = 0; f < nf; ++f) {
    const auto& t = faces[f];
    const Vector3d fn = (pts[t[1]] - pts[t[0]]).cross(pts[t[2]] - pts[t[0]]);
    vote[f] = fn.dot(normals[t[0]] + normals[t[1]] + normals[t[2]]);
  }
  std::vector<double> agreement(pts.size(), 0.0);
  for (std::size_t f = 0; f < faces.size(); ++f) agreement[components.root(faces[f][0])] += vote[f];
  for (auto& t : faces)
    if (agreement[components.root(t[0])] < 0) std::swap(t[1], t[2]);
}

// Limit (docs/fans.md, "Limits"): every neighbour query in a cell reads all of its points, so a
// cluster far denser than the rest (50,000 points within 1e-9 of each other beside a scan) made
// the fans quadratic in the cluster's size. The grid's cells hold ~2k points where the cloud is
// a surface; a cell with more than 4096 points and 64 times the cloud's mean per occupied cell
// is refused instead of meshed for minutes. Exact copies never get here (meshed once).
constexpr std::size_t kMaxPointsPerCell = 4096;

void check_crowding(const PointGrid& grid, int n) {
  const std::size_t fullest = grid.fullest_cell();
  const std::size_t mean =
      static_cast<std::size_t>(n) / std::max<std::size_t>(1, grid.occupied_cells());
  if (fullest <= std::max(kMaxPointsPerCell, 64 * mean)) return;
  std::ostringstream os;
  os << "build_fans: " << fullest << " points lie in one grid cell of edge " << grid.cell_edge()
     << " (the cloud's cells hold " << mean << " on average; at most "
     << std::max(kMaxPointsPerCell, 64 * mean)
     << "): a cluster far denser than the rest of the cloud; thin it (e.g. a voxel filter) or "
        "remove it";
  throw InvalidInputError(os.str());
}

void check_input(const std::vector<Vector3d>& points, const FanOptions& options) {
  options.validate();
  if (points.size() < 3)
    throw InvalidInputError("build_fans: needs at least 3 distinct points spread over a surface");
  if (points.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 16))
    throw InvalidInputError("build_fans: too many points");
  for (const auto& p : points)
    if (!p.allFinite()) throw InvalidInputError("build_fans: a point has a non-finite coordinate");
}

// The points in the grid's cell order, so that neighbours are close in memory (the fans touch
// the positions and normals of all neighbours; in input order that is a cache miss each).
struct SortedPoints {
  std::vector<int> perm;  // sorted index -> input index
  std::vector<Vector3d> points;
};
SortedPoints sort_by_cell(const std::vector<Vector3d>& input, const PointGrid& grid) {
  SortedPoints s{grid.order(), std::vector<Vector3d>(input.size())};
  for (std::size_t i = 0; i < s.perm.size(); ++i) s.points[i] = input[s.perm[i]];
  return s;
}

// Whether two points share a position. Copies fall into one grid cell, and cells hold a few
// points, so comparing within cells (in parallel) is far cheaper than sorting the cloud.
bool has_duplicates(const PointGrid& grid, const std::vector<Vector3d>& points, int threads) {
  const auto cells = static_cast<std::ptrdiff_t>(grid.cells());
  const auto& order = grid.order();
  int found = 0;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4096) reduction(| : found)
  for (std::ptrdiff_t c = 0; c < cells; ++c) {
    const std::size_t b = grid.cell_begin(c), e = grid.cell_begin(c + 1);
    if (e - b <= 32) {
      for (std::size_t i = b; i < e && !found; ++i)
        for (std::size_t j = i + 1; j < e && !found; ++j)
          found = points[order[i]] == points[order[j]];
      continue;
    }
    // A crowded cell: sorted by position, copies are neighbours (no quadratic work).
    std::vector<int> in_cell(order.begin() + b, order.begin() + e);
    const auto less = [&](int i, int j) {
      return std::tie(points[i].x(), points[i].y(), points[i].z()) <
             std::tie(points[j].x(), points[j].y(), points[j].z());
    };
    std::sort(in_cell.begin(), in_cell.end(), less);
    for (std::size_t i = 1; i < in_cell.size() && !found; ++i)
      found = points[in_cell[i - 1]] == points[in_cell[i]];
  }
  return found != 0;
}

}  // namespace

void FanOptions::validate() const {
  auto fail = [](const std::string& what) { throw InvalidInputError("fan options: " + what); };
  if (k < 1 || k > 1000) fail("k must be in 1..1000");
  if (!(alpha_deg >= 30.0 && alpha_deg < 180.0)) fail("alpha_deg must be in [30, 180)");
  if (!(dmax_factor > 0 && dmax_factor <= 100)) fail("dmax_factor must be in (0, 100]");
  if (!(max_edge >= 0) || !std::isfinite(max_edge)) fail("max_edge must be >= 0");
  if (!(max_edge_factor >= 0) || !std::isfinite(max_edge_factor))
    fail("max_edge_factor must be >= 0");
  if (!(max_normal_angle_deg >= 0 && max_normal_angle_deg <= 180))
    fail("max_normal_angle_deg must be in [0, 180]");
  if (max_hole_edges < 0) fail("max_hole_edges must be >= 0");
  if (threads < 0 || threads > kMaxThreads)
    fail("threads must be in 0.." + std::to_string(kMaxThreads) + " (0: all cores)");
}

std::vector<Vector3d> estimate_fan_normals(const std::vector<Vector3d>& input,
                                           const FanOptions& options) {
  check_input(input, options);
  PointGrid grid = cell_grid(input, options.k);
  const auto [perm, points] = sort_by_cell(input, grid);
  Context ctx(points, options, std::move(grid).reordered(points));
  compute_normals(ctx, nullptr);
  std::vector<Vector3d> out(input.size());
  for (std::size_t i = 0; i < perm.size(); ++i) out[perm[i]] = ctx.normals[i];
  return out;
}

namespace {

// Steps 1-6, 7c: one fan per point, independent of the others, so they run in parallel and
// the result does not depend on the thread count.
std::vector<std::vector<FanEntry>> build_all_fans(const Context& ctx, const FanOptions& options,
                                                  FanStats& st) {
  const int n = static_cast<int>(ctx.normals.size());
  std::vector<std::vector<FanEntry>> fans(n);
  std::size_t fallbacks = 0, open = 0;
#pragma omp parallel num_threads(omp_threads(options)) reduction(+ : fallbacks, open)
  {
    FanBuilder builder(ctx);
#pragma omp for schedule(dynamic, 256)
    for (int o = 0; o < n; ++o) {
      const int c = o;  // cell order (the points are sorted by cell)
      bool closed = builder.build(c, ctx.normals[c], fans[c]);
      if (!closed && !ctx.is_pca[c]) {
        // Gap (§3.4 fallback trigger): a fan still open at d_max is rebuilt once with the
        // PCA normal of the 10 nearest neighbours, oriented like the 3-NN normal.
        Vector3d pn = ctx.pca[c];
        if (pn.dot(ctx.normals[c]) < 0) pn = -pn;
        if (std::abs(pn.dot(ctx.normals[c])) < 1.0 - 1e-12) {
          ++fallbacks;
          std::vector<FanEntry> alt;
          if (builder.build(c, pn, alt)) {
            fans[c] = std::move(alt);
            closed = true;
          }
        }
      }
      if (!closed) ++open;
    }
  }
  st.pca_fallbacks = fallbacks;
  st.open_fans = open;
  return fans;
}

// Step 9 with votes: triangle (c, r1, r2) is proposed by c and, if they agree, by r1 and r2.
// Each distinct triangle is emitted once, by its smallest-index proposer, as (a, b, c, votes):
// 3 votes first, then 2, then 1, each in point order.
std::vector<std::array<int, 4>> vote_triangles(const std::vector<std::vector<FanEntry>>& fans,
                                               const FanOptions& options) {
  const int n = static_cast<int>(fans.size());
  // fan(v) has x and y as consecutive spokes with a triangle between them. Either order: the
  // votes must not depend on the normals' orientation, which noise can flip between
  // neighbours; the surface growth below orients the faces.
  auto has_pair = [&](int v, int x, int y) {
    const auto& f = fans[v];
    const std::size_t m = f.size();
    for (std::size_t i = 0; i < m; ++i)
      if (f[i].id == x) {
        const std::size_t prev = (i + m - 1) % m;
        return (f[i].closed_after && f[(i + 1) % m].id == y) ||
               (f[prev].closed_after && f[prev].id == y);
      }
    return false;
  };
  // Votes of every closed sector, once (0: another corner emits the triangle), then the
  // proposals written at prefix offsets straight into their order: 3 votes first, then 2, then
  // 1, each in point order. Neither depends on the thread count.
  std::vector<std::size_t> entry_start(static_cast<std::size_t>(n) + 1, 0);
  for (int c = 0; c < n; ++c) entry_start[c + 1] = entry_start[c] + fans[c].size();
  std::vector<std::uint8_t> votes(entry_start[n], 0);
  std::array<std::vector<std::size_t>, 4> offset;  // per vote count: proposals before point c
  for (int v = 1; v <= 3; ++v) offset[v].assign(static_cast<std::size_t>(n) + 1, 0);
#pragma omp parallel for num_threads(omp_threads(options)) schedule(dynamic, 512)
  for (int c = 0; c < n; ++c) {
    const auto& f = fans[c];
    const std::size_t m = f.size();
    for (std::size_t i = 0; i < m; ++i) {
      if (!f[i].closed_after) continue;
      const int r1 = f[i].id, r2 = f[(i + 1) % m].id;
      const bool v1 = has_pair(r1, r2, c), v2 = has_pair(r2, c, r1);
      int smallest = c;
      if (v1) smallest = std::min(smallest, r1);
      if (v2) smallest = std::min(smallest, r2);
      if (smallest != c) continue;
      const int v = 1 + int(v1) + int(v2);
      votes[entry_start[c] + i] = static_cast<std::uint8_t>(v);
      ++offset[v][c + 1];
    }
  }
  std::array<std::size_t, 5> level_start{};  // proposals with more votes come first
  for (int v = 3; v >= 1; --v) {
    for (int c = 0; c < n; ++c) offset[v][c + 1] += offset[v][c];
    level_start[v] = level_start[v + 1] + offset[v][n];
  }
  std::vector<std::array<int, 4>> proposals(level_start[1]);  // a, b, c, votes
#pragma omp parallel for num_threads(omp_threads(options)) schedule(dynamic, 512)
  for (int c = 0; c < n; ++c) {
    const auto& f = fans[c];
    const std::size_t m = f.size();
    std::array<std::size_t, 4> k{0, level_start[2] + offset[1][c], level_start[3] + offset[2][c],
                                 offset[3][c]};
    for (std::size_t i = 0; i < m; ++i) {
      const int v = votes[entry_start[c] + i];
      if (v > 0) proposals[k[v]++] = {c, f[i].id, f[(i + 1) % m].id, v};
    }
  }
  return proposals;
}

// The surface growth's blocks: each starts at the first point of a layer of cells (z = const),
// the one nearest to each share of `per_block` points, so that blocks are slabs of space, which
// their triangles cannot leave (a block cut inside a cell or a row had triangles of two blocks
// overlapping without a shared corner, where none of the assembly's tests looks). `starts`
// ends with n. `cuts`: the points of the two layers at each cut, whose faces the blocks'
// growths built without the candidates across the cut; `near_cuts`: of the four layers there.
struct GrowthBlocks {
  std::vector<int> starts;
  std::vector<std::pair<int, int>> cuts, near_cuts;
};
GrowthBlocks growth_blocks(const PointGrid& grid, int n, std::size_t per_block) {
  GrowthBlocks g{{0}, {}};
  auto& starts = g.starts;
  const int blocks = per_block == 0 ? 1 : static_cast<int>(std::max<std::size_t>(1, n / per_block));
  const auto& dims = grid.dims();
  const std::size_t layer = static_cast<std::size_t>(dims[0]) * dims[1];
  const auto layers_total = static_cast<std::size_t>(dims[2]);
  std::size_t z = 0;  // the layer the last cut is below
  for (int b = 1; b < blocks; ++b) {
    const auto target = static_cast<std::int64_t>(n) * b / blocks;
    // the layer boundary above the last cut nearest to the target (they do not decrease)
    std::size_t nearest = 0;
    std::int64_t nearest_gap = std::numeric_limits<std::int64_t>::max();
    for (std::size_t k = z + 1; k < layers_total; ++k) {
      const auto boundary = static_cast<std::int64_t>(grid.cell_begin(k * layer));
      if (std::abs(boundary - target) < nearest_gap) {
        nearest_gap = std::abs(boundary - target);
        nearest = k;
      }
      if (boundary > target) break;
    }
    if (nearest == 0) break;
    const std::size_t cut = grid.cell_begin(nearest * layer);
    if (cut > static_cast<std::size_t>(starts.back()) && cut < static_cast<std::size_t>(n)) {
      z = nearest;
      starts.push_back(static_cast<int>(cut));
      // the points of the layers [z - w, z + w), within the grid
      auto layers = [&](std::size_t w) {
        const std::size_t lo = z >= w ? z - w : 0;
        const std::size_t hi = std::min(z + w, layers_total);
        return std::pair(static_cast<int>(grid.cell_begin(lo * layer)),
                         static_cast<int>(grid.cell_begin(hi * layer)));
      };
      g.cuts.push_back(layers(1));
      g.near_cuts.push_back(layers(2));
    }
  }
  starts.push_back(n);
  return g;
}

// The candidates not yet used, in order.
std::vector<int> unused_candidates(const std::vector<std::uint8_t>& used) {
  std::vector<int> unused;
  for (std::size_t i = 0; i < used.size(); ++i)
    if (!used[i]) unused.push_back(static_cast<int>(i));
  return unused;
}

// Hole closing as the options ask (close_holes).
std::size_t close_small_holes(Assembly& as, const Context& ctx) {
  if (ctx.opt.max_hole_edges < 3) return 0;
  return close_holes(
      as, ctx.pts, ctx.normals, ctx.opt.max_hole_edges,
      ctx.opt.max_edge > 0 ? ctx.opt.max_edge : std::numeric_limits<double>::infinity());
}

// What the surface growths report.
struct GrowthCounts {
  std::size_t seeds = 0, glued = 0, unzipped = 0, hole_triangles = 0;
  void add(const SurfaceGrowth& g) {
    seeds += g.seeds();
    glued += g.glued();
    unzipped += g.unzipped();
  }
  GrowthCounts& operator+=(const GrowthCounts& o) {
    seeds += o.seeds;
    glued += o.glued;
    unzipped += o.unzipped;
    hole_triangles += o.hole_triangles;
    return *this;
  }
};

// The surface growth in blocks of consecutive points: points are in cell order, so a block is a
// slab of space, and its growth touches only its own vertices and faces; the blocks grow in
// parallel. The faces at the cuts are then taken back (their candidates usable again) and one
// growth builds them anew from the blocks' fronts with every candidate; then the holes are
// closed. Returns false, with the assembly and `used` to be reset, when a boundary edge is left
// near a cut: the fronts met there without closing (noisy clouds), where one growth for the
// whole cloud might not leave a hole.
bool grow_in_blocks(Assembly& as, const Context& ctx,
                    const std::vector<std::array<int, 4>>& proposals, const GrowthBlocks& split,
                    std::vector<std::uint8_t>& used, GrowthCounts& counts) {
  const auto& points = ctx.pts;
  const std::vector<int>& starts = split.starts;
  const int blocks = static_cast<int>(starts.size()) - 1;
  auto block_of = [&](int v) {
    return static_cast<int>(std::upper_bound(starts.begin(), starts.end(), v) - starts.begin()) - 1;
  };
  std::vector<std::vector<int>> inside(blocks);  // candidates with all corners in the block
  for (std::size_t i = 0; i < proposals.size(); ++i) {
    const auto& c = proposals[i];
    const int b = block_of(c[0]);
    if (block_of(c[1]) == b && block_of(c[2]) == b) inside[b].push_back(static_cast<int>(i));
  }
  std::vector<FaceSlots> slots(blocks);
  for (int b = 0; b < blocks; ++b) slots[b] = {as.reserve_faces(inside[b].size()), inside[b].size()};
  std::vector<GrowthCounts> block_counts(blocks);
  std::vector<int> candidate_of(as.faces().size(), -1);
#pragma omp parallel for num_threads(omp_threads(ctx.opt)) schedule(dynamic, 1)
  for (int b = 0; b < blocks; ++b) {
    SurfaceGrowth g(as, points, proposals, used, std::move(inside[b]), starts[b], starts[b + 1],
                    slots[b], &candidate_of);
    g.grow();
    block_counts[b].add(g);
  }
  for (const auto& c : block_counts) counts += c;
  auto within = [](const std::vector<std::pair<int, int>>& ranges, int v) {
    for (const auto& [first, end] : ranges)
      if (v >= first && v < end) return true;
    return false;
  };
  for (std::size_t f = 0; f < candidate_of.size(); ++f) {
    const auto& t = as.faces()[f];
    if (!as.alive()[f] ||
        !(within(split.cuts, t[0]) || within(split.cuts, t[1]) || within(split.cuts, t[2])))
      continue;
    as.remove(static_cast<int>(f));
    used[candidate_of[f]] = 0;
  }
  SurfaceGrowth across(as, points, proposals, used, unused_candidates(used), 0,
                       static_cast<int>(points.size()));
  across.resume();
  counts.add(across);
  counts.hole_triangles = close_small_holes(as, ctx);
  for (const auto& [f, k] : open_sides(as)) {
    const auto& t = as.faces()[f];
    if (within(split.near_cuts, t[k]) || within(split.near_cuts, t[(k + 1) % 3])) return false;
  }
  return true;
}

// The surface growth and hole closing; the growth in blocks (above) when the options ask for
// them and the cloud has room for several. The blocks depend on the cloud only, so the result does
// not depend on the thread count.
void grow_surface(Assembly& as, const Context& ctx,
                  const std::vector<std::array<int, 4>>& proposals, FanStats& st) {
  const int n = static_cast<int>(ctx.pts.size());
  std::vector<std::uint8_t> used(proposals.size(), 0);
  const GrowthBlocks split = growth_blocks(ctx.grid, n, ctx.opt.growth_block_points);
  GrowthCounts counts;
  const bool blocks = split.starts.size() > 2;
  st.growth_blocks = split.starts.size() - 1;
  if (!blocks || !grow_in_blocks(as, ctx, proposals, split, used, counts)) {
    if (blocks) {  // start over as one growth
      as.clear();
      std::fill(used.begin(), used.end(), 0);
      counts = {};
      st.growth_blocks = 1;
      st.growth_blocks_discarded = split.starts.size() - 1;
    }
    SurfaceGrowth g(as, ctx.pts, proposals, used, unused_candidates(used), 0, n);
    g.grow();
    counts.add(g);
    counts.hole_triangles = close_small_holes(as, ctx);
  }
  st.hole_triangles = counts.hole_triangles;
  st.seeds = counts.seeds;
  st.glued_triangles = counts.glued;
  st.unzipped_glues = counts.unzipped;
  st.rejected_triangles = static_cast<std::size_t>(std::count(used.begin(), used.end(), 0));
}

// The assembly's triangles oriented, mapped back to the input's order, turned round as a whole
// if they enclose a negative volume (without trusted normals), with the points' normals.
void write_mesh(const Assembly& as, const std::vector<Vector3d>& input,
                const std::vector<Vector3d>& points, const std::vector<int>& perm,
                const Context& ctx, bool trust_normals, const FanOptions& options,
                FanResult& result) {
  const int n = static_cast<int>(points.size());
  const auto [lo, hi] = ctx.grid.box();
  Mesh& mesh = result.mesh;
  mesh.positions = input;
  std::vector<std::array<int, 3>> faces;
  for (std::size_t f = 0; f < as.faces().size(); ++f)
    if (as.alive()[f]) faces.push_back(as.faces()[f]);
  const int threads = omp_threads(options);
  orient_components_by_normals(faces, points, ctx.normals, threads);
  const auto nf = static_cast<std::ptrdiff_t>(faces.size());
  mesh.triangles.resize(faces.size());
  // Per-face terms in parallel, summed in face order: the same sums as one sequential loop.
  std::vector<double> signed_volume(faces.size()), doubled_area(faces.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t f = 0; f < nf; ++f) {
    const auto& t = faces[f];
    mesh.triangles[f] = {perm[t[0]], perm[t[1]], perm[t[2]]};
    // the same coordinates as input[perm[..]], near in memory
    signed_volume[f] = points[t[0]].dot(points[t[1]].cross(points[t[2]]));
    doubled_area[f] = (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]).norm();
  }
  // Without given normals the oriented estimates may point inwards as a whole: turn
  // everything round if the enclosed volume is negative (meaningful on a closed surface).
  double volume = 0;
  for (const double v : signed_volume) volume += v;
  double area = 0;
  for (const double a : doubled_area) area += a;
  const bool flip = !trust_normals && volume < -1e-3 * area * (hi - lo).norm();
  if (flip) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t f = 0; f < nf; ++f) std::swap(mesh.triangles[f][1], mesh.triangles[f][2]);
  }
  mesh.normals.resize(n);
  std::size_t unused = 0;  // points in no face: their stars are empty
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : unused)
  for (int i = 0; i < n; ++i) {
    mesh.normals[perm[i]] = (flip ? -ctx.normals[i] : ctx.normals[i]).cast<float>();
    unused += as.star()[i].empty() ? 1 : 0;
  }
  result.stats.unused_points = unused;
}

// `grid`: the cell grid over `input` (cell_grid), built here when absent.
FanResult build_fans_distinct(const std::vector<Vector3d>& input, const FanOptions& options,
                              const std::vector<Eigen::Vector3f>* given_normals,
                              std::optional<PointGrid> grid = std::nullopt) {
  check_input(input, options);
  // Internally the points are in cell order; indices are mapped back at the end.
  if (!grid) grid.emplace(cell_grid(input, options.k));
  const auto [perm, points] = sort_by_cell(input, *grid);
  FanResult result;
  FanStats& st = result.stats;
  st.points = points.size();
  const int n = static_cast<int>(points.size());
  auto t0 = std::chrono::steady_clock::now();
  Context ctx(points, options, std::move(*grid).reordered(points));
  st.cell_edge = ctx.grid.cell_edge();
  check_crowding(ctx.grid, n);
  const auto [lo, hi] = ctx.grid.box();
  ctx.eps_len = 1e-9 * (hi - lo).norm();  // Gap (4b): "falls on c"
  ctx.d_max = options.dmax_factor * st.cell_edge;
  std::vector<Eigen::Vector3f> given_sorted;
  if (given_normals) {
    given_sorted.resize(n);
    for (int i = 0; i < n; ++i) given_sorted[i] = (*given_normals)[perm[i]];
  }
  compute_normals(ctx, given_normals ? &given_sorted : nullptr);
  st.seconds_normals = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  std::vector<std::vector<FanEntry>> fans = build_all_fans(ctx, options, st);
  st.seconds_fans = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  const std::vector<std::array<int, 4>> proposals = vote_triangles(fans, options);
  st.proposed_triangles = proposals.size();
  Assembly as(points, 1e-9, omp_threads(options));
  fans.clear();
  fans.shrink_to_fit();
  grow_surface(as, ctx, proposals, st);
  st.inserted_points = insert_unused(as, ctx);
  st.delaunay_flips = flip_to_delaunay(as, points, omp_threads(options));
  st.bowtie_faces_removed = detach_bowties(as, n, omp_threads(options));

  write_mesh(as, input, points, perm, ctx, given_normals || options.orient_away_from_axis, options,
             result);
  st.seconds_assembly = seconds_since(t0);
  return result;
}

// Exact duplicates are meshed once: n copies of one point would all share one grid cell and
// make every neighbour query there O(n) (50,000 copies: minutes), and they add nothing.
FanResult build_fans_impl(const std::vector<Vector3d>& input, const FanOptions& options,
                          const std::vector<Eigen::Vector3f>* given_normals) {
  check_input(input, options);
  // Most clouds have no copies: their cell order is found once and serves the fans too. A
  // cloud whose copies make its box degenerate (20,000 copies of one point beside a sheet) has
  // no usable cell size until the copies are gone: it goes the sorting way below.
  std::optional<PointGrid> grid;
  try {
    grid.emplace(cell_grid(input, options.k));
  } catch (const InvalidInputError&) {
  }
  if (grid && !has_duplicates(*grid, input, omp_threads(options)))
    return build_fans_distinct(input, options, given_normals, std::move(grid));
  grid.reset();
  const int n = static_cast<int>(input.size());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  const auto key = [&](int i) { return std::tuple(input[i].x(), input[i].y(), input[i].z(), i); };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return key(a) < key(b); });
  // Sorted by position then index, so each group of copies starts with its smallest index.
  std::vector<int> group_first(n);  // input index -> the first input index at its position
  std::vector<int> first;           // those first indices, in input order after the sort below
  for (int k = 0; k < n; ++k) {
    const int i = order[k];
    if (k == 0 || input[i] != input[order[k - 1]]) first.push_back(i);
    group_first[i] = first.back();
  }
  if (first.size() == 1)
    throw InvalidInputError(
        "build_fans: all points coincide (the fan mesher needs at least 3 "
        "distinct points spread over a surface)");
  std::sort(first.begin(), first.end());  // the distinct points keep the input's order
  std::vector<int> rank(n, -1);            // first input index -> index among the distinct
  for (std::size_t d = 0; d < first.size(); ++d) rank[first[d]] = static_cast<int>(d);
  std::vector<Vector3d> points(first.size());
  std::vector<Eigen::Vector3f> normals;
  for (std::size_t d = 0; d < first.size(); ++d) points[d] = input[first[d]];
  if (given_normals)
    for (int i : first) normals.push_back((*given_normals)[i]);
  FanResult r = build_fans_distinct(points, options, given_normals ? &normals : nullptr);

  // Back to input indices: each triangle on the first copies, every copy gets their normal.
  Mesh mesh;
  mesh.positions = input;
  for (const auto& t : r.mesh.triangles)
    mesh.triangles.push_back({first[t[0]], first[t[1]], first[t[2]]});
  mesh.normals.resize(n);
  for (int i = 0; i < n; ++i) mesh.normals[i] = r.mesh.normals[rank[group_first[i]]];
  r.mesh = std::move(mesh);
  r.stats.points = input.size();
  r.stats.duplicate_points = input.size() - first.size();
  r.stats.unused_points += r.stats.duplicate_points;
  return r;
}

}  // namespace

FanResult build_fans(const std::vector<Vector3d>& points, const FanOptions& options) {
  return build_fans_impl(points, options, nullptr);
}

FanResult build_fans(const PointCloud& input, const FanOptions& options) {
  const PointCloud cloud = input.finite_points();
  const bool normals = cloud.has_normals() && cloud.normals.size() == cloud.size();
  FanResult result = build_fans_impl(cloud.positions, options, normals ? &cloud.normals : nullptr);
  if (normals) result.mesh.normals = cloud.normals;
  if (cloud.has_colors() && cloud.colors.size() == cloud.size()) result.mesh.colors = cloud.colors;
  return result;
}

}  // namespace scanmesh
