// Subcommands that produce or inspect range grids: sim, info, export, clean.
#include <algorithm>
#include <cctype>
#include <memory>
#include <utility>

#include "cli_support.h"
#include "commands.h"
#include "pipeline.h"
#include "scanmesh/acquisition/scan_cleaning.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"

namespace scanmesh::cli {

namespace {

struct SimArgs {
  std::string scene;    //!< empty: built-in head
  std::string scanner;  //!< empty: built-in head scanner
  std::optional<std::uint64_t> seed;
  std::optional<double> noise_sigma_mm;
  std::string out;
};

struct InfoArgs {
  std::string file;
};

struct ExportArgs {
  std::string grid;
  std::string pcd, ply, texture, depth;
};

struct CleanArgs {
  std::string grid;
  std::string out;
  CleaningOptions options;
  int fill_holes = 0;  //!< fill interior holes of at most this many cells (0: off)
};

int run_sim(const SimArgs& args) {
  const sim::Scene scene = load_scene(args.scene);
  sim::ScannerConfig config = load_scanner(args.scanner);
  if (args.seed) config.seed = *args.seed;
  if (args.noise_sigma_mm) config.noise_sigma_mm = *args.noise_sigma_mm;
  config.validate();
  const auto scan = simulate_with_progress(scene, config);
  write_grid(args.out, scan.grid);
  say() << "wrote " << args.out << ": " << scan.grid.n_phi() << " x " << scan.grid.n_h()
        << " cells, " << scan.grid.valid_count() << " valid\n";
  result() = {{"out", args.out}, {"grid", grid_summary(scan.grid)}};
  return 0;
}

nlohmann::json describe(const std::filesystem::path& file) {
  if (looks_like_grid_file(file) || file.extension() == ".smg") {
    nlohmann::json j = grid_summary(read_grid(file));
    j["kind"] = "range grid";
    return j;
  }
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".ply" || ext == ".off" || ext == ".obj" || ext == ".stl") {
    nlohmann::json j = mesh_summary(read_mesh(file));
    j["kind"] = "mesh";
    return j;
  }
  if (!std::filesystem::exists(file))
    throw IoError("cannot open " + file.string() + ": no such file");
  throw FileFormatError(file,
                        "neither a scanmesh grid file (.smg) nor a mesh (.ply .off .obj .stl)");
}

void print_text(const nlohmann::json& j, const std::string& indent = "") {
  for (const auto& [key, value] : j.items()) {
    if (value.is_object()) {
      say() << indent << key << ":\n";
      print_text(value, indent + "  ");
    } else {
      say() << indent << key << ": "
            << (value.is_string() ? value.get<std::string>() : json_text(value, -1)) << "\n";
    }
  }
}

int run_info(const InfoArgs& args) {
  result() = describe(args.file);
  print_text(result());  // the same fields as text (--json prints the object itself)
  return 0;
}

int run_export(const ExportArgs& args) {
  if (args.pcd.empty() && args.ply.empty() && args.texture.empty() && args.depth.empty())
    throw InvalidInputError("export: name at least one of --pcd, --ply, --texture, --depth");
  const RangeGrid grid = read_grid(args.grid);
  if (!args.pcd.empty()) export_pcd(args.pcd, grid);
  if (!args.ply.empty()) export_ply_points(args.ply, grid);
  if (!args.texture.empty()) export_texture_png(args.texture, grid);
  if (!args.depth.empty()) export_depth_png(args.depth, grid);
  say() << "exported " << args.grid << " (" << grid.valid_count() << " valid cells)\n";
  result() = {{"grid", args.grid}, {"valid_cells", grid.valid_count()}};
  for (const auto& [key, path] : {std::pair<const char*, const std::string&>{"pcd", args.pcd},
                                  {"ply", args.ply},
                                  {"texture", args.texture},
                                  {"depth", args.depth}})
    if (!path.empty()) result()["outputs"][key] = path;
  return 0;
}

int run_clean(const CleanArgs& args) {
  RangeGrid grid = read_grid(args.grid);
  const CleaningReport report = clean_grid(grid, args.options);
  grid.metadata["cleaned"] = "spikes " + std::to_string(report.spikes_removed) +
                             ", fragment cells " + std::to_string(report.fragment_cells_removed);
  // Filling runs after the removals so the holes they leave are filled too; filled cells carry
  // confidence 0 (never measured) and the count is recorded in the file.
  HoleFillReport filled;
  if (args.fill_holes > 0) {
    filled = fill_small_holes(grid, args.fill_holes);
    grid.metadata["filled_cells"] = std::to_string(filled.cells);
  }
  write_grid(args.out, grid);
  say() << "removed " << report.spikes_removed << " spikes and " << report.fragment_cells_removed
        << " cells in " << report.fragments_removed << " fragments";
  if (args.fill_holes > 0)
    say() << "; filled " << filled.holes << " holes (" << filled.cells << " cells)";
  say() << "; " << grid.valid_count() << " valid cells remain\n";
  result() = {{"out", args.out},
              {"spikes_removed", report.spikes_removed},
              {"fragment_cells_removed", report.fragment_cells_removed},
              {"fragments_removed", report.fragments_removed},
              {"holes_filled", filled.holes},
              {"cells_filled", filled.cells},
              {"valid_cells", grid.valid_count()}};
  return 0;
}

}  // namespace

void add_cleaning_options(CLI::App& command, CleaningOptions& options) {
  command
      .add_option("--spike-mm", options.spike_threshold_mm,
                  "Spike threshold above the neighbour median (mm)")
      ->capture_default_str()
      ->check(in_range(0, 1e4));
  command
      .add_option("--spike-spread", options.spike_spread_factor,
                  "Extra threshold in units of the prediction spread")
      ->capture_default_str()
      ->check(in_range(0, 1e3));
  command
      .add_option("--min-fragment", options.min_component_cells,
                  "Pieces with fewer cells are removed")
      ->capture_default_str()
      ->check(in_range(1, 1e8));
}

void register_grid_commands(CLI::App& app, CommandList& commands) {
  auto sim = std::make_shared<SimArgs>();
  auto* sim_cmd =
      app.add_subcommand("sim", "Simulate a cylindrical range scan: scene + scanner -> grid file");
  sim_cmd->add_option("--scene", sim->scene, "Scene YAML (default: built-in head)")
      ->check(CLI::ExistingFile);
  sim_cmd->add_option("--scanner", sim->scanner, "Scanner YAML (default: built-in head scanner)")
      ->check(CLI::ExistingFile);
  sim_cmd->add_option("--seed", sim->seed, "Random seed of all defects")->check(seed_range());
  sim_cmd->add_option("--noise", sim->noise_sigma_mm, "Range noise sigma (mm)")
      ->check(in_range(0, 1e3));
  sim_cmd->add_option("-o,--out", sim->out, "Output grid file (.smg)")->required();
  commands.push_back({sim_cmd, [sim] { return run_sim(*sim); }});

  auto info = std::make_shared<InfoArgs>();
  auto* info_cmd =
      app.add_subcommand("info", "Describe a grid (.smg) or mesh (.ply .off .obj .stl) file");
  info_cmd->add_option("file", info->file, "Grid or mesh file")->required();
  commands.push_back({info_cmd, [info] { return run_info(*info); }});

  auto exp = std::make_shared<ExportArgs>();
  auto* export_cmd =
      app.add_subcommand("export", "Export a grid to PCD / PLY points / texture and depth PNG");
  export_cmd->add_option("grid", exp->grid, "Grid file (.smg)")->required();
  export_cmd->add_option("--pcd", exp->pcd, "Organised PCD point cloud");
  export_cmd->add_option("--ply", exp->ply, "PLY point cloud of the valid cells");
  export_cmd->add_option("--texture", exp->texture, "Texture PNG (pixel x, y = phi, h index)");
  export_cmd->add_option("--depth", exp->depth, "Depth picture PNG");
  commands.push_back({export_cmd, [exp] { return run_export(*exp); }});

  auto clean = std::make_shared<CleanArgs>();
  auto* clean_cmd = app.add_subcommand("clean", "Remove spikes and isolated fragments from a grid");
  clean_cmd->add_option("grid", clean->grid, "Grid file (.smg)")->required();
  clean_cmd->add_option("-o,--out", clean->out, "Cleaned grid file (.smg)")->required();
  add_cleaning_options(*clean_cmd, clean->options);
  clean_cmd
      ->add_option("--fill-holes", clean->fill_holes,
                   "Afterwards fill interior holes of at most this many cells (0: off)")
      ->check(in_range(0, 1e8))
      ->default_val(0);
  commands.push_back({clean_cmd, [clean] { return run_clean(*clean); }});
}

}  // namespace scanmesh::cli
