// scanmesh import: other scanners' clouds and meshes into a RangeGrid. Exact checks on analytic
// shapes (a sphere sampled as a cloud, a mesh, an organised lattice, a quarter turn) and checks
// without ground truth on the real-data corpus (docs/testing.md): the grid reproduces the input
// within half a cell, and the grid mesh of the imported grid lies within one cell spacing of
// the input.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>

#include "scanmesh/acquisition/scan_import.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "surface_distance_test_util.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
const fs::path kCorpus = SCANMESH_CORPUS_DIR;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(SCANMESH_BINARY_DIR) / "test_scan_import";
  fs::create_directories(dir);
  return dir / name;
}

double median_valid_radius(const RangeGrid& g) {
  std::vector<float> r;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i)
      if (g.valid(i, j)) r.push_back(g.radius(i, j));
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  return r[r.size() / 2];
}

//! The grid's cell spacing: the larger of dh and the arc of one column at the typical radius.
double cell_spacing(const RangeGrid& g) { return std::max(g.dh(), g.dphi() * median_valid_radius(g)); }

// A sphere of radius R about (cx, cy, cz), sampled at n random points with colours by height.
PointCloud sphere_cloud(int n, double R, const Eigen::Vector3d& centre, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  PointCloud c;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3d d(normal(rng), normal(rng), normal(rng));
    d.normalize();
    c.positions.push_back(centre + R * d);
    c.colors.push_back({static_cast<std::uint8_t>(127.5 * (d.z() + 1)), 50, 200});
  }
  c.width = n;
  return c;
}

// A UV sphere mesh (n_lat x n_lon quads) of radius R about `centre`.
Mesh sphere_mesh(int n_lat, int n_lon, double R, const Eigen::Vector3d& centre) {
  Mesh m;
  m.positions.push_back(centre + Eigen::Vector3d(0, 0, -R));
  for (int a = 1; a < n_lat; ++a)
    for (int b = 0; b < n_lon; ++b) {
      const double th = kPi * a / n_lat - kPi / 2, ph = 2 * kPi * b / n_lon;
      m.positions.push_back(centre +
                            R * Eigen::Vector3d(std::cos(th) * std::cos(ph),
                                                std::cos(th) * std::sin(ph), std::sin(th)));
    }
  m.positions.push_back(centre + Eigen::Vector3d(0, 0, R));
  const int top = static_cast<int>(m.positions.size()) - 1;
  const auto ring = [&](int a, int b) { return 1 + (a - 1) * n_lon + (b % n_lon); };
  for (int b = 0; b < n_lon; ++b) {
    m.triangles.push_back({0, ring(1, b + 1), ring(1, b)});
    m.triangles.push_back({top, ring(n_lat - 1, b), ring(n_lat - 1, b + 1)});
    for (int a = 1; a + 1 < n_lat; ++a) {
      m.triangles.push_back({ring(a, b), ring(a, b + 1), ring(a + 1, b + 1)});
      m.triangles.push_back({ring(a, b), ring(a + 1, b + 1), ring(a + 1, b)});
    }
  }
  return m;
}

// Every valid cell of a grid imported from a sphere of radius R about the axis point lies on
// the sphere (grid frame: the sphere's centre is at (0, 0, cz)).
void expect_on_sphere(const RangeGrid& g, double R, double cz, double tol) {
  double worst = 0;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i)
      if (g.valid(i, j))
        worst = std::max(worst, std::abs((g.cartesian(i, j) - Eigen::Vector3d(0, 0, cz)).norm() - R));
  EXPECT_LT(worst, tol);
}

TEST(ScanImport, SphereCloudBinsOntoTheSphereWithItsColours) {
  const Eigen::Vector3d centre(30, -20, 100);
  const PointCloud cloud = sphere_cloud(60000, 50, centre, 3);
  ImportOptions o;
  o.axis_point = centre;
  const ImportResult r = grid_from_cloud(cloud, o, "sphere.xyz");
  const RangeGrid& g = r.grid;
  // Cell size 1.5 sample spacings: the sphere's 60000 points give about 0.7 mm spacing.
  EXPECT_GT(r.report.sample_spacing_mm, 0.3);
  EXPECT_LT(r.report.sample_spacing_mm, 1.5);
  EXPECT_TRUE(r.report.coverage.full_turn);
  // One layer almost everywhere: nearly every point sets a cell (at the poles a cell's samples
  // spread over more radius than the layer gap).
  EXPECT_GT(r.report.samples_used, 0.99 * cloud.size());
  // A median of samples on the sphere is within the radial spread of one cell (near the poles
  // a cell spans more of the curved surface).
  expect_on_sphere(g, 50, centre.z(), 0.5 * cell_spacing(g) + 0.05);
  // The equator row is full and its colour is the mid-height value.
  const int eq = static_cast<int>(std::lround((centre.z() - g.h0()) / g.dh()));
  int valid = 0;
  for (int i = 0; i < g.n_phi(); ++i) valid += g.valid(i, eq);
  EXPECT_GT(valid, 0.95 * g.n_phi());
  for (int i = 0; i < g.n_phi(); ++i)
    if (g.valid(i, eq)) {
      EXPECT_NEAR(g.color(i, eq).r, 127, 6);
      EXPECT_EQ(g.color(i, eq).b, 200);
    }
}

TEST(ScanImport, OuterLayerWinsOverAnInnerSurface) {
  // Two coaxial cylinders (an arm in front of the body): the outer one is what the scanner sees.
  PointCloud c;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 40000; ++k) {
    const double phi = 2 * kPi * u(rng), h = 100 * u(rng);
    const double r = k % 3 == 0 ? 30.0 : 60.0;  // a third of the samples on the inner surface
    c.positions.emplace_back(r * std::cos(phi), r * std::sin(phi), h);
  }
  c.width = static_cast<int>(c.size());
  ImportOptions o;
  o.axis_point = Eigen::Vector3d::Zero();
  o.n_phi = 128;
  o.dh = 4;
  const RangeGrid g = grid_from_cloud(c, o, "layers.xyz").grid;
  // A cell whose few samples all fell on the inner surface (the half-height rows at the ends)
  // sees only that one; every cell that saw the outer surface takes it.
  int valid = 0, outer = 0;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i)
      if (g.valid(i, j)) {
        ++valid;
        outer += std::abs(g.radius(i, j) - 60.0f) < 1e-4;
      }
  EXPECT_GT(valid, 0.95 * g.cell_count());
  EXPECT_GT(outer, 0.99 * valid);
}

TEST(ScanImport, SphereMeshRayCastsOntoTheMesh) {
  const Eigen::Vector3d centre(-5, 8, 40);
  const Mesh m = sphere_mesh(60, 120, 25, centre);
  ImportOptions o;
  o.axis_point = centre;
  o.n_phi = 256;
  o.n_h = 100;
  const ImportResult r = grid_from_mesh(m, nullptr, o, "sphere.off");
  EXPECT_EQ(r.report.input_kind, "mesh");
  EXPECT_TRUE(r.report.coverage.full_turn);
  // Every ray from the axis hits the sphere between the poles: all rows but the first and the
  // last (at the poles' own heights) are full.
  for (int j = 1; j + 1 < r.grid.n_h(); ++j)
    for (int i = 0; i < r.grid.n_phi(); ++i) ASSERT_TRUE(r.grid.valid(i, j)) << i << " " << j;
  // Hits lie on the facets: within the chord error of the sphere (R (1 - cos(pi / 120))).
  expect_on_sphere(r.grid, 25, centre.z(), 25 * (1 - std::cos(kPi / 60)) + 1e-9);
  // And exactly on the input mesh.
  const test::DistanceField to_mesh(m, 1.0);
  for (int j = 0; j < r.grid.n_h(); j += 7)
    for (int i = 0; i < r.grid.n_phi(); i += 5)
      EXPECT_LT(to_mesh.distance(r.rotation.transpose() * r.grid.cartesian(i, j) + r.origin), 1e-6);
}

TEST(ScanImport, OrganisedLatticeOfACylinderRayCastsWithoutBridgingItsHole) {
  // A 100 x 40 lattice over half a cylinder of radius 80, with a missing block (NaN).
  PointCloud c;
  c.width = 100;
  c.height = 40;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 100; ++x) {
      const double phi = kPi * x / 99.0, h = 2.0 * y;
      const bool hole = x >= 40 && x < 50 && y >= 10 && y < 20;
      c.positions.push_back(hole ? Eigen::Vector3d::Constant(std::nan(""))
                                 : Eigen::Vector3d(80 * std::cos(phi), 80 * std::sin(phi), h));
    }
  ImportOptions o;
  o.axis_point = Eigen::Vector3d::Zero();
  o.n_phi = 400;
  o.dh = 1;
  const ImportResult r = grid_from_organised_cloud(c, o, "half.pcd");
  EXPECT_EQ(r.report.input_kind, "organised point cloud");
  const RangeGrid& g = r.grid;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i)
      if (g.valid(i, j)) {
        EXPECT_NEAR(g.radius(i, j), 80.0, 80 * (1 - std::cos(kPi / 198)) + 1e-4);  // float radii
      }
  // Half a turn covered, one arc of about 180 degrees starting at phi = 0.
  ASSERT_EQ(r.report.coverage.arcs.size(), 1u);
  EXPECT_NEAR(r.report.coverage.covered_fraction(), 0.5, 0.01);
  const auto [a, b] = r.report.coverage.arcs[0];
  EXPECT_NEAR(std::remainder(a, 2 * kPi), 0.0, 0.02);
  EXPECT_NEAR(b - a, kPi, 0.03);
  // The hole's centre (phi = 0.45 pi, h = 29) stays a hole: no triangle bridged it.
  EXPECT_FALSE(g.valid(static_cast<int>(std::lround(0.45 * kPi / g.dphi())),
                       static_cast<int>(std::lround(29 / g.dh()))));
}

TEST(ScanImport, QuarterTurnKeepsItsColumnsAndReportsTheArc) {
  PointCloud c = sphere_cloud(80000, 40, Eigen::Vector3d::Zero(), 9);
  PointCloud quarter;
  for (std::size_t k = 0; k < c.size(); ++k) {
    const double phi = std::atan2(c.positions[k].y(), c.positions[k].x());
    if (phi > 0.3 && phi < 0.3 + kPi / 2) quarter.positions.push_back(c.positions[k]);
  }
  quarter.width = static_cast<int>(quarter.size());
  ImportOptions o;
  o.axis_point = Eigen::Vector3d::Zero();
  const ImportResult r = grid_from_cloud(quarter, o, "quarter.xyz");
  EXPECT_FALSE(r.report.coverage.full_turn);
  ASSERT_EQ(r.report.coverage.arcs.size(), 1u);
  EXPECT_NEAR(r.report.coverage.covered_fraction(), 0.25, 0.01);
  EXPECT_NEAR(r.report.coverage.arcs[0].first, 0.3, 1.5 * r.grid.dphi());
  EXPECT_NEAR(r.report.coverage.arcs[0].second, 0.3 + kPi / 2, 1.5 * r.grid.dphi());
  // Columns outside the quarter have no valid cell.
  for (int i = 0; i < r.grid.n_phi(); ++i) {
    const double phi = r.grid.phi(i);
    if (phi > 0.3 + kPi / 2 + 2 * r.grid.dphi() || phi < 0.3 - 2 * r.grid.dphi())
      for (int j = 0; j < r.grid.n_h(); ++j) {
        EXPECT_FALSE(r.grid.valid(i, j));
      }
  }
}

TEST(ScanImport, EstimatedAxisFollowsALyingCylinder) {
  // A cylinder lying along x (length 300, radius 40): the estimated axis is x, the radius 40.
  PointCloud c;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 30000; ++k) {
    const double phi = 2 * kPi * u(rng), s = 300 * u(rng);
    c.positions.emplace_back(s, 40 * std::cos(phi) + 7, 40 * std::sin(phi) - 3);
  }
  c.width = static_cast<int>(c.size());
  ImportOptions o;
  o.direction = AxisDirection::Estimate;
  const ImportResult r = grid_from_cloud(c, o, "lying.xyz");
  EXPECT_GT(std::abs(r.report.axis.direction.x()), 0.999);
  EXPECT_NEAR(median_valid_radius(r.grid), 40.0, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Files and errors

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

void expect_file_error(const fs::path& p, const std::string& words) {
  try {
    import_scan(p);
    ADD_FAILURE() << "no FileFormatError for " << p;
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(ScanImport, FilesThatCannotBeAScanAreErrorsNamingTheFile) {
  write_text(scratch("empty.xyz"), "");
  expect_file_error(scratch("empty.xyz"), "no points");
  write_text(scratch("axis.xyz"), "0 0 0\n0 0 1\n0 0 2\n0 0 3\n");
  ImportOptions o;
  o.axis_point = Eigen::Vector3d::Zero();
  try {
    import_scan(scratch("axis.xyz"), o);
    ADD_FAILURE() << "points on the axis accepted";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("axis"), std::string::npos) << e.what();
  }
  write_text(scratch("nan.xyz"), "1 2 3\nnan 2 3\n");
  expect_file_error(scratch("nan.xyz"), "line 2");
  write_text(scratch("nofaces.off"), "OFF\n0 0 0\n");
  expect_file_error(scratch("nofaces.off"), "no points");
  write_text(scratch("text.vtk"), "not a vtk file\n");
  expect_file_error(scratch("text.vtk"), "not a VTK legacy file");
  write_text(scratch("image.vtk"), "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\n");
  expect_file_error(scratch("image.vtk"), "POLYDATA");
  write_text(scratch("scan.abc"), "1 2 3\n");
  EXPECT_THROW(import_scan(scratch("scan.abc")), InvalidInputError);
}

TEST(ScanImport, VtkLegacyAndXmlPolydataThroughVtksReaders) {
  // A unit-radius square tube around z: 4 points per ring, 2 rings, 4 quads, red/green colours.
  std::string legacy =
      "# vtk DataFile Version 3.0\ntube\nASCII\nDATASET POLYDATA\nPOINTS 8 float\n"
      "10 0 0 0 10 0 -10 0 0 0 -10 0\n10 0 20 0 10 20 -10 0 20 0 -10 20\n"
      "POLYGONS 4 20\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n"
      "POINT_DATA 8\nCOLOR_SCALARS rgb 3\n";
  for (int k = 0; k < 8; ++k) legacy += k < 4 ? "1 0 0\n" : "0 1 0\n";
  write_text(scratch("tube.vtk"), legacy);
  ImportOptions o;
  o.axis_point = Eigen::Vector3d::Zero();
  o.n_phi = 64;
  o.n_h = 11;
  const ImportResult r = import_scan(scratch("tube.vtk"), o);
  EXPECT_EQ(r.report.input_triangles, 8u);
  EXPECT_EQ(r.grid.valid_count(), r.grid.cell_count());
  // At phi = 0 the ray hits the corner at radius 10; at 45 degrees the face's middle at 10/sqrt 2.
  EXPECT_NEAR(r.grid.radius(0, 5), 10.0, 1e-5);
  EXPECT_NEAR(r.grid.radius(8, 5), 10.0 / std::sqrt(2.0), 1e-5);
  EXPECT_TRUE(r.report.colors);
  EXPECT_GT(r.grid.color(8, 0).r, 200);  // bottom row red, top row green
  EXPECT_GT(r.grid.color(8, 10).g, 200);
  const std::string xml =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\">\n<PolyData>\n"
      "<Piece NumberOfPoints=\"8\" NumberOfPolys=\"4\">\n<Points>\n"
      "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n"
      "10 0 0 0 10 0 -10 0 0 0 -10 0 10 0 20 0 10 20 -10 0 20 0 -10 20\n</DataArray>\n</Points>\n"
      "<Polys>\n<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n"
      "0 1 5 4 1 2 6 5 2 3 7 6 3 0 4 7\n</DataArray>\n"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n4 8 12 16\n</DataArray>\n"
      "</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  write_text(scratch("tube.vtp"), xml);
  const ImportResult x = import_scan(scratch("tube.vtp"), o);
  EXPECT_EQ(x.grid.radii(), r.grid.radii());
}

TEST(ScanImport, ObjTextureColoursTheGrid) {
  // A textured quad strip: the texture is a PNG with the left half red and the right half blue.
  Image8 tex(4, 2, 3);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) tex.set_rgb(x, y, x < 2 ? Rgb8{255, 0, 0} : Rgb8{0, 0, 255});
  write_png(scratch("strip.png"), tex);
  write_text(scratch("strip.mtl"), "newmtl m\nmap_Kd strip.png\n");
  write_text(scratch("strip.obj"),
             "mtllib strip.mtl\nv 50 -20 0\nv 50 20 0\nv 50 20 30\nv 50 -20 30\n"
             "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3 4/4\n");
  ImportOptions o;
  o.axis_point = Eigen::Vector3d::Zero();
  o.n_phi = 360;
  o.n_h = 10;
  const ImportResult r = import_scan(scratch("strip.obj"), o);
  EXPECT_TRUE(r.report.textured);
  const RangeGrid& g = r.grid;
  const int j = 5;
  const int left = g.wrap_phi(-10), right = 10;  // phi = -10 deg: texture u < 0.5
  ASSERT_TRUE(g.valid(left, j));
  ASSERT_TRUE(g.valid(right, j));
  EXPECT_EQ(g.color(left, j), (Rgb8{255, 0, 0}));
  EXPECT_EQ(g.color(right, j), (Rgb8{0, 0, 255}));
  EXPECT_NEAR(g.radius(0, j), 50.0, 1e-5);
}

// ---------------------------------------------------------------------------------------------
// The real-data corpus

struct CorpusFile {
  const char* path;
  bool mesh;
};
const CorpusFile kCorpusFiles[] = {
    {"points_3/kitten.xyz", false}, {"points_3/hippo1.ply", false},
    {"points_3/hippo2.ply", false}, {"points_3/oni.ply", false},
    {"points_3/radar.xyz", false},  {"meshes/nefertiti.off", true},
    {"meshes/head.off", true},      {"meshes/elephant.off", true},
    {"meshes/lion-head.off", true}, {"meshes/mannequin-devil.off", true}};

class CorpusImport : public ::testing::TestWithParam<CorpusFile> {};

// The input in the grid's frame: the cloud's points, or the mesh.
Mesh input_in_grid_frame(const CorpusFile& f, const ImportResult& r) {
  Mesh m;
  if (f.mesh)
    m = read_mesh(kCorpus / f.path);
  else
    m = test::point_mesh(read_point_cloud(kCorpus / f.path).positions);
  for (auto& p : m.positions) p = r.to_grid_frame(p);
  return m;
}

TEST_P(CorpusImport, GridReproducesTheInputWithinHalfACell) {
  const CorpusFile f = GetParam();
  const ImportResult r = import_scan(kCorpus / f.path);
  const RangeGrid& g = r.grid;
  ASSERT_GT(g.valid_count(), 100u) << f.path;
  const Mesh input = input_in_grid_frame(f, r);
  const double cell = cell_spacing(g);
  const test::DistanceField field(input, 2 * cell);
  // A valid cell sits at its centre's (phi, h) and the radius of its samples: half a cell's
  // diagonal from the samples at most (binned), on the surface (ray cast).
  std::size_t within = 0;
  double worst = 0;
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i) {
      if (!g.valid(i, j)) continue;
      const double half_diag = 0.5 * std::hypot(g.dh(), g.dphi() * g.radius(i, j));
      const double d = field.distance(g.cartesian(i, j));
      worst = std::max(worst, d / half_diag);
      within += d <= half_diag * (1 + 1e-9);
    }
  const double share = double(within) / g.valid_count();
  std::cout << f.path << ": " << g.n_phi() << " x " << g.n_h() << ", " << g.valid_count()
            << " valid, within half a cell " << 100 * share << " %, worst " << worst
            << " half-diagonals\n";
  EXPECT_EQ(within, g.valid_count()) << f.path << ": worst " << worst << " half-diagonals";
}

TEST_P(CorpusImport, GridMeshLiesWithinOneCellSpacingOfTheInput) {
  const CorpusFile f = GetParam();
  const ImportResult r = import_scan(kCorpus / f.path);
  const RangeGrid& g = r.grid;
  const double cell = cell_spacing(g);
  GridMeshOptions gm;
  gm.max_depth_jump_mm = 2 * cell;  // a jump of more than two cells is a silhouette, not surface
  const Mesh mesh = grid_mesh(g, gm).mesh;
  ASSERT_GT(mesh.face_count(), 50u) << f.path;
  const Mesh input = input_in_grid_frame(f, r);
  const test::DistanceField field(input, 3 * cell);
  // A cloud has no surface between its samples: the distance is to the plane through the
  // samples nearest to the mesh point (the cloud's local surface), which must also be close by.
  const auto distance = [&](const Eigen::Vector3d& p) {
    if (f.mesh) return field.distance(p);
    return field.distance(p) <= 2 * cell ? field.local_plane_distance(p)
                                         : std::numeric_limits<double>::infinity();
  };
  double worst = 0;
  std::size_t within = 0, samples = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    for (const Eigen::Vector3d& p : {a, Eigen::Vector3d((a + b + c) / 3), Eigen::Vector3d((a + b) / 2)}) {
      const double d = distance(p);
      worst = std::max(worst, d);
      within += d <= cell;
      ++samples;
    }
  }
  std::cout << f.path << ": grid mesh " << mesh.face_count() << " triangles, within one cell ("
            << cell << ") " << 100.0 * within / samples << " %, worst " << worst / cell
            << " cells\n";
  EXPECT_LE(worst, cell) << f.path;
}

INSTANTIATE_TEST_SUITE_P(RealData, CorpusImport, ::testing::ValuesIn(kCorpusFiles),
                         [](const ::testing::TestParamInfo<CorpusFile>& param_info) {
                           std::string n = fs::path(param_info.param.path).stem().string();
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace scanmesh
