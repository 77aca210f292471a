// scanmesh calibrate / reconstruct: the device path from laser frames to a range grid
// (docs/acquisition.md, docs/cli.md).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <tuple>

#include "calibration_capture.h"
#include "cli_support.h"
#include "commands.h"
#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/acquisition/reconstruction.h"
#include "scanmesh/acquisition/scan_cleaning.h"
#include "scanmesh/acquisition/session.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/sim/turntable_camera.h"
#include "sim_rig.h"
#include "sim_step_source.h"

namespace scanmesh::cli {
namespace {

sim::RigConfig load_rig(const std::string& path) {
  return path.empty() ? sim::builtin_ciclop_rig() : sim::RigConfig::from_yaml_file(path);
}

struct CalibrateArgs {
  std::string session;  //!< recorded calibration session (scan --calibration); empty with --sim
  bool sim = false;
  std::string rig, out;
  std::string size;  //!< simulated frame size (the built-in rig scaled); empty: the rig's
  int handheld = 16, poses = 3;
  double angle_step_deg = 10.0, angle_max_deg = 70.0;
};

int report_calibration(const CalibrationReport& rep, const std::string& out) {
  const Calibration& c = rep.calibration;
  c.write_yaml(out);
  sayf("calibrated from %d views (%d not found): %d corners, %d laser points\n", rep.views_detected,
       rep.views_rejected, c.corners, c.laser_points);
  sayf("  reprojection RMS %.4f px (OpenCV initial %.4f px), laser RMS %.4f mm\n",
       c.reprojection_rms_px, rep.opencv_rms_px, c.laser_rms_mm);
  sayf("  fx %.3f +- %.3f  fy %.3f +- %.3f  cx %.3f +- %.3f  cy %.3f +- %.3f\n", c.camera.fx,
       c.uncertainty.fx, c.camera.fy, c.uncertainty.fy, c.camera.cx, c.uncertainty.cx, c.camera.cy,
       c.uncertainty.cy);
  for (std::size_t k = 0; k < c.lasers.size(); ++k)
    sayf("  laser %s: normal +- %.4f deg, distance %.3f +- %.4f mm\n", c.lasers[k].name.c_str(),
         c.uncertainty.laser_normal_deg[k], c.lasers[k].distance_mm,
         c.uncertainty.laser_distance_mm[k]);
  sayf("  axis direction +- %.4f deg, axis point +- %.4f mm\n", c.uncertainty.axis_direction_deg,
       c.uncertainty.axis_point_mm);
  sayf("wrote %s\n", out.c_str());
  nlohmann::json lasers = nlohmann::json::array();
  for (std::size_t k = 0; k < c.lasers.size(); ++k)
    lasers.push_back({{"name", c.lasers[k].name},
                      {"distance_mm", c.lasers[k].distance_mm},
                      {"normal_uncertainty_deg", c.uncertainty.laser_normal_deg[k]},
                      {"distance_uncertainty_mm", c.uncertainty.laser_distance_mm[k]}});
  result() = {
      {"out", out},
      {"views_detected", rep.views_detected},
      {"views_rejected", rep.views_rejected},
      {"corners", c.corners},
      {"laser_points", c.laser_points},
      {"reprojection_rms_px", c.reprojection_rms_px},
      {"opencv_rms_px", rep.opencv_rms_px},
      {"laser_rms_mm", c.laser_rms_mm},
      {"camera",
       {{"fx", c.camera.fx}, {"fy", c.camera.fy}, {"cx", c.camera.cx}, {"cy", c.camera.cy}}},
      {"camera_uncertainty",
       {{"fx", c.uncertainty.fx},
        {"fy", c.uncertainty.fy},
        {"cx", c.uncertainty.cx},
        {"cy", c.uncertainty.cy}}},
      {"lasers", lasers},
      {"axis_direction_uncertainty_deg", c.uncertainty.axis_direction_deg},
      {"axis_point_uncertainty_mm", c.uncertainty.axis_point_mm}};
  return kSuccess;
}

// A recorded calibration session: every step is one view (its laser-off frame and one frame per
// laser); the pattern and the board poses come from session.json.
int run_calibrate_session(const CalibrateArgs& a) {
  const SessionReader session(a.session);
  const SessionHeader& h = session.manifest().header;
  if (!h.calibration)
    throw FileFormatError(std::filesystem::path(a.session) / "session.json",
                          "not a calibration session (record one with scan --calibration)");
  if (session.step_count() == 0)
    throw FileFormatError(std::filesystem::path(a.session) / "steps.jsonl",
                          "no recorded step: nothing to calibrate from (record the session with "
                          "'scan --calibration', or complete it with --resume)");
  if (!session.complete())
    std::cerr << "scanmesh: warning: " << a.session << " is incomplete (" << session.step_count()
              << " of " << h.step_count << " steps); 'scan --calibration --resume' completes it\n";
  const CalibrationSessionInfo& info = *h.calibration;
  std::vector<CalibrationView> views;
  Progress progress("reading views");
  for (std::size_t i = 0; i < session.step_count(); ++i) {
    ScanStep s = session.step(i);
    const std::size_t pose = info.step(i).first;
    views.push_back({std::move(s.laser_off), info.poses[pose].on_platter, s.angle_rad,
                     std::move(s.laser_on), static_cast<int>(pose)});
    progress.update(static_cast<int>(i + 1), static_cast<int>(session.step_count()));
  }
  progress.finish();
  CalibrationOptions opt;
  opt.pattern = {info.pattern.corner_cols, info.pattern.corner_rows, info.pattern.square_mm,
                 info.pattern.bottom_mm};
  return report_calibration(calibrate_scanner(views, h.laser_count, opt), a.out);
}

int run_calibrate(const CalibrateArgs& a) {
  if (!a.session.empty() && a.sim)
    throw InvalidInputError("calibrate: give a calibration SESSION folder or --sim, not both");
  if (!a.session.empty()) return run_calibrate_session(a);
  if (!a.sim)
    throw InvalidInputError(
        "calibrate: give a calibration SESSION folder (scan --calibration) or --sim");
  if (!a.size.empty() && !a.rig.empty())
    throw InvalidInputError("calibrate: give --rig or --size, not both");
  const sim::RigConfig rig =
      a.size.empty() ? load_rig(a.rig) : std::apply(scaled_ciclop_rig, parse_frame_size(a.size));
  // The pattern mode renders only the board and the platter; the scene is unused.
  const sim::Scene unused = sim::Scene::from_yaml_text(
      "objects:\n  - {type: sphere, name: unused, center: [0, 0, -1000], radius: 1}\n", "unused");
  sim::TurntableCamera camera(unused, rig);
  sim::CalibrationPlan plan;
  plan.handheld_views = a.handheld;
  plan.placements = builtin_platter_placements(a.poses);
  for (double d = -a.angle_max_deg; d <= a.angle_max_deg + 1e-9; d += a.angle_step_deg)
    plan.platter_angles_rad.push_back(d * kDeg);
  Progress progress("rendering calibration views");
  progress.update(0, 1);
  const auto shots = sim::render_calibration_shots(camera, plan);
  progress.finish();
  std::vector<CalibrationView> views;
  for (const auto& s : shots)
    views.push_back({s.image, s.on_turntable, s.angle_rad, s.laser_on, s.placement});
  CalibrationOptions opt;
  opt.pattern.corner_cols = plan.board.corner_cols;
  opt.pattern.corner_rows = plan.board.corner_rows;
  opt.pattern.square_mm = plan.board.square_mm;
  opt.pattern.bottom_mm = plan.platter_bottom_mm;
  return report_calibration(calibrate_scanner(views, camera.laser_count(), opt), a.out);
}

struct ReconstructCliArgs {
  std::string session;  //!< recorded session folder; empty with --sim
  bool sim = false;
  std::string scene, rig;
  int steps = 400;
  ReconstructArgs common;
};

}  // namespace

int run_reconstruct_from(const ScanStepSource& source, const ReconstructArgs& a) {
  const Calibration cal = Calibration::read_yaml(a.calib);
  ReconstructionOptions ro;
  ro.line.method = parse_peak_method(a.method);
  ro.grid.n_phi = a.n_phi;
  ro.grid.n_h = a.n_h;
  ro.grid.h0 = a.h0_mm;
  ro.grid.dh = a.dh_mm;
  ReconstructionStats st;
  Progress progress("reconstructing");
  RangeGrid grid = reconstruct_grid(source, cal, ro, &st, [&](std::size_t done, std::size_t total) {
    progress.update(static_cast<int>(done), static_cast<int>(total));
  });
  progress.finish();
  nlohmann::json& j = result();
  j["steps"] = st.steps;
  j["peaks"] = st.peaks;
  j["saturated"] = st.line.saturated;
  j["rejected"] = {{"wide", st.line.rejected_wide},
                   {"secondary", st.line.rejected_secondary},
                   {"room_light", st.line.rejected_ambient}};
  j["points_used"] = st.grid.used;
  j["platter_points"] = st.grid.platter_points;
  j["weak_points"] = st.grid.weak_points;
  j["cells"] = st.grid.cells;
  sayf(
      "%zu steps: %zu peaks (%zu saturated; rejected: %zu wide, %zu secondary, %zu room "
      "light), %zu points used (%zu on the platter, %zu weak), %zu cells\n",
      st.steps, st.peaks, st.line.saturated, st.line.rejected_wide, st.line.rejected_secondary,
      st.line.rejected_ambient, st.grid.used, st.grid.platter_points, st.grid.weak_points,
      st.grid.cells);
  if (a.clean) {
    const ScanCleaningReport r = clean_scan_grid(grid);
    sayf(
        "cleaning: %zu low-confidence, %zu platter, %zu hair, %zu spikes, %zu fragment "
        "cells removed; %zu holes (%zu cells) filled; %zu -> %zu valid cells\n",
        r.low_confidence_removed, r.platter_removed, r.hair_removed, r.spikes.spikes_removed,
        r.spikes.fragment_cells_removed, r.holes_filled, r.cells_filled, r.valid_before,
        r.valid_after);
    j["cleaning"] = {{"low_confidence_removed", r.low_confidence_removed},
                     {"platter_removed", r.platter_removed},
                     {"hair_removed", r.hair_removed},
                     {"spikes_removed", r.spikes.spikes_removed},
                     {"fragment_cells_removed", r.spikes.fragment_cells_removed},
                     {"holes_filled", r.holes_filled},
                     {"cells_filled", r.cells_filled},
                     {"valid_before", r.valid_before},
                     {"valid_after", r.valid_after}};
  }
  grid.metadata["calibration"] = a.calib;
  write_grid(a.out, grid);
  sayf("wrote %s\n", a.out.c_str());
  j["out"] = a.out;
  j["valid_cells"] = grid.valid_count();
  return kSuccess;
}

void register_vision_commands(CLI::App& app, CommandList& commands) {
  auto cal = std::make_shared<CalibrateArgs>();
  auto* cal_cmd = app.add_subcommand(
      "calibrate",
      "Calibrate camera, lasers and turntable axis from a calibration session (or --sim)");
  cal_cmd->add_option("session", cal->session,
                      "Calibration session folder (scan --calibration --out SESSION)");
  cal_cmd->add_flag("--sim", cal->sim, "Render the calibration views with the simulated camera");
  cal_cmd->add_option("--rig", cal->rig, "Simulated rig YAML (default: built-in Ciclop-like)")
      ->check(CLI::ExistingFile);
  cal_cmd->add_option("--size", cal->size,
                      "Simulated frame size WIDTHxHEIGHT (the built-in rig scaled, as scan --sim)");
  cal_cmd->add_option("--handheld", cal->handheld, "Hand-held board views")
      ->capture_default_str()
      ->check(in_range(0, 100));
  cal_cmd->add_option("--poses", cal->poses, "--sim: board placements on the platter")
      ->capture_default_str()
      ->check(in_range(1, kMaxPlatterPoses));
  cal_cmd->add_option("--angle-step", cal->angle_step_deg, "Platter views every this (deg)")
      ->capture_default_str()
      ->check(in_range(1.0, 90.0));
  cal_cmd->add_option("--angle-max", cal->angle_max_deg, "Platter views within +- this (deg)")
      ->capture_default_str()
      ->check(in_range(0.0, 85.0));
  cal_cmd->add_option("-o,--out", cal->out, "Calibration YAML to write")->required();
  commands.push_back({cal_cmd, [cal] { return run_calibrate(*cal); }});

  auto rec = std::make_shared<ReconstructCliArgs>();
  auto* rec_cmd = app.add_subcommand(
      "reconstruct", "Laser frames -> range grid: extract, triangulate, assemble, clean");
  rec_cmd->add_option("session", rec->session, "Recorded session folder (scanmesh scan --out)")
      ->check(CLI::ExistingDirectory);
  rec_cmd->add_flag("--sim", rec->sim, "Render the steps with the simulated camera");
  rec_cmd->add_option("--scene", rec->scene, "Scene YAML (default: built-in head)")
      ->check(CLI::ExistingFile);
  rec_cmd->add_option("--rig", rec->rig, "Simulated rig YAML (default: built-in Ciclop-like)")
      ->check(CLI::ExistingFile);
  rec_cmd->add_option("--steps", rec->steps, "Turntable steps per turn")
      ->capture_default_str()
      ->check(in_range(1, 100000));
  ReconstructArgs& c = rec->common;
  rec_cmd->add_option("--calib", c.calib, "Calibration YAML")->required()->check(CLI::ExistingFile);
  rec_cmd->add_option("--method", c.method, "Peak method: com, gaussian, blais-rioux")
      ->capture_default_str();
  rec_cmd->add_option("--n-phi", c.n_phi, "Grid columns")
      ->capture_default_str()
      ->check(in_range(2, 8192));
  rec_cmd->add_option("--n-h", c.n_h, "Grid rows")
      ->capture_default_str()
      ->check(in_range(2, 8192));
  rec_cmd->add_option("--h0", c.h0_mm, "Height of row 0 (mm)")
      ->capture_default_str()
      ->check(in_range(-1e6, 1e6));
  rec_cmd->add_option("--dh", c.dh_mm, "Row spacing (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  rec_cmd->add_flag("!--no-clean", c.clean, "Do not clean the assembled grid");
  rec_cmd->add_option("-o,--out", c.out, "Output grid file (.smg)")->required();
  commands.push_back(
      {rec_cmd, [rec] {
         if (!rec->session.empty() && rec->sim)
           throw InvalidInputError("reconstruct: give a SESSION folder or --sim, not both");
         if (!rec->session.empty()) {
           // Replay: the recorded steps go through the same pipeline with no device.
           const SessionReader session(rec->session);
           if (session.manifest().header.calibration)
             throw FileFormatError(std::filesystem::path(rec->session) / "session.json",
                                   "is a calibration session: use 'scanmesh calibrate' on it");
           if (!session.complete())
             std::cerr << "scanmesh: warning: " << rec->session << " is incomplete ("
                       << session.step_count() << " steps); 'scan --resume' completes it\n";
           return run_reconstruct_from(session, rec->common);
         }
         if (!rec->sim)
           throw InvalidInputError("reconstruct: give a recorded SESSION folder or --sim");
         const sim::Scene scene = rec->scene.empty() ? sim::builtin_head_scene()
                                                     : sim::Scene::from_yaml_file(rec->scene);
         const sim::TurntableCamera camera(scene, load_rig(rec->rig));
         // A recorded session plugs in here instead: any ScanStepSource.
         const SimulatedStepSource source(camera, static_cast<std::size_t>(rec->steps));
         return run_reconstruct_from(source, rec->common);
       }});
}

int run_sim_calibrate(const std::string& size, const std::string& out) {
  CalibrateArgs a;
  a.sim = true;
  a.size = size;
  a.out = out;
  return run_calibrate(a);
}

}  // namespace scanmesh::cli
