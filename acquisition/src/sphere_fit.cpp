#include "scanmesh/acquisition/sphere_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {
namespace {

void measure(const std::vector<Eigen::Vector3d>& p, SphereFit& f) {
  double ss = 0, mx = 0;
  for (const auto& q : p) {
    const double d = (q - f.centre).norm() - f.radius;
    ss += d * d;
    mx = std::max(mx, std::abs(d));
  }
  f.points = p.size();
  f.rms = std::sqrt(ss / static_cast<double>(p.size()));
  f.max_abs = mx;
}

}  // namespace

SphereFit fit_sphere(const std::vector<Eigen::Vector3d>& p) {
  if (p.size() < 4)
    throw InvalidInputError("sphere fit: " + std::to_string(p.size()) +
                            " points (needs at least 4)");
  const auto n = static_cast<Eigen::Index>(p.size());
  Eigen::MatrixXd a(n, 4);
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& q = p[static_cast<std::size_t>(i)];
    a.row(i) << 2 * q.x(), 2 * q.y(), 2 * q.z(), 1.0;
    b(i) = q.squaredNorm();
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  if (qr.rank() < 4)
    throw InvalidInputError("sphere fit: the " + std::to_string(p.size()) +
                            " points are degenerate (coplanar or collinear)");
  const Eigen::Vector4d s = qr.solve(b);
  SphereFit f;
  f.centre = s.head<3>();
  const double r2 = s(3) + f.centre.squaredNorm();
  if (!(r2 > 0)) throw InvalidInputError("sphere fit: no real sphere through the points");
  f.radius = std::sqrt(r2);
  for (int it = 0; it < 20; ++it) {
    Eigen::MatrixXd j(n, 4);
    Eigen::VectorXd res(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector3d d = p[static_cast<std::size_t>(i)] - f.centre;
      const double len = std::max(d.norm(), 1e-12);
      res(i) = len - f.radius;
      j.row(i) << -d.x() / len, -d.y() / len, -d.z() / len, -1.0;
    }
    const Eigen::Vector4d step = j.colPivHouseholderQr().solve(-res);
    f.centre += step.head<3>();
    f.radius += step(3);
    if (step.norm() < 1e-10) break;
  }
  measure(p, f);
  return f;
}

SphereFit fit_sphere_trimmed(const std::vector<Eigen::Vector3d>& points, double k_sigma,
                             double floor_mm, int rounds) {
  std::vector<Eigen::Vector3d> kept = points;
  SphereFit f = fit_sphere(kept);
  for (int round = 0; round < rounds; ++round) {
    const double limit = std::max(floor_mm, k_sigma * f.rms);
    std::vector<Eigen::Vector3d> next;
    next.reserve(kept.size());
    for (const auto& q : kept)
      if (std::abs((q - f.centre).norm() - f.radius) <= limit) next.push_back(q);
    if (next.size() == kept.size()) break;
    kept.swap(next);
    f = fit_sphere(kept);
  }
  f.rejected = points.size() - kept.size();
  return f;
}

std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>> split_two_objects(
    const std::vector<Eigen::Vector3d>& p) {
  if (p.size() < 2) throw InvalidInputError("split: fewer than 2 points");
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& q : p) mean += q.head<2>();
  mean /= static_cast<double>(p.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& q : p) {
    const Eigen::Vector2d d = q.head<2>() - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  const Eigen::Vector2d axis = es.eigenvectors().col(1);  // largest eigenvalue
  std::vector<double> t(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) t[i] = axis.dot(p[i].head<2>() - mean);
  double cut = 0;
  for (int it = 0; it < 50; ++it) {
    double s0 = 0, s1 = 0;
    std::size_t n0 = 0, n1 = 0;
    for (double v : t) (v < cut ? (s0 += v, ++n0) : (s1 += v, ++n1));
    if (n0 == 0 || n1 == 0) break;
    const double next = 0.5 * (s0 / static_cast<double>(n0) + s1 / static_cast<double>(n1));
    if (std::abs(next - cut) < 1e-9) break;
    cut = next;
  }
  std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>> out;
  for (std::size_t i = 0; i < p.size(); ++i) (t[i] < cut ? out.first : out.second).push_back(p[i]);
  return out;
}

}  // namespace scanmesh
