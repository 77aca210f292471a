// The stages the subcommands share, wired once: load inputs, simulate, clean, mesh, write.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/core/mesh.h"
#include "scanmesh/core/range_grid.h"
#include "scanmesh/core/render.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/reconstruction/surface_fields.h"
#include "scanmesh/sim/range_scanner.h"

namespace scanmesh::cli {

//! Scene from a YAML file, or the built-in head when `path` is empty.
sim::Scene load_scene(const std::string& path);
//! Scanner from a YAML file, or the built-in head scanner when `path` is empty.
sim::ScannerConfig load_scanner(const std::string& path);

//! Simulates with a progress bar on the terminal.
sim::SimulatedScan simulate_with_progress(const sim::Scene& scene,
                                          const sim::ScannerConfig& config);

//! Mesh views for the pictures: front, three-quarter and side of the built-in head.
Image8 render_views(const Mesh& mesh, int view_size = 560);

//! Writes mesh.ply / mesh.obj (+ .mtl pointing at texture_png if given) beside each other.
void write_mesh_files(const std::filesystem::path& ply, const std::filesystem::path& obj,
                      const Mesh& mesh, const std::string& texture_png);

//! JSON descriptions for report.json.
nlohmann::json to_json(const sim::ScannerConfig& c);
nlohmann::json to_json(const CleaningOptions& o);
nlohmann::json to_json(const CleaningReport& r);
nlohmann::json to_json(const GridMeshOptions& o);
nlohmann::json grid_summary(const RangeGrid& grid);
nlohmann::json mesh_summary(const Mesh& mesh);
nlohmann::json versions();

//! What the demo makes of a cleaned grid (apps/src/cmd_demo.cpp): the grid mesh and its files
//! (texture.png, depth.png, scan.pcd, mesh.ply, mesh.obj, mesh.mtl, fields.smf, curvature.png,
//! render.png) in `out`; stage times are added to `timings`. Shared by `demo` and
//! `demo --device-sim`.
struct GridProducts {
  GridMesh meshed;
  SurfaceFields fields;
  nlohmann::json mesh_json;  //!< report.json's "grid_mesh"
};
GridProducts write_grid_products(const std::filesystem::path& out, const RangeGrid& grid,
                                 const GridMeshOptions& meshing, nlohmann::json& timings);

}  // namespace scanmesh::cli
