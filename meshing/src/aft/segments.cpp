// Segment initialisation (seed 000 §5.1.2) and the "on rails" relaxation (§7.1 item 2).
#include <algorithm>
#include <cmath>

#include "aft_internal.h"
#include "scanmesh/core/errors.h"

namespace scanmesh::aft {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

// A segment sampled densely on the surface: cumulative 3D arc length and init measure.
struct Rail {
  std::vector<Vector2d> param;
  std::vector<Vector3d> pos;
  std::vector<double> arc;  // cumulative 3D arc length
  double length() const { return arc.back(); }
  // (phi, h) at arc length s (linear between samples).
  Vector2d at(double s) const {
    const auto it = std::upper_bound(arc.begin(), arc.end(), s);
    std::size_t k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - arc.begin(), 1));
    k = std::min(k, arc.size() - 1);
    const double span = arc[k] - arc[k - 1];
    const double t = span > 0 ? std::clamp((s - arc[k - 1]) / span, 0.0, 1.0) : 0.0;
    return param[k - 1] + t * (param[k] - param[k - 1]);
  }
};

Rail make_rail(const Segment& seg, const ScanSurface& surface, const std::string& who) {
  Rail r;
  for (std::size_t k = 0; k + 1 < seg.pts.size(); ++k) {
    const Vector2d a = seg.pts[k], b = seg.pts[k + 1];
    const int steps =
        std::max(1, static_cast<int>(std::ceil(std::max(std::fabs(b.x() - a.x()) / surface.dphi(),
                                                        std::fabs(b.y() - a.y()) / surface.dh()) *
                                               4)));
    for (int s = (k == 0 ? 0 : 1); s <= steps; ++s)
      r.param.push_back(a + (b - a) * (double(s) / steps));
  }
  for (const Vector2d& p : r.param) {
    const auto x = surface.position(p.x(), p.y());
    if (!x) throw InvalidInputError(who + " leaves the defined scan surface");
    r.pos.push_back(*x);
  }
  r.arc.assign(r.pos.size(), 0.0);
  for (std::size_t k = 1; k < r.pos.size(); ++k)
    r.arc[k] = r.arc[k - 1] + (r.pos[k] - r.pos[k - 1]).norm();
  return r;
}

}  // namespace

SegmentNodes initialise_segments(const RegionGraph& g, const LineSet& lines,
                                 const ScanSurface& surface, const RegionSettings& settings) {
  SegmentNodes out;
  out.params = g.nodes;
  std::vector<Rail> rails;
  std::vector<std::vector<double>> arcs;  // per segment: arc position of every chain node
  for (std::size_t s = 0; s < g.segments.size(); ++s) {
    const Segment& seg = g.segments[s];
    const AnimationLine& line = lines.lines[seg.line];
    rails.push_back(make_rail(seg, surface, "line '" + line.id + "' (" + line.source + ")"));
    const Rail& rail = rails.back();
    // d_I: the mean (or the finer) of the meshed neighbours' unit sizes; seams: the user's
    // spacing (docs/animation-meshes.md, "Segment spacing").
    double sum = 0, finer = 0;
    int n = 0;
    for (int r : {seg.left_region, seg.right_region})
      if (r >= 0 && !g.regions[r].opening) {
        const double unit =
            g.regions[r].unit_mm > 0 ? g.regions[r].unit_mm : settings.default_unit_mm;
        sum += unit;
        finer = n ? std::min(finer, unit) : unit;
        ++n;
      }
    double d = !n ? settings.default_unit_mm
                  : (settings.segment_spacing == SegmentSpacing::Finer ? finer : sum / n);
    if (line.kind == LineKind::Seam && line.node_spacing_mm > 0) d = line.node_spacing_mm;
    // The measure: arc length, or arc + weight * turning angle of the lifted curve, cut into
    // steps of d either way (so a straight line gets the arc-length rule's node count).
    std::vector<double> measure = rail.arc;
    if (settings.segment_init == SegmentInit::Curvature) {
      for (std::size_t k = 1; k < measure.size(); ++k) {
        double turn = 0;
        if (k + 1 < rail.pos.size()) {
          const Vector3d u = rail.pos[k] - rail.pos[k - 1], v = rail.pos[k + 1] - rail.pos[k];
          if (u.norm() > 0 && v.norm() > 0)
            turn = std::acos(std::clamp(u.dot(v) / (u.norm() * v.norm()), -1.0, 1.0));
        }
        measure[k] =
            measure[k - 1] + (rail.arc[k] - rail.arc[k - 1]) + settings.curvature_weight_mm * turn;
      }
    }
    const double total = measure.back();
    int intervals = static_cast<int>(std::floor(total / d)) + 1;  // N_nodes - 1
    if (seg.node0 == seg.node1) intervals = std::max(intervals, 3);
    const double d_prime = total / intervals;  // d_I'
    out.spacing_mm.push_back(rail.length() / intervals);
    std::vector<int> chain{seg.node0};
    std::vector<double> arc{0.0};
    for (int k = 1; k < intervals; ++k) {
      const double m = k * d_prime;
      const auto it = std::lower_bound(measure.begin(), measure.end(), m);
      std::size_t j = std::clamp<std::size_t>(it - measure.begin(), 1, measure.size() - 1);
      const double t = (m - measure[j - 1]) / std::max(measure[j] - measure[j - 1], 1e-300);
      const double a = rail.arc[j - 1] + t * (rail.arc[j] - rail.arc[j - 1]);
      chain.push_back(static_cast<int>(out.params.size()));
      out.params.push_back(rail.at(a));
      arc.push_back(a);
    }
    chain.push_back(seg.node1);
    arc.push_back(rail.length());
    out.chains.push_back(chain);
    arcs.push_back(arc);
  }
  // Relaxation on rails: interior nodes slide along their segment (end points fixed), pulled
  // to the middle of their neighbours and pushed by nodes of other segments closer than 0.75
  // of the local spacing, so nodes on close parallel segments end up offset.
  std::vector<Vector3d> pos(out.params.size());
  auto lift = [&](int i) {
    const auto x = surface.position(out.params[i].x(), out.params[i].y());
    pos[i] = x ? *x : Vector3d::Zero();
  };
  for (std::size_t i = 0; i < pos.size(); ++i) lift(static_cast<int>(i));
  std::vector<int> owner(out.params.size(), -1);
  for (std::size_t s = 0; s < out.chains.size(); ++s)
    for (std::size_t k = 1; k + 1 < out.chains[s].size(); ++k)
      owner[out.chains[s][k]] = static_cast<int>(s);
  double cell = 1e-3;
  for (double sp : out.spacing_mm) cell = std::max(cell, sp);
  detail::CellLists grid;  // nodes by cell at the start of a sweep, in index order
  for (int it = 0; it < settings.relax_iterations; ++it) {
    grid.clear();
    for (std::size_t i = 0; i < pos.size(); ++i)
      grid[detail::cell_key(pos[i], cell)].push_back(static_cast<int>(i));
    for (std::size_t s = 0; s < out.chains.size(); ++s) {
      auto& chain = out.chains[s];
      auto& arc = arcs[s];
      const double sp = out.spacing_mm[s];
      const double reach = 0.75 * sp;
      for (std::size_t k = 1; k + 1 < chain.size(); ++k) {
        const int i = chain[k];
        double target = 0.5 * (arc[k - 1] + arc[k + 1]);
        // tangent of the rail at this node
        const double ds = std::min(0.25 * sp, 0.5 * (arc[k + 1] - arc[k - 1]));
        const Vector2d pa = rails[s].at(arc[k] - ds), pb = rails[s].at(arc[k] + ds);
        const auto xa = surface.position(pa.x(), pa.y());
        const auto xb = surface.position(pb.x(), pb.y());
        if (!xa || !xb) continue;
        const Vector3d tangent = (*xb - *xa).normalized();
        double push = 0;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              const std::vector<int>* found =
                  grid.find(detail::cell_key(pos[i] + cell * Vector3d(dx, dy, dz), cell));
              if (!found) continue;
              for (int j : *found) {
                if (owner[j] == static_cast<int>(s) || j == chain[k - 1] || j == chain[k + 1])
                  continue;
                const Vector3d d = pos[i] - pos[j];
                const double dist = d.norm();
                if (dist >= reach || dist < 1e-12) continue;
                double along = d.dot(tangent) / dist;
                // Exactly facing nodes feel no tangential push: break the tie by segment order
                // so one of the two rails gives way (deterministic).
                if (std::fabs(along) < 0.1) along = owner[j] < static_cast<int>(s) ? 0.5 : -0.5;
                push += (reach - dist) * along;
              }
            }
        const double gap = arc[k + 1] - arc[k - 1];
        double a = arc[k] + 0.5 * (target - arc[k]) + 0.5 * push;
        a = std::clamp(a, arc[k - 1] + 0.3 * gap * 0.5, arc[k + 1] - 0.3 * gap * 0.5);
        arc[k] = a;
        out.params[i] = rails[s].at(a);
        lift(i);
      }
    }
  }
  return out;
}

}  // namespace scanmesh::aft
