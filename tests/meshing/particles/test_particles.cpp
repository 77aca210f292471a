// Tests of the spring-network triangulation (seed 003 §4; docs/particles.md). Each test
// asserts the acceptance numbers of issue 7.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <unordered_map>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/acquisition/scan_cleaning.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/particles/particles.h"
#include "scanmesh/reconstruction/scan_surface.h"
#include "scanmesh/sim/range_scanner.h"
#include "test_common.h"
#include "scanmesh_test_paths.h"

namespace scanmesh::particles {
namespace {

using Eigen::Vector3d;
using namespace testing;

void expect_closed_manifold(const Mesh& m, long long chi) {
  const TopologyStats s = topology_stats(m);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.nonmanifold_edges, 0u);
  EXPECT_EQ(s.inconsistent_edges, 0u);
  EXPECT_EQ(s.unreferenced_vertices, 0u);
  EXPECT_EQ(s.euler_characteristic, chi);
}

TEST(MarchingTetrahedra, SphereStartMeshIsClosedManifold) {
  const auto s = surface_of(sim::make_sphere(Vector3d::Zero(), 1.0), Vector3d::Constant(-1.2),
                            Vector3d::Constant(1.2));
  const Mesh m = marching_tetrahedra(*s, 0.25);
  ASSERT_GT(m.triangles.size(), 100u);
  expect_closed_manifold(m, 2);
}

TEST(SpringNetwork, SphereConvergesToUniformWellShapedClosedMesh) {
  const double R = 0.2;
  const auto s = surface_of(sim::make_sphere(Vector3d(0.1, -0.2, 0.3), 1.0),
                            Vector3d::Constant(-1.2), Vector3d::Constant(1.4));
  const ParticleMeshResult r = particle_mesh(*s, {.edge_length = R});
  const Mesh& m = r.mesh;
  ASSERT_GT(m.vertex_count(), 150u);
  expect_closed_manifold(m, 2);
  double worst = 0.0;
  for (const auto& p : m.positions)
    worst = std::max(worst, std::abs((p - Vector3d(0.1, -0.2, 0.3)).norm() - 1.0));
  EXPECT_LT(worst, 1e-4 * R);
  const auto lengths = edge_lengths(m);
  std::size_t within = 0;
  double mean = 0.0;
  for (double l : lengths) {
    within += std::abs(l - R) <= 0.15 * R ? 1 : 0;
    mean += l / static_cast<double>(lengths.size());
  }
  EXPECT_NEAR(mean, R, 0.05 * R);
  // Issue 7: "edge lengths within +-15% of R" -- every edge (decision 37's subdivided start:
  // twelve valence-5 particles, all others 6; measured 0.878-1.049 R).
  EXPECT_EQ(within, lengths.size());
  auto valences = valence_histogram(m);
  EXPECT_EQ(valences[5], 12);
  EXPECT_EQ(valences[5] + valences[6], static_cast<int>(m.vertex_count()));
  // Issue 7: min angle >= 30 deg for >= 95% of the triangles; here every triangle has it.
  EXPECT_GE(fraction_min_angle_at_least(m, 30.0), 1.0);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.vertex_ids.size(), m.vertex_count());
}

// Decision 37 across edge lengths: the subdivided start needs counts V - 2 = n^2 (V_c - 2),
// so not every R gets the icosahedral ideal; measured 2 Dec 2026 over R = 0.1 ... 0.4 (17
// values): every sphere mesh has exactly twelve 5s and no other defect, 13 of 17 have every
// edge within +-15 % of R and the rest >= 99.3 % (the layered start alone: 94.1-99.2 %).
TEST(SpringNetwork, SphereEdgesStayUniformAcrossEdgeLengths) {
  const auto s = surface_of(sim::make_sphere(Vector3d(0.1, -0.2, 0.3), 1.0),
                            Vector3d::Constant(-1.2), Vector3d::Constant(1.4));
  int all_within = 0;
  for (const double R : {0.14, 0.16, 0.18, 0.25, 0.3}) {
    SCOPED_TRACE(R);
    const ParticleMeshResult r = particle_mesh(*s, {.edge_length = R});
    expect_closed_manifold(r.mesh, 2);
    EXPECT_TRUE(r.converged);
    const auto lengths = edge_lengths(r.mesh);
    std::size_t within = 0;
    for (double l : lengths) within += std::abs(l - R) <= 0.15 * R ? 1 : 0;
    EXPECT_GE(static_cast<double>(within), 0.99 * static_cast<double>(lengths.size()));
    all_within += within == lengths.size() ? 1 : 0;
    EXPECT_EQ(valence_histogram(r.mesh)[5], 12);
    EXPECT_GE(fraction_min_angle_at_least(r.mesh, 30.0), 1.0);
  }
  EXPECT_GE(all_within, 3);
}

// Twelve particles on a sphere, unevenly placed and badly connected (an icosahedron with two
// edges flipped: two valence-4 and two valence-6 particles), spread into the regular
// icosahedron: the Thomson problem's answer for 12 charges, with its Delaunay connectivity.
TEST(SpringNetwork, SpreadEvenlyRestoresTheIcosahedron) {
  const Vector3d c(0.1, -0.2, 0.3);
  const auto s =
      surface_of(sim::make_sphere(c, 1.0), Vector3d::Constant(-1.2), Vector3d::Constant(1.4));
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  Mesh m;
  m.positions = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                 {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  // Flip edge 0-5 (quad 0-11-5-1 gets the diagonal 11-1) and edge 3-8 (quad 3-6-8-9 gets
  // 6-9), then jitter the positions.
  m.triangles[0] = {0, 11, 1};
  m.triangles[1] = {11, 5, 1};
  m.triangles[13] = {3, 6, 9};
  m.triangles[14] = {6, 8, 9};
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const Vector3d jitter(0.15 * std::sin(1.7 * i), 0.15 * std::cos(2.3 * i), 0.1 * std::sin(i));
    m.positions[i] = c + (m.positions[i].normalized() + jitter).normalized();
  }
  expect_closed_manifold(m, 2);
  ASSERT_NE(valence_histogram(m)[5], 12);
  SpringNetwork net(m, {.edge_length = 1.0});
  net.spread_evenly(*s, 200);
  const Mesh out = net.mesh();
  expect_closed_manifold(out, 2);
  EXPECT_EQ(valence_histogram(out)[5], 12);
  const auto lengths = edge_lengths(out);
  ASSERT_EQ(lengths.size(), 30u);
  // The icosahedron inscribed in the unit sphere has edge 4 / sqrt(10 + 2 sqrt(5)).
  const double edge = 4.0 / std::sqrt(10.0 + 2.0 * std::sqrt(5.0));
  for (double l : lengths) EXPECT_NEAR(l, edge, 1e-3);
  for (const auto& p : out.positions) EXPECT_NEAR((p - c).norm(), 1.0, 1e-9);
}

// Three separate spheres (the nearest one's distance field): the subdivided start spreads
// each component's charges on their own (review of decision 37: charges that repelled across
// components crowded each sphere's particles to one side; 38-71 fives, up to 35 sevens).
TEST(SpringNetwork, SeparateSpheresEachGetTwelveFives) {
  class ThreeSpheres final : public ImplicitSurface {
   public:
    std::optional<ImplicitValue> evaluate(const Vector3d& x) const override {
      ImplicitValue best{.value = std::numeric_limits<double>::infinity()};
      for (int k = 0; k < 3; ++k) {
        const Vector3d d = x - Vector3d(3.0 * k, 0, 0);
        if (d.norm() - 1.0 < best.value)
          best = {.value = d.norm() - 1.0, .gradient = d.normalized()};
      }
      return best;
    }
    Eigen::AlignedBox3d bounds() const override {
      return {Vector3d(-1.2, -1.2, -1.2), Vector3d(7.2, 1.2, 1.2)};
    }
  };
  const ParticleMeshResult r = particle_mesh(ThreeSpheres(), {.edge_length = 0.2});
  EXPECT_TRUE(r.converged);
  std::vector<int> comp;
  ASSERT_EQ(face_components(r.mesh, comp), 3);
  for (int c = 0; c < 3; ++c) {
    SCOPED_TRACE(c);
    const Mesh part = component_mesh(r.mesh, comp, c);
    expect_closed_manifold(part, 2);
    auto valences = valence_histogram(part);
    EXPECT_EQ(valences[5], 12);
    EXPECT_EQ(valences[5] + valences[6], static_cast<int>(part.vertex_count()));
  }
}

TEST(SpringNetwork, IsDeterministic) {
  const auto s = surface_of(sim::make_sphere(Vector3d::Zero(), 1.0), Vector3d::Constant(-1.2),
                            Vector3d::Constant(1.2));
  const ParticleMeshResult a = particle_mesh(*s, {.edge_length = 0.25});
  const ParticleMeshResult b = particle_mesh(*s, {.edge_length = 0.25});
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.vertex_ids, b.vertex_ids);
}

// The union (min) of two overlapping spheres has a concave crease. Static relaxation must not
// take the crease for a tear (§4.4 is off in relax()) and must converge.
TEST(SpringNetwork, UnionWithACreaseConvergesClosed) {
  class Union final : public ImplicitSurface {
   public:
    std::optional<ImplicitValue> evaluate(const Vector3d& x) const override {
      const Vector3d a = x - Vector3d(-0.6, 0, 0), b = x - Vector3d(0.6, 0, 0);
      const Vector3d& d = a.norm() < b.norm() ? a : b;
      return ImplicitValue{.value = d.norm() - 1.0, .gradient = d.normalized()};
    }
    Eigen::AlignedBox3d bounds() const override {
      return {Vector3d(-1.7, -1.1, -1.1), Vector3d(1.7, 1.1, 1.1)};
    }
  };
  const ParticleMeshResult r = particle_mesh(Union(), {.edge_length = 0.2});
  EXPECT_TRUE(r.converged) << r.iterations << " iterations";
  expect_closed_manifold(r.mesh, 2);
  EXPECT_GE(fraction_min_angle_at_least(r.mesh, 30.0), 0.9);
}

TEST(SpringNetwork, TorusHasEulerCharacteristicZero) {
  const double R = 0.12;
  const auto s = surface_of(sim::make_torus(Vector3d::Zero(), Vector3d::UnitZ(), 1.0, 0.4),
                            Vector3d(-1.5, -1.5, -0.5), Vector3d(1.5, 1.5, 0.5));
  const Mesh m = particle_mesh(*s, {.edge_length = R}).mesh;
  expect_closed_manifold(m, 0);
  double worst = 0.0;
  for (const auto& p : m.positions)
    worst = std::max(worst, std::abs(std::hypot(std::hypot(p.x(), p.y()) - 1.0, p.z()) - 0.4));
  EXPECT_LT(worst, 1e-4 * R);
  EXPECT_GE(fraction_min_angle_at_least(m, 30.0), 0.95);
}

TEST(SpringNetwork, AdaptiveEdgesAreShorterWhereCurvatureIsHigher) {
  const double R = 0.2;
  const auto obj = sim::make_ellipsoid(Vector3d::Zero(), Vector3d(2.0, 1.0, 0.7));
  const auto s = surface_of(obj, Vector3d(-2.2, -1.2, -0.9), Vector3d(2.2, 1.2, 0.9));
  auto correlation = [&](bool adaptive) {
    const Mesh m = particle_mesh(*s, {.edge_length = R, .adaptive = adaptive}).mesh;
    expect_closed_manifold(m, 2);
    // Smoothed adaptive rest lengths keep the triangles well shaped too (decision 31).
    EXPECT_GE(fraction_min_angle_at_least(m, 30.0), 0.95) << "adaptive " << adaptive;
    std::vector<double> len, curv;
    for (const auto& t : m.triangles)
      for (int k = 0; k < 3; ++k) {
        const Vector3d a = m.positions[t[k]], b = m.positions[t[(k + 1) % 3]];
        const sim::SurfaceGeometry g = sim::geometry_from_field(obj->field(0.5 * (a + b)));
        len.push_back((a - b).norm());
        curv.push_back(std::max(std::abs(g.k1), std::abs(g.k2)));
      }
    return pearson(len, curv);
  };
  const double adaptive = correlation(true);
  const double uniform = correlation(false);
  EXPECT_LT(adaptive, -0.5) << "uniform mode gives " << uniform;
  std::printf("correlation edge length / curvature: adaptive %.3f, uniform %.3f\n", adaptive,
              uniform);
  EXPECT_LT(adaptive, uniform - 0.3);
}

// The same law at a coarse R (a quarter of the particles): small enough for the sanitizer job,
// which leaves the finer test above out.
TEST(SpringNetwork, AdaptiveRestLengthsFollowTheCurvatureAtACoarseEdge) {
  const double R = 0.35;
  const auto obj = sim::make_ellipsoid(Vector3d::Zero(), Vector3d(2.0, 1.0, 0.7));
  const auto s = surface_of(obj, Vector3d(-2.2, -1.2, -0.9), Vector3d(2.2, 1.2, 0.9));
  const ParticleMeshResult r = particle_mesh(*s, {.edge_length = R, .adaptive = true});
  expect_closed_manifold(r.mesh, 2);
  std::vector<double> len, curv;
  for (const auto& t : r.mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vector3d a = r.mesh.positions[t[k]], b = r.mesh.positions[t[(k + 1) % 3]];
      const sim::SurfaceGeometry g = sim::geometry_from_field(obj->field(0.5 * (a + b)));
      len.push_back((a - b).norm());
      curv.push_back(std::max(std::abs(g.k1), std::abs(g.k2)));
    }
  const double c = pearson(len, curv);
  std::printf("coarse adaptive ellipsoid: %zu vertices, correlation %.3f\n",
              r.mesh.positions.size(), c);
  EXPECT_LT(c, -0.4);
}

// The network's own counters: iterations done so far and particles alive, next to the mesh it
// hands out.
TEST(SpringNetwork, CountsItsIterationsAndParticles) {
  const auto s = surface_of(sim::make_sphere(Vector3d::Zero(), 1.0), Vector3d::Constant(-1.2),
                            Vector3d::Constant(1.2));
  SpringNetwork net(marching_tetrahedra(*s, 0.4), {.edge_length = 0.3});
  EXPECT_EQ(net.iteration(), 0);
  const std::size_t start = net.vertex_count();
  EXPECT_EQ(start, net.mesh().positions.size());
  int changes = 0;
  for (int i = 0; i < 5; ++i) changes += net.step(*s).changed() ? 1 : 0;
  EXPECT_EQ(net.iteration(), 5);
  EXPECT_EQ(net.vertex_count(), net.mesh().positions.size());
  EXPECT_EQ(net.vertex_count(), net.vertex_ids().size());
  std::printf("sphere at 0.4 relaxed for 0.3: %zu -> %zu particles, %d changing steps\n", start,
              net.vertex_count(), changes);
  const int more = net.relax(*s);
  EXPECT_EQ(net.iteration(), 5 + more);
  expect_closed_manifold(net.mesh(), 2);
}

// Decision 33's dislocation glides (off by default): on a sphere from the layered start (the
// subdivided start leaves no 7-5 pair to glide), the glides keep the mesh closed and leave no
// more valence-7 particles than without them.
TEST(SpringNetwork, DislocationGlidesKeepTheMeshClosedAndRemoveSevens) {
  const auto s = surface_of(sim::make_sphere(Vector3d::Zero(), 1.0), Vector3d::Constant(-1.2),
                            Vector3d::Constant(1.2));
  auto sevens = [&](int glide) {
    const ParticleMeshResult r =
        particle_mesh(*s, {.edge_length = 0.25, .max_subdivision = 0, .max_glide = glide});
    expect_closed_manifold(r.mesh, 2);
    const auto v = valence_histogram(r.mesh);
    int n7 = 0, n5 = 0;
    for (const auto& [val, count] : v) n7 += val >= 7 ? count : 0, n5 += val == 5 ? count : 0;
    std::printf("glide %d: %d fives, %d sevens or more\n", glide, n5, n7);
    return n7;
  };
  const int without = sevens(0);
  EXPECT_LE(sevens(6), without);
}

TEST(SpringNetwork, RejectsImpossibleOptions) {
  Mesh tri;
  tri.positions = {Vector3d::Zero(), Vector3d::UnitX(), Vector3d::UnitY()};
  tri.triangles = {{0, 1, 2}};
  EXPECT_THROW(SpringNetwork(tri, {.edge_length = -1.0}), InvalidInputError);
  EXPECT_THROW(SpringNetwork(tri, {.d_min = 0.8, .d_max = 1.2}), InvalidInputError);
  EXPECT_THROW(SpringNetwork(tri, {.subdivision_accept = 1.5}), InvalidInputError);
  EXPECT_THROW(SpringNetwork(tri, {.subdivision_trials = -1}), InvalidInputError);
  // relaxed_network() checks too, before any network exists (an accept level below 0 once
  // skipped every start and dereferenced an empty result).
  const auto sphere = surface_of(sim::make_sphere(Vector3d::Zero(), 1.0), Vector3d::Constant(-1.2),
                                 Vector3d::Constant(1.2));
  EXPECT_THROW(particle_mesh(
                   *sphere, {.edge_length = 0.3, .max_subdivision = 0, .subdivision_accept = -2.0}),
               InvalidInputError);
  EXPECT_THROW(
      particle_mesh(*sphere, {.edge_length = 0.3,
                              .subdivision_accept = std::numeric_limits<double>::quiet_NaN()}),
      InvalidInputError);
  Mesh bad = tri;
  bad.triangles.push_back({0, 1, 2});  // the same orientation twice: not a manifold
  EXPECT_THROW(SpringNetwork(bad, {}), InvalidInputError);
}

std::shared_ptr<const sim::AnimatedSkeleton> load_skeleton(const std::string& name) {
  return std::make_shared<const sim::AnimatedSkeleton>(sim::AnimatedSkeleton::from_yaml_file(
      std::filesystem::path(SCANMESH_SOURCE_DIR) / "configs/sim" / name));
}

SurfaceAtTime surface_at(std::shared_ptr<const sim::AnimatedSkeleton> sk) {
  return [sk](double t) -> std::shared_ptr<const ImplicitSurface> {
    return std::make_shared<cli::AnimatedSkeletonSurface>(sk, t);
  };
}

// Largest angle between the normals of two faces sharing an edge (degrees): a fold, where the
// mesh doubles back on itself, has one near 180.
double sharpest_fold_deg(const Mesh& m) {
  std::map<std::pair<int, int>, std::vector<Vector3d>> normals;
  for (const auto& t : m.triangles) {
    const Vector3d n = (m.positions[t[1]] - m.positions[t[0]])
                           .cross(m.positions[t[2]] - m.positions[t[0]])
                           .normalized();
    for (int k = 0; k < 3; ++k)
      normals[std::minmax(t[k], t[(k + 1) % 3])].push_back(n);
  }
  double worst = 0.0;
  for (const auto& [e, ns] : normals)
    if (ns.size() == 2)
      worst = std::max(worst, std::acos(std::clamp(ns[0].dot(ns[1]), -1.0, 1.0)) * 180.0 /
                                  std::numbers::pi);
  return worst;
}

// Faces whose normal points against the surface's gradient at their centroid (turned over).
int turned_faces(const Mesh& m, const ImplicitSurface& surface) {
  int n = 0;
  for (const auto& t : m.triangles) {
    const Vector3d c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
    const auto f = surface.evaluate(c);
    const Vector3d normal = (m.positions[t[1]] - m.positions[t[0]])
                                .cross(m.positions[t[2]] - m.positions[t[0]]);
    if (f && normal.dot(f->gradient) < 0.0) ++n;
  }
  return n;
}

// Issue 31: no frame of an animation has crossing faces (frames 6-8 of the 9-frame
// separation had 16, 25 and 34 crossing face pairs), and once the closing fans of a cut have
// had a frame to relax, no face is turned over and no edge folded. The frames of the pinching
// neck and the frame of the cut itself still carry sharp edges (docs/particles.md, decisions 39-40).
void expect_every_frame_untangled(const std::vector<AnimationFrame>& frames,
                                  const SurfaceAtTime& surface) {
  std::size_t cut_frame = frames.size();
  for (std::size_t f = 0; f < frames.size(); ++f)
    if (frames[f].cuts + frames[f].fallback_cuts > 0 && cut_frame == frames.size()) cut_frame = f;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    const Mesh& m = frames[f].mesh;
    EXPECT_EQ(count_intersecting_faces(m), 0u);
    if (f <= cut_frame) continue;
    EXPECT_EQ(turned_faces(m, *surface(frames[f].time)), 0);
    EXPECT_LT(sharpest_fold_deg(m), 120.0);
  }
}

void expect_two_closed_spheres(int frame_count, int steps, double R, bool midpoints_on_surface) {
  const auto sk = load_skeleton("two_blobs_apart.yaml");
  const auto frames = animate(surface_at(sk), sk->start_time(), sk->end_time(), frame_count,
                              {.edge_length = R}, steps);
  expect_every_frame_untangled(frames, surface_at(sk));
  // Frame 0: one blended peanut, a single sphere-like component.
  std::vector<int> comp;
  ASSERT_EQ(face_components(frames.front().mesh, comp), 1);
  expect_closed_manifold(frames.front().mesh, 2);
  const Mesh& last = frames.back().mesh;
  // The separation is done by the ring cut of §4.4 (eq. 25, two closing fans), not by the
  // fallbacks (gap decisions 25-26).
  int cuts = 0, fallback = 0;
  for (const auto& f : frames) cuts += f.cuts, fallback += f.fallback_cuts;
  EXPECT_EQ(cuts, 1);
  EXPECT_EQ(fallback, 0);
  ASSERT_EQ(face_components(last, comp), 2);
  // No lost or duplicated faces: closed components (below) and no vertex triple twice.
  std::set<std::array<int, 3>> seen;
  for (auto t : last.triangles) {
    std::sort(t.begin(), t.end());
    EXPECT_TRUE(seen.insert(t).second) << "duplicated face";
  }
  const auto final_surface = surface_at(sk)(sk->end_time());
  for (int c = 0; c < 2; ++c) {
    const Mesh part = component_mesh(last, comp, c);
    expect_closed_manifold(part, 2);
    // Each part lies on one side of the gap: all vertices on the same side of x = 0 (with a
    // margin once the closing fans have had steps to relax onto the surface).
    const double margin = midpoints_on_surface ? 0.3 : 0.0;
    double lo = 1e9, hi = -1e9;
    for (const auto& p : part.positions) lo = std::min(lo, p.x()), hi = std::max(hi, p.x());
    EXPECT_TRUE(lo > margin || hi < -margin) << "component spans x in [" << lo << ", " << hi << "]";
  }
  // No triangle spans the gap (each component lies on one side, above). With enough steps
  // after the cut the closing fans have also relaxed onto the surface: every edge midpoint is
  // inside or near it.
  if (!midpoints_on_surface) return;
  for (const auto& t : last.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vector3d mid = 0.5 * (last.positions[t[k]] + last.positions[t[(k + 1) % 3]]);
      const auto f = final_surface->evaluate(mid);
      ASSERT_TRUE(f.has_value());
      EXPECT_LT(f->value, 0.02);
    }
}

TEST(Topology, TwoBlobsPulledApartEndAsTwoClosedSpheres) {
  expect_two_closed_spheres(9, 30, 0.2, true);
}

// Few steps per frame: the neck tears within one frame; the ring still forms after a few steps
// of constriction (ring_patience) and is cut cleanly.
TEST(Topology, FastSeparationStillGivesTwoClosedSpheres) {
  expect_two_closed_spheres(3, 5, 0.2, false);
}

// Without patience (ring_patience 0) the band of ring candidates is removed wholesale as soon
// as it appears (gap decision 26): the fallback, whose holes are closed by fans, must also end
// in two closed spheres without crossings.
TEST(Topology, FallbackCutWithoutPatienceStillGivesClosedPieces) {
  const auto sk = load_skeleton("two_blobs_apart.yaml");
  ParticleOptions o{.edge_length = 0.3};
  o.ring_patience = 0;
  const auto frames = animate(surface_at(sk), sk->start_time(), sk->end_time(), 4, o, 8);
  int cuts = 0, fallback = 0;
  for (const auto& f : frames) cuts += f.cuts, fallback += f.fallback_cuts;
  std::printf("no patience: %d ring cuts, %d fallback cuts\n", cuts, fallback);
  const Mesh& last = frames.back().mesh;
  std::vector<int> comp;
  const int pieces = face_components(last, comp);
  EXPECT_EQ(pieces, 2);
  EXPECT_GE(fallback, 1);
  for (int c = 0; c < pieces; ++c) expect_closed_manifold(component_mesh(last, comp, c), 2);
  EXPECT_EQ(count_intersecting_faces(last), 0u);
}

TEST(Topology, FinerMeshSeparatesToo) { expect_two_closed_spheres(6, 20, 0.12, true); }

// Other resolutions and a medium speed (5 frames x 10 steps): still one ring cut each.
TEST(Topology, SeparatesByOneRingCutAtSeveralResolutions) {
  for (const double R : {0.15, 0.25, 0.3}) {
    SCOPED_TRACE(R);
    expect_two_closed_spheres(5, 10, R, true);
  }
}

TEST(Animation, KeepsIdentitiesOfUnchangedVertices) {
  const auto sk = load_skeleton("blob_glide.yaml");
  const auto frames =
      animate(surface_at(sk), sk->start_time(), sk->end_time(), 5, {.edge_length = 0.25}, 10);
  ASSERT_EQ(frames.size(), 5u);
  expect_every_frame_untangled(frames, surface_at(sk));
  for (std::size_t f = 1; f < frames.size(); ++f) {
    std::unordered_map<std::uint64_t, Vector3d> before;
    for (std::size_t i = 0; i < frames[f - 1].vertex_ids.size(); ++i)
      before.emplace(frames[f - 1].vertex_ids[i], frames[f - 1].mesh.positions[i]);
    ASSERT_EQ(before.size(), frames[f - 1].vertex_ids.size()) << "ids must be unique";
    std::size_t kept = 0;
    for (std::size_t i = 0; i < frames[f].vertex_ids.size(); ++i) {
      const auto it = before.find(frames[f].vertex_ids[i]);
      if (it == before.end()) continue;
      ++kept;
      // A kept identity is the same particle: it moved at most with the surface.
      EXPECT_LT((frames[f].mesh.positions[i] - it->second).norm(), 0.5);
    }
    EXPECT_GE(static_cast<double>(kept) / static_cast<double>(before.size()), 0.9);
    // The blob glides without tearing: no cut of any kind.
    EXPECT_EQ(frames[f].cuts, 0);
    EXPECT_EQ(frames[f].fallback_cuts, 0);
  }
  // The per-frame PLY keeps the ids.
  const auto dir = std::filesystem::path(SCANMESH_BINARY_DIR) / "test_particles_out";
  std::filesystem::create_directories(dir);
  write_ply_with_ids(dir / "frame.ply", frames.back().mesh, frames.back().vertex_ids);
  EXPECT_EQ(read_ply_ids(dir / "frame.ply"), frames.back().vertex_ids);
  EXPECT_EQ(read_ply(dir / "frame.ply").triangles, frames.back().mesh.triangles);
}

TEST(ScanMode, SimulatedSphereGridGivesVerticesOnTheTrueSphere) {
  sim::Scene scene;
  scene.objects.push_back(sim::make_sphere(Vector3d(0, 0, 100), 80.0));
  sim::ScannerConfig cfg;
  cfg.n_phi = 128;
  cfg.n_h = 96;
  cfg.h0_mm = 52.0;
  cfg.dh_mm = 1.0;
  const sim::SimulatedScan scan = sim::simulate_scan(scene, cfg);
  const ScanSurface surface(scan.grid);
  const ScanImplicitSurface implicit(surface);
  const double R = 8.0;
  const ParticleMeshResult r = particle_mesh(implicit, {.edge_length = R});
  EXPECT_TRUE(r.converged) << r.iterations << " iterations";
  const Mesh& m = r.mesh;
  ASSERT_GT(m.vertex_count(), 100u);
  // Border particles slide along the border (decision 19), so the border triangles are
  // relaxed too: measured 99.3% of the triangles >= 30 deg, the worst 20.5 deg.
  EXPECT_GE(fraction_min_angle_at_least(m, 30.0), 0.95);
  EXPECT_GE(fraction_min_angle_at_least(m, 15.0), 1.0);
  const TopologyStats st = topology_stats(m);
  EXPECT_EQ(st.nonmanifold_edges, 0u);
  EXPECT_EQ(st.boundary_loops, 2u);  // a band: open at the top and the bottom
  double worst = 0.0;
  for (const auto& p : m.positions)
    worst = std::max(worst, std::abs((p - Vector3d(0, 0, 100)).norm() - 80.0));
  EXPECT_LT(worst, 0.05);
}

// A step the range grid cannot follow (decision 43): two stacked bands, r = 60 and 80 mm (with
// a 3-lobed wobble), and one invalid row between them, as the cleaner leaves the underside of
// the nose. The start mesh spans the step with particles where F is undefined or far from
// F = 0; they are removed and the step stays open, so the mesh is the two bands the data
// has. Before decision 43 the particles on the step never settled (3,000 iterations, not
// converged) and the mesh was one band across the step.
TEST(ScanMode, AStepTheGridCannotFollowStaysOpenAndTheBandsSettle) {
  const int n_phi = 96, n_h = 64, gap_row = 32;
  const auto radius_at = [](double phi, bool upper) {
    return (upper ? 80.0 : 60.0) + 3.0 * std::cos(3.0 * phi);
  };
  RangeGrid grid(n_phi, n_h, 0.0, 0.0, 1.0);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi && j != gap_row; ++i)
      grid.set_sample(i, j, static_cast<float>(radius_at(grid.phi(i), j > gap_row)));
  const ScanSurface surface(grid);
  const ScanImplicitSurface implicit(surface);
  const ParticleMeshResult r = particle_mesh(implicit, {.edge_length = 6.0});
  EXPECT_TRUE(r.converged) << r.iterations << " iterations";
  const Mesh& m = r.mesh;
  ASSERT_GT(m.vertex_count(), 400u);
  const TopologyStats st = topology_stats(m);
  EXPECT_EQ(st.nonmanifold_edges, 0u);
  EXPECT_EQ(st.boundary_loops, 4u);  // each band open at its top and bottom
  // The patches next to the invalid row are undefined: the lower band ends at h = 31, the
  // upper one starts at h = 33, and no triangle joins them.
  for (const auto& t : m.triangles) {
    double lo = 1e9, hi = -1e9;
    for (int k : t) lo = std::min(lo, m.positions[k].z()), hi = std::max(hi, m.positions[k].z());
    EXPECT_FALSE(lo < gap_row - 0.5 && hi > gap_row + 0.5) << "triangle across the step";
  }
  double worst = 0.0;
  for (const auto& p : m.positions) {
    const double phi = std::atan2(p.y(), p.x());
    const double truth = radius_at(phi, p.z() > gap_row);
    worst = std::max(worst, std::abs(std::hypot(p.x(), p.y()) - truth));
  }
  EXPECT_LT(worst, 0.1);
}

}  // namespace
}  // namespace scanmesh::particles

namespace scanmesh::particles {
namespace {

// The built-in head scanned on an n x n grid over the same height range, cleaned like
// `scanmesh clean`, and its range surface as an implicit surface.
struct HeadRangeSurface {
  explicit HeadRangeSurface(int n) : HeadRangeSurface(scanner_for(n)) {}
  explicit HeadRangeSurface(const sim::ScannerConfig& config)
      : scanner(config), grid(scan(scanner)) {}
  static sim::ScannerConfig scanner_for(int n) {
    sim::ScannerConfig cfg = sim::builtin_head_scanner();
    cfg.dh_mm *= static_cast<double>(cfg.n_h) / n;
    cfg.n_phi = cfg.n_h = n;
    return cfg;
  }
  static RangeGrid scan(const sim::ScannerConfig& cfg) {
    RangeGrid g = sim::simulate_scan(sim::builtin_head_scene(), cfg).grid;
    clean_grid(g);
    return g;
  }
  sim::ScannerConfig scanner;
  RangeGrid grid;
  ScanSurface surface{grid};
  ScanImplicitSurface implicit{surface};
};

// Triangles turned over against the range surface's outward normal (F's gradient at the
// centroid), and how many centroids could be checked (F defined there).
std::pair<std::size_t, std::size_t> turned_triangles(const Mesh& m,
                                                     const ImplicitSurface& surface) {
  std::size_t turned = 0, checked = 0;
  for (const auto& t : m.triangles) {
    const Vector3d c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
    const auto f = surface.evaluate(c);
    if (!f) continue;
    ++checked;
    const Vector3d n =
        (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    turned += n.dot(f->gradient) <= 0.0 ? 1 : 0;
  }
  return {turned, checked};
}

// Checks a scan-mode mesh: no non-manifold edge or vertex, consistently oriented, every vertex
// where F is defined on F = 0 (first order, to 1e-6 mm). Returns the vertices where F is
// defined and the longest edge over R.
std::pair<std::size_t, double> expect_manifold_on_surface(const Mesh& m,
                                                          const ImplicitSurface& implicit,
                                                          double R) {
  const MeshCheckReport check = check_mesh(m, {.self_intersections = false});
  EXPECT_EQ(check.topology.nonmanifold_edges, 0u);
  EXPECT_EQ(check.nonmanifold_vertices, 0u);
  EXPECT_EQ(check.topology.inconsistent_edges, 0u);
  std::size_t defined = 0;
  for (const auto& p : m.positions) {
    const auto f = implicit.evaluate(p);
    if (!f) continue;
    ++defined;
    EXPECT_LT(std::abs(f->value) / f->gradient.norm(), 1e-6);
  }
  double longest = 0.0;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (m.positions[t[k]] - m.positions[t[(k + 1) % 3]]).norm());
  return {defined, longest / R};
}

// Issue 7, scan mode on the full simulated head (built-in head scene and scanner, grid reduced
// to 128 x 128 with the same height range; cleaned like `scanmesh clean`). Before decisions
// 34-35 relax() hit its 3,000-iteration limit here (flips and Rule 1 collapses undoing each
// other; slivers at the borders turning over); measured now: 275 iterations.
TEST(ScanMode, SimulatedHeadConvergesToAManifoldMeshOnTheRangeSurface) {
  const HeadRangeSurface head(128);
  const sim::ScannerConfig& cfg = head.scanner;
  const ScanImplicitSurface& implicit = head.implicit;
  const ParticleMeshResult r = particle_mesh(implicit, {.edge_length = 4.0});
  EXPECT_TRUE(r.converged) << r.iterations << " iterations";
  const Mesh& m = r.mesh;
  ASSERT_GT(m.vertex_count(), 2000u);
  // Every vertex where the range surface is defined lies on it (first-order distance). Since
  // decision 43 a particle where F stays undefined is removed, but one that slid off the end
  // of a patch within its last `ring_patience` steps can remain.
  const std::size_t defined = expect_manifold_on_surface(m, implicit, 4.0).first;
  EXPECT_GE(defined, m.vertex_count() * 97 / 100);
  // Orientation against the grid surface's outward normal at each triangle's centroid: none
  // turned over (decision 38 drops the turned triangles at borders; before it 7 of 8,296, all
  // touching a border; 221 before border edges could collapse, decision 35).
  const auto [turned, checked] = turned_triangles(m, implicit);
  EXPECT_EQ(turned, 0u);
  EXPECT_GT(checked, m.triangles.size() * 97 / 100);
  // Distance to the ground truth: the true surface along the scanner ray through the vertex.
  const sim::Scene scene = sim::builtin_head_scene();
  std::vector<double> err;
  for (const auto& p : m.positions) {
    const Vector3d dir = -Vector3d(p.x(), p.y(), 0.0).normalized();
    const Vector3d origin =
        Vector3d(p.x(), p.y(), 0.0).normalized() * cfg.radius_mm + Vector3d(0, 0, p.z());
    const auto hit = scene.intersect(origin, dir, 0.0, 2.0 * cfg.radius_mm);
    if (!hit) continue;
    err.push_back(std::abs((origin + hit->t * dir - p).norm()));
  }
  ASSERT_GT(err.size(), m.vertex_count() * 9 / 10);
  std::sort(err.begin(), err.end());
  const double median = err[err.size() / 2], p95 = err[err.size() * 95 / 100];
  std::printf(
      "head: %zu vertices, %d iterations, turned %zu / %zu, truth error median %.3f "
      "p95 %.3f max %.3f mm\n",
      m.vertex_count(), r.iterations, turned, checked, median, p95, err.back());
  EXPECT_LT(median, 0.5);
  EXPECT_LT(p95, 3.0);
}

// The head at 64 x 64 cells (R = 6 mm): small enough for the sanitizer job, and it has turned
// triangles at its borders that decision 38 drops (whole border fans among them).
TEST(ScanMode, CoarseHeadConvergesWithoutTurnedTriangles) {
  const HeadRangeSurface head(64);
  const ScanImplicitSurface& implicit = head.implicit;
  const ParticleMeshResult r = particle_mesh(implicit, {.edge_length = 6.0});
  EXPECT_TRUE(r.converged) << r.iterations << " iterations";
  const Mesh& m = r.mesh;
  ASSERT_GT(m.vertex_count(), 1000u);
  const TopologyStats st = topology_stats(m);
  EXPECT_EQ(st.nonmanifold_edges, 0u);
  EXPECT_EQ(st.inconsistent_edges, 0u);
  EXPECT_EQ(st.unreferenced_vertices, 0u);
  const auto [turned, checked] = turned_triangles(m, implicit);
  EXPECT_EQ(turned, 0u);
  EXPECT_GT(checked, m.triangles.size() * 95 / 100);
  std::printf("64 x 64 head, R = 6: %zu vertices, %d iterations, %zu border loops\n",
              m.vertex_count(), r.iterations, st.boundary_loops);
}

// The full-resolution head (512 x 512, the CLI's default scanner and the one without defects)
// converges (issue 31). Before decision 43 neither did within 3,000 iterations: under the nose
// the grid steps 17 mm between two rows, the start mesh spanned the step, and the particles
// there never settled (the nose grew from 34 to 4,200 particles). The time is measured
// against a bound in bench_particles, not here.
TEST(ScanMode, FullResolutionHeadConvergesWithTheStepsOpen) {
  sim::ScannerConfig ideal = sim::builtin_head_scanner();
  ideal.noise_sigma_mm = 0.05;
  ideal.grazing_dropout = ideal.occlusion = ideal.hair = false;
  ideal.spike_probability = 0;
  for (const sim::ScannerConfig& scanner : {sim::builtin_head_scanner(), ideal}) {
    const HeadRangeSurface head(scanner);
    ASSERT_EQ(head.grid.n_h(), 512);
    const ScanImplicitSurface& implicit = head.implicit;
    const ParticleMeshResult r = particle_mesh(implicit, {.edge_length = 4.0});
    EXPECT_TRUE(r.converged) << r.iterations << " iterations";
    const Mesh& m = r.mesh;
    ASSERT_GT(m.vertex_count(), 4000u);
    // No particle left hanging across a step: every one on the surface (a particle where F
    // is undefined is removed, decision 43), and no spring spans a step (the longest edge is
    // printed below; the rules split springs above 1.45 R).
    const auto [defined, longest] = expect_manifold_on_surface(m, implicit, 4.0);
    EXPECT_EQ(defined, m.vertex_count());
    EXPECT_LT(longest, 2.0);
    const auto [turned, checked] = turned_triangles(m, implicit);
    EXPECT_EQ(turned, 0u);
    EXPECT_GT(checked, m.triangles.size() * 97 / 100);
    const TopologyStats st = topology_stats(m);
    EXPECT_GE(st.boundary_loops, 8u);  // top, neck and the holes of the data: 10 and 26
    std::printf("512 x 512 head (%s): %zu vertices, %d iterations, %zu border loops, longest "
                "edge %.2f R\n",
                scanner.hair ? "hair" : "ideal", m.vertex_count(), r.iterations,
                st.boundary_loops, longest);
  }
}

// The head with its small holes filled first (`scanmesh clean --fill-holes 200`, decision 36):
// the filled hair zone is rough below R (hair noise 1.5 mm on 1.8 mm cells), its gradient
// turns within a spring's length, and before decision 44 a few particles cycled for ever (a
// 2-cycle of the Newton step between two bumps; a particle the springs pushed into a turned
// position and the untangling took out again; a split and a collapse undoing each other):
// 3,000 iterations, not converged. Past the flip freeze such moves are damped and settle.
TEST(ScanMode, FilledRoughHairZoneSettles) {
  RangeGrid grid = HeadRangeSurface::scan(HeadRangeSurface::scanner_for(128));
  fill_small_holes(grid, 200);
  const ScanSurface surface(grid);
  const ScanImplicitSurface implicit(surface);
  const ParticleMeshResult r = particle_mesh(implicit, {.edge_length = 4.0});
  EXPECT_TRUE(r.converged) << r.iterations << " iterations";
  // The calming starts at the flip freeze (iteration 500): this run must get there, or it
  // does not test decision 44 (measured 582 iterations).
  EXPECT_GT(r.iterations, 500);
  const Mesh& m = r.mesh;
  const auto [defined, longest] = expect_manifold_on_surface(m, implicit, 4.0);
  EXPECT_EQ(defined, m.vertex_count());
  // The filled head is meshed nearly whole: measured 99.7 % of the grid mesh's area.
  EXPECT_GT(surface_area(m), 0.95 * surface_area(grid_mesh(grid).mesh));
  std::printf("filled 128 x 128 head, R = 4: %zu vertices, %d iterations\n", m.vertex_count(),
              r.iterations);
}

}  // namespace
}  // namespace scanmesh::particles
