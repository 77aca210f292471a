// Subcommands that produce or show meshes: grid-mesh, render.
#include <cctype>
#include <filesystem>
#include <memory>
#include <utility>
#include <vector>

#include "cli_support.h"
#include "commands.h"
#include "pipeline.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/point_cloud_io.h"

namespace scanmesh::cli {

namespace {

struct GridMeshArgs {
  std::string grid;
  std::string out_ply, out_obj, out_stl, render_png;
  GridMeshOptions options;
};

struct RenderArgs {
  std::string mesh;
  std::string out;
  int size = 640;
  double azimuth_deg = 180.0, elevation_deg = 10.0;
  bool wireframe = false;
};

// A depth-jump bound of more rows than this gets a note (the built-in head: 18 rows).
constexpr double kDepthJumpRowsNote = 64;

int run_grid_mesh(const GridMeshArgs& args) {
  if (args.out_ply.empty() && args.out_obj.empty() && args.out_stl.empty() &&
      args.render_png.empty())
    throw InvalidInputError("grid-mesh: name at least one output (--out, --obj, --stl, --render)");
  const RangeGrid grid = read_grid(args.grid);
  const GridMesh result = grid_mesh(grid, args.options);
  std::string texture_name;
  std::vector<std::filesystem::path> outputs{args.out_ply, args.out_obj, args.out_stl,
                                             args.render_png};
  if (!args.out_obj.empty()) {
    const std::filesystem::path obj(args.out_obj);
    texture_name = obj.stem().string() + "_texture.png";
    outputs.push_back(obj.parent_path() / texture_name);
    outputs.push_back(std::filesystem::path(obj).replace_extension(".mtl"));
  }
  NewFilesGuard created(outputs);  // a failure half way (a full disk) leaves no new file
  if (!args.out_obj.empty())
    export_texture_png(std::filesystem::path(args.out_obj).parent_path() / texture_name, grid);
  write_mesh_files(args.out_ply, args.out_obj, result.mesh, texture_name);
  if (!args.out_stl.empty()) write_stl(args.out_stl, result.mesh);
  if (!args.render_png.empty()) write_png(args.render_png, render_views(result.mesh));
  created.keep();
  say() << "meshed " << result.quads_meshed << " quads: " << result.mesh.vertex_count()
        << " vertices, " << result.mesh.face_count() << " triangles ("
        << result.quads_skipped_for_holes << " quads skipped at holes, "
        << result.quads_skipped_for_depth_jumps << " at depth jumps)\n";
  // The depth-jump bound is a length (8 mm suits the built-in scanner's ~1 mm cells); a grid
  // imported from a file in other units (lion-head: 0.7 units across) makes it hundreds of
  // rows, so it never fires and the mesh bridges the jumps (docs/acquisition.md).
  const double bound_rows = args.options.max_depth_jump_mm / grid.dh();
  if (bound_rows > kDepthJumpRowsNote)
    sayf(
        "note: --max-jump %g is %.0f rows of this grid (dh %.3g), so hardly any quad counts as "
        "a depth jump; for a grid in other units than mm try --max-jump %.3g (8 rows)\n",
        args.options.max_depth_jump_mm, bound_rows, grid.dh(), 8 * grid.dh());
  nlohmann::json& j = cli::result();
  j = {{"quads_meshed", result.quads_meshed},
       {"quads_skipped_for_holes", result.quads_skipped_for_holes},
       {"quads_skipped_for_depth_jumps", result.quads_skipped_for_depth_jumps},
       {"depth_jump_bound_rows", bound_rows},
       {"mesh", mesh_summary(result.mesh)}};
  for (const auto& [key, path] : {std::pair<const char*, const std::string&>{"ply", args.out_ply},
                                  {"obj", args.out_obj},
                                  {"stl", args.out_stl},
                                  {"render", args.render_png}})
    if (!path.empty()) j["outputs"][key] = path;
  return 0;
}

// A mesh file, or a point cloud (.xyz .txt .pts .pcd) as a mesh without triangles, which the
// renderer draws as points; a PLY without faces is a cloud already.
Mesh read_mesh_or_cloud(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".xyz" && ext != ".txt" && ext != ".pts" && ext != ".pcd") return read_mesh(path);
  const PointCloud cloud = read_point_cloud(path).finite_points();
  Mesh mesh;
  mesh.positions = cloud.positions;
  mesh.normals = cloud.normals;
  mesh.colors = cloud.colors;
  return mesh;
}

int run_render(const RenderArgs& args) {
  const Mesh mesh = read_mesh_or_cloud(args.mesh);
  write_png(args.out, render_mesh(mesh, {.width = args.size,
                                         .height = args.size,
                                         .azimuth_deg = args.azimuth_deg,
                                         .elevation_deg = args.elevation_deg,
                                         .draw_wireframe = args.wireframe}));
  say() << "wrote " << args.out << "\n";
  result() = {{"out", args.out},
              {"vertices", mesh.vertex_count()},
              {"faces", mesh.face_count()},
              {"drawn_as", mesh.triangles.empty() ? "points" : "triangles"}};
  return 0;
}

}  // namespace

void add_mesh_options(CLI::App& command, GridMeshOptions& options) {
  command
      .add_option("--max-jump", options.max_depth_jump_mm,
                  "No triangles across depth jumps above this (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  command.add_flag("!--open-seam", options.close_seam,
                   "Do not connect the last phi column to the first");
}

void register_mesh_commands(CLI::App& app, CommandList& commands) {
  auto gm = std::make_shared<GridMeshArgs>();
  auto* gm_cmd =
      app.add_subcommand("grid-mesh", "Triangulate a grid: two triangles per valid cell quad");
  gm_cmd->add_option("grid", gm->grid, "Grid file (.smg)")->required();
  gm_cmd->add_option("-o,--out", gm->out_ply, "Mesh PLY");
  gm_cmd->add_option("--obj", gm->out_obj, "Mesh OBJ (+ .mtl and <stem>_texture.png)");
  gm_cmd->add_option("--stl", gm->out_stl, "Mesh STL");
  gm_cmd->add_option("--render", gm->render_png, "Shaded picture of the mesh (PNG)");
  add_mesh_options(*gm_cmd, gm->options);
  commands.push_back({gm_cmd, [gm] { return run_grid_mesh(*gm); }});

  auto render = std::make_shared<RenderArgs>();
  auto* render_cmd = app.add_subcommand(
      "render", "Render a mesh (.ply .off .obj .stl) or a point cloud (.xyz .pcd) to a shaded PNG");
  render_cmd
      ->add_option("mesh", render->mesh,
                   "Mesh (.ply .off .obj .stl) or point cloud (.xyz .txt .pts .pcd, or a PLY "
                   "without faces): drawn as points")
      ->required();
  render_cmd->add_option("-o,--out", render->out, "Output PNG")->required();
  render_cmd->add_option("--size", render->size, "Image size in pixels")
      ->capture_default_str()
      ->check(in_range(16, 8192));
  render_cmd->add_option("--azimuth", render->azimuth_deg, "Camera azimuth (deg)")
      ->capture_default_str()
      ->check(in_range(-360, 360));
  render_cmd->add_option("--elevation", render->elevation_deg, "Camera elevation (deg)")
      ->capture_default_str()
      ->check(in_range(-90, 90));
  render_cmd->add_flag("--wireframe", render->wireframe, "Draw triangle edges");
  commands.push_back({render_cmd, [render] { return run_render(*render); }});
}

}  // namespace scanmesh::cli
