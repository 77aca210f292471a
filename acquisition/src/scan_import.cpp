// Scans from other scanners into a RangeGrid (docs/acquisition.md, "Importing scans").
#include "scanmesh/acquisition/scan_import.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh_io.h"

namespace scanmesh {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Clouds: a cell 2 sample spacings wide holds about four samples where the surface faces the
// axis, enough for a median and few empty cells (1.5 left a tenth of them empty on the corpus
// clouds); meshes: one cell per edge length.
constexpr double kCloudCellPerSpacing = 2.0;
constexpr double kMeshCellPerSpacing = 1.0;
// Samples per cell at which the confidence of a binned cell reaches 1.
constexpr double kFullConfidenceSamples = 3.0;

// A sample in the grid frame's cylindrical coordinates.
struct CylSample {
  double phi, h, r;
};

struct Frame {
  Eigen::Matrix3d rotation;  // rows: e1, e2, axis
  Eigen::Vector3d origin;
  CylinderAxis axis;
};

Eigen::Vector3d centroid(const std::vector<Eigen::Vector3d>& pts) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : pts) c += p;
  return c / static_cast<double>(pts.size());
}

Eigen::Vector3d principal_direction(const std::vector<Eigen::Vector3d>& pts,
                                    const Eigen::Vector3d& c) {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - c) * (p - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d d = eig.eigenvectors().col(2);  // largest eigenvalue
  // Sign convention: the largest component positive (z up for a standing object).
  Eigen::Index k = 0;
  d.cwiseAbs().maxCoeff(&k);
  return d[k] < 0 ? Eigen::Vector3d(-d) : d;
}

// Coordinates beyond a kilometre from the origin are no turntable scan; the bound keeps every
// later sum, hash key and cell index far from overflow on hostile files.
constexpr double kMaxCoordinate = 1e6;

void check_extent(const std::vector<Eigen::Vector3d>& pts, const std::filesystem::path& source) {
  for (const auto& p : pts)
    if (!(p.cwiseAbs().maxCoeff() <= kMaxCoordinate))
      throw FileFormatError(source, "a coordinate is not finite or beyond 1e6 in magnitude");
}

Frame make_frame(const std::vector<Eigen::Vector3d>& pts, const ImportOptions& options) {
  Frame f;
  const Eigen::Vector3d c = centroid(pts);
  Eigen::Vector3d dir = Eigen::Vector3d::UnitZ();
  if (options.direction == AxisDirection::Given) {
    if (!options.axis_direction.allFinite() || options.axis_direction.norm() < 1e-12)
      throw InvalidInputError("the axis direction must be a non-zero vector");
    dir = options.axis_direction.normalized();
  } else if (options.direction == AxisDirection::Estimate) {
    dir = principal_direction(pts, c);
  }
  Eigen::Vector3d point = options.axis_point.value_or(c);
  if (!(point.cwiseAbs().maxCoeff() <= kMaxCoordinate))
    throw InvalidInputError("the axis point must be finite and within 1e6 of the origin");
  // The axis point moved along the axis to the height of the data's centroid: h = 0 there for
  // an estimated axis; for +z the file's own heights are kept (h = z).
  if (options.direction == AxisDirection::Z) point.z() = 0;
  // e1: x projected onto the plane across the axis (y if x is nearly along the axis), so that
  // with the +z axis phi is the file's own atan2(y, x).
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX() - dir * dir.x();
  if (e1.norm() < 0.1) e1 = Eigen::Vector3d::UnitY() - dir * dir.y();
  e1.normalize();
  const Eigen::Vector3d e2 = dir.cross(e1);
  f.rotation.row(0) = e1.transpose();
  f.rotation.row(1) = e2.transpose();
  f.rotation.row(2) = dir.transpose();
  f.origin = point;
  f.axis = {point, dir};
  return f;
}

CylSample to_cylinder(const Frame& f, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = f.rotation * (p - f.origin);
  double phi = std::atan2(q.y(), q.x());
  if (phi < 0) phi += kTwoPi;
  return {phi, q.z(), std::hypot(q.x(), q.y())};
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The sample spacing of a cloud: sqrt of the surface area per sample, from the disc that holds
// each point's 8 nearest neighbours (pi r8^2 / 8), median over up to 20000 points. The nearest-
// neighbour distance alone is half the spacing on a random sampling and equals it on a
// scanner's regular one; the 8-neighbour disc measures both alike (0.89 s on a square lattice).
double median_sample_spacing(const std::vector<Eigen::Vector3d>& pts) {
  constexpr int kNeighbours = 8;
  Eigen::AlignedBox3d box;
  for (const auto& p : pts) box.extend(p);
  const double diag = box.diagonal().norm();
  if (pts.size() <= kNeighbours || diag <= 0) return 0;
  // Hash cells about one expected spacing wide (N samples over a box of diagonal d: ~ d/sqrt N).
  const double cell = std::max(diag / std::sqrt(static_cast<double>(pts.size())), 1e-9);
  const auto key = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d g = ((p - box.min()) / cell).array().floor();
    return std::array<long long, 3>{static_cast<long long>(g.x()), static_cast<long long>(g.y()),
                                    static_cast<long long>(g.z())};
  };
  struct KeyHash {
    std::size_t operator()(const std::array<long long, 3>& k) const {
      return static_cast<std::size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
    }
  };
  std::unordered_map<std::array<long long, 3>, std::vector<int>, KeyHash> cells;
  for (std::size_t i = 0; i < pts.size(); ++i) cells[key(pts[i])].push_back(static_cast<int>(i));
  const std::size_t step = std::max<std::size_t>(1, pts.size() / 20000);
  std::vector<double> spacing, dist;
  for (std::size_t i = 0; i < pts.size(); i += step) {
    const auto k = key(pts[i]);
    // Rings of cells until 8 neighbours are found within the searched radius.
    for (long long ring = 1; ring <= 4; ++ring) {
      dist.clear();
      for (long long dx = -ring; dx <= ring; ++dx)
        for (long long dy = -ring; dy <= ring; ++dy)
          for (long long dz = -ring; dz <= ring; ++dz) {
            const auto it = cells.find({k[0] + dx, k[1] + dy, k[2] + dz});
            if (it == cells.end()) continue;
            for (int j : it->second)
              if (j != static_cast<int>(i)) dist.push_back((pts[j] - pts[i]).norm());
          }
      if (dist.size() < kNeighbours) continue;
      std::nth_element(dist.begin(), dist.begin() + (kNeighbours - 1), dist.end());
      const double r8 = dist[kNeighbours - 1];
      if (r8 > ring * cell) continue;  // a nearer neighbour may sit outside the searched cells
      spacing.push_back(std::sqrt(std::numbers::pi * r8 * r8 / kNeighbours));
      break;
    }
  }
  return median(std::move(spacing));
}

double median_edge_length(const Mesh& mesh) {
  std::vector<double> len;
  len.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      len.push_back((mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]).norm());
  return median(std::move(len));
}

// The grid's shape from the samples' extent and the cell size (options override each part).
RangeGrid make_grid(const std::vector<CylSample>& samples, double cell_mm,
                    const ImportOptions& options, const std::filesystem::path& source) {
  double hmin = std::numeric_limits<double>::infinity(), hmax = -hmin;
  std::vector<double> radii;
  radii.reserve(samples.size());
  for (const auto& s : samples) {
    hmin = std::min(hmin, s.h);
    hmax = std::max(hmax, s.h);
    radii.push_back(s.r);
  }
  const double r_typical = median(std::move(radii));
  if (!(r_typical > 1e-9 * std::max(1.0, hmax - hmin)))
    throw FileFormatError(source, "the points lie on the rotation axis (median radius " +
                                      std::to_string(r_typical) +
                                      "); give the axis with --axis-point / --axis");
  if (options.n_phi < 0 || options.n_h < 0 || options.dh < 0 || !std::isfinite(options.dh))
    throw InvalidInputError("--n-phi, --n-h and --dh must be positive (0 = automatic)");
  if (!(cell_mm > 0)) cell_mm = std::max(hmax - hmin, kTwoPi * r_typical) / 512.0;
  const double span = hmax - hmin;
  double dh = options.dh > 0 ? options.dh : cell_mm;
  int n_h = options.n_h;
  if (n_h == 0) {
    const double rows = std::ceil(span / dh - 1e-9) + 1;
    if (rows > 1 << 16)
      throw InvalidInputError("the scan is " + std::to_string(rows) +
                              " rows tall at dh = " + std::to_string(dh) +
                              " mm; give a larger --dh or --n-h");
    n_h = std::max(2, static_cast<int>(rows));
  } else if (options.dh == 0) {
    dh = n_h > 1 ? std::max(span / (n_h - 1), 1e-9) : std::max(span, 1e-9);
  }
  int n_phi = options.n_phi;
  if (n_phi == 0)
    n_phi = std::clamp(static_cast<int>(std::lround(kTwoPi * r_typical / cell_mm)), 16, 8192);
  if (static_cast<std::uint64_t>(n_phi) * static_cast<std::uint64_t>(n_h) > kMaxGridCells)
    throw InvalidInputError("a grid of " + std::to_string(n_phi) + " x " + std::to_string(n_h) +
                            " cells is larger than " + std::to_string(kMaxGridCells) +
                            "; give a smaller --n-phi / --n-h or a larger --dh");
  if (dh < kMinGridLengthMm)
    throw InvalidInputError("a row height of " + std::to_string(dh) +
                            " is below the 1e-9 a grid may hold: give a larger --dh (or scale "
                            "the scan to millimetres)");
  // Row 0 at the lowest sample: h_j = hmin + j dh covers the data with cell centres on it.
  return RangeGrid(n_phi, n_h, 0.0, hmin, dh);
}

int column_of(const RangeGrid& g, double phi) {
  return g.wrap_phi(static_cast<int>(std::lround((phi - g.phi0()) / g.dphi())));
}
int row_of(const RangeGrid& g, double h) {
  return static_cast<int>(std::lround((h - g.h0()) / g.dh()));
}

std::string vec_text(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s.precision(9);
  s << v.x() << "," << v.y() << "," << v.z();
  return s.str();
}

void finish(ImportResult& out, const Frame& f, const std::filesystem::path& source) {
  out.report.axis = f.axis;
  out.rotation = f.rotation;
  out.origin = f.origin;
  out.report.coverage = turn_coverage(out.grid);
  auto& md = out.grid.metadata;
  md["source"] = source.filename().string();
  md["import.kind"] = out.report.input_kind;
  md["import.method"] = out.report.method;
  md["import.axis_point"] = vec_text(f.axis.point);
  md["import.axis_direction"] = vec_text(f.axis.direction);
  std::ostringstream cov;
  cov.precision(4);
  cov << 100.0 * out.report.coverage.covered_fraction() << " %";
  md["import.turn_covered"] = cov.str();
  if (out.grid.valid_count() == 0)
    throw FileFormatError(source, "no cell of the grid received data");
}

// ---------------------------------------------------------------------------------------------
// Binning

struct Binned {
  std::size_t cell;
  float r;
  int point;
};

// The outermost layer of one cell's samples (sorted by radius, largest first) that holds at
// least a quarter of them: [begin, end) within the run.
std::pair<std::size_t, std::size_t> outer_layer(const std::vector<Binned>& run, double gap) {
  const std::size_t need = std::max<std::size_t>(1, (run.size() + 3) / 4);
  std::size_t begin = 0;
  for (std::size_t k = 1; k <= run.size(); ++k) {
    if (k < run.size() && run[k - 1].r - run[k].r <= gap) continue;
    if (k - begin >= need) return {begin, k};
    begin = k;
  }
  return {0, run.size()};
}

}  // namespace

TurnCoverage turn_coverage(const RangeGrid& grid) {
  TurnCoverage c;
  c.columns = grid.n_phi();
  std::vector<char> covered(static_cast<std::size_t>(grid.n_phi()), 0);
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i)
      if (grid.valid(i, j)) covered[i] = 1;
  c.covered_columns = static_cast<int>(std::count(covered.begin(), covered.end(), 1));
  c.full_turn = c.covered_columns == c.columns;
  if (c.covered_columns == 0) return c;
  const double d = grid.dphi();
  if (c.full_turn) {
    c.arcs.push_back({grid.phi0(), grid.phi0() + kTwoPi});
    return c;
  }
  // Runs of covered columns, starting after an uncovered one so that a run across the seam is
  // one arc. Cell i covers [phi_i - d/2, phi_i + d/2).
  int start = 0;
  while (covered[start]) ++start;
  for (int k = 1; k <= grid.n_phi(); ++k) {
    const int i = (start + k) % grid.n_phi();
    if (!covered[i]) continue;
    int len = 0;
    while (covered[(i + len) % grid.n_phi()]) ++len;
    double a = grid.phi(i) - 0.5 * d;
    if (a < grid.phi0()) a += kTwoPi;
    c.arcs.push_back({a, a + len * d});
    k += len;
  }
  std::sort(c.arcs.begin(), c.arcs.end(), [](const auto& x, const auto& y) {
    return x.second - x.first > y.second - y.first;
  });
  return c;
}

// A scan without colours gets one light neutral grey in every cell: black (the grid's default)
// rendered every imported shape as a black silhouette; grey shades like clay and reads as
// "no colour" on the texture (docs/acquisition.md, "Importing scans").
constexpr Rgb8 kUncolouredGrey{190, 190, 190};

void paint_uncoloured(RangeGrid& g) {
  std::fill(g.colors().begin(), g.colors().end(), kUncolouredGrey);
}

ImportResult grid_from_cloud(const PointCloud& input, const ImportOptions& options,
                             const std::filesystem::path& source) {
  const PointCloud cloud = input.organised() ? input.finite_points() : input;
  if (cloud.positions.empty()) throw FileFormatError(source, "the cloud has no points");
  for (const auto& p : cloud.positions)
    if (!p.allFinite()) throw FileFormatError(source, "the cloud has a non-finite point");
  check_extent(cloud.positions, source);
  const Frame frame = make_frame(cloud.positions, options);
  std::vector<CylSample> cyl;
  cyl.reserve(cloud.size());
  for (const auto& p : cloud.positions) cyl.push_back(to_cylinder(frame, p));
  ImportResult out;
  out.report.input_kind = "point cloud";
  out.report.method = "binned (outermost-layer median)";
  out.report.input_points = cloud.size();
  out.report.colors = cloud.has_colors();
  out.report.sample_spacing_mm = median_sample_spacing(cloud.positions);
  out.report.cell_mm = kCloudCellPerSpacing * out.report.sample_spacing_mm;
  out.grid = make_grid(cyl, out.report.cell_mm, options, source);
  RangeGrid& g = out.grid;
  if (!out.report.colors) paint_uncoloured(g);

  std::vector<Binned> bins;
  bins.reserve(cyl.size());
  for (std::size_t k = 0; k < cyl.size(); ++k) {
    const int j = row_of(g, cyl[k].h);
    if (j < 0 || j >= g.n_h() || !(cyl[k].r > 0)) continue;
    bins.push_back({g.index(column_of(g, cyl[k].phi), j), static_cast<float>(cyl[k].r),
                    static_cast<int>(k)});
  }
  std::sort(bins.begin(), bins.end(), [](const Binned& a, const Binned& b) {
    return a.cell != b.cell ? a.cell < b.cell : a.r > b.r;
  });
  const double gap = options.layer_gap_cells * std::max(g.dh(), out.report.cell_mm);
  std::vector<Binned> run;
  std::vector<double> layer_r;
  for (std::size_t b = 0; b < bins.size();) {
    std::size_t e = b;
    while (e < bins.size() && bins[e].cell == bins[b].cell) ++e;
    run.assign(bins.begin() + static_cast<std::ptrdiff_t>(b),
               bins.begin() + static_cast<std::ptrdiff_t>(e));
    const auto [lb, le] = outer_layer(run, gap);
    layer_r.clear();
    Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
    for (std::size_t k = lb; k < le; ++k) {
      layer_r.push_back(run[k].r);
      if (cloud.has_colors()) {
        const Rgb8 c = cloud.colors[run[k].point];
        rgb += Eigen::Vector3d(c.r, c.g, c.b);
      }
    }
    const int i = static_cast<int>(bins[b].cell % g.n_phi());
    const int j = static_cast<int>(bins[b].cell / g.n_phi());
    const double n = static_cast<double>(le - lb);
    const float radius = static_cast<float>(median(layer_r));
    b = e;
    if (!(radius >= kMinGridLengthMm)) continue;  // on the axis: no cell a grid may hold
    g.set_sample(i, j, radius, static_cast<float>(std::min(1.0, n / kFullConfidenceSamples)));
    if (cloud.has_colors()) {
      rgb /= n;
      g.set_color(i, j, {static_cast<std::uint8_t>(std::lround(rgb.x())),
                         static_cast<std::uint8_t>(std::lround(rgb.y())),
                         static_cast<std::uint8_t>(std::lround(rgb.z()))});
    }
    out.report.samples_used += le - lb;
  }
  finish(out, frame, source);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Ray casting

namespace {

// Colour of a hit at barycentric (u, v) of triangle t: texture first, then vertex colours.
std::optional<Rgb8> hit_color(const Mesh& mesh, const Image8* texture, std::size_t t, double u,
                              double v) {
  const double w = 1.0 - u - v;
  if (texture && texture->width > 0 && mesh.has_texcoords()) {
    const auto& ft = mesh.face_texcoords[t];
    const Eigen::Vector2f uv = static_cast<float>(w) * mesh.texcoords[ft[0]] +
                               static_cast<float>(u) * mesh.texcoords[ft[1]] +
                               static_cast<float>(v) * mesh.texcoords[ft[2]];
    // v = 0 at the image bottom (OBJ); texture repeats outside [0, 1).
    const double fu = uv.x() - std::floor(uv.x()), fv = uv.y() - std::floor(uv.y());
    const int x = std::clamp(static_cast<int>(fu * texture->width), 0, texture->width - 1);
    const int y = std::clamp(static_cast<int>((1.0 - fv) * texture->height), 0, texture->height - 1);
    return texture->rgb(x, y);
  }
  if (mesh.has_colors()) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3d c = w * Eigen::Vector3d(mesh.colors[tri[0]].r, mesh.colors[tri[0]].g,
                                                  mesh.colors[tri[0]].b) +
                              u * Eigen::Vector3d(mesh.colors[tri[1]].r, mesh.colors[tri[1]].g,
                                                  mesh.colors[tri[1]].b) +
                              v * Eigen::Vector3d(mesh.colors[tri[2]].r, mesh.colors[tri[2]].g,
                                                  mesh.colors[tri[2]].b);
    return Rgb8{static_cast<std::uint8_t>(std::lround(std::clamp(c.x(), 0.0, 255.0))),
                static_cast<std::uint8_t>(std::lround(std::clamp(c.y(), 0.0, 255.0))),
                static_cast<std::uint8_t>(std::lround(std::clamp(c.z(), 0.0, 255.0)))};
  }
  return std::nullopt;
}

// Möller–Trumbore for the horizontal ray from (0, 0, h) along (cos phi, sin phi, 0) in the grid
// frame: distance t > 0 and barycentric (u, v), or nothing.
struct RayHit {
  double t, u, v, cos_incidence;
};
std::optional<RayHit> cast(const std::array<Eigen::Vector3d, 3>& q, double phi, double h) {
  const Eigen::Vector3d o(0, 0, h), d(std::cos(phi), std::sin(phi), 0);
  const Eigen::Vector3d e1 = q[1] - q[0], e2 = q[2] - q[0];
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  const double scale = e1.norm() * e2.norm();
  if (std::abs(det) <= 1e-12 * scale) return std::nullopt;  // ray in the triangle's plane
  const Eigen::Vector3d s = o - q[0];
  // A little slack at the edges: a ray through a shared edge or corner must hit one of the
  // triangles despite rounding (the outermost hit wins, so hitting both is harmless).
  constexpr double kSlack = 1e-9;
  const double u = s.dot(p) / det;
  if (u < -kSlack || u > 1 + kSlack) return std::nullopt;
  const Eigen::Vector3d qv = s.cross(e1);
  const double v = d.dot(qv) / det;
  if (v < -kSlack || u + v > 1 + kSlack) return std::nullopt;
  const double t = e2.dot(qv) / det;
  if (!(t > 0)) return std::nullopt;
  const Eigen::Vector3d n = e1.cross(e2);
  return RayHit{t, u, v, std::abs(n.dot(d)) / n.norm()};
}

// The mesh without vertices no triangle uses: they would move the axis, the height range and
// the resolution (a scan cut to part of the turn often keeps every vertex of the whole).
Mesh without_unused_vertices(const Mesh& mesh) {
  std::vector<int> remap(mesh.positions.size(), -1);
  Mesh out;
  out.texcoords = mesh.texcoords;
  out.face_texcoords = mesh.face_texcoords;
  out.triangles = mesh.triangles;
  for (auto& t : out.triangles)
    for (int& v : t) {
      if (remap[v] < 0) {
        remap[v] = static_cast<int>(out.positions.size());
        out.positions.push_back(mesh.positions[v]);
        if (mesh.has_colors()) out.colors.push_back(mesh.colors[v]);
        if (mesh.has_normals()) out.normals.push_back(mesh.normals[v]);
      }
      v = remap[v];
    }
  return out;
}

}  // namespace

ImportResult grid_from_mesh(const Mesh& input, const Image8* texture, const ImportOptions& options,
                            const std::filesystem::path& source) {
  if (input.positions.empty()) throw FileFormatError(source, "the mesh has no vertices");
  if (input.triangles.empty()) throw FileFormatError(source, "the mesh has no faces");
  input.validate();
  const Mesh mesh = without_unused_vertices(input);
  check_extent(mesh.positions, source);
  const Frame frame = make_frame(mesh.positions, options);
  std::vector<Eigen::Vector3d> q(mesh.positions.size());
  std::vector<CylSample> cyl(mesh.positions.size());
  for (std::size_t k = 0; k < q.size(); ++k) {
    q[k] = frame.rotation * (mesh.positions[k] - frame.origin);
    cyl[k] = to_cylinder(frame, mesh.positions[k]);
  }
  ImportResult out;
  out.report.input_kind = "mesh";
  out.report.method = "ray cast (outermost hit)";
  out.report.input_points = mesh.positions.size();
  out.report.input_triangles = mesh.triangles.size();
  out.report.textured = texture && texture->width > 0 && mesh.has_texcoords();
  out.report.colors = out.report.textured || mesh.has_colors();
  out.report.sample_spacing_mm = median_edge_length(mesh);
  out.report.cell_mm = kMeshCellPerSpacing * out.report.sample_spacing_mm;
  out.grid = make_grid(cyl, out.report.cell_mm, options, source);
  RangeGrid& g = out.grid;
  if (!out.report.colors) paint_uncoloured(g);
  const double d = g.dphi();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const std::array<Eigen::Vector3d, 3> corners{q[tri[0]], q[tri[1]], q[tri[2]]};
    // The triangle's (phi, h) footprint, phi unwrapped about its first corner; a triangle
    // around the axis (a cap) or touching it is tested against every column.
    double lo = cyl[tri[0]].phi, hi = lo, hlo = cyl[tri[0]].h, hhi = hlo;
    bool around_axis = false;
    for (int k = 1; k < 3; ++k) {
      double a = cyl[tri[k]].phi;
      while (a - cyl[tri[0]].phi > std::numbers::pi) a -= kTwoPi;
      while (a - cyl[tri[0]].phi < -std::numbers::pi) a += kTwoPi;
      lo = std::min(lo, a);
      hi = std::max(hi, a);
      hlo = std::min(hlo, cyl[tri[k]].h);
      hhi = std::max(hhi, cyl[tri[k]].h);
    }
    for (int k = 0; k < 3; ++k) around_axis |= cyl[tri[k]].r < 1e-9;
    around_axis |= hi - lo > std::numbers::pi;
    if (!around_axis) {
      // Does the axis pierce the triangle's (x, y) projection? Then it spans every angle.
      const auto side = [&](int a, int b) {
        return corners[a].x() * corners[b].y() - corners[a].y() * corners[b].x();
      };
      const double s0 = side(0, 1), s1 = side(1, 2), s2 = side(2, 0);
      around_axis = (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
    }
    // Candidate cells with a margin (rays through a corner); the ray test decides.
    constexpr double kMargin = 1e-6;
    const int j0 = std::max(0, static_cast<int>(std::ceil((hlo - g.h0()) / g.dh() - kMargin)));
    const int j1 =
        std::min(g.n_h() - 1, static_cast<int>(std::floor((hhi - g.h0()) / g.dh() + kMargin)));
    const int i0 = around_axis ? 0 : static_cast<int>(std::ceil((lo - g.phi0()) / d - kMargin));
    const int i1 =
        around_axis ? g.n_phi() - 1 : static_cast<int>(std::floor((hi - g.phi0()) / d + kMargin));
    for (int j = j0; j <= j1; ++j)
      for (int ii = i0; ii <= i1; ++ii) {
        const int i = g.wrap_phi(ii);
        const auto hit = cast(corners, g.phi(i), g.h(j));
        if (!hit || !(static_cast<float>(hit->t) >= kMinGridLengthMm) ||
            (g.valid(i, j) && g.radius(i, j) >= hit->t))
          continue;
        g.set_sample(i, j, static_cast<float>(hit->t),
                     static_cast<float>(std::clamp(hit->cos_incidence, 0.05, 1.0)));
        if (const auto c = hit_color(mesh, out.report.textured ? texture : nullptr, t, hit->u,
                                     hit->v))
          g.set_color(i, j, *c);
      }
  }
  out.report.samples_used = g.valid_count();
  finish(out, frame, source);
  return out;
}

Mesh lattice_mesh(const PointCloud& cloud, double max_jump_factor) {
  Mesh mesh;
  mesh.positions = cloud.positions;
  if (cloud.has_colors()) mesh.colors = cloud.colors;
  const int w = cloud.width, h = cloud.height;
  const auto at = [&](int x, int y) { return static_cast<std::size_t>(y) * w + x; };
  std::vector<double> steps;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x)
      if (cloud.positions[at(x, y)].allFinite() && cloud.positions[at(x + 1, y)].allFinite())
        steps.push_back((cloud.positions[at(x, y)] - cloud.positions[at(x + 1, y)]).norm());
  const double limit = max_jump_factor * median(steps);
  const auto joined = [&](std::size_t a, std::size_t b) {
    return (cloud.positions[a] - cloud.positions[b]).norm() <= limit;
  };
  const auto add = [&](std::size_t a, std::size_t b, std::size_t c) {
    for (std::size_t k : {a, b, c})
      if (!cloud.positions[k].allFinite()) return;
    if (joined(a, b) && joined(b, c) && joined(c, a))
      mesh.triangles.push_back({static_cast<int>(a), static_cast<int>(b), static_cast<int>(c)});
  };
  for (int y = 0; y + 1 < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      add(at(x, y), at(x + 1, y), at(x + 1, y + 1));
      add(at(x, y), at(x + 1, y + 1), at(x, y + 1));
    }
  // Missing pixels stay as vertices no triangle uses; they must be finite for Mesh::validate.
  for (auto& p : mesh.positions)
    if (!p.allFinite()) p = Eigen::Vector3d::Zero();
  return mesh;
}

ImportResult grid_from_organised_cloud(const PointCloud& cloud, const ImportOptions& options,
                                       const std::filesystem::path& source) {
  if (!cloud.organised() || cloud.finite_count() == 0)
    throw FileFormatError(source, "not an organised cloud with finite points");
  Mesh lattice = lattice_mesh(cloud, options.max_lattice_jump);
  if (lattice.triangles.empty()) {
    ImportResult r = grid_from_cloud(cloud.finite_points(), options, source);
    r.report.input_kind = "organised point cloud";
    return r;
  }
  // grid_from_mesh drops the lattice's unused slots (they sit at the origin).
  ImportResult r = grid_from_mesh(lattice, nullptr, options, source);
  r.report.input_kind = "organised point cloud";
  r.report.input_points = cloud.finite_count();
  r.report.input_triangles = 0;
  r.grid.metadata["import.kind"] = r.report.input_kind;
  return r;
}

namespace {

std::string lower_ext(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

ImportResult from_mesh_or_cloud(Mesh mesh, const Image8* texture, const ImportOptions& options,
                                const std::filesystem::path& source) {
  if (!mesh.triangles.empty()) return grid_from_mesh(mesh, texture, options, source);
  PointCloud cloud;  // a file with vertices only: a point cloud
  cloud.positions = std::move(mesh.positions);
  cloud.normals = std::move(mesh.normals);
  cloud.colors = std::move(mesh.colors);
  cloud.width = static_cast<int>(cloud.positions.size());
  return grid_from_cloud(cloud, options, source);
}

// The OBJ's texture (PNG or JPEG) as decoded: grey, RGB or RGBA, which hit_color reads through
// Image8::rgb(). An empty image and the reason in `problem` when it cannot be read, which the
// report then names (the geometry is still imported).
Image8 read_texture(const std::filesystem::path& image, std::string& problem) {
  try {
    return decode_image(read_file_bytes(image), image);
  } catch (const Error& e) {
    problem = e.what();
    return {};
  }
}

}  // namespace

ImportResult import_scan(const std::filesystem::path& input, const ImportOptions& options) {
  const std::string ext = lower_ext(input);
  if (ext == ".ply" || ext == ".off" || ext == ".stl")
    return from_mesh_or_cloud(read_mesh(input), nullptr, options, input);
  if (ext == ".obj") {
    ObjMesh obj = read_obj(input);
    Image8 texture;
    std::string problem;
    if (!obj.texture.empty()) texture = read_texture(obj.texture, problem);
    ImportResult r = from_mesh_or_cloud(std::move(obj.mesh), &texture, options, input);
    if (!obj.texture.empty() && texture.width == 0)
      r.report.warnings.push_back("texture " + obj.texture.string() + " could not be read (" +
                                  problem + "); the grid has no colours");
    return r;
  }
  if (ext == ".vtk" || ext == ".vtp")
    return from_mesh_or_cloud(read_vtk_polydata(input), nullptr, options, input);
  if (ext == ".pcd") {
    const PointCloud cloud = read_point_cloud(input);
    return cloud.organised() ? grid_from_organised_cloud(cloud, options, input)
                             : grid_from_cloud(cloud, options, input);
  }
  if (ext == ".xyz" || ext == ".txt" || ext == ".pts")
    return grid_from_cloud(read_point_cloud(input), options, input);
  if (ext == ".smg")
    throw InvalidInputError(input.string() + " is already a range grid (nothing to import)");
  throw InvalidInputError("cannot import '" + ext + "' files (" + input.string() +
                          "): use .ply .pcd .xyz .txt .pts .off .obj .stl .vtk or .vtp");
}

}  // namespace scanmesh
