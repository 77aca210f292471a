#include "scanmesh/meshing/mesh_check.h"

#include "scanmesh/core/errors.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "kernel/triangle_grid.h"

namespace scanmesh {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;

double orient3d(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a);
}
double orient2d(const Vector2d& a, const Vector2d& b, const Vector2d& c) {
  const Vector2d u = b - a, v = c - a;
  return u.x() * v.y() - u.y() * v.x();
}
int sgn(double x) { return (x > 0) - (x < 0); }

// Segment p-q crosses the interior of triangle (a, b, c) (non-coplanar case, strict).
bool segment_crosses_triangle(const Vector3d& p, const Vector3d& q, const Vector3d& a,
                              const Vector3d& b, const Vector3d& c) {
  const int s1 = sgn(orient3d(a, b, c, p)), s2 = sgn(orient3d(a, b, c, q));
  if (s1 == 0 || s2 == 0 || s1 == s2) return false;
  const int o1 = sgn(orient3d(p, q, a, b)), o2 = sgn(orient3d(p, q, b, c)),
            o3 = sgn(orient3d(p, q, c, a));
  return o1 != 0 && o1 == o2 && o2 == o3;
}

// Interiors of two coplanar triangles overlap (separating axis; touching is not overlap).
bool coplanar_overlap(const std::array<Vector3d, 3>& t, const std::array<Vector3d, 3>& u,
                      const Vector3d& normal) {
  int drop = 0;
  normal.cwiseAbs().maxCoeff(&drop);
  const int x = (drop + 1) % 3, y = (drop + 2) % 3;
  std::array<Vector2d, 3> a, b;
  for (int k = 0; k < 3; ++k) {
    a[k] = {t[k][x], t[k][y]};
    b[k] = {u[k][x], u[k][y]};
  }
  double scale = 0;
  for (int k = 0; k < 3; ++k)
    scale = std::max(
        {scale, (a[k] - a[(k + 1) % 3]).squaredNorm(), (b[k] - b[(k + 1) % 3]).squaredNorm()});
  const double tol = 1e-12 * scale;
  auto separates = [tol](const std::array<Vector2d, 3>& p, const std::array<Vector2d, 3>& q) {
    const double o = orient2d(p[0], p[1], p[2]);
    if (o == 0) return true;  // degenerate: counted elsewhere
    const double s = o > 0 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k) {
      bool out = true;
      for (int i = 0; i < 3 && out; ++i)
        if (s * orient2d(p[k], p[(k + 1) % 3], q[i]) > tol) out = false;
      if (out) return true;
    }
    return false;
  };
  return !separates(a, b) && !separates(b, a);
}

// Two faces intersect improperly. Faces sharing corners may touch there (and along a shared
// edge); anything more is an intersection.
}  // namespace

bool triangles_intersect(const std::vector<Vector3d>& P, const std::array<int, 3>& f,
                         const std::array<int, 3>& g) {
  std::array<Vector3d, 3> a{P[f[0]], P[f[1]], P[f[2]]}, b{P[g[0]], P[g[1]], P[g[2]]};
  int shared = 0;
  std::array<int, 3> fi{-1, -1, -1};  // fi[k]: index in g of f[k], or -1
  std::array<bool, 3> g_shared{false, false, false};
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      if (f[k] == g[j]) {
        fi[k] = j;
        g_shared[j] = true;
        ++shared;
      }
  if (shared == 3) return false;  // duplicate, counted separately
  const Vector3d na = (a[1] - a[0]).cross(a[2] - a[0]);
  const Vector3d nb = (b[1] - b[0]).cross(b[2] - b[0]);
  double scale2 = 0;
  for (int k = 0; k < 3; ++k)
    scale2 = std::max(
        {scale2, (a[k] - a[(k + 1) % 3]).squaredNorm(), (b[k] - b[(k + 1) % 3]).squaredNorm()});
  const double tol = 1e-12 * scale2 * std::sqrt(scale2);
  // A shared corner lies in f's plane by definition; only g's other corners are tested (the
  // stitched mesh's check meets every pair of neighbouring triangles, most sharing an edge).
  bool coplanar = true;
  for (int k = 0; k < 3 && coplanar; ++k)
    if (!g_shared[k] && std::abs(orient3d(a[0], a[1], a[2], b[k])) > tol) coplanar = false;
  if (coplanar) return coplanar_overlap(a, b, na.squaredNorm() > 0 ? na : nb);
  if (shared == 2) return false;  // non-coplanar faces on a common edge meet only on it
  if (shared == 1) {
    int kf = 0;
    while (fi[kf] < 0) ++kf;
    const int kg = fi[kf];
    const Vector3d& p1 = a[(kf + 1) % 3];
    const Vector3d& q1 = a[(kf + 2) % 3];
    const Vector3d& p2 = b[(kg + 1) % 3];
    const Vector3d& q2 = b[(kg + 2) % 3];
    return segment_crosses_triangle(p1, q1, b[0], b[1], b[2]) ||
           segment_crosses_triangle(p2, q2, a[0], a[1], a[2]);
  }
  for (int k = 0; k < 3; ++k) {
    if (segment_crosses_triangle(a[k], a[(k + 1) % 3], b[0], b[1], b[2])) return true;
    if (segment_crosses_triangle(b[k], b[(k + 1) % 3], a[0], a[1], a[2])) return true;
  }
  return false;
}

std::size_t count_intersecting_faces(const Mesh& mesh, const std::vector<int>* labels,
                                     const std::vector<char>* involved) {
  return intersecting_face_pairs(mesh, labels, involved).size();
}

std::vector<std::array<int, 2>> intersecting_face_pairs(const Mesh& mesh,
                                                        const std::vector<int>* labels,
                                                        const std::vector<char>* involved,
                                                        std::size_t max_candidate_pairs,
                                                        bool* complete) {
  const auto& P = mesh.positions;
  const auto& F = mesh.triangles;
  if (complete) *complete = true;
  if (F.size() < 2) return {};
  const std::vector<char> repeats = faces_repeating_earlier_geometry(mesh);
  std::vector<Vector3d> lo(F.size()), hi(F.size());
  Vector3d glo = P[F[0][0]], ghi = glo;
  double mean = 0;
  for (std::size_t i = 0; i < F.size(); ++i) {
    lo[i] = P[F[i][0]].cwiseMin(P[F[i][1]]).cwiseMin(P[F[i][2]]);
    hi[i] = P[F[i][0]].cwiseMax(P[F[i][1]]).cwiseMax(P[F[i][2]]);
    glo = glo.cwiseMin(lo[i]);
    ghi = ghi.cwiseMax(hi[i]);
    mean += (hi[i] - lo[i]).maxCoeff();
  }
  mean /= static_cast<double>(F.size());
  double cell = std::max(2.0 * mean, 1e-12 * (ghi - glo).norm());
  std::array<long long, 3> dims{};
  while (true) {
    for (int a = 0; a < 3; ++a)
      dims[a] = static_cast<long long>(std::floor((ghi[a] - glo[a]) / cell)) + 1;
    if (static_cast<double>(dims[0]) * dims[1] * dims[2] <= 8.0 * F.size() + 64) break;
    cell *= 1.5;
  }
  const kernel::TriangleGrid grid({glo, cell, dims}, lo, hi, &repeats);
  std::vector<long long> keys;  // cells holding two faces or more
  double candidates = 0;
  for (std::size_t k = 0; k < grid.cells(); ++k) {
    const double size = static_cast<double>(grid.triangles_in(k).size());
    if (size < 2) continue;
    keys.push_back(static_cast<long long>(k));
    candidates += 0.5 * size * (size - 1);
  }
  if (candidates > static_cast<double>(max_candidate_pairs)) {
    if (complete) *complete = false;
    return {};
  }
  std::vector<std::vector<std::array<int, 2>>> found(keys.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (std::size_t c = 0; c < keys.size(); ++c) {
    const long long key = keys[c];
    const std::span<const int> list = grid.triangles_in(static_cast<std::size_t>(key));
    for (std::size_t i = 0; i < list.size(); ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) {
        const int f = list[i], g = list[j];
        if (labels && (*labels)[f] == (*labels)[g]) continue;
        if (involved && !(*involved)[f] && !(*involved)[g]) continue;
        const Vector3d l = lo[f].cwiseMax(lo[g]), h = hi[f].cwiseMin(hi[g]);
        if ((l.array() > h.array()).any()) continue;
        // count the pair only in the cell holding the low corner of the box overlap
        if (grid.flat(grid.cell_of(l)) != static_cast<std::size_t>(key)) continue;
        if (triangles_intersect(mesh.positions, F[f], F[g]))
          found[c].push_back({std::min(f, g), std::max(f, g)});
      }
  }
  std::vector<std::array<int, 2>> pairs;
  for (const auto& list : found) pairs.insert(pairs.end(), list.begin(), list.end());
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

double point_triangle_squared_distance(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                                       const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).squaredNorm();
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).squaredNorm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).squaredNorm();
}

bool MeshCheckReport::defect_free() const {
  return edge_manifold() && nonmanifold_vertices == 0 && duplicate_faces == 0 &&
         degenerate_faces == 0 && (!self_intersections_checked || self_intersections == 0);
}

MeshCheckReport check_mesh(const Mesh& mesh, const MeshCheckOptions& options) {
  MeshCheckReport r;
  const auto& P = mesh.positions;
  const auto& F = mesh.triangles;
  r.vertices = P.size();
  r.faces = F.size();
  r.topology = topology_stats(mesh);

  std::vector<std::array<int, 3>> sorted(F);
  for (auto& t : sorted) std::sort(t.begin(), t.end());
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i] == sorted[i - 1]) ++r.duplicate_faces;

  // Vertex manifoldness: the faces around v, joined when they share an edge through v.
  std::vector<std::size_t> start(P.size() + 1, 0);
  for (const auto& t : F)
    for (int v : t) ++start[v + 1];
  for (std::size_t v = 0; v < P.size(); ++v) start[v + 1] += start[v];
  std::vector<int> incident(start.back());
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < F.size(); ++f)
      for (int v : F[f]) incident[fill[v]++] = static_cast<int>(f);
  }
  // Faces around v that share an edge through v share a corner other than v: sorting the
  // (corner, face) pairs puts them side by side, so the work is O(k log k) for valence k.
  std::vector<int> parent;
  std::vector<std::pair<int, int>> corner_face;
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];  // path halving, no recursion
    return x;
  };
  for (std::size_t v = 0; v < P.size(); ++v) {
    const std::size_t b = start[v], e = start[v + 1];
    if (e - b < 2) continue;
    parent.resize(e - b);
    std::iota(parent.begin(), parent.end(), 0);
    corner_face.clear();
    for (std::size_t i = b; i < e; ++i)
      for (int x : F[incident[i]])
        if (x != static_cast<int>(v)) corner_face.emplace_back(x, static_cast<int>(i - b));
    std::sort(corner_face.begin(), corner_face.end());
    for (std::size_t k = 1; k < corner_face.size(); ++k)
      if (corner_face[k].first == corner_face[k - 1].first)
        parent[find(corner_face[k].second)] = find(corner_face[k - 1].second);
    int roots = 0;
    for (std::size_t i = 0; i < e - b; ++i)
      roots += find(static_cast<int>(i)) == static_cast<int>(i);
    if (roots > 1) ++r.nonmanifold_vertices;
  }

  double sum_angle = 0, sum_q = 0;
  std::size_t good = 0;
  r.min_angle_deg = F.empty() ? 0 : 180.0;
  r.min_radius_ratio = F.empty() ? 0 : 1.0;
  for (const auto& t : F) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      ++r.degenerate_faces;
      r.min_angle_histogram[0]++;
      r.min_angle_deg = 0;
      r.min_radius_ratio = 0;
      continue;
    }
    const Vector3d &a = P[t[0]], &b = P[t[1]], &c = P[t[2]];
    if ((b - a).cross(c - a).squaredNorm() == 0) ++r.degenerate_faces;
    const double m = triangle_min_angle(a, b, c) * 180.0 / kPi;
    const double q = radius_ratio(a, b, c);
    r.min_angle_deg = std::min(r.min_angle_deg, m);
    r.min_radius_ratio = std::min(r.min_radius_ratio, q);
    sum_angle += m;
    sum_q += q;
    if (m >= 30.0) ++good;
    r.min_angle_histogram[std::min<std::size_t>(11, static_cast<std::size_t>(m / 5.0))]++;
  }
  if (!F.empty()) {
    r.mean_min_angle_deg = sum_angle / static_cast<double>(F.size());
    r.mean_radius_ratio = sum_q / static_cast<double>(F.size());
    r.fraction_min_angle_ge_30 = static_cast<double>(good) / static_cast<double>(F.size());
  }
  if (options.self_intersections) {
    const std::size_t budget = default_candidate_pair_budget(F.size());
    bool complete = true;
    r.self_intersections =
        intersecting_face_pairs(mesh, nullptr, nullptr, budget, &complete).size();
    r.self_intersections_checked = complete;
    if (!complete)
      r.self_intersections_not_checked_reason = "faces crowd one place (more than " +
                                                std::to_string(budget) +
                                                " candidate pairs in the broad phase)";
  }
  return r;
}

std::string MeshCheckReport::to_text() const {
  std::ostringstream o;
  o << "vertices              " << vertices << "\n"
    << "faces                 " << faces << "\n"
    << "edges                 " << topology.edges << "\n"
    << "duplicate faces       " << duplicate_faces << "\n"
    << "degenerate faces      " << degenerate_faces << "\n"
    << "non-manifold edges    " << topology.nonmanifold_edges << "\n"
    << "non-manifold vertices " << nonmanifold_vertices << "\n"
    << "inconsistent edges    " << topology.inconsistent_edges << "\n"
    << "self-intersections    "
    << (self_intersections_checked ? std::to_string(self_intersections)
        : self_intersections_not_checked_reason.empty()
            ? std::string("not checked")
            : "not checked: " + self_intersections_not_checked_reason)
    << "\n"
    << "boundary loops        " << topology.boundary_loops;
  if (!topology.boundary_loop_lengths.empty()) {
    o << " (edges:";
    for (std::size_t i = 0; i < topology.boundary_loop_lengths.size() && i < 10; ++i)
      o << " " << topology.boundary_loop_lengths[i];
    if (topology.boundary_loop_lengths.size() > 10) o << " ...";
    o << ")";
  }
  o << "\n"
    << "unreferenced vertices " << topology.unreferenced_vertices << "\n"
    << "components            " << topology.components << "\n"
    << "Euler characteristic  " << topology.euler_characteristic << "\n";
  if (defect_free() && topology.inconsistent_edges == 0)
    o << "genus                 " << topology.genus() << "\n";
  o << "min angle [deg]       " << min_angle_deg << " (mean of per-face minima "
    << mean_min_angle_deg << ")\n"
    << "radius ratio 2r/R     min " << min_radius_ratio << ", mean " << mean_radius_ratio
    << "  (1 = equilateral)\n"
    << "faces min angle >= 30 " << 100.0 * fraction_min_angle_ge_30 << " %\n"
    << "min-angle histogram   ";
  for (std::size_t i = 0; i < min_angle_histogram.size(); ++i)
    o << (i ? " " : "") << min_angle_histogram[i];
  o << "  (5 deg bins from 0)\n";
  for (const PropertyVerdict& v : mesh_verdicts(*this)) {
    std::string name = property_name(v.property);
    name.resize(22, ' ');
    o << name << (!v.known ? "not checked" : v.holds ? "yes" : "NO");
    if (!v.evidence.empty()) o << " (" << v.evidence << ")";
    o << "\n";
  }
  return o.str();
}

namespace {
constexpr std::array<MeshProperty, 8> kAllProperties{
    MeshProperty::NonEmpty,       MeshProperty::Closed,      MeshProperty::EdgeManifold,
    MeshProperty::VertexManifold, MeshProperty::Oriented,    MeshProperty::IntersectionFree,
    MeshProperty::NoDegenerate,   MeshProperty::NoDuplicates};
}  // namespace

const char* property_name(MeshProperty p) {
  switch (p) {
    case MeshProperty::NonEmpty:
      return "non-empty";
    case MeshProperty::Closed:
      return "closed";
    case MeshProperty::EdgeManifold:
      return "edge-manifold";
    case MeshProperty::VertexManifold:
      return "vertex-manifold";
    case MeshProperty::Oriented:
      return "oriented";
    case MeshProperty::IntersectionFree:
      return "intersection-free";
    case MeshProperty::NoDegenerate:
      return "no-degenerate";
    case MeshProperty::NoDuplicates:
      return "no-duplicates";
  }
  return "?";
}

std::span<const MeshProperty> all_mesh_properties() { return kAllProperties; }

std::vector<MeshProperty> parse_mesh_properties(const std::string& list) {
  std::vector<MeshProperty> out;
  std::string valid;
  for (MeshProperty p : kAllProperties)
    valid += std::string(valid.empty() ? "" : ", ") + property_name(p);
  std::size_t begin = 0;
  while (begin <= list.size()) {
    const std::size_t end = std::min(list.find(',', begin), list.size());
    const std::string name = list.substr(begin, end - begin);
    begin = end + 1;
    if (name.empty()) continue;
    const auto* it = std::find_if(kAllProperties.begin(), kAllProperties.end(),
                                  [&](MeshProperty p) { return name == property_name(p); });
    if (it == kAllProperties.end())
      throw InvalidInputError("unknown mesh property '" + name + "' (valid: " + valid + ")");
    out.push_back(*it);
  }
  if (out.empty()) throw InvalidInputError("no mesh property given (valid: " + valid + ")");
  return out;
}

std::vector<PropertyVerdict> mesh_verdicts(const MeshCheckReport& r) {
  const TopologyStats& t = r.topology;
  auto count = [](std::size_t n, const char* what) {
    return n ? std::to_string(n) + " " + what : std::string();
  };
  std::vector<PropertyVerdict> v;
  v.push_back({MeshProperty::NonEmpty, true, r.faces > 0, r.faces ? "" : "no faces"});
  std::string open = count(t.boundary_loops, "boundary loops");
  if (t.boundary_edges) open += " (" + std::to_string(t.boundary_edges) + " boundary edges)";
  if (r.faces == 0) open = "no faces";
  if (!r.edge_manifold()) open += std::string(open.empty() ? "" : ", ") + "not edge-manifold";
  v.push_back({MeshProperty::Closed, true,
               r.faces > 0 && t.boundary_edges == 0 && r.edge_manifold(), open});
  v.push_back({MeshProperty::EdgeManifold, true, r.edge_manifold(),
               count(t.nonmanifold_edges, "edges with more than two faces")});
  v.push_back({MeshProperty::VertexManifold, true, r.nonmanifold_vertices == 0,
               count(r.nonmanifold_vertices, "vertices whose faces form several fans")});
  v.push_back({MeshProperty::Oriented, true, t.inconsistent_edges == 0,
               count(t.inconsistent_edges, "edges traversed twice in one direction")});
  v.push_back({MeshProperty::IntersectionFree, r.self_intersections_checked,
               r.self_intersections_checked && r.self_intersections == 0,
               r.self_intersections_not_checked_reason.empty()
                   ? count(r.self_intersections, "intersecting face pairs")
                   : r.self_intersections_not_checked_reason});
  v.push_back({MeshProperty::NoDegenerate, true, r.degenerate_faces == 0,
               count(r.degenerate_faces, "degenerate faces")});
  v.push_back({MeshProperty::NoDuplicates, true, r.duplicate_faces == 0,
               count(r.duplicate_faces, "duplicate faces")});
  return v;
}

void write_min_angle_histogram_png(const std::filesystem::path& path, const MeshCheckReport& report,
                                   const std::string& title) {
  const auto& h = report.min_angle_histogram;
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < h.size(); ++i) labels.push_back(std::to_string(i * 5));
  // Bins from 30 deg on are drawn as good: the animation meshes' goal (seed 000, issue 4).
  write_histogram_png(path, std::span<const std::size_t>(h.data(), h.size()), labels, title,
                      {.begin = 6, .end = h.size()});
}

}  // namespace scanmesh
