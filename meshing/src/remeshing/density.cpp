// Density Psi = kappa_max^-2 with clipping, n_filter smoothing and gamma contrast (seed 001 §3.1).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/remeshing/remesh.h"

namespace scanmesh::remeshing {

namespace {

using Vec3 = Eigen::Vector3d;

// Vertex adjacency in compressed rows: the neighbours of v are nbr[first[v] .. first[v + 1]).
struct Adjacency {
  std::vector<int> first, nbr;
  explicit Adjacency(const TriangleMesh& m) : first(m.pos.size() + 1, 0) {
    for (std::size_t v = 0; v < m.pos.size(); ++v) {
      const kernel::NeighbourList ring = m.neighbours(static_cast<int>(v));
      nbr.insert(nbr.end(), ring.begin(), ring.end());
      std::sort(nbr.begin() + first[v], nbr.end());
      first[v + 1] = static_cast<int>(nbr.size());
    }
  }
};

// The vertices within `radius` of v reached over mesh edges (breadth first, v first).
void collect_patch(const TriangleMesh& m, const Adjacency& adj, int v, double radius,
                   std::vector<int>& stamp, std::vector<int>& out) {
  out.assign(1, v);
  stamp[v] = v;
  const double r2 = radius * radius;
  for (std::size_t i = 0; i < out.size(); ++i)
    for (int k = adj.first[out[i]]; k < adj.first[out[i] + 1]; ++k) {
      const int w = adj.nbr[k];
      if (stamp[w] == v || (m.pos[w] - m.pos[v]).squaredNorm() >= r2) continue;
      stamp[w] = v;
      out.push_back(w);
    }
}

// Shape operator of the graph z = q0 x^2 + q1 xy + q2 y^2 + q3 x + q4 y at the origin
// (first-order corrected by the slope): max |principal curvature|.
double graph_kappa_max(double a, double b, double c, double dx, double dy) {
  const double E = 1 + dx * dx, F = dx * dy, G = 1 + dy * dy;
  const double w = std::sqrt(1 + dx * dx + dy * dy);
  Eigen::Matrix2d I, II;
  I << E, F, F, G;
  II << 2 * a / w, b / w, b / w, 2 * c / w;
  const Eigen::Matrix2d S = I.inverse() * II;
  const double tr = S.trace(), det = S.determinant();
  const double disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
  return std::max(std::abs(tr / 2 + disc), std::abs(tr / 2 - disc));
}

// kappa_max of the weighted least-squares quadric z = a x^2 + b xy + c y^2 + d x + e y + f over
// a patch around `centre` (f free: the centre is a noisy sample, not a point of the surface);
// NaN when the patch does not determine it. At most ~128 of the patch's points are used.
double patch_kappa_max(const TriangleMesh& m, const std::vector<Vec3>& normal,
                       const std::vector<int>& patch, int centre, double radius) {
  const Vec3 p0 = m.pos[centre];
  auto weight = [&](int u) {
    const double t = (m.pos[u] - p0).squaredNorm() / (radius * radius);
    return (1 - t) * (1 - t);
  };
  Vec3 nz = Vec3::Zero();
  for (int u : patch) nz += weight(u) * normal[u];
  if (!(nz.norm() > 0)) return std::numeric_limits<double>::quiet_NaN();
  nz.normalize();
  const Vec3 ax = std::abs(nz.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 ex = (ax - ax.dot(nz) * nz).normalized(), ey = nz.cross(ex);
  const std::size_t stride = std::max<std::size_t>(1, patch.size() / 128);
  Eigen::Matrix<double, 6, 6> ata = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> atb = Eigen::Matrix<double, 6, 1>::Zero();
  int used = 0;
  for (std::size_t i = 0; i < patch.size(); i += stride) {
    const int u = patch[i];
    // A vertex facing away is the far side of a thin sheet reached around its rim.
    if (normal[u].dot(nz) <= 0.2 * normal[u].norm()) continue;
    const Vec3 d = m.pos[u] - p0;
    const double x = d.dot(ex), y = d.dot(ey), w = weight(u);
    Eigen::Matrix<double, 6, 1> row;
    row << x * x, x * y, y * y, x, y, 1;
    ata += w * row * row.transpose();
    atb += w * d.dot(nz) * row;
    ++used;
  }
  if (used < 10) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::ColPivHouseholderQR<Eigen::Matrix<double, 6, 6>> qr(ata);
  if (qr.rank() < 6) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix<double, 6, 1> q = qr.solve(atb);
  return graph_kappa_max(q(0), q(1), q(2), q(3), q(4));
}

// Per vertex: the sum of its live faces' (p1 - p0) x (p2 - p0), an area-weighted normal that is
// not normalised (zero where the faces cancel or there are none).
std::vector<Vec3> area_weighted_normals(const TriangleMesh& m) {
  std::vector<Vec3> normal(m.pos.size(), Vec3::Zero());
  for (std::size_t f = 0; f < m.tri.size(); ++f) {
    if (!m.face_alive[f]) continue;
    const auto& t = m.tri[f];
    const Vec3 nf = (m.pos[t[1]] - m.pos[t[0]]).cross(m.pos[t[2]] - m.pos[t[0]]);
    for (int c : t) normal[c] += nf;
  }
  return normal;
}

// kappa_max of the least-squares quadric over each vertex's 2-ring (of the vertices flagged in
// `only`, when given; the others get 0).
std::vector<double> kappa_on_rings(const TriangleMesh& m, const std::vector<char>* only) {
  const int n = static_cast<int>(m.pos.size());
  std::vector<double> kappa(n, 0.0);
  const std::vector<Vec3> normal = area_weighted_normals(m);
  std::vector<int> ring, mark(n, -1);
#pragma omp parallel for schedule(dynamic, 256) private(ring) firstprivate(mark)
  for (int v = 0; v < n; ++v) {
    if ((only && !(*only)[v]) || m.vfaces[v].empty() || normal[v].norm() == 0) continue;
    // 2-ring.
    ring.clear();
    mark[v] = v;
    auto add_ring = [&](int x) {  // the corners of x's faces not met yet
      for (int f : m.vfaces[x])
        for (int c : m.tri[f])
          if (mark[c] != v) {
            mark[c] = v;
            ring.push_back(c);
          }
    };
    add_ring(v);
    const std::size_t first = ring.size();
    for (std::size_t i = 0; i < first; ++i) add_ring(ring[i]);
    if (ring.size() < 5) continue;
    const Eigen::Vector3d nz = normal[v].normalized();
    Eigen::Vector3d ax =
        std::abs(nz.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d ex = (ax - ax.dot(nz) * nz).normalized();
    const Eigen::Vector3d ey = nz.cross(ex);
    // z = a x^2 + b xy + c y^2 + d x + e y (through the vertex).
    Eigen::MatrixXd A(ring.size(), 5);
    Eigen::VectorXd rhs(ring.size());
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Eigen::Vector3d d = m.pos[ring[i]] - m.pos[v];
      const double x = d.dot(ex), y = d.dot(ey);
      A.row(static_cast<Eigen::Index>(i)) << x * x, x * y, y * y, x, y;
      rhs(static_cast<Eigen::Index>(i)) = d.dot(nz);
    }
    const Eigen::VectorXd q = A.colPivHouseholderQr().solve(rhs);
    kappa[v] = graph_kappa_max(q(0), q(1), q(2), q(3), q(4));
  }
  return kappa;
}

double median_edge_length(const TriangleMesh& m) {
  std::vector<double> len;
  for (std::size_t f = 0; f < m.tri.size(); f += 7)  // a sample is plenty for a median
    if (m.face_alive[f]) len.push_back((m.pos[m.tri[f][0]] - m.pos[m.tri[f][1]]).norm());
  if (len.empty()) return 0;
  std::nth_element(len.begin(), len.begin() + len.size() / 2, len.end());
  return len[len.size() / 2];
}

std::vector<double> kappa_at_scale(const TriangleMesh& m, double radius) {
  const int n = static_cast<int>(m.pos.size());
  std::vector<Vec3> normal = area_weighted_normals(m);
  for (Vec3& x : normal)
    if (x.norm() > 0) x.normalize();
  const Adjacency adj(m);
  // Samples: every vertex not yet within radius / 2 of one (greedy cover, index order).
  std::vector<int> samples, stamp(n, -1), patch;
  std::vector<char> covered(n, 0);
  for (int v = 0; v < n; ++v) {
    if (covered[v] || m.vfaces[v].empty()) continue;
    samples.push_back(v);
    collect_patch(m, adj, v, radius / 2, stamp, patch);
    for (int u : patch) covered[u] = 1;
  }
  const int ns = static_cast<int>(samples.size());
  std::vector<std::vector<int>> patches(ns);
  std::vector<double> fit(ns);
  // Fresh marks: the cover's marks would hide vertices from the patches of their own samples,
  // differently for every thread schedule.
  std::fill(stamp.begin(), stamp.end(), -1);
#pragma omp parallel for schedule(dynamic, 64) firstprivate(stamp)
  for (int i = 0; i < ns; ++i) {
    collect_patch(m, adj, samples[i], radius, stamp, patches[i]);
    fit[i] = patch_kappa_max(m, normal, patches[i], samples[i], radius);
  }
  std::vector<double> sum(n, 0.0), wsum(n, 0.0);
  for (int i = 0; i < ns; ++i) {
    if (!std::isfinite(fit[i])) continue;
    const Vec3 c = m.pos[samples[i]];
    for (int u : patches[i]) {
      const double t = (m.pos[u] - c).norm() / radius;
      const double w = (1 - t) * (1 - t) + 1e-6;
      sum[u] += w * fit[i];
      wsum[u] += w;
    }
  }
  std::vector<double> kappa(n, 0.0);
  bool gaps = false;
  for (int v = 0; v < n; ++v) {
    if (wsum[v] > 0)
      kappa[v] = sum[v] / wsum[v];
    else
      gaps = gaps || !m.vfaces[v].empty();
  }
  if (gaps) {
    // Patches too small or flat-sided to fit (tiny pieces of the input): their 2-ring, fitted
    // for these vertices alone (fitting every vertex was a third of the density's time).
    std::vector<char> gap(n, 0);
    for (int v = 0; v < n; ++v) gap[v] = wsum[v] == 0;
    const std::vector<double> ring = kappa_on_rings(m, &gap);
    for (int v = 0; v < n; ++v)
      if (gap[v]) kappa[v] = ring[v];
  }
  return kappa;
}

}  // namespace

std::vector<double> estimate_kappa_max(const TriangleMesh& m, double radius) {
  if (radius > 2 * median_edge_length(m)) return kappa_at_scale(m, radius);
  return kappa_on_rings(m, nullptr);
}

double density_scale(const TriangleMesh& m, const std::vector<double>& psi, int target_vertices) {
  double integral = 0;
  for (std::size_t f = 0; f < m.tri.size(); ++f) {
    if (!m.face_alive[f]) continue;
    const auto& t = m.tri[f];
    const double p = (psi[t[0]] + psi[t[1]] + psi[t[2]]) / 3;
    integral += m.face_area(static_cast<int>(f)) / p;
  }
  return std::sqrt(2.0 / std::sqrt(3.0) * integral / target_vertices);
}

void limit_gradation(const TriangleMesh& m, std::vector<double>& psi, int target_vertices,
                     double gradation) {
  if (!(gradation > 0) || target_vertices <= 0) return;
  const int n = static_cast<int>(m.pos.size());
  const Adjacency adj(m);
  // Two passes: refining raises the count integral, so the scale (and with it the slope of
  // the absolute h) is re-estimated once.
  for (int pass = 0; pass < 2; ++pass) {
    const double scale = density_scale(m, psi, target_vertices);
    if (!(scale > 0)) return;
    std::vector<double> h(n);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    for (int v = 0; v < n; ++v) {
      h[v] = scale * std::sqrt(psi[v]);
      queue.push({h[v], v});
    }
    while (!queue.empty()) {
      const auto [hv, v] = queue.top();
      queue.pop();
      if (hv > h[v]) continue;
      for (int k = adj.first[v]; k < adj.first[v + 1]; ++k) {
        const int w = adj.nbr[k];
        const double bound = hv + gradation * (m.pos[w] - m.pos[v]).norm();
        if (bound < h[w]) {
          h[w] = bound;
          queue.push({bound, w});
        }
      }
    }
    for (int v = 0; v < n; ++v) psi[v] = (h[v] / scale) * (h[v] / scale);
  }
}

std::vector<double> compute_density(const TriangleMesh& m, const DensityOptions& o) {
  const int n = static_cast<int>(m.pos.size());
  std::vector<double> psi(n, 1.0);
  if (!o.user.empty()) {
    if (static_cast<int>(o.user.size()) != n)
      throw InvalidInputError("density field has " + std::to_string(o.user.size()) +
                              " values for " + std::to_string(n) + " vertices");
    for (double x : o.user)
      if (!(x > 0) || !std::isfinite(x))
        throw InvalidInputError("density field values must be positive and finite");
    psi = o.user;
  } else if (o.gamma != 0) {
    const std::vector<double> kappa = estimate_kappa_max(m, std::max(0.0, o.curvature_radius));
    for (int v = 0; v < n; ++v) psi[v] = 1.0 / std::max(kappa[v] * kappa[v], 1e-12);
  }
  if (o.clip < 1) throw InvalidInputError("density clip must be >= 1");
  if (o.n_filter < 0) throw InvalidInputError("n_filter must be >= 0");
  auto median = [&](std::vector<double> x) {
    std::vector<double> live;
    for (int v = 0; v < n; ++v)
      if (!m.vfaces[v].empty()) live.push_back(x[v]);
    if (live.empty()) return 1.0;
    std::nth_element(live.begin(), live.begin() + live.size() / 2, live.end());
    return live[live.size() / 2];
  };
  // Clip extremes: target edge length sqrt(Psi) within a factor `clip` of the median.
  auto clip = [&](std::vector<double>& x, double factor) {
    const double med = median(x);
    for (double& p : x) p = std::clamp(p, med / (factor * factor), med * factor * factor);
  };
  clip(psi, o.clip);
  // Low-pass (3.3): mean of the neighbours, the vertex itself excluded, across the skeleton.
  // The neighbour lists are gathered once, in TriangleMesh::neighbours' order (the sums' order).
  std::vector<int> first(n + 1, 0), nbr;
  if (o.n_filter > 0)
    for (int v = 0; v < n; ++v) {
      for (int w : m.neighbours(v)) nbr.push_back(w);
      first[v + 1] = static_cast<int>(nbr.size());
    }
  std::vector<double> next(n);
  for (int it = 0; it < o.n_filter; ++it) {
    for (int v = 0; v < n; ++v) {
      if (first[v] == first[v + 1]) {
        next[v] = psi[v];
        continue;
      }
      double s = 0;
      for (int k = first[v]; k < first[v + 1]; ++k) s += psi[nbr[k]];
      next[v] = s / static_cast<double>(first[v + 1] - first[v]);
    }
    psi.swap(next);
  }
  const double med = median(psi);
  for (double& p : psi) p = std::pow(p / med, o.user.empty() ? o.gamma : 1.0);
  if (o.user.empty() && o.gamma == 0) std::fill(psi.begin(), psi.end(), 1.0);
  clip(psi, o.clip);  // the contrast can widen the range again
  const double med2 = median(psi);
  for (double& p : psi) p /= med2;
  return psi;
}

}  // namespace scanmesh::remeshing
