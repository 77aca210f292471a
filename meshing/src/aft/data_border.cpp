// The data border of a partial scan: the defined surface's outer boundary traced as closed
// animation lines, and the user's lines clipped to it (data_border.h; docs/animation-meshes.md,
// "Partial scans: the data border"). Geometry in texture pixels, x unwrapped with period n_phi.
#include "scanmesh/meshing/aft/data_border.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "aft_internal.h"
#include "scanmesh/core/errors.h"

namespace scanmesh::aft {

using detail::periodic_copy_near;
using detail::signed_area;
using Eigen::Vector2d;

namespace {

// Patch (i, j) of the surface (corners: cells i, i + 1 and rows j, j + 1) covers the pixel
// square [i + 0.5, i + 1.5) x [j + 0.5, j + 1.5); its centre is pixel (i + 1, j + 1).
struct PatchMask {
  int width = 0, rows = 0;  // patch columns (= n_phi) and patch rows (= n_h - 1)
  std::vector<std::uint8_t> defined;

  explicit PatchMask(const ScanSurface& s) : width(s.n_phi()), rows(s.n_h() - 1) {
    defined.resize(static_cast<std::size_t>(width) * std::max(rows, 0));
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < width; ++i) {
        const Vector2d q = pixel_to_param(s, {i + 1.0, j + 1.0});
        defined[index(i, j)] = s.defined(q.x(), q.y());
      }
  }
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * width + (((i % width) + width) % width);
  }
  bool at(int i, int j) const { return j >= 0 && j < rows && defined[index(i, j)]; }
};

// Counts of undefined patches over boxes (x periodic, rows outside the grid undefined), so that
// the distance below is only searched near the data's edge.
class UndefinedCounts {
 public:
  explicit UndefinedCounts(const PatchMask& m) : m_(m), sum_((m.rows + 1) * (3 * m.width + 1)) {
    const int w3 = 3 * m.width;  // three copies side by side: a box may cross the seam
    for (int j = 0; j < m.rows; ++j)
      for (int i = 0; i < w3; ++i)
        sum_[(j + 1) * (w3 + 1) + i + 1] = sum_[j * (w3 + 1) + i + 1] +
                                           sum_[(j + 1) * (w3 + 1) + i] - sum_[j * (w3 + 1) + i] +
                                           !m.at(i, j);
  }
  // Undefined patches in columns [i0, i1] x rows [j0, j1] (i unwrapped within one turn).
  int count(int i0, int i1, int j0, int j1) const {
    if (j0 < 0 || j1 >= m_.rows) return 1;
    const int w3 = 3 * m_.width;
    const int a = i0 + m_.width, b = i1 + m_.width + 1;
    return sum_[(j1 + 1) * (w3 + 1) + b] - sum_[j0 * (w3 + 1) + b] - sum_[(j1 + 1) * (w3 + 1) + a] +
           sum_[j0 * (w3 + 1) + a];
  }

 private:
  const PatchMask& m_;
  std::vector<int> sum_;
};

// Distance from pixel point p to the undefined area (undefined patches and the rows beyond the
// grid), capped at `reach` pixels.
double distance_to_undefined(const PatchMask& m, const UndefinedCounts& counts, Vector2d p,
                             double reach) {
  const int pi = static_cast<int>(std::floor(p.x() - 0.5));
  const int pj = static_cast<int>(std::floor(p.y() - 0.5));
  if (!m.at(pi, pj)) return 0.0;
  double d = std::min({reach, p.y() - 0.5, m.rows + 0.5 - p.y()});
  const int r = static_cast<int>(std::ceil(reach));
  const int j0 = std::max(pj - r, 0), j1 = std::min(pj + r, m.rows - 1);
  if (counts.count(pi - r, pi + r, j0, j1) == 0) return d;
  for (int j = j0; j <= j1; ++j)
    for (int i = pi - r; i <= pi + r; ++i) {
      if (m.at(i, j)) continue;
      const double dx = std::max({i + 0.5 - p.x(), p.x() - (i + 1.5), 0.0});
      const double dy = std::max({j + 0.5 - p.y(), p.y() - (j + 1.5), 0.0});
      d = std::min(d, std::hypot(dx, dy));
    }
  return d;
}

constexpr double kStep = 0.5;  // the distance field's sampling (pixels)

// f = distance - margin on a lattice of kStep over the patches, one row of "outside" padding
// above and below so that every contour closes. Sample (a, b) sits at pixel
// (0.5 + (a + 0.5) kStep, 0.5 + (b + 0.5) kStep), b = -1 and b = rows_ - 2 being the padding.
class OffsetField {
 public:
  OffsetField(const PatchMask& m, double margin)
      : cols_(static_cast<int>(m.width / kStep)),
        rows_(static_cast<int>(m.rows / kStep) + 2),
        f_(static_cast<std::size_t>(cols_) * rows_, -margin) {
    const UndefinedCounts counts(m);
    const double reach = margin + 1.0;
    for (int b = 0; b + 2 < rows_; ++b)
      for (int a = 0; a < cols_; ++a)
        f_[static_cast<std::size_t>(b + 1) * cols_ + a] =
            distance_to_undefined(m, counts, position(a, b), reach) - margin;
  }
  int cols() const { return cols_; }
  int rows() const { return rows_ - 1; }  // b runs over [-1, rows())
  double at(int a, int b) const {
    return f_[static_cast<std::size_t>(b + 1) * cols_ + ((a % cols_) + cols_) % cols_];
  }
  static Vector2d position(int a, int b) {
    return {0.5 + (a + 0.5) * kStep, 0.5 + (b + 0.5) * kStep};
  }

 private:
  int cols_, rows_;
  std::vector<double> f_;
};

// Marching squares, inside (f > 0) on the left of every contour segment. A saddle keeps its
// two inside corners apart: the conservative choice, it never bridges undefined data.
struct ContourSegment {
  long from_edge, to_edge;  // lattice edges crossed, as keys
  Vector2d from, to;
};

std::vector<ContourSegment> contour_segments(const OffsetField& f) {
  std::vector<ContourSegment> out;
  const long cols = f.cols();
  // Lattice edge keys: horizontal (a, b)-(a+1, b) -> 2 k, vertical (a, b)-(a, b+1) -> 2 k + 1.
  auto key = [&](int a, int b, bool vertical) {
    return 2 * ((b + 1L) * cols + ((a % cols) + cols) % cols) + (vertical ? 1 : 0);
  };
  for (int b = -1; b + 1 < f.rows(); ++b)
    for (int a = 0; a < f.cols(); ++a) {
      // Corners counter-clockwise (y up) and the edges leaving them.
      const int ca[4] = {a, a + 1, a + 1, a}, cb[4] = {b, b, b + 1, b + 1};
      const long edge[4] = {key(a, b, false), key(a + 1, b, true), key(a, b + 1, false),
                            key(a, b, true)};
      double v[4];
      for (int k = 0; k < 4; ++k) v[k] = f.at(ca[k], cb[k]);
      // Crossings in counter-clockwise order alternate between exits (inside -> outside) and
      // entries; each exit joins the entry before it, which keeps the inside on the left.
      int crossing[4], count = 0;
      for (int k = 0; k < 4; ++k)
        if ((v[k] > 0) != (v[(k + 1) % 4] > 0)) crossing[count++] = k;
      auto point = [&](int k) {
        const int n = (k + 1) % 4;
        const Vector2d p = OffsetField::position(ca[k], cb[k]);
        const Vector2d q = OffsetField::position(ca[n], cb[n]);
        return Vector2d(p + v[k] / (v[k] - v[n]) * (q - p));
      };
      for (int m = 0; m < count; ++m) {
        const int k = crossing[m];
        if (v[k] <= 0) continue;  // an entry
        const int e = crossing[(m + count - 1) % count];
        out.push_back({edge[k], edge[e], point(k), point(e)});
      }
    }
  return out;
}

// Closed contours from the segments, x unwrapped along each.
std::vector<std::vector<Vector2d>> link_contours(const std::vector<ContourSegment>& segs,
                                                 double W) {
  std::map<long, std::size_t> starting_at;
  for (std::size_t s = 0; s < segs.size(); ++s) starting_at[segs[s].from_edge] = s;
  std::vector<bool> used(segs.size(), false);
  std::vector<std::vector<Vector2d>> loops;
  for (std::size_t s0 = 0; s0 < segs.size(); ++s0) {
    if (used[s0]) continue;
    std::vector<Vector2d> loop;
    std::size_t s = s0;
    while (!used[s]) {
      used[s] = true;
      Vector2d p = segs[s].from;
      if (!loop.empty()) p.x() += W * std::round((loop.back().x() - p.x()) / W);
      loop.push_back(p);
      const auto next = starting_at.find(segs[s].to_edge);
      if (next == starting_at.end()) break;
      s = next->second;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

// Turns round the axis of a closed contour whose x is unwrapped along it.
int winding(const std::vector<Vector2d>& loop, double W) {
  const Vector2d& last = loop.back();
  Vector2d first = loop.front();
  first.x() += W * std::round((last.x() - first.x()) / W);
  return static_cast<int>(std::lround((first.x() - loop.front().x()) / W));
}

void douglas_peucker(const std::vector<Vector2d>& p, std::size_t i0, std::size_t i1, double tol,
                     std::vector<Vector2d>& out) {
  double worst = -1;
  std::size_t k = i0;
  for (std::size_t i = i0 + 1; i < i1; ++i) {
    const double d = detail::point_segment_distance(p[i], p[i0], p[i1]);
    if (d > worst) {
      worst = d;
      k = i;
    }
  }
  if (worst > tol) {
    douglas_peucker(p, i0, k, tol, out);
    douglas_peucker(p, k, i1, tol, out);
  } else {
    out.push_back(p[i1]);
  }
}

// A closed contour simplified; `turns` != 0: the contour goes round the axis and its closing
// piece runs one turn on.
std::vector<Vector2d> simplify_closed(std::vector<Vector2d> loop, int turns, double W, double tol) {
  Vector2d closing = loop.front();
  closing.x() += turns * W;
  std::size_t far = 0;
  if (turns == 0) {
    for (std::size_t i = 1; i < loop.size(); ++i)
      if ((loop[i] - loop[0]).norm() > (loop[far] - loop[0]).norm()) far = i;
  } else {
    far = loop.size() / 2;  // any split: the ends are a turn apart
  }
  loop.push_back(closing);
  std::vector<Vector2d> out{loop[0]};
  douglas_peucker(loop, 0, far, tol, out);
  douglas_peucker(loop, far, loop.size() - 1, tol, out);
  out.pop_back();  // the closing point repeats the first
  return out;
}

// validate_lines' test: every quarter pixel of the closed polygon on the defined surface.
bool on_defined_surface(const std::vector<Vector2d>& poly, int turns, const ScanSurface& s) {
  const double W = s.n_phi();
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const Vector2d a = poly[k];
    Vector2d b = poly[(k + 1) % poly.size()];
    if (k + 1 == poly.size()) b.x() += turns * W;
    const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() * 4)));
    for (int i = 0; i <= steps; ++i) {
      const Vector2d p = a + (b - a) * (static_cast<double>(i) / steps);
      const Vector2d q = pixel_to_param(s, p);
      if (p.y() < 0.5 || p.y() > s.n_h() - 0.5 || !s.defined(q.x(), q.y())) return false;
    }
  }
  return true;
}

struct TracedLoop {
  std::vector<Vector2d> pts;
  int turns = 0;
};

// The outer contours at one margin (nullopt if one of them leaves the defined surface).
std::optional<std::vector<TracedLoop>> trace_at(const ScanSurface& s, const PatchMask& mask,
                                                double margin, const DataBorderOptions& o) {
  const double W = s.n_phi();
  std::vector<TracedLoop> kept;
  for (auto& loop : link_contours(contour_segments(OffsetField(mask, margin)), W)) {
    if (loop.size() < 3) continue;
    const int turns = winding(loop, W);
    // Winding 0: counter-clockwise = an outer boundary, clockwise = a hole (no border). A
    // contour round the axis bounds a component that goes all the way round.
    if (turns == 0 && signed_area(loop) < o.min_area_px) continue;
    TracedLoop t{simplify_closed(std::move(loop), turns, W, o.tolerance_px), turns};
    if (t.pts.size() < 3 || !on_defined_surface(t.pts, turns, s)) return std::nullopt;
    kept.push_back(std::move(t));
  }
  return kept;
}

// Vertices where the border turns by more than kSharpTurn: the mesh should have a node there
// (a segment's nodes are placed by arc length, and a chord across a corner of the data would
// cut it off). Corners closer than kMinCornerGapPx along the border are skipped: a border
// part must be a valid line of its own (validate_lines: >= 2 pixels).
constexpr double kSharpTurn = 50 * M_PI / 180;
constexpr double kMinCornerGapPx = 4.0;

std::vector<std::size_t> sharp_corners(const std::vector<Vector2d>& p, int turns, double W) {
  const std::size_t n = p.size();
  auto vertex = [&](std::size_t k) {  // unwrapped along the loop, one turn on past the end
    Vector2d q = p[k % n];
    q.x() += turns * W * static_cast<double>(k / n);
    return q;
  };
  std::vector<std::size_t> corners;
  double since = 0, first_at = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const Vector2d u = vertex(k + n) - vertex(k + n - 1), v = vertex(k + n + 1) - vertex(k + n);
    since += u.norm();
    const double turn = std::atan2(std::fabs(u.x() * v.y() - u.y() * v.x()), u.dot(v));
    if (turn < kSharpTurn || (!corners.empty() && since < kMinCornerGapPx)) continue;
    if (corners.empty()) first_at = since;
    corners.push_back(k);
    since = 0;
  }
  // The gap from the last corner round to the first.
  if (corners.size() > 1 && since + first_at < kMinCornerGapPx) corners.pop_back();
  return corners;
}

// The border's vertices from corner c0 to corner c1 (past the loop's end when c1 <= c0).
std::vector<Vector2d> corner_to_corner(const TracedLoop& t, std::size_t c0, std::size_t c1,
                                       double W) {
  const std::size_t n = t.pts.size();
  const std::size_t end = c1 > c0 ? c1 : c1 + n;
  std::vector<Vector2d> out;
  for (std::size_t k = c0; k <= end; ++k) {
    Vector2d q = t.pts[k % n];
    q.x() += t.turns * W * static_cast<double>(k / n);
    out.push_back(q);
  }
  return out;
}

}  // namespace

DataBorderMode parse_data_border_mode(std::string_view name) {
  if (name == "auto") return DataBorderMode::Auto;
  if (name == "on") return DataBorderMode::On;
  if (name == "off") return DataBorderMode::Off;
  throw InvalidInputError("data border must be auto, on or off, not \"" + std::string(name) + "\"");
}

const char* to_string(DataBorderMode mode) {
  switch (mode) {  // no default: -Wswitch names a mode added without a name here
    case DataBorderMode::On:
      return "on";
    case DataBorderMode::Off:
      return "off";
    case DataBorderMode::Auto:
      break;
  }
  return "auto";
}

bool misses_part_of_the_turn(const ScanSurface& surface) {
  const PatchMask mask(surface);
  for (int i = 0; i < mask.width; ++i) {
    bool any = false;
    for (int j = 0; j < mask.rows && !any; ++j) any = mask.at(i, j);
    if (!any) return true;
  }
  return false;
}

std::vector<AnimationLine> trace_data_border(const ScanSurface& surface,
                                             const DataBorderOptions& options) {
  const PatchMask mask(surface);
  // The offset contour keeps the margin up to its sampling and the simplification's tolerance;
  // where a narrow neck of data still lets it touch undefined patches, a wider margin is tried.
  std::optional<std::vector<TracedLoop>> loops;
  for (int attempt = 0; attempt < 4 && !loops; ++attempt)
    loops = trace_at(surface, mask, options.margin_px + 0.5 * attempt, options);
  if (!loops)
    throw InvalidInputError(
        "the data border could not be traced inside the defined surface (the data are "
        "narrower than a few cells everywhere); draw the border by hand and use --data-border "
        "off");
  std::vector<AnimationLine> lines;
  for (std::size_t n = 0; n < loops->size(); ++n) {
    AnimationLine line;
    line.id = "data-border-" + std::to_string(n + 1);
    line.kind = LineKind::DataBorder;
    line.source = "data border";
    const TracedLoop& t = (*loops)[n];
    const std::vector<std::size_t> corners = sharp_corners(t.pts, t.turns, surface.n_phi());
    if (corners.size() < 2) {
      line.closed = true;
      line.pixels = t.pts;
      lines.push_back(std::move(line));
      continue;
    }
    // Open lines from corner to corner: their ends join, so every corner is a graph node.
    for (std::size_t c = 0; c < corners.size(); ++c) {
      AnimationLine part = line;
      part.id += "." + std::to_string(c + 1);
      part.pixels =
          corner_to_corner(t, corners[c], corners[(c + 1) % corners.size()], surface.n_phi());
      lines.push_back(std::move(part));
    }
  }
  return lines;
}

// ---------------------------------------------------------------------------------------------

namespace {

struct Piece {
  Vector2d a, b;
};

// The pieces of a line's curve, the closing piece of a closed one included (its end unwrapped
// next to its start, as analyze_regions does).
std::vector<Piece> pieces_of(const std::vector<Vector2d>& c, bool closed, double W) {
  std::vector<Piece> out;
  const std::size_t n = closed ? c.size() : c.size() - 1;
  for (std::size_t k = 0; k < n; ++k) {
    Vector2d b = c[(k + 1) % c.size()];
    if (k + 1 == c.size()) b.x() += W * std::round((c[k].x() - b.x()) / W);
    out.push_back({c[k], b});
  }
  return out;
}

std::vector<Piece> border_pieces(const std::vector<AnimationLine>& border, double W) {
  std::vector<Piece> out;
  for (const AnimationLine& line : border) {
    const auto p = pieces_of(line_curve(line, W), line.closed, W);
    out.insert(out.end(), p.begin(), p.end());
  }
  return out;
}

// Inside the border: an odd number of border pieces above q (a vertical ray; it also counts
// right between the two contours of a component that goes round the axis).
bool inside_border(const std::vector<Piece>& border, Vector2d q, double W) {
  int above = 0;
  for (const Piece& p : border) {
    const double x = q.x() + W * std::round((0.5 * (p.a.x() + p.b.x()) - q.x()) / W);
    if ((p.a.x() <= x) == (p.b.x() <= x)) continue;
    const double y = p.a.y() + (x - p.a.x()) / (p.b.x() - p.a.x()) * (p.b.y() - p.a.y());
    if (y > q.y()) ++above;
  }
  return above % 2 == 1;
}

// Parameters t in (0, 1] of the piece where it crosses the border.
void crossings(const Piece& p, const std::vector<Piece>& border, double W,
               std::vector<double>& ts) {
  const Vector2d r = p.b - p.a;
  for (const Piece& q0 : border)
    for (int k = -1; k <= 1; ++k) {
      const Piece q = periodic_copy_near(p, q0, W, k);
      const Vector2d s = q.b - q.a, w = q.a - p.a;
      const double den = r.x() * s.y() - r.y() * s.x();
      if (std::fabs(den) <= 1e-12 * r.norm() * s.norm()) continue;  // parallel: no crossing
      const double t = (w.x() * s.y() - w.y() * s.x()) / den;
      const double u = (w.x() * r.y() - w.y() * r.x()) / den;
      if (t >= 0 && t <= 1 && u >= 0 && u <= 1) ts.push_back(t);
    }
}

double polyline_length(const std::vector<Vector2d>& p) {
  double s = 0;
  for (std::size_t k = 1; k < p.size(); ++k) s += (p[k] - p[k - 1]).norm();
  return s;
}

// The parts of one line inside the border; nullopt: the line does not cross it.
std::optional<std::vector<AnimationLine>> clip_line(const AnimationLine& line,
                                                    const std::vector<Piece>& border, double W) {
  const std::vector<Piece> pieces = pieces_of(line_curve(line, W), line.closed, W);
  std::vector<double> cuts;  // piece index + t
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    std::vector<double> ts;
    crossings(pieces[k], border, W, ts);
    for (double t : ts) cuts.push_back(k + t);
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end(), [](double a, double b) { return b - a < 1e-9; }),
             cuts.end());
  if (cuts.empty()) return std::nullopt;
  const double n = static_cast<double>(pieces.size());
  // The curve continued past its end (closed lines: one more trip, shifted by its advance).
  const double advance = pieces.back().b.x() - pieces.front().a.x();
  auto point_at = [&](double s) {
    const double trips = line.closed ? std::floor(s / n) : 0.0;
    const double local = s - trips * n;
    const std::size_t k = std::min(static_cast<std::size_t>(local), pieces.size() - 1);
    Vector2d p = pieces[k].a + (local - k) * (pieces[k].b - pieces[k].a);
    p.x() += trips * advance;
    return p;
  };
  std::vector<std::pair<double, double>> runs;
  if (line.closed) {
    for (std::size_t k = 0; k < cuts.size(); ++k)
      runs.push_back({cuts[k], k + 1 < cuts.size() ? cuts[k + 1] : cuts[0] + n});
  } else {
    double from = 0;
    for (double c : cuts) {
      runs.push_back({from, c});
      from = c;
    }
    runs.push_back({from, n});
  }
  std::vector<AnimationLine> kept;
  for (const auto& [s0, s1] : runs) {
    if (s1 - s0 < 1e-9 || !inside_border(border, point_at(0.5 * (s0 + s1)), W)) continue;
    std::vector<Vector2d> pts{point_at(s0)};
    for (double v = std::floor(s0) + 1; v < s1 - 1e-9; v += 1) pts.push_back(point_at(v));
    pts.push_back(point_at(s1));
    if (polyline_length(pts) < 2.0) continue;  // a graze of the border: not a line
    AnimationLine part = line;
    if (!kept.empty()) part.id += "." + std::to_string(kept.size() + 1);
    part.closed = false;
    part.smooth = false;  // the flattened curve is the geometry now
    part.pixels = std::move(pts);
    kept.push_back(std::move(part));
  }
  return kept;
}

struct ClipCounts {
  int clipped = 0, dropped = 0;
};

LineSet clip_counted(const LineSet& set, const std::vector<AnimationLine>& border,
                     const ScanSurface& surface, ClipCounts& counts) {
  const double W = surface.n_phi();
  const std::vector<Piece> borders = border_pieces(border, W);
  LineSet out;
  out.file = set.file;
  for (const AnimationLine& line : set.lines) {
    auto parts = clip_line(line, borders, W);
    if (!parts) {
      if (inside_border(borders, line_curve(line, W).front(), W)) {
        out.lines.push_back(line);
      } else {
        ++counts.dropped;
      }
      continue;
    }
    ++counts.clipped;
    for (AnimationLine& part : *parts) out.lines.push_back(std::move(part));
  }
  return out;
}

}  // namespace

LineSet clip_lines_to_border(const LineSet& lines, const std::vector<AnimationLine>& border,
                             const ScanSurface& surface) {
  ClipCounts counts;
  return clip_counted(lines, border, surface, counts);
}

DataBorderResult with_data_border(const LineSet& lines, const ScanSurface& surface,
                                  DataBorderMode mode, const DataBorderOptions& options) {
  DataBorderResult r;
  r.border_on = mode == DataBorderMode::On ||
                (mode == DataBorderMode::Auto && misses_part_of_the_turn(surface));
  if (!r.border_on) {
    r.lines = lines;
    return r;
  }
  const std::vector<AnimationLine> border = trace_data_border(surface, options);
  ClipCounts counts;
  r.lines = clip_counted(lines, border, surface, counts);
  r.clipped_lines = counts.clipped;
  r.dropped_lines = counts.dropped;
  r.border_lines = static_cast<int>(border.size());
  r.lines.lines.insert(r.lines.lines.end(), border.begin(), border.end());
  return r;
}

}  // namespace scanmesh::aft
