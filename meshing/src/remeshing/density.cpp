// Density Psi = kappa_max^-2 with clipping, n_filter smoothing and gamma contrast (seed 001 §3.1).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/remeshing/remesh.h"

namespace scanmesh::remeshing {

std::vector<double> estimate_kappa_max(const NmMesh& m) {
  const int n = static_cast<int>(m.pos.size());
  std::vector<double> kappa(n, 0.0);
  std::vector<Eigen::Vector3d> normal(n, Eigen::Vector3d::Zero());
  for (std::size_t f = 0; f < m.tri.size(); ++f) {
    if (!m.face_alive[f]) continue;
    const auto& t = m.tri[f];
    const Eigen::Vector3d nf = (m.pos[t[1]] - m.pos[t[0]]).cross(m.pos[t[2]] - m.pos[t[0]]);
    for (int c : t) normal[c] += nf;
  }
  std::vector<int> ring, mark(n, -1);
#pragma omp parallel for schedule(dynamic, 256) private(ring) firstprivate(mark)
  for (int v = 0; v < n; ++v) {
    if (m.vfaces[v].empty() || normal[v].norm() == 0) continue;
    // 2-ring.
    ring.clear();
    mark[v] = v;
    for (int f : m.vfaces[v])
      for (int c : m.tri[f])
        if (mark[c] != v) {
          mark[c] = v;
          ring.push_back(c);
        }
    const std::size_t first = ring.size();
    for (std::size_t i = 0; i < first; ++i)
      for (int f : m.vfaces[ring[i]])
        for (int c : m.tri[f])
          if (mark[c] != v) {
            mark[c] = v;
            ring.push_back(c);
          }
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
    const double dx = q(3), dy = q(4);
    // Shape operator of the graph at the origin (first-order corrected by the slope).
    const double E = 1 + dx * dx, F = dx * dy, G = 1 + dy * dy;
    const double w = std::sqrt(1 + dx * dx + dy * dy);
    const double L = 2 * q(0) / w, M = q(1) / w, N = 2 * q(2) / w;
    Eigen::Matrix2d I, II;
    I << E, F, F, G;
    II << L, M, M, N;
    const Eigen::Matrix2d S = I.inverse() * II;
    const double tr = S.trace(), det = S.determinant();
    const double disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
    kappa[v] = std::max(std::abs(tr / 2 + disc), std::abs(tr / 2 - disc));
  }
  return kappa;
}

std::vector<double> compute_density(const NmMesh& m, const DensityOptions& o) {
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
    const std::vector<double> kappa = estimate_kappa_max(m);
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
  std::vector<double> next(n);
  for (int it = 0; it < o.n_filter; ++it) {
    for (int v = 0; v < n; ++v) {
      const auto nb = m.neighbours(v);
      if (nb.empty()) {
        next[v] = psi[v];
        continue;
      }
      double s = 0;
      for (int w : nb) s += psi[w];
      next[v] = s / static_cast<double>(nb.size());
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
