// The meshers, bound as the CLI calls them: grid mesh (apps/src/cmd_mesh.cpp), point-cloud fans
// (cmd_fans.cpp), adaptive remeshing (cmd_remesh.cpp), animation meshes and regions
// (cmd_aft.cpp).
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "common.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/aft/data_border.h"
#include "scanmesh/meshing/aft/region_setup.h"
#include "scanmesh/meshing/fans/fans.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/remeshing/remesh.h"
#include "scanmesh/meshing/remeshing/remesh_quality.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::python {

namespace {

py::dict fan_stats(const FanStats& s) {
  py::dict d;
  SCANMESH_PUT_FIELDS(d, s, points, duplicate_points, cell_edge, pca_fallbacks, open_fans,
                      proposed_triangles, rejected_triangles, seeds, growth_blocks,
                      growth_blocks_discarded, glued_triangles, unzipped_glues,
                      bowtie_faces_removed, hole_triangles, inserted_points, delaunay_flips,
                      unused_points, seconds_normals, seconds_fans, seconds_assembly);
  return d;
}

py::dict remesh_stats(const remeshing::RemeshStats& s) {
  py::dict d;
  SCANMESH_PUT_FIELDS(d, s, input_vertices, input_faces, output_vertices, output_faces,
                      skeleton_segments, branch_vertices, patches, collapses, splits, flips, moves,
                      rejected_error, rejected_topology, skeleton_splits, skeleton_collapses,
                      intersecting_faces_before_repair, polish_bad_before, polish_bad_after,
                      polish_moves, polish_flips, repair_splits, seconds_setup, seconds_adapt,
                      seconds_count, seconds_regularize, seconds_smooth, seconds_total);
  return d;
}

py::dict prepare_stats(const remeshing::PrepareStats& s) {
  py::dict d;
  SCANMESH_PUT_FIELDS(d, s, components_removed, faces_removed, holes_filled, faces_added,
                      degenerate_removed, needles_welded, caps_flipped, caps_removed,
                      spike_faces_removed, pinch_faces_removed, tip_faces_removed);
  return d;
}

// The scan clean-up `scanmesh remesh` chooses (choose_prepare in cmd_remesh.cpp): "auto" runs it
// when the input looks like a scan, True always, False never; explicit values override.
remeshing::PrepareOptions choose_prepare(const Mesh& raw, int target, py::handle prepare,
                                         std::optional<int> min_component,
                                         std::optional<int> fill_holes,
                                         std::optional<double> needle_angle_deg, bool remove_spikes,
                                         std::optional<double> tip_angle_deg, bool& ran) {
  using namespace remeshing;
  bool run = false;
  if (py::isinstance<py::str>(prepare)) {
    if (prepare.cast<std::string>() != "auto")
      throw InvalidInputError("remesh: prepare must be 'auto', True or False");
    run = looks_like_scan(raw);
  } else if (py::isinstance<py::bool_>(prepare)) {
    run = prepare.cast<bool>();
  } else {
    throw py::type_error("remesh: prepare must be 'auto', True or False");
  }
  PrepareOptions po;
  if (run) po = scan_prepare_options(raw, target);
  ran = run;
  if (min_component) {
    require_range("remesh", "min_component", *min_component, 0, 1e9);
    po.min_component_faces = *min_component;
  }
  if (fill_holes) {
    require_range("remesh", "fill_holes", *fill_holes, 0, 1e6);
    po.max_hole_edges = *fill_holes;
  }
  if (needle_angle_deg) {
    require_range("remesh", "needle_angle_deg", *needle_angle_deg, 0, 60);
    po.needle_angle_deg = *needle_angle_deg;
  }
  if (remove_spikes && !po.remove_spikes) {
    po.remove_spikes = true;
    po.tip_reach_mm = uniform_edge_length(raw, target);
  }
  if (tip_angle_deg) {
    require_range("remesh", "tip_angle_deg", *tip_angle_deg, 0, 180);
    po.tip_angle_deg = *tip_angle_deg;
  }
  return po;
}

// The data-border counts of a region setup, as the regions / animesh reports give them.
py::dict border_dict(const aft::RegionSetup& l) {
  py::dict d;
  d["mode"] = aft::to_string(l.border_mode);
  d["on"] = l.border.border_on;
  SCANMESH_PUT_FIELDS(d, l.border, border_lines, clipped_lines, dropped_lines);
  return d;
}

py::list regions_list(const aft::RegionGraph& g) {
  py::list regions;
  for (std::size_t r = 0; r < g.regions.size(); ++r) {
    const aft::Region& region = g.regions[r];
    py::dict d;
    d["index"] = r;
    SCANMESH_PUT_FIELDS(d, region, name, opening, area, unit_mm, mesher);
    d["label_point"] = py::make_tuple(region.label_point.x(), region.label_point.y());
    regions.append(d);
  }
  return regions;
}

py::dict animesh_report(const aft::RegionSetup& l, const aft::AnimationMesh& am,
                        const aft::AnimationMeshQuality& q, const MeshCheckReport& check) {
  py::dict d;
  int steiner = 0, unmeshed = 0;
  for (auto s : am.steiner) steiner += s;
  for (const auto& s : am.region_stats) unmeshed += s.unmeshed_front_edges;
  d["vertices"] = am.mesh.positions.size();
  d["triangles"] = am.mesh.triangles.size();
  d["steiner_points"] = steiner;
  d["unmeshed_front_edges"] = unmeshed;
  SCANMESH_PUT_FIELDS(d, am, flips, valence_flip_retries, regions_remeshed, serial_postprocessing);
  py::dict repair;
  repair["optimise"] = am.repair_operations[0];
  repair["flip"] = am.repair_operations[1];
  repair["collapse"] = am.repair_operations[2] + am.repair_operations[3];
  repair["split"] = am.repair_operations[4];
  repair["left_below_20_deg"] = am.repair_left_below_20;
  repair["left_above_deviation_goal"] = am.repair_left_above_deviation_goal;
  repair["forced_below_20_deg"] = am.repair_forced_below_20;
  d["small_angle_repair"] = repair;
  py::dict quality;
  quality["min_angle_deg"] = q.min_angle_deg;
  quality["min_angle_away_from_sharp_junctions_deg"] = q.min_angle_non_exempt_deg;
  quality["exempt_triangles"] = q.small_angle_exempt;
  SCANMESH_PUT_FIELDS(quality, q, max_angle_deg, fraction_min_angle_ge_30, fraction_min_angle_ge_20,
                      mean_radius_ratio, min_radius_ratio);
  quality["min_angle_histogram_5deg"] =
      std::vector<int>(q.min_angle_histogram.begin(), q.min_angle_histogram.end());
  quality["radius_ratio_histogram_0.1"] =
      std::vector<int>(q.radius_ratio_histogram.begin(), q.radius_ratio_histogram.end());
  SCANMESH_PUT_FIELDS(quality, q, valence_histogram, hausdorff_mesh_to_surface_mm,
                      hausdorff_surface_to_mesh_mm, max_vertex_offset_mm, vertices_off_surface);
  quality["text"] = q.to_text();
  d["quality"] = quality;
  py::list regions = regions_list(l.graph);
  for (const auto& s : am.region_stats) {
    py::dict r = regions[static_cast<std::size_t>(s.region)].cast<py::dict>();
    SCANMESH_PUT_FIELDS(r, s, triangles, steiner_points, chose_new, chose_existing,
                        chose_circumcentre, rejected_circumcentres, unmeshed_front_edges, mesher);
  }
  d["regions"] = regions;
  d["data_border"] = border_dict(l);
  d["seams"] = am.seams;
  std::vector<double> params(2 * am.params.size());
  for (std::size_t v = 0; v < am.params.size(); ++v) {
    params[2 * v] = am.params[v].x();
    params[2 * v + 1] = am.params[v].y();
  }
  d["params"] = owned(std::move(params), {static_cast<py::ssize_t>(am.params.size()), 2});
  std::vector<int> line_edges(2 * am.line_edges.size());
  for (std::size_t e = 0; e < am.line_edges.size(); ++e) {
    line_edges[2 * e] = am.line_edges[e][0];
    line_edges[2 * e + 1] = am.line_edges[e][1];
  }
  d["line_edges"] =
      owned(std::move(line_edges), {static_cast<py::ssize_t>(am.line_edges.size()), 2});
  py::dict c;
  c["edge_manifold"] = check.edge_manifold();
  c["duplicate_faces"] = check.duplicate_faces;
  c["self_intersections"] = check.self_intersections;
  c["boundary_loops"] = check.topology.boundary_loops;
  d["check"] = c;
  d["complete"] = unmeshed == 0 && check.edge_manifold() && check.self_intersections == 0 &&
                  check.duplicate_faces == 0;
  return d;
}

void bind_grid_mesh(py::module_& m) {
  const GridMeshOptions gm;
  m.def(
      "grid_mesh",
      [](const RangeGrid& grid, double max_depth_jump_mm, bool close_seam, bool with_colors,
         bool with_texcoords) {
        GridMeshOptions o;
        SCANMESH_SET_FIELDS(o, max_depth_jump_mm, close_seam, with_colors, with_texcoords);
        GridMesh r;
        {
          py::gil_scoped_release release;
          r = grid_mesh(grid, o);
        }
        py::dict info;
        const auto n = static_cast<py::ssize_t>(r.vertex_cell.size());
        info["vertex_cell"] = owned(std::move(r.vertex_cell), {n});
        info["quads_meshed"] = r.quads_meshed;
        info["quads_skipped_for_holes"] = r.quads_skipped_for_holes;
        info["quads_skipped_for_depth_jumps"] = r.quads_skipped_for_depth_jumps;
        return py::make_tuple(std::move(r.mesh), info);
      },
      py::arg("grid"), py::kw_only(), py::arg("max_depth_jump_mm") = gm.max_depth_jump_mm,
      py::arg("close_seam") = gm.close_seam, py::arg("with_colors") = gm.with_colors,
      py::arg("with_texcoords") = gm.with_texcoords, R"doc(
The grid mesh (grid_mesh, as `scanmesh grid-mesh`): two triangles per quad of four valid cells
whose radii differ by at most max_depth_jump_mm; never across a hole. Returns (Mesh, info):
info["vertex_cell"] (uint64 (N,), the RangeGrid index j * n_phi + i of each vertex's cell),
quads_meshed, quads_skipped_for_holes, quads_skipped_for_depth_jumps. ValueError for a
non-positive depth limit.)doc");
}

void bind_fans(py::module_& m) {
  const FanOptions fo;
  m.def(
      "build_fans",
      [](py::handle points, py::handle normals, py::handle colors, int k, double alpha_deg,
         double dmax_factor, double max_edge, double max_edge_factor, double max_normal_angle_deg,
         int max_hole_edges, bool pca_normals, bool orient_away_from_axis, std::uint64_t seed,
         int threads, std::size_t growth_block_points) {
        FanOptions o;
        SCANMESH_SET_FIELDS(o, k, alpha_deg, dmax_factor, max_edge, max_edge_factor,
                            max_normal_angle_deg, max_hole_edges, pca_normals,
                            orient_away_from_axis, seed, threads, growth_block_points);
        o.validate();
        FanResult r;
        if (py::isinstance<PointCloud>(points)) {
          if (!normals.is_none() || !colors.is_none())
            value_error("build_fans: give normals and colors in the PointCloud, not beside it");
          const PointCloud& cloud = points.cast<const PointCloud&>();
          py::gil_scoped_release release;
          r = build_fans(cloud, o);
        } else if (normals.is_none() && colors.is_none()) {
          const std::vector<Eigen::Vector3d> p = to_vec3d(points, "points");
          py::gil_scoped_release release;
          r = build_fans(p, o);
        } else {
          const PointCloud cloud = to_cloud(points, "points", normals, colors);
          if ((cloud.has_normals() && cloud.normals.size() != cloud.positions.size()) ||
              (cloud.has_colors() && cloud.colors.size() != cloud.positions.size()))
            value_error("build_fans: normals and colors need one row per point");
          py::gil_scoped_release release;
          r = build_fans(cloud, o);
        }
        py::dict stats = fan_stats(r.stats);
        return py::make_tuple(std::move(r.mesh), stats);
      },
      py::arg("points"), py::kw_only(), py::arg("normals") = py::none(),
      py::arg("colors") = py::none(), py::arg("k") = fo.k, py::arg("alpha_deg") = fo.alpha_deg,
      py::arg("dmax_factor") = fo.dmax_factor, py::arg("max_edge") = fo.max_edge,
      py::arg("max_edge_factor") = fo.max_edge_factor,
      py::arg("max_normal_angle_deg") = fo.max_normal_angle_deg,
      py::arg("max_hole_edges") = fo.max_hole_edges, py::arg("pca_normals") = fo.pca_normals,
      py::arg("orient_away_from_axis") = fo.orient_away_from_axis, py::arg("seed") = fo.seed,
      py::arg("threads") = fo.threads, py::arg("growth_block_points") = fo.growth_block_points,
      R"doc(
Seed 002's point-cloud fans (build_fans, as `scanmesh fans`; docs/fans.md). points: an (N, 3)
array (optionally with normals (N, 3), which decide the outside, and colors (N, 3) uint8) or a
PointCloud (read_point_cloud; non-finite points dropped). The keyword arguments are FanOptions
with the library defaults: k (points per cell), alpha_deg (completeness angle), dmax_factor,
max_edge, max_edge_factor, max_normal_angle_deg, max_hole_edges, pca_normals,
orient_away_from_axis (the CLI sets it for .smg clouds), seed, threads (0: all; the output does
not depend on it), growth_block_points (parallel surface growth in blocks of about this many
points; 0: one growth). The mesh's vertices are the input points, in order.
Returns (Mesh, stats dict). ValueError with the library's message for invalid options, fewer
than 3 points or non-finite coordinates.)doc");
}

// remesh(): the CLI's range checks, the scan clean-up, remeshing, and the report.
py::tuple remesh_and_report(
    const Mesh& mesh, int target_vertices, py::handle prepare, std::optional<int> min_component,
    std::optional<int> fill_holes, std::optional<double> needle_angle_deg, bool remove_spikes,
    std::optional<double> tip_angle_deg, const std::string& scheme,
    std::optional<std::filesystem::path> features, double sharp_angle_deg, double kink_angle_deg,
    double kink_window, double kink_reach_mm, bool label_borders, double gamma, int n_filter,
    double clip, double curvature_radius, double gradation, double theta_dist_deg,
    double theta_glatt_deg, int adapt_iterations, int n_area, int n_step, int drive_limit,
    bool regularize_queue, bool prevent_intersections, int smoothing_passes, int polish_rounds,
    double polish_angle_deg, int polish_flip_cost, double polish_floor_deg,
    double polish_floor_glatt_deg, double polish_floor_dist_deg, bool quality) {
  using namespace remeshing;
  // The CLI's range checks (cmd_remesh.cpp), for the options remesh() takes as given.
  const char* w = "remesh";
  require_range(w, "sharp_angle_deg", sharp_angle_deg, 0, 180);
  require_range(w, "kink_angle_deg", kink_angle_deg, 0, 180);
  require_range(w, "kink_window", kink_window, 0, 1e6);
  require_range(w, "kink_reach_mm", kink_reach_mm, 0, 1e6);
  require_range(w, "gamma", gamma, 0, 10);
  require_range(w, "n_filter", n_filter, 0, 1000);
  require_range(w, "clip", clip, 1, 1000);
  require_range(w, "curvature_radius", curvature_radius, -1, 1e6);
  require_range(w, "gradation", gradation, 0, 1000);
  require_range(w, "theta_dist_deg", theta_dist_deg, 0, 180);
  require_range(w, "theta_glatt_deg", theta_glatt_deg, 0, 180);
  require_range(w, "adapt_iterations", adapt_iterations, 0, 1000);
  require_range(w, "n_area", n_area, 0, 1000);
  require_range(w, "n_step", n_step, 0, 1000);
  require_range(w, "drive_limit", drive_limit, 0, 1000);
  require_range(w, "smoothing_passes", smoothing_passes, 0, 1000);
  require_range(w, "polish_rounds", polish_rounds, 0, 1000);
  require_range(w, "polish_angle_deg", polish_angle_deg, 0, 60);
  require_range(w, "polish_flip_cost", polish_flip_cost, 0, 1000);
  require_range(w, "polish_floor_deg", polish_floor_deg, 0, 60);
  require_range(w, "polish_floor_glatt_deg", polish_floor_glatt_deg, 0, 180);
  require_range(w, "polish_floor_dist_deg", polish_floor_dist_deg, 0, 180);
  RemeshOptions o;
  o.target_vertices = target_vertices;
  o.scheme = parse_remesh_scheme(scheme);
  SCANMESH_SET_FIELDS(o.skeleton, sharp_angle_deg, kink_angle_deg, kink_window, kink_reach_mm,
                      label_borders);
  SCANMESH_SET_FIELDS(o.density, gamma, n_filter, clip, curvature_radius, gradation);
  SCANMESH_SET_FIELDS(o, theta_dist_deg, theta_glatt_deg, adapt_iterations, n_area, n_step,
                      drive_limit, regularize_queue, prevent_intersections, smoothing_passes,
                      polish_rounds, polish_angle_deg, polish_flip_cost, polish_floor_deg,
                      polish_floor_glatt_deg, polish_floor_dist_deg);
  if (features) o.features = read_feature_lines(*features);
  bool prepared = false;
  const PrepareOptions po =
      choose_prepare(mesh, target_vertices, prepare, min_component, fill_holes, needle_angle_deg,
                     remove_spikes, tip_angle_deg, prepared);
  PrepareStats ps;
  RemeshResult r;
  std::string quality_json;
  {
    py::gil_scoped_release release;
    const Mesh input = prepare_input(mesh, po, &ps);
    r = remesh(input, o);
    // As the CLI: a count missed by more than 1 % raises (ValueError), it is no result.
    require_vertex_count(r, target_vertices, topology_stats(input).boundary_loops);
    if (quality) quality_json = evaluate_remesh(input, r).to_json();
  }
  py::dict report;
  report["stats"] = remesh_stats(r.stats);
  report["prepared"] = prepared;
  report["prepare"] = prepare_stats(ps);
  std::vector<std::uint8_t> kind(r.kind.size());
  for (std::size_t v = 0; v < r.kind.size(); ++v) kind[v] = static_cast<std::uint8_t>(r.kind[v]);
  const auto nv = static_cast<py::ssize_t>(kind.size());
  report["vertex_kind"] = owned(std::move(kind), {nv});
  const auto nd = static_cast<py::ssize_t>(r.density.size());
  report["density"] = owned(std::move(r.density), {nd});
  if (quality) report["quality"] = py::module_::import("json").attr("loads")(quality_json);
  return py::make_tuple(std::move(r.mesh), report);
}

void bind_remeshing(py::module_& m) {
  const remeshing::RemeshOptions ro;
  m.def("remesh", &remesh_and_report, py::arg("mesh"),
        py::arg("target_vertices") = ro.target_vertices, py::kw_only(), py::arg("prepare") = "auto",
        py::arg("min_component") = py::none(), py::arg("fill_holes") = py::none(),
        py::arg("needle_angle_deg") = py::none(), py::arg("remove_spikes") = false,
        py::arg("tip_angle_deg") = py::none(), py::arg("scheme") = to_string(ro.scheme),
        py::arg("features") = py::none(), py::arg("sharp_angle_deg") = ro.skeleton.sharp_angle_deg,
        py::arg("kink_angle_deg") = ro.skeleton.kink_angle_deg,
        py::arg("kink_window") = ro.skeleton.kink_window,
        py::arg("kink_reach_mm") = ro.skeleton.kink_reach_mm,
        py::arg("label_borders") = ro.skeleton.label_borders, py::arg("gamma") = ro.density.gamma,
        py::arg("n_filter") = ro.density.n_filter, py::arg("clip") = ro.density.clip,
        py::arg("curvature_radius") = ro.density.curvature_radius,
        py::arg("gradation") = ro.density.gradation, py::arg("theta_dist_deg") = ro.theta_dist_deg,
        py::arg("theta_glatt_deg") = ro.theta_glatt_deg,
        py::arg("adapt_iterations") = ro.adapt_iterations, py::arg("n_area") = ro.n_area,
        py::arg("n_step") = ro.n_step, py::arg("drive_limit") = ro.drive_limit,
        py::arg("regularize_queue") = ro.regularize_queue,
        py::arg("prevent_intersections") = ro.prevent_intersections,
        py::arg("smoothing_passes") = ro.smoothing_passes,
        py::arg("polish_rounds") = ro.polish_rounds,
        py::arg("polish_angle_deg") = ro.polish_angle_deg,
        py::arg("polish_flip_cost") = ro.polish_flip_cost,
        py::arg("polish_floor_deg") = ro.polish_floor_deg,
        py::arg("polish_floor_glatt_deg") = ro.polish_floor_glatt_deg,
        py::arg("polish_floor_dist_deg") = ro.polish_floor_dist_deg, py::arg("quality") = false,
        R"doc(
Seed 001 adaptive remeshing to a vertex count (remesh, as `scanmesh remesh`; docs/remeshing.md).
prepare: "auto" (the CLI's default: the scan clean-up runs when the input looks like a scan),
True or False; min_component, fill_holes, needle_angle_deg, remove_spikes, tip_angle_deg
override the clean-up as the CLI's options of those names do. The other keyword arguments are
RemeshOptions with the library defaults (scheme "regularize" | "lloyd"; the skeleton's
sharp_angle_deg (0: off; the CLI's `--features auto` is 60), kink_angle_deg, kink_window,
kink_reach_mm, label_borders; the density's gamma, n_filter, clip, curvature_radius,
gradation; theta_dist_deg, theta_glatt_deg, ...); features: a feature-lines file.
Unlike the CLI, a vertex count missed by more than 1 % is not an error: compare
report["stats"]["output_vertices"]. quality=True adds report["quality"] (evaluate_remesh).
Returns (Mesh, report dict: stats, prepared, prepare, vertex_kind (uint8 per output vertex: 0
free, 1 skeleton, 2 branch), density (Psi per input vertex)). ValueError for an empty mesh, a
target outside [4, 10^7] or an option outside the CLI's range.)doc");
}

void bind_animesh(py::module_& m) {
  m.def(
      "animesh",
      [](const RangeGrid& grid, std::optional<std::filesystem::path> lines,
         std::optional<std::filesystem::path> settings, std::optional<std::string> data_border,
         const std::string& line_rows, std::optional<std::uint64_t> seed,
         std::optional<std::string> strategy) {
        std::optional<aft::EdgeStrategy> order;
        if (strategy) {
          if (*strategy == "random")
            order = aft::EdgeStrategy::Random;
          else if (*strategy == "shortest")
            order = aft::EdgeStrategy::Shortest;
          else if (*strategy == "longest")
            order = aft::EdgeStrategy::Longest;
          else
            throw InvalidInputError("animesh: strategy must be random, shortest or longest, got '" +
                                    *strategy + "'");
        }
        std::unique_ptr<aft::RegionSetup> l;
        aft::AnimationMesh am;
        aft::AnimationMeshQuality q;
        MeshCheckReport check;
        {
          py::gil_scoped_release release;
          l = std::make_unique<aft::RegionSetup>(
              aft::set_up_regions(grid, lines, settings, data_border, line_rows));
          if (seed) l->settings.seed = *seed;
          if (order) l->settings.strategy = *order;
          am = aft::build_animation_mesh(l->graph, l->lines, *l->surface, l->settings);
          q = aft::evaluate_quality(am, *l->surface, 6, &l->graph);
          check = check_mesh(am.mesh);
        }
        py::dict report = animesh_report(*l, am, q, check);
        return py::make_tuple(std::move(am.mesh), report);
      },
      py::arg("grid"), py::arg("lines") = py::none(), py::arg("settings") = py::none(),
      py::kw_only(), py::arg("data_border") = py::none(), py::arg("line_rows") = "top",
      py::arg("seed") = py::none(), py::arg("strategy") = py::none(), R"doc(
Seed 000's animation mesh (as `scanmesh animesh`; docs/animation-meshes.md): the animation
lines file (.svg / .json; None: the data border only) cut the scan surface into regions, the
region settings file (.yaml / .json; None: defaults) gives their unit sizes and meshers, each
region is meshed by advancing fronts (or surface Delaunay) and all are stitched.
data_border: "auto" | "on" | "off" (None: the settings' value, else auto); line_rows: how the
files' y coordinates count, "top" (texture rows down from the top of the upright picture, the
convention) or "bottom" (older files; the CLI's --line-rows); seed and strategy
("random" | "shortest" | "longest") override the settings. Returns (Mesh with face_labels =
region index, report dict: counts, quality, regions, check, complete (False where the CLI exits
with "incomplete mesh"), params ((phi, h) per vertex), line_edges, seams, data_border).
FileFormatError (ValueError) for malformed lines or settings, naming the file.)doc");
}

void bind_regions(py::module_& m) {
  m.def(
      "regions",
      [](const RangeGrid& grid, std::optional<std::filesystem::path> lines,
         std::optional<std::filesystem::path> settings, std::optional<std::string> data_border,
         const std::string& line_rows) {
        std::unique_ptr<aft::RegionSetup> l;
        {
          py::gil_scoped_release release;
          l = std::make_unique<aft::RegionSetup>(
              aft::set_up_regions(grid, lines, settings, data_border, line_rows));
        }
        py::dict d;
        d["regions"] = regions_list(l->graph);
        d["data_border"] = border_dict(*l);
        d["text"] = l->graph.to_text();
        return d;
      },
      py::arg("grid"), py::arg("lines") = py::none(), py::arg("settings") = py::none(),
      py::kw_only(), py::arg("data_border") = py::none(), py::arg("line_rows") = "top", R"doc(
The region analysis of animation lines over a grid (as `scanmesh regions`; options as for
animesh). Returns a dict:
regions (list of dicts: index, name, opening, area, unit_mm, mesher, label_point (phi, h)),
data_border, text (the CLI's summary).)doc");
}

}  // namespace

void init_meshing(py::module_& m) {
  bind_grid_mesh(m);
  bind_fans(m);
  bind_remeshing(m);
  bind_animesh(m);
  bind_regions(m);
}

}  // namespace scanmesh::python
