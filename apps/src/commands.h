// The scanmesh subcommands. Each takes its parsed arguments and returns an exit code; errors
// are thrown as scanmesh's typed exceptions and mapped in main().
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

// A subcommand registered by a stage's cmd_<stage>.cpp: the parsed CLI11 subcommand and what
// runs it. A stage adds `void register_<stage>_commands(CLI::App&, CommandList&)` below and one
// call in main.cpp; its argument structs live in the closure (e.g. a shared_ptr).
struct RegisteredCommand {
  CLI::App* command = nullptr;
  std::function<int()> run;
};
using CommandList = std::vector<RegisteredCommand>;

struct SimArgs {
  std::string scene;    //!< empty: built-in head
  std::string scanner;  //!< empty: built-in head scanner
  std::optional<std::uint64_t> seed;
  std::optional<double> noise_sigma_mm;
  std::string out;
};
int run_sim(const SimArgs& args);

struct InfoArgs {
  std::string file;
};
int run_info(const InfoArgs& args);

struct ExportArgs {
  std::string grid;
  std::string pcd, ply, texture, depth;
};
int run_export(const ExportArgs& args);

struct CleanArgs {
  std::string grid;
  std::string out;
  CleaningOptions options;
  int fill_holes = 0;  //!< fill interior holes of at most this many cells (0: off)
};
int run_clean(const CleanArgs& args);

struct GridMeshArgs {
  std::string grid;
  std::string out_ply, out_obj, out_stl, render_png;
  GridMeshOptions options;
};
int run_grid_mesh(const GridMeshArgs& args);

struct RenderArgs {
  std::string mesh;
  std::string out;
  int size = 640;
  double azimuth_deg = 180.0, elevation_deg = 10.0;
  bool wireframe = false;
};
int run_render(const RenderArgs& args);

struct CurvatureArgs {
  std::string grid;
  std::string out;                      //!< output directory
  std::string method = "grid-quadric";  //!< analytic | grid-quadric | quadric | seed
  double radius_mm = 0;                 //!< quadric neighbourhood radius; <= 0: the default
};
int run_curvature(const CurvatureArgs& args);

//! `demo --device-sim`: the device path instead of the direct range simulator
//! (apps/src/cmd_device_demo.cpp).
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
int run_demo(const DemoArgs& args);
//! Adds --device-sim and its options to the demo subcommand.
void add_device_demo_options(CLI::App& demo, DeviceDemoArgs& args);
int run_device_demo(const DemoArgs& args);

}  // namespace scanmesh::cli

// --- point-cloud fans (seed 002) and the mesh checker: apps/src/cmd_fans.cpp ---
#include "scanmesh/meshing/fans/fans.h"

namespace scanmesh::cli {

struct FansArgs {
  std::string cloud;  //!< .ply, .pcd, .xyz/.txt/.pts or .smg (valid cells)
  std::string out;
  std::string render_png, histogram_png;
  std::string report;  //!< JSON: stage statistics and the checker's verdicts
  bool check = false;  //!< print the checker report of the result
  FanOptions options;
};
int run_fans(const FansArgs& args);

struct CheckArgs {
  std::string mesh;
  std::string histogram_png;
  bool skip_intersections = false;
  std::string require;  //!< comma-separated MeshProperty names that decide the exit code
};
int run_check(const CheckArgs& args);

struct ParticlesArgs {
  std::string scene;  //!< static scene or animated skeleton YAML
  std::string grid;   //!< scan mode: grid file
  double edge = 0.0;  //!< R
  bool adaptive = false;
  int frames = 10;
  int steps_per_frame = 20;
  bool no_flips = false;
  std::uint64_t seed = 1;
  std::string out;
};
int run_particles(const ParticlesArgs& args);

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

// --- animation meshes (seed 000): apps/src/cmd_aft.cpp ---
namespace scanmesh::cli {
void register_aft_commands(CLI::App& app, CommandList& commands);
}  // namespace scanmesh::cli

// --- seed 001 adaptive remeshing: apps/src/cmd_remesh.cpp ---
namespace scanmesh::cli {
void register_remesh_commands(CLI::App& app, CommandList& commands);
}  // namespace scanmesh::cli

// --- the web UI: apps/src/serve/ ---
namespace scanmesh::cli {
void register_serve_commands(CLI::App& app, CommandList& commands);
}  // namespace scanmesh::cli
