// Subcommands that produce or show meshes: grid-mesh, render.
#include <filesystem>
#include <iostream>
#include <vector>

#include "commands.h"
#include "pipeline.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"

namespace scanmesh::cli {

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
  std::cout << "meshed " << result.quads_meshed << " quads: " << result.mesh.vertex_count()
            << " vertices, " << result.mesh.face_count() << " triangles ("
            << result.quads_skipped_for_holes << " quads skipped at holes, "
            << result.quads_skipped_for_depth_jumps << " at depth jumps)\n";
  return 0;
}

int run_render(const RenderArgs& args) {
  const Mesh mesh = read_mesh(args.mesh);
  write_png(args.out, render_mesh(mesh, {.width = args.size,
                                         .height = args.size,
                                         .azimuth_deg = args.azimuth_deg,
                                         .elevation_deg = args.elevation_deg,
                                         .draw_wireframe = args.wireframe}));
  std::cout << "wrote " << args.out << "\n";
  return 0;
}

}  // namespace scanmesh::cli
