// Stitching the region meshes into one animation mesh, the final 3D Delaunay flips and
// tangential smoothing, and the quality report.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "aft_internal.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/mesh_topology.h"

namespace scanmesh::aft {

using detail::angle_at;
using detail::min_angle;
using detail::ukey;
using detail::wrap_angle;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

// Edge flips that raise the smaller of the two triangles' minimum angles (max-min in 3D),
// never across a constraint, never producing a triangle that faces away from the surface.
int delaunay_flips(std::vector<std::array<int, 3>>& T, const std::vector<Vector3d>& P,
                   const std::vector<Vector3d>& normal,
                   const std::unordered_set<std::uint64_t>& constraint) {
  int flips = 0;
  // Edge -> its two triangles, kept up to date by the flips. (It was rebuilt from T for every
  // pass; a flip's outcome does not depend on the order of the two triangles, so this gives
  // the same flips.)
  std::unordered_map<std::uint64_t, std::array<int, 2>> adj;
  adj.reserve(2 * T.size());
  for (std::size_t t = 0; t < T.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto& e = adj.try_emplace(ukey(T[t][k], T[t][(k + 1) % 3]), std::array<int, 2>{-1, -1})
                    .first->second;
      (e[0] < 0 ? e[0] : e[1]) = static_cast<int>(t);
    }
  // The first pass visits every edge; later passes only the edges whose test can now give
  // another answer: the edges of the quads flipped in the pass before, and edges that were
  // refused because their flipped diagonal r-s already existed, once that r-s is flipped away.
  // (The passes re-tested every edge, 0.45 s of 43,000 triangles at a quarter of the sample
  // units.) Not the old order exactly: an edge touched by a flip later in the same pass is
  // re-tested in the next pass, where the full passes re-tested it in the same one; on the
  // sample head and at half and a quarter of its units the meshes have the same triangle counts
  // and angle figures. Key order in every pass, so the result is deterministic.
  std::unordered_map<std::uint64_t, std::vector<std::uint64_t>> blocked_by;
  std::vector<std::uint64_t> keys, dirty;
  keys.reserve(adj.size());
  for (const auto& kv : adj) keys.push_back(kv.first);
  for (int pass = 0; pass < 30; ++pass) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    dirty.clear();
    int pass_flips = 0;
    for (const std::uint64_t key : keys) {
      if (constraint.count(key)) continue;
      const auto it = adj.find(key);
      if (it == adj.end()) continue;
      const auto [t1, t2] = it->second;
      if (t1 < 0 || t2 < 0) continue;
      const int p = static_cast<int>(key >> 32), q = static_cast<int>(key & 0xffffffffu);
      auto opposite = [&](int t) {
        for (int k = 0; k < 3; ++k)
          if (T[t][k] != p && T[t][k] != q) return T[t][k];
        return -1;
      };
      // orient so that t1 = (p, q, r)
      int a = p, b = q;
      {
        int k = 0;
        while (T[t1][k] != a) ++k;
        if (T[t1][(k + 1) % 3] != b) std::swap(a, b);
      }
      const int r = opposite(t1), s = opposite(t2);
      if (r < 0 || s < 0 || r == s) continue;
      if (adj.count(ukey(r, s))) {
        blocked_by[ukey(r, s)].push_back(key);
        continue;
      }
      const double before = std::min(min_angle(P[a], P[b], P[r]), min_angle(P[b], P[a], P[s]));
      const double after = std::min(min_angle(P[r], P[a], P[s]), min_angle(P[s], P[b], P[r]));
      if (after <= before + 1e-6) continue;
      auto faces_out = [&](int x, int y, int z) {
        const Vector3d n = (P[y] - P[x]).cross(P[z] - P[x]);
        const Vector3d m = normal[x] + normal[y] + normal[z];
        return n.dot(m) > 0.05 * n.norm() * m.norm();
      };
      if (!faces_out(r, a, s) || !faces_out(s, b, r)) continue;
      T[t1] = {r, a, s};
      T[t2] = {s, b, r};
      adj.erase(it);
      adj[ukey(r, s)] = {t1, t2};
      // the outer edges a-s (was in t2) and b-r (was in t1) change owners
      auto reown = [&](int x, int y, int from, int to) {
        auto& e = adj[ukey(x, y)];
        for (int& v : e)
          if (v == from) v = to;
      };
      reown(a, s, t2, t1);
      reown(b, r, t1, t2);
      for (const std::uint64_t k : {ukey(r, s), ukey(a, s), ukey(s, b), ukey(b, r), ukey(r, a)})
        dirty.push_back(k);
      if (const auto bl = blocked_by.find(key); bl != blocked_by.end()) {
        dirty.insert(dirty.end(), bl->second.begin(), bl->second.end());
        blocked_by.erase(bl);
      }
      ++pass_flips;
    }
    flips += pass_flips;
    if (pass_flips == 0) break;
    keys.swap(dirty);
  }
  return flips;
}

// Gauss-Seidel sweeps moving each Steiner point to the projection of its neighbours' centroid.
// The projection starts from the point's own (phi, h), next to the answer. (One linear step
// through the surface's Jacobian instead, as the repair's search takes, was cheaper but left
// more small angles at a quarter of the sample units: 0.14 % of the triangles below 20 deg
// instead of 0.09 %; the centroid moves are up to half an edge, the search's steps a quarter
// and less.) A move is kept if the smallest incident angle grows and no incident triangle turns
// away from the point's normal.
void smooth_steiner_points(const std::vector<std::array<int, 3>>& tris, detail::NodeStore& store,
                           const ScanSurface& surface, std::size_t boundary_nodes, int iterations) {
  std::vector<std::vector<int>> vt(store.pos.size());
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int v : tris[t]) vt[v].push_back(static_cast<int>(t));
  const auto star_min = [&](std::size_t v) {
    double m = 1e9;
    for (int t : vt[v])
      m = std::min(m,
                   min_angle(store.pos[tris[t][0]], store.pos[tris[t][1]], store.pos[tris[t][2]]));
    return m;
  };
  for (int it = 0; it < iterations; ++it)
    for (std::size_t v = boundary_nodes; v < store.pos.size(); ++v) {
      if (vt[v].empty()) continue;
      Vector3d c = Vector3d::Zero();
      int n = 0;
      for (int t : vt[v])
        for (int w : tris[t])
          if (w != static_cast<int>(v)) {
            c += store.pos[w];
            ++n;
          }
      c /= n;
      const Vector2d old_param = store.params[v];
      const double before = star_min(v);
      const Vector3d old_pos = store.pos[v], old_n = store.normal[v];
      const auto pr = surface.project(c, old_param);
      if (!pr) continue;
      const Vector2d param(pr->phi, pr->h);
      if (!store.move(static_cast<int>(v), param, surface)) continue;
      bool ok = true;
      for (int t : vt[v]) {
        const Vector3d &a = store.pos[tris[t][0]], &b = store.pos[tris[t][1]],
                       &d = store.pos[tris[t][2]];
        const Vector3d nn = (b - a).cross(d - a);
        if (min_angle(a, b, d) <= before || nn.dot(store.normal[v]) <= 0.3 * nn.norm()) {
          ok = false;
          break;
        }
      }
      if (!ok) {
        store.params[v] = old_param;
        store.pos[v] = old_pos;
        store.normal[v] = old_n;
      }
    }
}

// What a region's own post-processing cannot see, counted on the stitched mesh: pairs of
// triangles of different regions that cross (more than sharing a corner or an edge), and edges
// with more than two triangles (a flip or collapse made an edge between two segment nodes that
// another region has too).
struct StitchDefects {
  std::size_t crossings = 0, overfull_edges = 0;
};
StitchDefects stitch_defects(const std::vector<std::array<int, 3>>& tris,
                             const std::vector<int>& labels, const std::vector<Vector3d>& pos) {
  Mesh mesh;
  mesh.positions = pos;
  mesh.triangles = tris;
  return {count_intersecting_faces(mesh, &labels), topology_stats(mesh).nonmanifold_edges};
}

}  // namespace

AnimationMesh build_animation_mesh(const RegionGraph& g, const LineSet& lines,
                                   const ScanSurface& surface, const RegionSettings& settings) {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };
  auto stage_start = Clock::now();
  AnimationMesh am;
  const SegmentNodes seg = initialise_segments(g, lines, surface, settings);
  detail::NodeStore store;
  for (std::size_t i = 0; i < seg.params.size(); ++i)
    if (store.add(seg.params[i], surface) < 0)
      throw InvalidInputError("segment node " + std::to_string(i) + " is off the scan surface");
  const std::size_t boundary_nodes = store.params.size();
  am.seconds.segments = seconds_since(stage_start);
  stage_start = Clock::now();
  // One job per meshed region. The regions share only the segment nodes (fixed, the first
  // boundary_nodes entries of the store), so each is meshed on its own copy of them, in
  // parallel; the Steiner points are then appended region by region in region order, which
  // gives the same node numbering, and the same mesh, as meshing the regions one after another.
  struct RegionJob {
    int region;
    detail::RegionMeshInput in;
    detail::NodeStore nodes;
    RegionMeshStats stats;
    std::vector<std::array<int, 3>> tris;
    int flips = 0;
    detail::RepairStats repair;
    // The region as the mesher left it, for the serial fallback (see below).
    detail::NodeStore nodes_meshed;
    std::vector<std::array<int, 3>> tris_meshed;
    AnimationMesh::StageSeconds thread_seconds;
  };
  std::vector<RegionJob> jobs;
  for (std::size_t r = 0; r < g.regions.size(); ++r) {
    const Region& reg = g.regions[r];
    if (reg.opening) continue;
    detail::RegionMeshInput in;
    in.unit_mm = reg.unit_mm > 0 ? reg.unit_mm : settings.default_unit_mm;
    in.strategy = settings.strategy;
    in.chordal_tolerance_mm = settings.chordal_tolerance_mm;
    in.min_unit_mm = settings.min_unit_mm;
    in.seed = settings.seed + 1000003ull * r;
    std::vector<int> cycles{reg.outer};
    cycles.insert(cycles.end(), reg.inner.begin(), reg.inner.end());
    // The region as the polygon of its boundary nodes (the chords the front starts from, not
    // the curves: a chord cutting a curved opening's corner must not count as leaving).
    for (int c : cycles) {
      std::vector<Vector2d> poly;
      for (const HalfEdgeRef& he : g.cycles[c].edges) {
        std::vector<int> chain = seg.chains[he.segment];
        if (!he.forward) std::reverse(chain.begin(), chain.end());
        for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
          Vector2d p = seg.params[chain[k]];
          if (!poly.empty()) p.x() = poly.back().x() + wrap_angle(p.x() - poly.back().x());
          poly.push_back(p);
        }
      }
      in.polygons.push_back(poly);
    }
    for (int c : cycles)
      for (const HalfEdgeRef& he : g.cycles[c].edges) {
        std::vector<int> chain = seg.chains[he.segment];
        if (!he.forward) std::reverse(chain.begin(), chain.end());
        for (std::size_t k = 0; k + 1 < chain.size(); ++k)
          in.front.push_back({chain[k], chain[k + 1]});
      }
    jobs.push_back({static_cast<int>(r), std::move(in), {}, {}, {}, 0, {}, {}, {}, {}});
  }
  // Constraint edges: every segment chain. Their ends are segment nodes, which have the same
  // index in every region's store and in the stitched one.
  std::unordered_set<std::uint64_t> constraint;
  for (const auto& chain : seg.chains)
    for (std::size_t k = 0; k + 1 < chain.size(); ++k)
      constraint.insert(ukey(chain[k], chain[k + 1]));
  // Largest fronts first, so that a big region does not start last.
  std::vector<int> order(jobs.size());
  for (std::size_t k = 0; k < jobs.size(); ++k) order[k] = static_cast<int>(k);
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return jobs[x].in.front.size() > jobs[y].in.front.size(); });
  // Small-angle repair (a little above 20 deg so that later rounding cannot drop below it).
  const auto repair = [&](std::vector<std::array<int, 3>>& tris, std::vector<int>& labels,
                          detail::NodeStore& nodes) {
    return detail::repair_small_angles(tris, labels, nodes, surface, constraint, boundary_nodes,
                                       20.5 * M_PI / 180, 20.0 * M_PI / 180,
                                       settings.repair_rounds);
  };
  // Flips, tangential smoothing of the Steiner points (towards the neighbours' centroid, on the
  // surface, kept only if the smallest incident angle grows), flips again, and the small-angle
  // repair: of one region in its job, or of the stitched mesh in the fallback below.
  struct PostResult {
    int flips = 0;
    detail::RepairStats repair;
    AnimationMesh::StageSeconds seconds;
  };
  const auto postprocess = [&](std::vector<std::array<int, 3>>& tris, std::vector<int>& labels,
                               detail::NodeStore& nodes) {
    PostResult out;
    auto t0 = Clock::now();
    out.flips = delaunay_flips(tris, nodes.pos, nodes.normal, constraint);
    out.seconds.flips = seconds_since(t0);
    t0 = Clock::now();
    smooth_steiner_points(tris, nodes, surface, boundary_nodes, settings.smooth_iterations);
    out.seconds.smoothing = seconds_since(t0);
    t0 = Clock::now();
    out.flips += delaunay_flips(tris, nodes.pos, nodes.normal, constraint);
    out.seconds.flips += seconds_since(t0);
    t0 = Clock::now();
    out.repair = repair(tris, labels, nodes);
    out.seconds.repair = seconds_since(t0);
    return out;
  };
  // Per region, none of these stages crosses a region border: flips never flip a constraint
  // edge (every border is one), and only Steiner points move, whose stars lie in their region.
  // The job's numbering is the stitched one shifted, so the smoothing's Gauss-Seidel order and
  // the flips' key order are kept. What a region does not see is the others' triangles: the
  // repair tests a changed triangle for crossings against its own region only, and a flip or
  // collapse cannot know that the edge it makes between two segment nodes exists in another
  // region. Both are checked on the stitched mesh (below).
  const auto postprocess_region = [&](RegionJob& job) {
    job.nodes_meshed = job.nodes;
    job.tris_meshed = job.tris;
    std::vector<int> labels(job.tris.size(), job.region);
    const PostResult r = postprocess(job.tris, labels, job.nodes);
    job.flips = r.flips;
    job.repair = r.repair;
    job.thread_seconds.flips = r.seconds.flips;
    job.thread_seconds.smoothing = r.seconds.smoothing;
    job.thread_seconds.repair = r.seconds.repair;
  };
  std::vector<std::exception_ptr> errors(jobs.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t k = 0; k < order.size(); ++k) {
    RegionJob& job = jobs[order[k]];
    const auto job_start = Clock::now();
    try {
      job.nodes = store;
      job.stats.region = job.region;
      std::optional<std::vector<std::array<int, 3>>> region_tris;
      if (g.regions[job.region].mesher == "delaunay") {
        region_tris = detail::delaunay_mesh_region(job.nodes, surface, job.in, job.stats);
        if (region_tris) job.stats.mesher = "delaunay";
      }
      if (!region_tris)
        region_tris = detail::aft_mesh_region(job.nodes, surface, job.in, job.stats);
      job.tris = std::move(*region_tris);
      job.thread_seconds.regions = seconds_since(job_start);
      if (settings.parallel_postprocessing) {
        postprocess_region(job);
      } else {
        job.nodes_meshed = job.nodes;
        job.tris_meshed = job.tris;
      }
    } catch (...) {
      errors[order[k]] = std::current_exception();
    }
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  // Stitching: the Steiner points appended region by region.
  const auto stitch = [&](bool as_meshed, detail::NodeStore& nodes,
                          std::vector<std::array<int, 3>>& tris, std::vector<int>& labels) {
    nodes = store;
    for (const RegionJob& job : jobs) {
      const detail::NodeStore& jn = as_meshed ? job.nodes_meshed : job.nodes;
      const int offset = static_cast<int>(nodes.pos.size() - boundary_nodes);
      for (std::size_t v = boundary_nodes; v < jn.pos.size(); ++v) {
        nodes.params.push_back(jn.params[v]);
        nodes.pos.push_back(jn.pos[v]);
        nodes.normal.push_back(jn.normal[v]);
      }
      for (auto t : as_meshed ? job.tris_meshed : job.tris) {
        for (int& v : t)
          if (v >= static_cast<int>(boundary_nodes)) v += offset;
        tris.push_back(t);
        labels.push_back(job.region);
      }
    }
  };
  detail::NodeStore stitched;
  std::vector<std::array<int, 3>> tris;
  std::vector<int> labels;
  stitch(false, stitched, tris, labels);
  for (const RegionJob& job : jobs) {
    am.region_stats.push_back(job.stats);
    am.flips += job.flips;
    for (int k = 0; k < 5; ++k) am.repair_operations[k] += job.repair.operations[k];
    am.repair_left_below_20 += job.repair.left_below_goal;
    am.repair_forced_below_20 += job.repair.forced_below_goal;
    am.thread_seconds.regions += job.thread_seconds.regions;
    am.thread_seconds.flips += job.thread_seconds.flips;
    am.thread_seconds.smoothing += job.thread_seconds.smoothing;
    am.thread_seconds.repair += job.thread_seconds.repair;
  }
  am.seconds.regions = seconds_since(stage_start);
  stage_start = Clock::now();
  // The regions did not see each other (above). If the stitched mesh has an edge with more
  // than two triangles, or more crossings between regions than the meshers left, the flips,
  // smoothing and repair are done again on the stitched mesh as the meshers left it, where every
  // edge and every changed triangle is tested against the whole mesh. (Neither has happened on
  // the sample head at any unit size tried.)
  const StitchDefects defects = stitch_defects(tris, labels, stitched.pos);
  if (!settings.parallel_postprocessing || defects.crossings > 0 || defects.overfull_edges > 0) {
    detail::NodeStore meshed;
    std::vector<std::array<int, 3>> tris_meshed;
    std::vector<int> labels_meshed;
    stitch(true, meshed, tris_meshed, labels_meshed);
    if (!settings.parallel_postprocessing || defects.overfull_edges > 0 ||
        defects.crossings > stitch_defects(tris_meshed, labels_meshed, meshed.pos).crossings) {
      const PostResult r = postprocess(tris_meshed, labels_meshed, meshed);
      am.flips = r.flips;
      am.repair_operations = r.repair.operations;
      am.repair_left_below_20 = r.repair.left_below_goal;
      am.repair_forced_below_20 = r.repair.forced_below_goal;
      am.serial_postprocessing = true;
      am.seconds.flips = r.seconds.flips;
      am.seconds.smoothing = r.seconds.smoothing;
      am.seconds.repair = r.seconds.repair;
      stitched = std::move(meshed);
      tris = std::move(tris_meshed);
      labels = std::move(labels_meshed);
    }
  }
  am.seconds.check = seconds_since(stage_start);
  for (RegionJob& job : jobs) job = {};
  detail::NodeStore& store_all = stitched;
  // Compact: drop nodes no triangle uses (segments bordering nothing meshed).
  std::vector<int> used(store_all.pos.size(), 0);
  for (const auto& t : tris)
    for (int v : t) used[v] = 1;
  // Nodes of opening/seam chains stay even if unused? No: only used nodes are mesh vertices.
  std::vector<int> remap(store_all.pos.size(), -1);
  for (std::size_t v = 0; v < store_all.pos.size(); ++v)
    if (used[v]) {
      remap[v] = static_cast<int>(am.mesh.positions.size());
      am.mesh.positions.push_back(store_all.pos[v]);
      am.params.push_back(store_all.params[v]);
      am.steiner.push_back(v >= boundary_nodes);
    }
  for (std::size_t t = 0; t < tris.size(); ++t) {
    am.mesh.triangles.push_back({remap[tris[t][0]], remap[tris[t][1]], remap[tris[t][2]]});
    am.mesh.face_labels.push_back(labels[t]);
  }
  for (std::size_t s = 0; s < seg.chains.size(); ++s) {
    std::vector<int> chain;
    bool complete = true;
    for (int v : seg.chains[s]) {
      chain.push_back(remap[v]);
      complete &= remap[v] >= 0;
    }
    am.segment_chains.push_back(chain);
    if (!complete) continue;
    for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
      am.line_edges.push_back({chain[k], chain[k + 1]});
      am.line_edge_line.push_back(g.segments[s].line);
    }
  }
  // Seams: each seam line's node list in line order (segments are in line order already).
  for (std::size_t s = 0; s < g.segments.size(); ++s) {
    const AnimationLine& line = lines.lines[g.segments[s].line];
    if (line.kind != LineKind::Seam) continue;
    auto& list = am.seams[line.id];
    for (int v : am.segment_chains[s])
      if (list.empty() || list.back() != v) list.push_back(v);
  }
  am.mesh.compute_vertex_normals();
  return am;
}

std::string AnimationMeshQuality::to_text() const {
  std::ostringstream os;
  os.precision(4);
  os << "min angle " << min_angle_deg << " deg (" << min_angle_non_exempt_deg
     << " deg away from sharp line junctions, " << small_angle_exempt
     << " triangles exempt), max angle " << max_angle_deg << " deg\n";
  os << "min angle >= 30 deg: " << 100 * fraction_min_angle_ge_30
     << " %, >= 20 deg: " << 100 * fraction_min_angle_ge_20 << " %\n";
  os << "q = 2 r_in / R_circ: mean " << mean_q << ", min " << min_q << "\n";
  os << "Hausdorff to the scan surface: mesh->surface " << hausdorff_mesh_to_surface_mm
     << " mm, surface->mesh " << hausdorff_surface_to_mesh_mm << " mm; max vertex offset "
     << max_vertex_offset_mm << " mm\n";
  os << "valence:";
  for (const auto& [v, n] : valence_histogram) os << " " << v << ":" << n;
  os << "\ntriangles per region:";
  for (std::size_t r = 0; r < triangles_per_region.size(); ++r)
    if (triangles_per_region[r]) os << " " << r << ":" << triangles_per_region[r];
  os << "\n";
  return os.str();
}

AnimationMeshQuality evaluate_quality(const AnimationMesh& am, const ScanSurface& surface,
                                      int samples) {
  AnimationMeshQuality q;
  const auto& P = am.mesh.positions;
  const auto& T = am.mesh.triangles;
  std::unordered_set<std::uint64_t> line_edge;
  for (const auto& e : am.line_edges) line_edge.insert(ukey(e[0], e[1]));
  q.min_angle_deg = 180;
  q.min_angle_non_exempt_deg = 180;
  q.min_q = 1;
  int ge30 = 0, ge20 = 0;
  std::vector<int> valence(P.size(), 0);
  std::unordered_set<std::uint64_t> edges;
  for (std::size_t t = 0; t < T.size(); ++t) {
    const auto& f = T[t];
    std::array<double, 3> ang{};
    for (int k = 0; k < 3; ++k) ang[k] = angle_at(P[f[k]], P[f[(k + 1) % 3]], P[f[(k + 2) % 3]]);
    const int kmin = static_cast<int>(std::min_element(ang.begin(), ang.end()) - ang.begin());
    const double mn = ang[kmin] * 180 / M_PI,
                 mx = *std::max_element(ang.begin(), ang.end()) * 180 / M_PI;
    q.min_angle_deg = std::min(q.min_angle_deg, mn);
    q.max_angle_deg = std::max(q.max_angle_deg, mx);
    const bool exempt = mn < 20 && line_edge.count(ukey(f[kmin], f[(kmin + 1) % 3])) &&
                        line_edge.count(ukey(f[kmin], f[(kmin + 2) % 3]));
    if (exempt)
      ++q.small_angle_exempt;
    else
      q.min_angle_non_exempt_deg = std::min(q.min_angle_non_exempt_deg, mn);
    ge30 += mn >= 30;
    ge20 += mn >= 20;
    q.min_angle_histogram[std::min(11, static_cast<int>(mn / 5))]++;
    const double a = (P[f[1]] - P[f[0]]).norm(), b = (P[f[2]] - P[f[1]]).norm(),
                 c = (P[f[0]] - P[f[2]]).norm();
    const double area = 0.5 * (P[f[1]] - P[f[0]]).cross(P[f[2]] - P[f[0]]).norm();
    const double s = 0.5 * (a + b + c);
    const double qq = s > 0 && a * b * c > 0 ? 8 * area * area / (s * a * b * c) : 0;
    q.mean_q += qq;
    q.min_q = std::min(q.min_q, qq);
    q.q_histogram[std::clamp(static_cast<int>(qq * 10), 0, 9)]++;
    for (int k = 0; k < 3; ++k) edges.insert(ukey(f[k], f[(k + 1) % 3]));
    const int label = t < am.mesh.face_labels.size() ? am.mesh.face_labels[t] : 0;
    if (label >= static_cast<int>(q.triangles_per_region.size()))
      q.triangles_per_region.resize(label + 1);
    q.triangles_per_region[label]++;
  }
  for (const auto k : edges) {
    valence[k >> 32]++;
    valence[k & 0xffffffffu]++;
  }
  for (int v : valence)
    if (v) q.valence_histogram[v]++;
  if (!T.empty()) {
    q.mean_q /= T.size();
    q.fraction_min_angle_ge_30 = static_cast<double>(ge30) / T.size();
    q.fraction_min_angle_ge_20 = static_cast<double>(ge20) / T.size();
  }
  for (const Vector3d& p : P)
    if (const auto pr = surface.project(p))
      q.max_vertex_offset_mm = std::max(q.max_vertex_offset_mm, pr->distance);
  // Two-way sampled Hausdorff with exact distances to triangle sets (surface_distance.cpp).
  const detail::TwoWayDistance d = detail::sampled_hausdorff(am, surface, samples);
  q.hausdorff_mesh_to_surface_mm = d.mesh_to_surface_mm;
  q.hausdorff_surface_to_mesh_mm = d.surface_to_mesh_mm;
  return q;
}

}  // namespace scanmesh::aft
