// Subcommands of the point-cloud fan mesher (seed 002): fans, and the shared mesh checker.
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "pipeline.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/meshing/fans/fans.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::cli {

namespace {

struct FansArgs {
  std::string cloud;  //!< .ply, .pcd, .xyz/.txt/.pts or .smg (valid cells)
  std::string out;
  std::string render_png, histogram_png;
  std::string report;  //!< JSON: stage statistics and the checker's verdicts
  bool check = false;  //!< print the checker report of the result
  FanOptions options;
};

struct CheckArgs {
  std::string mesh;
  std::string histogram_png;
  bool skip_intersections = false;
  std::string require;  //!< comma-separated MeshProperty names that decide the exit code
};

// The checker's report with one verdict per property (null where it was not tested): the
// "check" block of the fans report and what `check --json` prints.
nlohmann::json check_json(const MeshCheckReport& check) {
  nlohmann::json verdicts, evidence;
  for (const PropertyVerdict& v : mesh_verdicts(check)) {
    verdicts[property_name(v.property)] = v.known ? nlohmann::json(v.holds) : nlohmann::json();
    evidence[property_name(v.property)] = v.evidence;
  }
  const TopologyStats& t = check.topology;
  return {{"vertices", check.vertices},
          {"faces", check.faces},
          {"edges", t.edges},
          {"nonmanifold_vertices", check.nonmanifold_vertices},
          {"nonmanifold_edges", t.nonmanifold_edges},
          {"inconsistently_oriented_edges", t.inconsistent_edges},
          {"duplicate_faces", check.duplicate_faces},
          {"degenerate_faces", check.degenerate_faces},
          {"self_intersections", check.self_intersections_checked
                                     ? nlohmann::json(check.self_intersections)
                                     : nlohmann::json()},
          {"boundary_loops", t.boundary_loops},
          {"boundary_loop_lengths", t.boundary_loop_lengths},
          {"unreferenced_vertices", t.unreferenced_vertices},
          {"components", t.components},
          {"euler_characteristic", t.euler_characteristic},
          {"genus", t.genus()},
          {"min_angle_deg", check.min_angle_deg},
          {"mean_min_angle_deg", check.mean_min_angle_deg},
          {"min_radius_ratio", check.min_radius_ratio},
          {"mean_radius_ratio", check.mean_radius_ratio},
          {"fraction_min_angle_ge_30", check.fraction_min_angle_ge_30},
          {"min_angle_histogram_5deg", check.min_angle_histogram},
          {"verdicts", verdicts},
          {"evidence", evidence}};
}

// What was meshed, how the stages went and the checker's verdicts (docs/formats.md).
nlohmann::json fans_report_json(const std::string& input, const PointCloud& cloud,
                                const FanResult& r, const MeshCheckReport* check) {
  const FanStats& s = r.stats;
  nlohmann::json j = {
      {"input", input},
      {"points", s.points},
      {"input_colours", cloud.has_colors()},
      {"input_normals", cloud.has_normals()},
      {"triangles", r.mesh.face_count()},
      {"duplicate_points", s.duplicate_points},
      {"seconds",
       {{"normals", s.seconds_normals},
        {"fans", s.seconds_fans},
        {"assembly", s.seconds_assembly}}},
      {"fans",
       {{"cell_edge", s.cell_edge},
        {"pca_fallbacks", s.pca_fallbacks},
        {"open_fans", s.open_fans},
        {"candidates", s.proposed_triangles},
        {"unused_candidates", s.rejected_triangles}}},
      {"surface_growth",
       {{"seeds", s.seeds},
        {"blocks", s.growth_blocks},
        {"blocks_discarded", s.growth_blocks_discarded},
        {"glued_triangles", s.glued_triangles},
        {"glues_taken_back", s.unzipped_glues},
        {"hole_triangles", s.hole_triangles},
        {"inserted_points", s.inserted_points},
        {"delaunay_flips", s.delaunay_flips},
        {"bowtie_faces_removed", s.bowtie_faces_removed},
        {"unused_points", s.unused_points}}},
  };
  if (check) j["check"] = check_json(*check);
  return j;
}

int run_fans(const FansArgs& args) {
  args.options.validate();
  const PointCloud cloud = read_point_cloud(args.cloud);
  FanOptions options = args.options;
  // A grid's cells come from a turntable scan: their outside is away from the axis.
  if (std::filesystem::path(args.cloud).extension() == ".smg") options.orient_away_from_axis = true;
  FanResult result;
  try {
    result = build_fans(cloud, options);
  } catch (const InvalidInputError& e) {
    // The cloud itself cannot be meshed (too few points, all coincident, a crowded cluster):
    // name the file.
    throw InvalidInputError(args.cloud + ": " + e.what());
  }
  const FanStats& s = result.stats;
  const bool need_check = !args.histogram_png.empty() || args.check || !args.report.empty() ||
                          output_mode() == OutputMode::Json;
  const MeshCheckReport report = need_check ? check_mesh(result.mesh) : MeshCheckReport{};
  // The mesh, its pictures and its report appear together or not at all.
  StagedFiles outputs;
  write_ply(outputs.stage(args.out), result.mesh);
  if (!args.render_png.empty())
    write_png(outputs.stage(args.render_png), render_views(result.mesh));
  if (!args.histogram_png.empty())
    write_min_angle_histogram_png(outputs.stage(args.histogram_png), report);
  const nlohmann::json summary =
      fans_report_json(args.cloud, cloud, result, need_check ? &report : nullptr);
  if (!args.report.empty())
    write_file_atomically(outputs.stage(args.report), json_text(summary) + "\n");
  outputs.commit();
  std::ostringstream text;
  text << std::fixed << std::setprecision(3) << "fans: " << s.points << " points -> "
       << result.mesh.face_count() << " triangles in "
       << s.seconds_normals + s.seconds_fans + s.seconds_assembly << " s (normals "
       << s.seconds_normals << ", fans " << s.seconds_fans << ", assembly " << s.seconds_assembly
       << ")\n"
       << "  cell edge " << s.cell_edge << ", PCA fallbacks " << s.pca_fallbacks << ", open fans "
       << s.open_fans << ", unused candidates " << s.rejected_triangles << ", hole triangles "
       << s.hole_triangles << ", inserted points " << s.inserted_points << ", unused points "
       << s.unused_points << "\n"
       << "  surface growth: " << s.growth_blocks << " block(s)"
       << (s.growth_blocks_discarded ? " (" + std::to_string(s.growth_blocks_discarded) +
                                           " blocks discarded: the fronts did not close at a cut)"
                                     : std::string())
       << ", " << s.seeds << " seeds, " << s.glued_triangles << " glued triangles, "
       << s.unzipped_glues << " glues taken back, " << s.delaunay_flips << " Delaunay flips, "
       << s.bowtie_faces_removed << " faces off bow-ties\n";
  say() << text.str();
  if (args.check) say() << report.to_text();
  say() << "wrote " << args.out << "\n";
  cli::result() = summary;  // (`result` here is the fans' result)
  cli::result()["out"] = args.out;
  return kSuccess;
}

int run_check(const CheckArgs& args) {
  std::vector<MeshProperty> required;
  if (!args.require.empty()) required = parse_mesh_properties(args.require);
  const bool wants_intersections =
      std::find(required.begin(), required.end(), MeshProperty::IntersectionFree) != required.end();
  if (wants_intersections && args.skip_intersections)
    throw InvalidInputError(
        "--require intersection-free needs the self-intersection test, "
        "which --no-intersections skips");
  const Mesh mesh = read_mesh(args.mesh);
  const MeshCheckReport report = check_mesh(mesh, {.self_intersections = !args.skip_intersections});
  say() << args.mesh << "\n" << report.to_text();
  result() = check_json(report);
  result()["mesh"] = args.mesh;
  if (!args.histogram_png.empty()) write_min_angle_histogram_png(args.histogram_png, report);
  if (required.empty()) return report.edge_manifold() ? kSuccess : kNotEdgeManifold;
  // Only the required properties decide the exit code; each failing one is named on stderr.
  bool all_hold = true;
  for (const PropertyVerdict& v : mesh_verdicts(report)) {
    if (std::find(required.begin(), required.end(), v.property) == required.end()) continue;
    if (v.holds) continue;
    all_hold = false;
    std::cerr << "scanmesh check: " << args.mesh << " is not " << property_name(v.property)
              << (v.evidence.empty() ? "" : ": " + v.evidence) << "\n";
  }
  return all_hold ? kSuccess : kRequirementNotMet;
}

}  // namespace

void register_fans_commands(CLI::App& app, CommandList& commands) {
  auto fans = std::make_shared<FansArgs>();
  auto* fans_cmd = app.add_subcommand(
      "fans",
      "Mesh an unorganised point cloud: a triangle fan around every point, assembled "
      "into one manifold mesh");
  fans_cmd->add_option("cloud", fans->cloud, "Point cloud (.ply, .pcd, .xyz/.txt/.pts, .smg)")
      ->required();
  fans_cmd->add_option("-o,--out", fans->out, "Output mesh (.ply)")->required();
  fans_cmd->add_option("--alpha", fans->options.alpha_deg, "Completeness angle (deg)")
      ->capture_default_str()
      ->check(in_range(30, 179.9));
  fans_cmd->add_option("--dmax", fans->options.dmax_factor, "Largest search radius (x cell edge)")
      ->capture_default_str()
      ->check(above(0, 100));
  fans_cmd->add_option("--k", fans->options.k, "Expected points per grid cell")
      ->capture_default_str()
      ->check(in_range(1, 1000));
  fans_cmd->add_option("--max-edge", fans->options.max_edge, "Longest edge (input units; 0: off)")
      ->capture_default_str()
      ->check(in_range(0, 1e9));
  fans_cmd
      ->add_option("--max-edge-factor", fans->options.max_edge_factor,
                   "Longest edge as a multiple of the local spacing (0: off)")
      ->capture_default_str()
      ->check(in_range(0, 1e6));
  fans_cmd
      ->add_option("--max-normal-angle", fans->options.max_normal_angle_deg,
                   "Largest angle between neighbouring normals (deg; 0: off)")
      ->capture_default_str()
      ->check(in_range(0, 180));
  fans_cmd
      ->add_option("--max-hole", fans->options.max_hole_edges,
                   "Close holes left between fans up to this many edges (0: off)")
      ->capture_default_str()
      ->check(in_range(0, 1e6));
  fans_cmd->add_flag("--pca-normals", fans->options.pca_normals, "PCA normals for every point");
  fans_cmd
      ->add_option("--growth-block", fans->options.growth_block_points,
                   "Grow the surface in parallel blocks of about this many points (0: one "
                   "growth); kept only where the blocks' fronts close at every cut")
      ->capture_default_str();
  fans_cmd->add_option("--threads", fans->options.threads, "Threads (0: all)")
      ->capture_default_str()
      ->check(in_range(0, FanOptions::kMaxThreads));
  fans_cmd->add_option("--render", fans->render_png, "Shaded picture of the mesh (PNG)");
  fans_cmd->add_option("--histogram", fans->histogram_png, "Min-angle histogram (PNG)");
  fans_cmd->add_option("--report", fans->report,
                       "JSON report: stage statistics, topology and the checker's verdicts");
  fans_cmd->add_flag("--check", fans->check, "Print the mesh checker's report");
  commands.push_back({fans_cmd, [fans] { return run_fans(*fans); }});

  auto check = std::make_shared<CheckArgs>();
  auto* check_cmd = app.add_subcommand(
      "check", "Mesh checker: duplicates, non-manifold edges/vertices, self-intersections, holes");
  check_cmd->add_option("mesh", check->mesh, "Mesh (.ply, .off, .obj, .stl)")->required();
  check_cmd->add_option("--histogram", check->histogram_png, "Min-angle histogram (PNG)");
  check_cmd->add_flag("--no-intersections", check->skip_intersections,
                      "Skip the self-intersection test");
  check_cmd->add_option("--require", check->require,
                        "Comma-separated properties that set the exit code (10 when one fails): "
                        "non-empty, closed, edge-manifold, vertex-manifold, oriented, "
                        "intersection-free, no-degenerate, no-duplicates");
  commands.push_back({check_cmd, [check] { return run_check(*check); }});
}

}  // namespace scanmesh::cli
