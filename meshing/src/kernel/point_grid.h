// The meshing kernel's point index (issue 28): a uniform 3D cell grid for radius and k-nearest-
// neighbour queries (seed 002 §3.4, the thesis's `clusterspace`), flat cell arrays filled by a
// counting sort, O(n) to build. Used by the point-cloud fans and the Witkin-Heckbert sampler.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace scanmesh::kernel {

//! The points' bounding box without its far outliers, per axis: the 1 % .. 99 % quantile range
//! widened to four interquartile ranges beyond the quartiles, within the true box. A 1 % quantile
//! itself further than 16 interquartile ranges out is taken for an outlier and left out: with
//! more than 1 % of stray points on a side (200 of kitten's 5,410 points scattered up to 1e308)
//! it made the box astronomically large, every point one cell and the fans quadratic. A real
//! object's tails stay inside (hippo2's feet are 1 % quantile at 5 IQR; a uniform spread spans
//! two IQR). Quantiles of at most 65,536 evenly strided points, so the cost stays O(n) and small.
inline std::pair<Eigen::Vector3d, Eigen::Vector3d> robust_box(
    const std::vector<Eigen::Vector3d>& points) {
  const std::size_t n = points.size();
  const std::size_t stride = std::max<std::size_t>(1, n / 65536);
  std::vector<double> v;
  v.reserve(n / stride + 1);
  Eigen::Vector3d lo, hi;
  for (int a = 0; a < 3; ++a) {
    v.clear();
    double mn = points[0][a], mx = points[0][a];
    for (const auto& p : points) {
      mn = std::min(mn, p[a]);
      mx = std::max(mx, p[a]);
    }
    for (std::size_t i = 0; i < n; i += stride) v.push_back(points[i][a]);
    auto quantile = [&](double q) {
      const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
      std::nth_element(v.begin(), v.begin() + k, v.end());
      return v[static_cast<std::size_t>(k)];
    };
    const double q01 = quantile(0.01), q25 = quantile(0.25), q75 = quantile(0.75),
                 q99 = quantile(0.99);
    const double iqr = q75 - q25;
    const double low_tail = q01 >= q25 - 16.0 * iqr ? q01 : q25;
    const double high_tail = q99 <= q75 + 16.0 * iqr ? q99 : q75;
    lo[a] = std::max(mn, std::min(low_tail, q25 - 4.0 * iqr));
    hi[a] = std::min(mx, std::max(high_tail, q75 + 4.0 * iqr));
    // A handful of points has no outliers to speak of (three points have a zero IQR).
    if (n < 64) lo[a] = mn, hi[a] = mx;
    if (!std::isfinite(hi[a] - lo[a])) lo[a] = hi[a] = q25;  // the box itself overflows
  }
  return {lo, hi};
}

class PointGrid {
 public:
  //! `cell_edge` is the seed's l; it is enlarged when the grid would have more than 8 cells per
  //! point (degenerate, very flat bounding boxes), which keeps memory O(n).
  //! The grid spans `robust_box(points)`: far outliers fall into the border cells, which reach to
  //! infinity, so one point at 1e20 neither makes the grid astronomically large nor puts every
  //! other point into one cell.
  PointGrid(const std::vector<Eigen::Vector3d>& points, double cell_edge)
      : PointGrid(points, cell_edge, robust_box(points)) {}
  //! With the points' robust_box() already at hand.
  PointGrid(const std::vector<Eigen::Vector3d>& points, double cell_edge,
            const std::pair<Eigen::Vector3d, Eigen::Vector3d>& box)
      : points_(points), lo_(box.first), hi_(box.second) {
    cell_ = cell_edge;
    const double limit = 8.0 * static_cast<double>(points.size()) + 64.0;
    while (true) {
      double cells = 1.0;  // in double: the int dimensions are formed only once they fit
      std::array<double, 3> extent{};
      for (int a = 0; a < 3; ++a) {
        extent[a] = std::floor((hi_[a] - lo_[a]) / cell_) + 1.0;
        cells *= extent[a];
      }
      if (cells <= limit) {
        for (int a = 0; a < 3; ++a) dims_[a] = static_cast<int>(extent[a]);
        break;
      }
      cell_ *= std::max(1.25, 0.9 * std::cbrt(cells / limit));
    }
    const std::size_t cells = static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2];
    start_.assign(cells + 1, 0);
    std::vector<std::size_t> cell_of(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto c = coord(points[i]);
      cell_of[i] = flat(c[0], c[1], c[2]);
      ++start_[cell_of[i] + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
    order_.resize(points.size());
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < points.size(); ++i)
      order_[fill[cell_of[i]]++] = static_cast<int>(i);
  }

  //! This grid over `sorted`, the same points in this grid's order (sorted[i] is the point
  //! order()[i]): a caller that puts its points into cell order needs no second grid.
  PointGrid reordered(const std::vector<Eigen::Vector3d>& sorted) && {
    PointGrid g(std::move(*this), sorted);
    for (std::size_t i = 0; i < g.order_.size(); ++i) g.order_[i] = static_cast<int>(i);
    return g;
  }

  double cell_edge() const { return cell_; }
  //! The box the cells span (the points' robust_box()).
  std::pair<Eigen::Vector3d, Eigen::Vector3d> box() const { return {lo_, hi_}; }
  //! The most points any one cell holds (a crowded cell makes every query there O(its size)).
  std::size_t fullest_cell() const {
    std::size_t most = 0;
    for (std::size_t c = 0; c + 1 < start_.size(); ++c)
      most = std::max<std::size_t>(most, start_[c + 1] - start_[c]);
    return most;
  }
  //! Cells holding at least one point.
  std::size_t occupied_cells() const {
    std::size_t n = 0;
    for (std::size_t c = 0; c + 1 < start_.size(); ++c) n += start_[c + 1] > start_[c];
    return n;
  }
  //! Point indices sorted by cell: iterating in this order keeps neighbouring work together.
  const std::vector<int>& order() const { return order_; }
  //! Number of cells; the points of cell c are order()[cell_begin(c) .. cell_begin(c + 1)).
  std::size_t cells() const { return start_.size() - 1; }
  //! Cells per axis; a cell's index is (z * dims[1] + y) * dims[0] + x, so the points of the
  //! layers z < k come first in order(): the first cell_begin(k * dims[0] * dims[1]).
  const std::array<int, 3>& dims() const { return dims_; }
  std::size_t cell_begin(std::size_t c) const { return start_[c]; }

  //! Calls f(index, squared distance) for every point with |p - c| <= r.
  template <class F>
  void visit_ball(const Eigen::Vector3d& c, double r, F&& f) const {
    const auto a = coord(c - Eigen::Vector3d::Constant(r));
    const auto b = coord(c + Eigen::Vector3d::Constant(r));
    const double r2 = r * r;
    // Cells of the bounding cube that the ball misses are skipped (about half of a large
    // cube); the slack absorbs the rounding of a point's cell index near a cell face.
    const double slack = 1e-7 * cell_;
    auto gap2 = [&](int axis, int i) {
      // Border cells also hold the points beyond the box (coord() clamps them).
      const double lo = i == 0 ? -kHuge : lo_[axis] + i * cell_;
      const double hi = i == dims_[axis] - 1 ? kHuge : lo_[axis] + (i + 1) * cell_;
      const double g = std::max({lo - c[axis], c[axis] - hi, 0.0});
      const double gs = std::max(0.0, g - slack);
      return gs * gs;
    };
    // The x gaps of a small ball (the common case), once instead of once per row.
    constexpr int kRow = 8;
    std::array<double, kRow> gx{};
    const bool short_rows = b[0] - a[0] < kRow;
    if (short_rows)
      for (int x = a[0]; x <= b[0]; ++x) gx[x - a[0]] = gap2(0, x);
    for (int z = a[2]; z <= b[2]; ++z) {
      const double gz = gap2(2, z);
      if (gz > r2) continue;
      for (int y = a[1]; y <= b[1]; ++y) {
        const double gzy = gz + gap2(1, y);
        if (gzy > r2) continue;
        for (int x = a[0]; x <= b[0]; ++x) {
          if (gzy + (short_rows ? gx[x - a[0]] : gap2(0, x)) > r2) continue;
          const std::size_t cell = flat(x, y, z);
          for (std::size_t k = start_[cell]; k < start_[cell + 1]; ++k) {
            const int i = order_[k];
            const double d2 = (points_[i] - c).squaredNorm();
            if (d2 <= r2) f(i, d2);
          }
        }
      }
    }
  }

  //! (squared distance, index) of every point p other than `skip` with min_d2 < |p - c|^2 <=
  //! r^2, in no particular order (visit_ball() as a list, for callers that filter further).
  //! Whole rows of cells (contiguous in order_) are scanned and every point is written, the
  //! count advancing only for those inside: the in-or-out branch, a coin toss for the points
  //! near the ball's surface, was most of a k-nearest query's cost.
  void collect_shell(const Eigen::Vector3d& c, double min_d2, double r, int skip,
                     std::vector<std::pair<double, int>>& out) const {
    const auto a = coord(c - Eigen::Vector3d::Constant(r));
    const auto b = coord(c + Eigen::Vector3d::Constant(r));
    const double r2 = r * r;
    std::size_t count = 0;
    for (int z = a[2]; z <= b[2]; ++z)
      for (int y = a[1]; y <= b[1]; ++y) {
        const std::size_t first = start_[flat(a[0], y, z)], last = start_[flat(b[0], y, z) + 1];
        if (out.size() < count + (last - first)) out.resize(count + (last - first));
        for (std::size_t k = first; k < last; ++k) {
          const int j = order_[k];
          const double d2 = (points_[j] - c).squaredNorm();
          out[count] = {d2, j};
          count += static_cast<std::size_t>(d2 <= r2) & static_cast<std::size_t>(d2 > min_d2) &
                   static_cast<std::size_t>(j != skip);
        }
      }
    out.resize(count);
  }

  //! The K nearest other points of point i, nearest first, as (squared distance, index).
  //! Ties are broken by index, so the result is deterministic. The search stops at a radius of
  //! a thousand times the grid's extent: a far outlier may get fewer than K (or none).
  void knn(int i, int K, std::vector<std::pair<double, int>>& out) const {
    const Eigen::Vector3d& c = points_[i];
    const std::size_t want = std::min<std::size_t>(K, points_.size() - 1);
    // First radius from the density of the point's own cell, taken as a patch of surface
    // through it (K points on a disc of radius r), so that one visit usually suffices; the
    // result is the same for any first radius, since the ball is grown until it holds K.
    const double own = static_cast<double>(points_in_cell_of(c));  // >= 1: point i itself
    double r = cell_ * std::sqrt(static_cast<double>(K + 1) / (kPi * own));
    r = std::clamp(r * 1.15, 0.05 * cell_, 4.0 * cell_);
    while (true) {
      collect_shell(c, -1.0, r, i, out);
      if (out.size() >= want || r > 1e3 * cell_ * (dims_[0] + dims_[1] + dims_[2])) break;
      // Too few: grow by the missing share of the disc area (at least 1.3x, at most 2x).
      const double grow =
          out.empty()
              ? 2.0
              : std::sqrt(static_cast<double>(want) / static_cast<double>(out.size())) * 1.15;
      r *= std::clamp(grow, 1.3, 2.0);
    }
    // The K smallest (distance, index) pairs, sorted (a total order): insertion into the sorted
    // front of `out`, which most of the few dozen points a query finds skip with one compare
    // against the K-th (cheaper than nth_element and a sort of the front).
    const std::size_t keep = std::min(want, out.size());
    if (keep == 0) {
      out.clear();
      return;
    }
    for (std::size_t t = 1; t < out.size(); ++t) {
      const std::size_t end = std::min(t, keep);  // out[0, end) is sorted
      if (end == keep && !(out[t] < out[keep - 1])) continue;
      const auto e = out[t];
      // A full front drops its last entry (K entries are below it); otherwise out[t] is next.
      std::size_t pos = end == keep ? keep - 1 : t;
      for (; pos > 0 && e < out[pos - 1]; --pos) out[pos] = out[pos - 1];
      out[pos] = e;
    }
    out.resize(keep);
  }

 private:
  static constexpr double kPi = 3.14159265358979323846;
  static constexpr double kHuge = 1e300;

  PointGrid(PointGrid&& other, const std::vector<Eigen::Vector3d>& points)
      : points_(points),
        lo_(other.lo_),
        hi_(other.hi_),
        cell_(other.cell_),
        dims_(other.dims_),
        start_(std::move(other.start_)),
        order_(std::move(other.order_)) {}

  std::size_t points_in_cell_of(const Eigen::Vector3d& p) const {
    const auto c = coord(p);
    const std::size_t cell = flat(c[0], c[1], c[2]);
    return start_[cell + 1] - start_[cell];
  }
  std::array<int, 3> coord(const Eigen::Vector3d& p) const {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
      double v = std::floor((p[a] - lo_[a]) / cell_);
      // NaN (an infinite ball radius meeting an infinite offset) would survive the clamp and
      // turn into an arbitrary int: count it as the first cell, like any far point below.
      if (std::isnan(v)) v = 0.0;
      c[a] = static_cast<int>(std::clamp(v, 0.0, static_cast<double>(dims_[a] - 1)));
    }
    return c;
  }
  std::size_t flat(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * dims_[1] + y) * dims_[0] + x;
  }

  const std::vector<Eigen::Vector3d>& points_;
  Eigen::Vector3d lo_, hi_;
  double cell_ = 1.0;
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::uint32_t> start_;  // n < 2^31 (checked by build_fans)
  std::vector<int> order_;
};

}  // namespace scanmesh::kernel
