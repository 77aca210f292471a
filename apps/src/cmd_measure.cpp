// `scanmesh check-calibration`: re-measures known spheres with a calibration (issue 9, item 2;
// docs/acquisition.md, "Checking a calibration"). VDI/VDE 2634-2 style: the probing errors of a
// sphere (fitted radius against the nominal one, RMS and largest distance of the points to the
// fitted sphere) and the sphere-spacing error of a two-sphere dumbbell. In simulation both
// artefacts are rendered by the simulated turntable camera of the rig the calibration is for;
// a recorded session of one artefact can be checked instead.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "commands.h"
#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/acquisition/reconstruction.h"
#include "scanmesh/acquisition/session.h"
#include "scanmesh/acquisition/sphere_fit.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/turntable_camera.h"
#include "sim_rig.h"
#include "sim_step_source.h"

namespace scanmesh::cli {
namespace {

struct MeasureArgs {
  std::string calib, session, object, report;
  bool sim = false;
  std::string size = "640x480";
  int steps = 72;
  double sphere_radius_mm = 50.0;     //!< the single sphere
  double ball_radius_mm = 25.0;       //!< each dumbbell ball
  double ball_spacing_mm = 90.0;      //!< dumbbell centre distance
  double max_radius_error_mm = 0.05;  //!< |fitted - nominal radius|
  double max_rms_mm = 0.1;            //!< RMS point-to-sphere distance
  double max_spacing_error_mm = 0.1;  //!< |fitted - nominal spacing|
  double min_height_mm = 2.0;         //!< points lower than this are the platter
};

// The artefacts in simulation: where they stand on the platter (object frame, mm).
sim::Scene sphere_scene(double r) {
  return sim::Scene::from_yaml_text(
      "name: probing sphere\nobjects:\n  - {type: sphere, name: ball, center: [0, 0, " +
          std::to_string(r + 20.0) + "], radius: " + std::to_string(r) +
          "}\ntexture: {seed: 3, base_color: [200, 200, 200]}\n",
      "built-in probing sphere");
}
sim::Scene dumbbell_scene(double r, double spacing) {
  const std::string z = std::to_string(r + 35.0), x = std::to_string(spacing / 2);
  return sim::Scene::from_yaml_text(
      "name: dumbbell\nobjects:\n  - {type: sphere, name: a, center: [-" + x + ", 0, " + z +
          "], radius: " + std::to_string(r) + "}\n  - {type: sphere, name: b, center: [" + x +
          ", 0, " + z + "], radius: " + std::to_string(r) +
          "}\ntexture: {seed: 3, base_color: [200, 200, 200]}\n",
      "built-in dumbbell");
}

std::vector<Eigen::Vector3d> object_points(const ScanStepSource& source, const Calibration& cal,
                                           double min_height, const std::string& label) {
  Progress progress("measuring " + label);
  ReconstructionStats st;
  const auto pts = triangulate_scan(source, cal, {}, &st, [&](std::size_t done, std::size_t n) {
    progress.update(static_cast<int>(done), static_cast<int>(n));
  });
  progress.finish();
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : pts)
    if (p.p.z() > min_height) out.push_back(p.p);
  sayf("%s: %zu steps, %zu peaks, %zu points above the platter\n", label.c_str(), st.steps,
       st.peaks, out.size());
  if (out.size() < 100)
    throw InvalidInputError("check-calibration: only " + std::to_string(out.size()) +
                            " points of the " + label + " (is it in view?)");
  return out;
}

nlohmann::json sphere_json(const SphereFit& f, double nominal) {
  return {{"centre_mm", {f.centre.x(), f.centre.y(), f.centre.z()}},
          {"radius_mm", f.radius},
          {"nominal_radius_mm", nominal},
          {"radius_error_mm", f.radius - nominal},
          {"rms_distance_mm", f.rms},
          {"max_abs_distance_mm", f.max_abs},
          {"points", f.points},
          {"outliers_left_out", f.rejected}};
}

struct Verdict {
  bool pass = true;
  nlohmann::json failures = nlohmann::json::array();
  void check(const std::string& what, double value, double limit) {
    if (std::abs(value) <= limit) return;
    pass = false;
    char line[160];
    std::snprintf(line, sizeof line, "%s %.4f mm exceeds +- %.4f mm", what.c_str(), value, limit);
    failures.push_back(line);
  }
};

void report_sphere(const char* name, const SphereFit& f, double nominal, const MeasureArgs& a,
                   Verdict& v) {
  sayf(
      "  %s: radius %.4f mm (nominal %.3f, error %+.4f), RMS %.4f mm, max %.4f mm, "
      "%zu points\n",
      name, f.radius, nominal, f.radius - nominal, f.rms, f.max_abs, f.points);
  v.check(std::string(name) + " radius error", f.radius - nominal, a.max_radius_error_mm);
  v.check(std::string(name) + " RMS distance", f.rms, a.max_rms_mm);
}

nlohmann::json measure_sphere(const std::vector<Eigen::Vector3d>& pts, const MeasureArgs& a,
                              Verdict& v) {
  const SphereFit f = fit_sphere_trimmed(pts);
  report_sphere("sphere", f, a.sphere_radius_mm, a, v);
  return sphere_json(f, a.sphere_radius_mm);
}

nlohmann::json measure_dumbbell(const std::vector<Eigen::Vector3d>& pts, const MeasureArgs& a,
                                Verdict& v) {
  const auto [left, right] = split_two_objects(pts);
  const SphereFit fa = fit_sphere_trimmed(left), fb = fit_sphere_trimmed(right);
  report_sphere("dumbbell ball 1", fa, a.ball_radius_mm, a, v);
  report_sphere("dumbbell ball 2", fb, a.ball_radius_mm, a, v);
  const double spacing = (fa.centre - fb.centre).norm();
  sayf("  dumbbell: spacing %.4f mm (nominal %.3f, error %+.4f)\n", spacing, a.ball_spacing_mm,
       spacing - a.ball_spacing_mm);
  v.check("dumbbell spacing error", spacing - a.ball_spacing_mm, a.max_spacing_error_mm);
  return {{"ball_1", sphere_json(fa, a.ball_radius_mm)},
          {"ball_2", sphere_json(fb, a.ball_radius_mm)},
          {"spacing_mm", spacing},
          {"nominal_spacing_mm", a.ball_spacing_mm},
          {"spacing_error_mm", spacing - a.ball_spacing_mm}};
}

int run_measure(const MeasureArgs& a) {
  if (a.sim == !a.session.empty())
    throw InvalidInputError("check-calibration: give --sim or a recorded SESSION folder");
  if (!a.session.empty() && a.object != "sphere" && a.object != "dumbbell")
    throw InvalidInputError(
        "check-calibration SESSION: --object sphere|dumbbell says what it holds");
  const Calibration cal = Calibration::read_yaml(a.calib);
  Verdict verdict;
  nlohmann::json report = {{"calibration", a.calib},
                           {"tolerances_mm",
                            {{"radius_error", a.max_radius_error_mm},
                             {"rms_distance", a.max_rms_mm},
                             {"spacing_error", a.max_spacing_error_mm}}}};
  if (a.sim) {
    const auto [w, h] = parse_frame_size(a.size);
    if (cal.camera.width != w || cal.camera.height != h)
      throw InvalidInputError(
          "check-calibration: " + a.calib + " is for " + std::to_string(cal.camera.width) + "x" +
          std::to_string(cal.camera.height) + " frames but --size is " + a.size);
    const sim::RigConfig rig = scaled_ciclop_rig(w, h);
    report["simulation"] = {{"frame_size", a.size}, {"steps", a.steps}};
    {
      const sim::Scene scene = sphere_scene(a.sphere_radius_mm);
      const sim::TurntableCamera camera(scene, rig);
      const SimulatedStepSource source(camera, static_cast<std::size_t>(a.steps));
      report["sphere"] =
          measure_sphere(object_points(source, cal, a.min_height_mm, "sphere"), a, verdict);
    }
    {
      const sim::Scene scene = dumbbell_scene(a.ball_radius_mm, a.ball_spacing_mm);
      const sim::TurntableCamera camera(scene, rig);
      const SimulatedStepSource source(camera, static_cast<std::size_t>(a.steps));
      report["dumbbell"] =
          measure_dumbbell(object_points(source, cal, a.min_height_mm, "dumbbell"), a, verdict);
    }
  } else {
    const SessionReader session(a.session);
    const auto& cam = session.manifest().header.camera;
    if (cam.width != cal.camera.width || cam.height != cal.camera.height)
      throw InvalidInputError(
          "check-calibration: " + a.session + " has " + std::to_string(cam.width) + "x" +
          std::to_string(cam.height) + " frames but " + a.calib + " is for " +
          std::to_string(cal.camera.width) + "x" + std::to_string(cal.camera.height));
    report["session"] = a.session;
    const auto pts = object_points(session, cal, a.min_height_mm, a.object);
    report[a.object] =
        a.object == "sphere" ? measure_sphere(pts, a, verdict) : measure_dumbbell(pts, a, verdict);
  }
  report["pass"] = verdict.pass;
  report["failures"] = verdict.failures;
  if (!a.report.empty()) write_file_atomically(a.report, json_text(report) + "\n");
  result() = report;
  if (verdict.pass) {
    sayf(
        "check-calibration: PASS (within +- %.3f mm radius, %.3f mm RMS, +- %.3f mm "
        "spacing)\n",
        a.max_radius_error_mm, a.max_rms_mm, a.max_spacing_error_mm);
    return kSuccess;
  }
  sayf("check-calibration: FAIL\n");
  for (const auto& f : verdict.failures) sayf("  %s\n", f.get<std::string>().c_str());
  return kOutOfTolerance;
}

}  // namespace

void register_measure_commands(CLI::App& app, CommandList& commands) {
  auto a = std::make_shared<MeasureArgs>();
  auto* cmd = app.add_subcommand(
      "check-calibration",
      "Re-measure known spheres (probing sphere, dumbbell) with a calibration; exit 8 when an "
      "error exceeds its tolerance");
  cmd->add_option("session", a->session, "Recorded session of one artefact (scanmesh scan)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--calib", a->calib, "Calibration YAML")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--sim", a->sim,
                "Scan the probing sphere and the dumbbell with the simulated turntable camera");
  cmd->add_option("--object", a->object, "What SESSION holds: sphere | dumbbell")
      ->check(CLI::IsMember({"sphere", "dumbbell"}));
  cmd->add_option("--size", a->size, "--sim: frame size WIDTHxHEIGHT (as calibrate --size)")
      ->capture_default_str();
  cmd->add_option("--steps", a->steps, "--sim: turntable steps per turn")
      ->capture_default_str()
      ->check(in_range(4, 100000));
  cmd->add_option("--sphere-radius", a->sphere_radius_mm, "Nominal probing-sphere radius (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  cmd->add_option("--ball-radius", a->ball_radius_mm, "Nominal dumbbell ball radius (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  cmd->add_option("--spacing", a->ball_spacing_mm, "Nominal dumbbell centre distance (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  cmd->add_option("--max-radius-error", a->max_radius_error_mm, "Tolerance (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  cmd->add_option("--max-rms", a->max_rms_mm, "Tolerance (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  cmd->add_option("--max-spacing-error", a->max_spacing_error_mm, "Tolerance (mm)")
      ->capture_default_str()
      ->check(above(0, 1e6));
  cmd->add_option("--min-height", a->min_height_mm,
                  "Points lower than this above the platter are left out (mm)")
      ->capture_default_str()
      ->check(in_range(-1e6, 1e6));
  cmd->add_option("--report", a->report, "Also write the measurements as JSON");
  commands.push_back({cmd, [a] { return run_measure(*a); }});
}

}  // namespace scanmesh::cli
