// `scanmesh remesh`: seed 001 adaptive remeshing with feature skeleton (docs/remeshing.md).
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/remeshing/remesh.h"
#include "scanmesh/meshing/remeshing/remesh_quality.h"

namespace scanmesh::cli {

namespace {

// The options that map one to one onto the library's are bound straight to `options`; the
// fields beside it are the ones the command line says differently (a name for the scheme, a
// file or "auto" for the features, a flag for uniform density or no prevention).
struct RemeshArgs {
  std::string mesh;
  std::string out;
  remeshing::RemeshOptions options;
  std::string features;  // file, "auto" or empty
  double sharp_deg = 60.0;  // the sharp-edge angle of --features auto
  bool uniform = false;
  std::string scheme = "regularize";
  bool no_intersections = false;
  // The scan clean-up: auto (when the input looks like a scan), forced or off; each explicit
  // clean-up option overrides what auto chose.
  bool force_prepare = false, no_prepare = false;
  std::optional<int> min_component, fill_holes;
  std::optional<double> needle_angle, tip_angle;
  bool remove_spikes = false;
  bool allow_local_intersections = false;
  bool write_prepared = false;
};

remeshing::PrepareOptions choose_prepare(const Mesh& raw, const RemeshArgs& a) {
  using namespace remeshing;
  PrepareOptions po;
  const TopologyStats ts = topology_stats(raw);
  const bool scan = looks_like_scan(ts);
  if (!a.no_prepare && (a.force_prepare || scan)) {
    po = scan_prepare_options(raw, a.options.target_vertices);
    say() << "prepare: " << (scan ? "the input looks like a scan" : "asked for") << " ("
          << ts.boundary_loops << " boundary loops, " << ts.components << " components, "
          << ts.border_ears << " border ears): scan clean-up at the output's edge length "
          << po.tip_reach_mm << " mm (--no-prepare to skip)\n";
  }
  if (a.min_component) po.min_component_faces = *a.min_component;
  if (a.fill_holes) po.max_hole_edges = *a.fill_holes;
  if (a.needle_angle) po.needle_angle_deg = *a.needle_angle;
  if (a.remove_spikes && !po.remove_spikes) {
    po.remove_spikes = true;
    po.tip_reach_mm = uniform_edge_length(raw, a.options.target_vertices);
  }
  if (a.tip_angle) po.tip_angle_deg = *a.tip_angle;
  return po;
}

void print_prepare_stats(const remeshing::PrepareOptions& po, const remeshing::PrepareStats& ps) {
  if (ps.repeated_faces_removed > 0)
    say() << "prepare: " << ps.repeated_faces_removed
          << " faces removed that repeat an earlier face's corners\n";
  if (po.needle_angle_deg > 0)
    say() << "prepare: " << ps.degenerate_removed << " degenerate faces removed, "
          << ps.needles_welded << " needles welded, " << ps.caps_flipped << " caps flipped, "
          << ps.caps_removed << " caps removed\n";
  if (po.remove_spikes)
    say() << "prepare: " << ps.spike_faces_removed << " spike faces and " << ps.pinch_faces_removed
          << " faces at pinch vertices and " << ps.tip_faces_removed
          << " at border tips sharper than " << po.tip_angle_deg << " deg over " << po.tip_reach_mm
          << " mm removed, " << ps.neck_faces_removed << " at necks and veils thinner than "
          << 0.25 * po.tip_reach_mm << " mm\n";
  if (po.min_component_faces > 0 || po.min_component_area > 0 || po.max_hole_edges > 0 ||
      po.max_hole_perimeter > 0)
    say() << "prepare: removed " << ps.components_removed << " components (" << ps.faces_removed
          << " faces), closed " << ps.holes_filled << " holes (" << ps.faces_added << " faces)\n";
}

int run_remesh(const RemeshArgs& a) {
  using namespace remeshing;
  PrepareStats ps;
  const Mesh raw = read_mesh(a.mesh);
  OutputFolder folder(a.out);  // before the work: a bad --out fails at once
  const PrepareOptions po = choose_prepare(raw, a);
  const Mesh input = prepare_input(raw, po, &ps);
  print_prepare_stats(po, ps);
  std::size_t input_loops = 0;
  {
    const TopologyStats ts = topology_stats(input);
    input_loops = ts.boundary_loops;
    say() << "input: " << input.triangles.size() << " triangles, " << ts.boundary_loops
          << " boundary loops";
    if (!ts.boundary_loop_lengths.empty())
      say() << " (longest " << ts.boundary_loop_lengths.front() << " edges, shortest "
            << ts.boundary_loop_lengths.back() << ")";
    say() << ", " << ts.nonmanifold_edges << " non-manifold and " << ts.inconsistent_edges
          << " inconsistently oriented edges\n";
  }
  RemeshOptions o = a.options;
  o.scheme = parse_remesh_scheme(a.scheme);
  if (a.uniform) o.density.gamma = 0.0;
  o.prevent_intersections = !a.allow_local_intersections;
  if (a.features == "auto") {
    o.skeleton.sharp_angle_deg = a.sharp_deg;
  } else if (!a.features.empty()) {
    o.features = read_feature_lines(a.features);
  }
  auto progress = std::make_shared<Progress>("remesh");
  o.progress = [progress](const std::string&, double f) {
    progress->update(static_cast<int>(f * 100), 100);
  };
  const RemeshResult r = remesh(input, o);
  progress->finish();
  require_vertex_count(r, a.options.target_vertices, input_loops);
  const std::filesystem::path dir(a.out);
  StagedFiles outputs;  // all outputs or none
  write_ply(outputs.stage(dir / "mesh.ply"), r.mesh);
  if (a.write_prepared) write_ply(outputs.stage(dir / "prepared.ply"), input);
  const RemeshQuality q = evaluate_remesh(input, r, !a.no_intersections);
  const RemeshStats& s = r.stats;
  const nlohmann::json report = {
      {"input", a.mesh},
      {"target_vertices", a.options.target_vertices},
      {"scheme", a.scheme},
      {"gamma", o.density.gamma},
      {"n_filter", o.density.n_filter},
      {"curvature_radius", o.density.curvature_radius},
      {"gradation", o.density.gradation},
      {"prepare",
       {{"components_removed", ps.components_removed},
        {"holes_filled", ps.holes_filled},
        {"spike_faces_removed", ps.spike_faces_removed},
        {"pinch_faces_removed", ps.pinch_faces_removed},
        {"tip_faces_removed", ps.tip_faces_removed},
        {"neck_faces_removed", ps.neck_faces_removed},
        {"needles_welded", ps.needles_welded},
        {"repeated_faces_removed", ps.repeated_faces_removed}}},
      {"stats",
       {{"input_vertices", s.input_vertices},
        {"input_faces", s.input_faces},
        {"output_vertices", s.output_vertices},
        {"output_faces", s.output_faces},
        {"skeleton_segments", s.skeleton_segments},
        {"branch_vertices", s.branch_vertices},
        {"patches", s.patches},
        {"collapses", s.collapses},
        {"splits", s.splits},
        {"flips", s.flips},
        {"moves", s.moves},
        {"rejected_error", s.rejected_error},
        {"rejected_topology", s.rejected_topology},
        {"skeleton_splits", s.skeleton_splits},
        {"skeleton_collapses", s.skeleton_collapses},
        {"intersecting_faces_before_repair", s.intersecting_faces_before_repair},
        {"repair_splits", s.repair_splits},
        {"input_intersecting_faces", s.input_intersecting_faces},
        {"input_defect_zone_faces", s.input_defect_zone_faces},
        {"polish_bad_before", s.polish_bad_before},
        {"polish_bad_after", s.polish_bad_after},
        {"polish_moves", s.polish_moves},
        {"polish_flips", s.polish_flips},
        {"seconds_setup", s.seconds_setup},
        {"seconds_adapt", s.seconds_adapt},
        {"seconds_count", s.seconds_count},
        {"seconds_regularize", s.seconds_regularize},
        {"seconds_smooth", s.seconds_smooth},
        {"seconds_total", s.seconds_total}}},
      {"quality", nlohmann::json::parse(q.to_json())}};
  write_file_atomically(outputs.stage(dir / "report.json"), json_text(report) + "\n");
  write_png(outputs.stage(dir / "quality.png"), render_quality(r));
  write_png(outputs.stage(dir / "histograms.png"), quality_histograms(q));
  write_png(outputs.stage(dir / "density.png"), render_density(input, r.density));
  outputs.commit();
  folder.keep();
  std::ostringstream text;
  text << std::fixed << std::setprecision(3) << "remesh: " << s.input_vertices << " -> "
       << s.output_vertices << " vertices, " << s.output_faces << " faces in " << s.seconds_total
       << " s\n"
       << "  skeleton: " << s.skeleton_segments << " segments, " << s.branch_vertices
       << " branch vertices, " << s.patches << " patches\n"
       << "  min angle " << q.min_angle_deg
       << " deg, >= 30 deg: " << 100 * q.fraction_min_angle_ge_30 << " %, mean aspect ratio R/2r "
       << q.aspect_ratio_mean << ", irregular valence " << 100 * q.fraction_irregular << " %\n"
       << "  triangles < 30 deg at: branch " << q.bad_at_branch << ", boundary "
       << q.bad_at_boundary << ", other skeleton " << q.bad_at_skeleton << ", interior "
       << q.bad_interior
       << "\n"
       // %g: an input with a vertex at 1e308 printed 155 digits in fixed notation
       << "  Hausdorff " << format_number(q.hausdorff) << " mm ("
       << format_number(100 * q.hausdorff / q.bbox_diagonal)
       << " % of the diagonal), mean distance " << format_number(q.mean_distance) << " mm\n"
       << "  polish: faces < " << o.polish_angle_deg << " deg " << s.polish_bad_before << " -> "
       << s.polish_bad_after << " (" << s.polish_moves << " moves, " << s.polish_flips
       << " flips); repair splits " << s.repair_splits;
  if (q.self_intersections_checked)
    text << ", self-intersections " << q.self_intersections << " (faces cutting another "
         << "before the repair pass: " << s.intersecting_faces_before_repair << ")";
  if (s.input_intersecting_faces > 0)
    text << "\n  the input cuts itself: " << s.input_intersecting_faces
         << " faces cut another input face; within two output edges of them ("
         << s.input_defect_zone_faces
         << " input faces) the output follows the input's crossings and is checked for "
            "degenerate faces only";
  text << "\nwrote " << a.out << "/{mesh.ply,report.json,quality.png,histograms.png,density.png}\n";
  say() << text.str();
  result() = report;
  result()["out"] = a.out;
  return kSuccess;
}

}  // namespace

void register_remesh_commands(CLI::App& app, CommandList& commands) {
  auto args = std::make_shared<RemeshArgs>();
  auto* c = app.add_subcommand("remesh",
                               "Seed 001 adaptive remeshing to a vertex count, keeping seams, "
                               "boundaries and feature lines");
  c->add_option("mesh", args->mesh, "Input mesh (.ply with face labels kept, .off, .obj, .stl)")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--vertices", args->options.target_vertices, "Target vertex count")
      ->required()
      ->check(in_range(4, 1e8));
  c->add_option("--features", args->features,
                "Feature lines file (docs/formats.md) or 'auto' (sharp edges by dihedral angle)");
  c->add_option("--sharp", args->sharp_deg,
                "Dihedral angle (deg) of sharp edges for --features auto")
      ->check(in_range(0, 180));
  c->add_option("--kink-angle", args->options.skeleton.kink_angle_deg,
                "Turn (deg) of a skeleton chain that makes a fixed branch vertex (thesis: 60)")
      ->check(in_range(0, 180));
  c->add_option("--kink-reach", args->options.skeleton.kink_reach_mm,
                "Arc length (mm) over which kinks are measured (0: the mean target edge length)")
      ->check(in_range(0, 1e6));
  c->add_option("--gamma", args->options.density.gamma, "Density contrast gamma (0: uniform)")
      ->check(in_range(0, 10));
  c->add_option("--filter", args->options.density.n_filter,
                "n_filter smoothing passes of the density")
      ->check(in_range(0, 1000));
  c->add_option("--clip", args->options.density.clip,
                "Max ratio of target edge length to its median")
      ->check(in_range(1, 1000));
  c->add_flag("--uniform", args->uniform, "Uniform density (same as --gamma 0)");
  c->add_option("--curvature-radius", args->options.density.curvature_radius,
                "Radius (mm) the density's curvature is fitted over (-1: the output's mean edge "
                "length; 0: the input's 2-ring, as seed 001)")
      ->check(in_range(-1, 1e6));
  c->add_option("--gradation", args->options.density.gradation,
                "Largest slope of the target edge length over the surface (0: no limit)")
      ->check(in_range(0, 1000));
  c->add_option("--scheme", args->scheme, "regularize | lloyd")
      ->check(CLI::IsMember({"regularize", "lloyd"}));
  c->add_option("--theta-dist", args->options.theta_dist_deg, "E_dist threshold (deg)")
      ->check(in_range(0, 180));
  c->add_option("--theta-glatt", args->options.theta_glatt_deg, "E_glatt threshold (deg)")
      ->check(in_range(0, 180));
  c->add_flag("--no-intersections", args->no_intersections,
              "Skip the self-intersection test of the report");
  auto* prepare = c->add_flag("--prepare", args->force_prepare,
                              "Run the scan clean-up even when the input does not look like a "
                              "scan");
  c->add_flag("--no-prepare", args->no_prepare,
              "No scan clean-up (by default it runs when the input has more than 8 boundary "
              "loops or components); explicit clean-up options still apply")
      ->excludes(prepare);
  c->add_option("--min-component", args->min_component,
                "Drop connected components with fewer faces before remeshing (0: keep all; "
                "default: the clean-up's area rule)")
      ->check(in_range(0, 1e9));
  c->add_option("--fill-holes", args->fill_holes,
                "Close boundary loops with at most this many edges before remeshing (0: none; "
                "default: the clean-up's perimeter rule)")
      ->check(in_range(0, 1e6));
  c->add_option("--needle-angle", args->needle_angle,
                "Repair input triangles with a min angle below this (deg): degenerate faces "
                "dropped, needles welded, caps flipped (0: off)")
      ->check(in_range(0, 60));
  c->add_flag("--remove-spikes", args->remove_spikes,
              "Strip one-triangle-wide spikes and strands of a ragged border and the smaller "
              "fans at pinch vertices before remeshing");
  c->add_flag("--regularize-queue", args->options.regularize_queue,
              "Regularisation flips from a priority queue, worst valence deviation first");
  c->add_flag("--no-prevention", args->allow_local_intersections,
              "Do not refuse operations whose faces cut a neighbouring face (for measuring)");
  c->add_option("--tip-angle", args->tip_angle,
                "With --remove-spikes: border tips sharper than this (deg) over one target edge "
                "length are removed")
      ->check(in_range(0, 180));
  c->add_option("--polish-rounds", args->options.polish_rounds,
                "Angle polish rounds after the smoothing (0: off; docs/remeshing.md)")
      ->check(in_range(0, 1000));
  c->add_option("--polish-angle", args->options.polish_angle_deg,
                "The polish works on faces whose min angle is below this (deg)")
      ->check(in_range(0, 60));
  c->add_option("--polish-flip-cost", args->options.polish_flip_cost,
                "Largest valence cost (rise of R) of a polish flip; 4 = a flip in a regular patch")
      ->check(in_range(0, 1000));
  c->add_option("--polish-floor", args->options.polish_floor_deg,
                "Faces still below this min angle (deg) after the polish get more rounds with "
                "the normal error bounds widened (0: off)")
      ->check(in_range(0, 60));
  c->add_flag("--write-prepared", args->write_prepared,
              "Also write the cleaned-up input the remesher saw (DIR/prepared.ply)");
  c->add_option("--out", args->out, "Output directory")->required();
  commands.push_back({c, [args] { return run_remesh(*args); }});
}

}  // namespace scanmesh::cli
