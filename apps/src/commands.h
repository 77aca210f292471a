// The scanmesh subcommands. Each runs on its parsed arguments and returns an exit code; errors
// are thrown as scanmesh's typed exceptions and mapped to exit codes by run_guarded().
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/meshing/grid_mesh.h"

namespace CLI {
class App;
}

namespace scanmesh::cli {

// Every subcommand is registered the same way: its stage's cmd_<stage>.cpp defines
// `void register_<stage>_commands(CLI::App&, CommandList&)`, which adds the subcommands with
// their options bound to an argument struct held by the closure (a shared_ptr), and main.cpp
// calls the registrations in the order `scanmesh --help` lists them.
struct RegisteredCommand {
  CLI::App* command = nullptr;
  std::function<int()> run;
};
using CommandList = std::vector<RegisteredCommand>;

// --- range grids: sim, info, export, clean: apps/src/cmd_grid.cpp ---
void register_grid_commands(CLI::App& app, CommandList& commands);
//! --spike-mm, --spike-spread, --min-fragment (clean, demo).
void add_cleaning_options(CLI::App& command, CleaningOptions& options);

// --- meshes of grids and pictures of meshes: grid-mesh, render: apps/src/cmd_mesh.cpp ---
void register_mesh_commands(CLI::App& app, CommandList& commands);
//! --max-jump, --open-seam (grid-mesh, demo).
void add_mesh_options(CLI::App& command, GridMeshOptions& options);

// --- normals and curvature of a grid: apps/src/cmd_curvature.cpp ---
void register_curvature_commands(CLI::App& app, CommandList& commands);

// --- point-cloud fans and the mesh checker: fans, check: apps/src/cmd_fans.cpp ---
void register_fans_commands(CLI::App& app, CommandList& commands);

// --- particle spring networks: apps/src/cmd_particles.cpp ---
void register_particles_commands(CLI::App& app, CommandList& commands);

// --- the demo: apps/src/cmd_demo.cpp, its device path in apps/src/cmd_device_demo.cpp ---
void register_demo_commands(CLI::App& app, CommandList& commands);

//! `demo --device-sim`: the device path instead of the direct range simulator.
struct DeviceDemoArgs {
  bool enabled = false;
  int steps = 90;
  std::string size = "640x480";
  int n_phi = 180, n_h = 256;
  double h0_mm = 0.0, dh_mm = 0.9;
  double time_scale = 0.001;
};

struct DemoArgs {
  std::string out = "scanmesh-demo";
  DeviceDemoArgs device;
  std::string scene, scanner;
  std::optional<std::uint64_t> seed;
  CleaningOptions cleaning;
  GridMeshOptions meshing;
};
//! Adds --device-sim and its options to the demo subcommand.
void add_device_demo_options(CLI::App& demo, DeviceDemoArgs& args);
int run_device_demo(const DemoArgs& args);

}  // namespace scanmesh::cli

// --- device path: calibration and reconstruction from laser frames: apps/src/cmd_vision.cpp ---
namespace scanmesh {
class ScanStepSource;
}

namespace scanmesh::cli {

struct ReconstructArgs {
  std::string calib;  //!< calibration YAML
  std::string out;    //!< grid file
  std::string method = "gaussian";
  int n_phi = 512, n_h = 512;
  double h0_mm = 0.0, dh_mm = 0.45;
  bool clean = true;
};
//! Reconstructs a grid from any step source (simulated or a recorded session).
int run_reconstruct_from(const ScanStepSource& source, const ReconstructArgs& args);
void register_vision_commands(CLI::App& app, CommandList& commands);
//! `calibrate --sim --size SIZE --out OUT` as the command runs it.
int run_sim_calibrate(const std::string& size, const std::string& out);

}  // namespace scanmesh::cli

// --- devices, scan sessions and replay: apps/src/cmd_devices.cpp ---
namespace scanmesh::cli {
void register_devices_commands(CLI::App& app, CommandList& commands);
//! `scan --sim --scene SCENE --steps N --size WxH --time-scale T --out OUT` as the command runs it.
struct SimScanRequest {
  std::string scene = "head", out, size = "640x480";
  int steps = 90;
  double time_scale = 0.001;
};
int run_sim_scan(const SimScanRequest& request);
}  // namespace scanmesh::cli

// --- check-calibration: re-measure known spheres: apps/src/cmd_measure.cpp ---
namespace scanmesh::cli {
void register_measure_commands(CLI::App& app, CommandList& commands);
void register_import_commands(CLI::App& app, CommandList& commands);
}  // namespace scanmesh::cli

// --- animation meshes: regions, animesh: apps/src/cmd_aft.cpp ---
namespace scanmesh::cli {
void register_aft_commands(CLI::App& app, CommandList& commands);
}  // namespace scanmesh::cli

// --- adaptive remeshing: apps/src/cmd_remesh.cpp ---
namespace scanmesh::cli {
void register_remesh_commands(CLI::App& app, CommandList& commands);
}  // namespace scanmesh::cli

// --- the web UI: apps/src/serve/ ---
namespace scanmesh::cli {
void register_serve_commands(CLI::App& app, CommandList& commands);
}  // namespace scanmesh::cli
