// scanmesh: one binary, one subcommand per pipeline stage (docs/cli.md).
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>

#include "cli_support.h"
#include "commands.h"

namespace {

using namespace scanmesh::cli;

void add_cleaning_options(CLI::App& cmd, scanmesh::CleaningOptions& o) {
  cmd.add_option("--spike-mm", o.spike_threshold_mm,
                 "Spike threshold above the neighbour median (mm)")
      ->capture_default_str()
      ->check(in_range(0, 1e4));
  cmd.add_option("--spike-spread", o.spike_spread_factor,
                 "Extra threshold in units of the prediction spread")
      ->capture_default_str()
      ->check(in_range(0, 1e3));
  cmd.add_option("--min-fragment", o.min_component_cells, "Pieces with fewer cells are removed")
      ->capture_default_str()
      ->check(in_range(1, 1e8));
}

void add_mesh_options(CLI::App& cmd, scanmesh::GridMeshOptions& o) {
  cmd.add_option("--max-jump", o.max_depth_jump_mm,
                 "No triangles across depth jumps above this (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  cmd.add_flag("!--open-seam", o.close_seam, "Do not connect the last phi column to the first");
}

}  // namespace

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f) must end a write with an error (EFBIG: exit 5, the staged
  // outputs removed), not kill the process with SIGXFSZ half way (exit 153, a texture and a
  // temporary left behind).
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"scanmesh: rotary laser scans to range grids to meshes", "scanmesh"};
  app.set_version_flag("--version", SCANMESH_VERSION);
  app.require_subcommand(1);

  SimArgs sim;
  auto* sim_cmd =
      app.add_subcommand("sim", "Simulate a cylindrical range scan: scene + scanner -> grid file");
  sim_cmd->add_option("--scene", sim.scene, "Scene YAML (default: built-in head)")
      ->check(CLI::ExistingFile);
  sim_cmd->add_option("--scanner", sim.scanner, "Scanner YAML (default: built-in head scanner)")
      ->check(CLI::ExistingFile);
  sim_cmd->add_option("--seed", sim.seed, "Random seed of all defects")->check(seed_range());
  sim_cmd->add_option("--noise", sim.noise_sigma_mm, "Range noise sigma (mm)")
      ->check(in_range(0, 1e3));
  sim_cmd->add_option("-o,--out", sim.out, "Output grid file (.smg)")->required();

  InfoArgs info;
  auto* info_cmd = app.add_subcommand("info", "Describe a grid (.smg) or mesh (.ply .off .obj .stl) file");
  info_cmd->add_option("file", info.file, "Grid or mesh file")->required();

  ExportArgs exp;
  auto* export_cmd =
      app.add_subcommand("export", "Export a grid to PCD / PLY points / texture and depth PNG");
  export_cmd->add_option("grid", exp.grid, "Grid file (.smg)")->required();
  export_cmd->add_option("--pcd", exp.pcd, "Organised PCD point cloud");
  export_cmd->add_option("--ply", exp.ply, "PLY point cloud of the valid cells");
  export_cmd->add_option("--texture", exp.texture, "Texture PNG (pixel x, y = phi, h index)");
  export_cmd->add_option("--depth", exp.depth, "Depth picture PNG");

  CleanArgs clean;
  auto* clean_cmd = app.add_subcommand("clean", "Remove spikes and isolated fragments from a grid");
  clean_cmd->add_option("grid", clean.grid, "Grid file (.smg)")->required();
  clean_cmd->add_option("-o,--out", clean.out, "Cleaned grid file (.smg)")->required();
  add_cleaning_options(*clean_cmd, clean.options);
  clean_cmd
      ->add_option("--fill-holes", clean.fill_holes,
                   "Afterwards fill interior holes of at most this many cells (0: off)")
      ->check(in_range(0, 1e8))
      ->default_val(0);

  GridMeshArgs gm;
  auto* gm_cmd =
      app.add_subcommand("grid-mesh", "Triangulate a grid: two triangles per valid cell quad");
  gm_cmd->add_option("grid", gm.grid, "Grid file (.smg)")->required();
  gm_cmd->add_option("-o,--out", gm.out_ply, "Mesh PLY");
  gm_cmd->add_option("--obj", gm.out_obj, "Mesh OBJ (+ .mtl and <stem>_texture.png)");
  gm_cmd->add_option("--stl", gm.out_stl, "Mesh STL");
  gm_cmd->add_option("--render", gm.render_png, "Shaded picture of the mesh (PNG)");
  add_mesh_options(*gm_cmd, gm.options);

  RenderArgs render;
  auto* render_cmd = app.add_subcommand(
      "render", "Render a mesh (.ply .off .obj .stl) or a point cloud (.xyz .pcd) to a shaded PNG");
  render_cmd
      ->add_option("mesh", render.mesh,
                   "Mesh (.ply .off .obj .stl) or point cloud (.xyz .txt .pts .pcd, or a PLY "
                   "without faces): drawn as points")
      ->required();
  render_cmd->add_option("-o,--out", render.out, "Output PNG")->required();
  render_cmd->add_option("--size", render.size, "Image size in pixels")
      ->capture_default_str()
      ->check(in_range(16, 8192));
  render_cmd->add_option("--azimuth", render.azimuth_deg, "Camera azimuth (deg)")
      ->capture_default_str()
      ->check(in_range(-360, 360));
  render_cmd->add_option("--elevation", render.elevation_deg, "Camera elevation (deg)")
      ->capture_default_str()
      ->check(in_range(-90, 90));
  render_cmd->add_flag("--wireframe", render.wireframe, "Draw triangle edges");

  CurvatureArgs curv;
  auto* curv_cmd = app.add_subcommand(
      "curvature", "Normals and curvature of a grid: fields file, pictures and curvature.json");
  curv_cmd->add_option("grid", curv.grid, "Grid file (.smg)")->required();
  curv_cmd->add_option("-o,--out", curv.out, "Output folder")->required();
  curv_cmd
      ->add_option("--method", curv.method,
                   "analytic, grid-quadric, quadric or seed (seed 000's operator)")
      ->capture_default_str()
      ->check(CLI::IsMember({"analytic", "grid-quadric", "quadric", "seed", "seed000"}));
  curv_cmd
      ->add_option("--radius", curv.radius_mm,
                   "Neighbourhood radius of the quadric fit (mm; 0: default)")
      ->capture_default_str()
      ->check(in_range(0, 1e4));

  FansArgs fans;
  auto* fans_cmd = app.add_subcommand(
      "fans", "Mesh an unorganised point cloud with seed 002's point-cloud fans");
  fans_cmd->add_option("cloud", fans.cloud, "Point cloud (.ply, .pcd, .xyz/.txt/.pts, .smg)")
      ->required();
  fans_cmd->add_option("-o,--out", fans.out, "Output mesh (.ply)")->required();
  fans_cmd->add_option("--alpha", fans.options.alpha_deg, "Completeness angle (deg)")
      ->capture_default_str()
      ->check(in_range(30, 179.9));
  fans_cmd->add_option("--dmax", fans.options.dmax_factor, "Largest search radius (x cell edge)")
      ->capture_default_str()
      ->check(above(0, 100));
  fans_cmd->add_option("--k", fans.options.k, "Expected points per grid cell")
      ->capture_default_str()
      ->check(in_range(1, 1000));
  fans_cmd->add_option("--max-edge", fans.options.max_edge, "Longest edge (input units; 0: off)")
      ->capture_default_str()
      ->check(in_range(0, 1e9));
  fans_cmd
      ->add_option("--max-edge-factor", fans.options.max_edge_factor,
                   "Longest edge as a multiple of the local spacing (0: off)")
      ->capture_default_str()
      ->check(in_range(0, 1e6));
  fans_cmd
      ->add_option("--max-normal-angle", fans.options.max_normal_angle_deg,
                   "Largest angle between neighbouring normals (deg; 0: off)")
      ->capture_default_str()
      ->check(in_range(0, 180));
  fans_cmd
      ->add_option("--max-hole", fans.options.max_hole_edges,
                   "Close holes left between fans up to this many edges (0: off)")
      ->capture_default_str()
      ->check(in_range(0, 1e6));
  fans_cmd->add_flag("--pca-normals", fans.options.pca_normals, "PCA normals for every point");
  fans_cmd->add_option("--threads", fans.options.threads, "Threads (0: all)")
      ->capture_default_str()
      ->check(in_range(0, scanmesh::FanOptions::kMaxThreads));
  fans_cmd->add_option("--render", fans.render_png, "Shaded picture of the mesh (PNG)");
  fans_cmd->add_option("--histogram", fans.histogram_png, "Min-angle histogram (PNG)");
  fans_cmd->add_option("--report", fans.report,
                       "JSON report: stage statistics, topology and the checker's verdicts");
  fans_cmd->add_flag("--check", fans.check, "Print the mesh checker's report");

  CheckArgs check;
  auto* check_cmd = app.add_subcommand(
      "check", "Mesh checker: duplicates, non-manifold edges/vertices, self-intersections, holes");
  check_cmd->add_option("mesh", check.mesh, "Mesh (.ply, .off, .obj, .stl)")->required();
  check_cmd->add_option("--histogram", check.histogram_png, "Min-angle histogram (PNG)");
  check_cmd->add_flag("--no-intersections", check.skip_intersections,
                      "Skip the self-intersection test");
  check_cmd->add_option("--require", check.require,
                        "Comma-separated properties that set the exit code (10 when one fails): "
                        "non-empty, closed, edge-manifold, vertex-manifold, oriented, "
                        "intersection-free, no-degenerate, no-duplicates");

  ParticlesArgs particles;
  auto* particles_cmd = app.add_subcommand(
      "particles", "Seed 003 spring-network mesh of an implicit scene, animation or scan surface");
  particles_cmd->add_option("scene", particles.scene, "Scene YAML (static or with keyframes)")
      ->check(CLI::ExistingFile);
  particles_cmd->add_option("--grid", particles.grid, "Mesh a scan's continuous surface (.smg)")
      ->check(CLI::ExistingFile);
  particles_cmd->add_option("--edge", particles.edge, "Target edge length R (mm)")
      ->required()
      ->check(above(0, 1e6));
  particles_cmd->add_flag("--adaptive", particles.adaptive, "Curvature-adaptive rest lengths");
  particles_cmd->add_option("--frames", particles.frames, "Frames of an animated scene")
      ->capture_default_str()
      ->check(in_range(1, 100000));
  particles_cmd->add_option("--steps", particles.steps_per_frame, "Iterations per frame")
      ->capture_default_str()
      ->check(in_range(1, 100000));
  particles_cmd->add_flag("--no-flips", particles.no_flips, "Disable edge flips to valence 6");
  particles_cmd->add_option("--seed", particles.seed, "Random seed")
      ->capture_default_str()
      ->check(seed_range());
  particles_cmd->add_option("-o,--out", particles.out, "Output folder")->required();

  DemoArgs demo;
  auto* demo_cmd =
      app.add_subcommand("demo", "Simulated head scan -> clean grid -> mesh, pictures and report");
  demo_cmd->add_option("-o,--out", demo.out, "Output folder")->capture_default_str();
  demo_cmd->add_option("--scene", demo.scene, "Scene YAML (default: built-in head)")
      ->check(CLI::ExistingFile);
  demo_cmd->add_option("--scanner", demo.scanner, "Scanner YAML (default: built-in head scanner)")
      ->check(CLI::ExistingFile);
  demo_cmd->add_option("--seed", demo.seed, "Random seed of all defects")->check(seed_range());
  add_cleaning_options(*demo_cmd, demo.cleaning);
  add_mesh_options(*demo_cmd, demo.meshing);
  add_device_demo_options(*demo_cmd, demo.device);

  // Stages added later register their subcommands here, one line each (commands.h).
  CommandList commands;
  register_vision_commands(app, commands);
  register_devices_commands(app, commands);
  register_aft_commands(app, commands);
  register_remesh_commands(app, commands);
  register_serve_commands(app, commands);
  register_measure_commands(app, commands);
  register_import_commands(app, commands);
  add_output_flags(app);  // --json and --quiet on every subcommand (docs/cli.md, "Output")

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One clear line, then where to look; never CLI11's multi-line dump.
    std::cerr << "scanmesh: usage error: " << e.what() << " (see 'scanmesh "
              << (app.get_subcommands().empty() ? ""
                                                : app.get_subcommands().front()->get_name() + " ")
              << "--help')\n";
    return kUsageError;
  }
  set_output_mode(parsed_output_mode(app));

  return run_guarded([&] {
    for (const auto& c : commands)
      if (*c.command) return c.run();
    if (*sim_cmd) return run_sim(sim);
    if (*info_cmd) return run_info(info);
    if (*export_cmd) return run_export(exp);
    if (*clean_cmd) return run_clean(clean);
    if (*gm_cmd) return run_grid_mesh(gm);
    if (*render_cmd) return run_render(render);
    if (*curv_cmd) return run_curvature(curv);
    if (*fans_cmd) return run_fans(fans);
    if (*check_cmd) return run_check(check);
    if (*particles_cmd) return run_particles(particles);
    return run_demo(demo);
  });
}
