// `scanmesh demo --device-sim`: the demo through the device path instead of the direct range
// simulator. The same functions the commands run, in order:
//   scan --sim (simulated board on a pty behind the real termios driver + simulated turntable
//   camera -> session folder) -> calibrate --sim (the same rig) -> reconstruct SESSION (extract,
//   triangulate, assemble, clean) -> the demo's mesh, pictures and report.json,
// and the grid compared with the direct range simulator of the same scene (docs/acquisition.md).
#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "cli_support.h"
#include "commands.h"
#include "pipeline.h"
#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/acquisition/session.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "sim_rig.h"

namespace scanmesh::cli {
namespace {

namespace fs = std::filesystem;

// Device grid against the direct range simulator's grid and its exact radii, over cells valid in
// both (the direct simulator is run without noise or defects: it is the reference).
nlohmann::json compare_with_direct(const RangeGrid& device, const sim::SimulatedScan& direct) {
  double ss = 0, ss_truth = 0, sum = 0, max_abs = 0;
  std::size_t n = 0, above_1mm = 0, device_only = 0, direct_only = 0;
  for (std::size_t k = 0; k < device.cell_count(); ++k) {
    const bool a = device.validity()[k], b = direct.grid.validity()[k];
    device_only += a && !b;
    direct_only += b && !a;
    if (!a || !b) continue;
    const double d = device.radii()[k] - direct.grid.radii()[k];
    const double dt = device.radii()[k] - direct.truth[k].radius;
    ss += d * d;
    ss_truth += dt * dt;
    sum += d;
    max_abs = std::max(max_abs, std::abs(d));
    above_1mm += std::abs(d) > 1.0;
    ++n;
  }
  const double dn = static_cast<double>(std::max<std::size_t>(n, 1));
  return {{"cells_valid_in_both", n},
          {"cells_valid_only_in_device_grid", device_only},
          {"cells_valid_only_in_direct_grid", direct_only},
          {"coverage_of_direct_grid",
           static_cast<double>(n) /
               static_cast<double>(std::max<std::size_t>(direct.grid.valid_count(), 1))},
          {"rms_difference_mm", std::sqrt(ss / dn)},
          {"mean_difference_mm", sum / dn},
          {"max_abs_difference_mm", max_abs},
          {"cells_differing_by_more_than_1mm", above_1mm},
          {"rms_error_vs_exact_surface_mm", std::sqrt(ss_truth / dn)}};
}

}  // namespace

void add_device_demo_options(CLI::App& demo, DeviceDemoArgs& a) {
  demo.add_flag("--device-sim", a.enabled,
                "Run the device path: simulated board + camera -> session -> calibration -> "
                "reconstruction (instead of the direct range simulator)");
  demo.add_option("--steps", a.steps, "--device-sim: turntable steps per turn")
      ->capture_default_str()
      ->check(in_range(4, 100000));
  demo.add_option("--size", a.size, "--device-sim: camera frame size WIDTHxHEIGHT")
      ->capture_default_str();
  demo.add_option("--n-phi", a.n_phi, "--device-sim: grid columns")
      ->capture_default_str()
      ->check(in_range(8, 8192));
  demo.add_option("--n-h", a.n_h, "--device-sim: grid rows")
      ->capture_default_str()
      ->check(in_range(8, 8192));
  demo.add_option("--h0", a.h0_mm, "--device-sim: height of grid row 0 (mm)")
      ->capture_default_str()
      ->check(in_range(-1e6, 1e6));
  demo.add_option("--dh", a.dh_mm, "--device-sim: grid row spacing (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  demo.add_option("--time-scale", a.time_scale,
                  "--device-sim: simulated device time per real second (board moves, settling)")
      ->capture_default_str()
      ->check(in_range(1e-6, 1.0));
}

int run_device_demo(const DemoArgs& args) {
  const DeviceDemoArgs& d = args.device;
  if (!args.scanner.empty())
    throw InvalidInputError(
        "demo --device-sim: --scanner configures the direct range simulator; "
        "the device path takes --steps, --size and the grid options");
  parse_frame_size(d.size);  // fail before any work
  const fs::path out(args.out);
  OutputFolder folder(out);
  nlohmann::json timings;
  Stopwatch total, t;

  // 1. Scan: a fresh session folder inside the output folder (the demo owns it).
  const fs::path session_dir = out / "session";
  if (fs::exists(session_dir / "session.json")) {
    say() << "[1/5] removing the previous demo session in " << session_dir.string() << "\n";
    std::error_code ec;
    fs::remove_all(session_dir, ec);
    if (ec) throw IoError("cannot remove '" + session_dir.string() + "': " + ec.message());
  }
  say() << "[1/5] scan: " << d.steps << " steps, " << d.size
        << " frames, simulated board on a pty + simulated turntable camera\n";
  SimScanRequest scan;
  scan.scene = args.scene.empty() ? "head" : args.scene;
  scan.out = session_dir.string();
  scan.size = d.size;
  scan.steps = d.steps;
  scan.time_scale = d.time_scale;
  if (const int rc = run_sim_scan(scan); rc != kSuccess) return rc;
  timings["scan_s"] = t.seconds();

  // 2. Calibrate the same (scaled) rig from its own chessboard views.
  t = {};
  const fs::path calib = out / "calibration.yaml";
  say() << "[2/5] calibrate: simulated chessboard views at " << d.size << "\n";
  if (const int rc = run_sim_calibrate(d.size, calib.string()); rc != kSuccess) return rc;
  timings["calibrate_s"] = t.seconds();
  const Calibration cal = Calibration::read_yaml(calib);

  // 3. Reconstruct the recorded session with that calibration (cleaned, as `reconstruct` does).
  t = {};
  say() << "[3/5] reconstruct: " << session_dir.string() << " -> scan.smg\n";
  ReconstructArgs rec;
  rec.calib = calib.string();
  rec.out = (out / "scan.smg").string();
  rec.n_phi = d.n_phi;
  rec.n_h = d.n_h;
  rec.h0_mm = d.h0_mm;
  rec.dh_mm = d.dh_mm;
  const SessionReader session(session_dir);
  if (const int rc = run_reconstruct_from(session, rec); rc != kSuccess) return rc;
  timings["reconstruct_s"] = t.seconds();
  const RangeGrid grid = read_grid(out / "scan.smg");

  // 4. The direct range simulator of the same scene on the same grid: the reference.
  t = {};
  say() << "[4/5] direct range simulator of the same scene on the same grid\n";
  const sim::Scene scene = load_scene(args.scene);
  sim::ScannerConfig ref;
  ref.n_phi = d.n_phi;
  ref.n_h = d.n_h;
  ref.h0_mm = d.h0_mm;
  ref.dh_mm = d.dh_mm;
  ref.noise_sigma_mm = 0.0;
  ref.grazing_dropout = false;
  ref.hair = false;
  ref.height_band = false;
  ref.spike_probability = 0.0;
  if (args.seed) ref.seed = *args.seed;
  ref.validate();
  const sim::SimulatedScan direct = simulate_with_progress(scene, ref);
  write_grid(out / "direct.smg", direct.grid);
  const nlohmann::json comparison = compare_with_direct(grid, direct);
  timings["direct_simulation_s"] = t.seconds();

  // 5. The demo's downstream: mesh, pictures, curvature.
  say() << "[5/5] mesh, pictures, curvature\n";
  const GridProducts products = write_grid_products(out, grid, args.meshing, timings);
  timings["total_s"] = total.seconds();

  const nlohmann::json report = {
      {"scene", scene.name},
      {"path", "device (demo --device-sim)"},
      {"device",
       {{"steps", d.steps},
        {"frame_size", d.size},
        {"time_scale", d.time_scale},
        {"session_frames", session.step_count() * (session.manifest().header.laser_count + 1)}}},
      {"calibration",
       {{"file", "calibration.yaml"},
        {"reprojection_rms_px", cal.reprojection_rms_px},
        {"laser_rms_mm", cal.laser_rms_mm},
        {"views", cal.views},
        {"corners", cal.corners},
        {"laser_points", cal.laser_points}}},
      {"grid", grid_summary(grid)},
      {"comparison_with_direct_range_simulator", comparison},
      {"grid_mesh", products.mesh_json},
      {"curvature",
       {{"method", to_string(products.fields.method)},
        {"defined_cells", products.fields.defined_count()}}},
      {"timings", timings},
      {"versions", versions()},
      {"files",
       {"session/", "calibration.yaml", "scan.smg", "direct.smg", "scan.pcd", "mesh.ply",
        "mesh.obj", "mesh.mtl", "texture.png", "depth.png", "render.png", "fields.smf",
        "curvature.png", "report.json"}}};
  write_file_atomically(out / "report.json", json_text(report) + "\n");

  say() << "scanmesh demo --device-sim: " << scene.name << ", " << grid.n_phi() << " x "
        << grid.n_h() << " grid, " << grid.valid_count() << " valid cells\n"
        << "  mesh: " << products.meshed.mesh.vertex_count() << " vertices, "
        << products.meshed.mesh.face_count() << " triangles\n"
        << "  vs direct range simulator: RMS " << comparison["rms_difference_mm"].get<double>()
        << " mm over " << comparison["cells_valid_in_both"].get<std::size_t>()
        << " cells valid in both\n"
        << "  outputs in " << out.string()
        << "/: session/ calibration.yaml scan.smg direct.smg mesh.ply mesh.obj texture.png "
           "depth.png render.png curvature.png report.json ("
        << timings["total_s"].get<double>() << " s)\n";
  result() = report;
  result()["out"] = out.string();
  folder.keep();
  return kSuccess;
}

}  // namespace scanmesh::cli
