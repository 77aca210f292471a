// Calibration sessions (`scanmesh scan --calibration`): the board poses a user of a Ciclop-like
// scanner is asked for, the prompt between poses on real hardware, and the simulated board that
// the simulated camera renders in each pose (docs/acquisition.md, "Calibration sessions").
#pragma once

#include <cstddef>
#include <functional>
#include <memory>

#include "scanmesh/acquisition/session.h"
#include "scanmesh/sim/sim_camera.h"
#include "scanmesh/sim/turntable_camera.h"

namespace scanmesh::cli {

struct CalibrationPlanArgs {
  int platter_poses = 3;  //!< board placements on the platter (1..kMaxPlatterPoses)
  int handheld = 0;       //!< hand-held views (table still)
  double angle_step_deg = 10.0, angle_max_deg = 70.0;
};
constexpr int kMaxPlatterPoses = 5;

//! The session plan: the built-in 11 x 6 / 13 mm chessboard, the platter placements (each swept
//! through -max..max in steps) and the hand-held views. Throws InvalidInputError.
CalibrationSessionInfo make_calibration_plan(const CalibrationPlanArgs& args);

//! The first n platter placements of the plan (the simulated board of `calibrate --sim` too).
std::vector<sim::BoardPlacement> builtin_platter_placements(int n);

//! The simulated world of a calibration session: a TurntableCamera in pattern mode whose board
//! stands where pose k of `info` puts it after set_pose(k).
class SimCalibrationBoard {
 public:
  SimCalibrationBoard(const CalibrationSessionInfo& info, int width, int height);
  sim::FrameRenderer renderer() const;
  void set_pose(std::size_t pose);
  //! The exact board of pose k (object frame).
  sim::ChessboardPattern pose_pattern(std::size_t pose) const;

 private:
  CalibrationSessionInfo info_;
  std::shared_ptr<sim::Scene> unused_scene_;
  std::shared_ptr<sim::TurntableCamera> camera_;
  std::vector<sim::ChessboardPattern> patterns_;
};

//! Called before each step: when step i begins a pose (or is the first step of this run), asks
//! the user to place the board (on stderr) and waits for Enter on stdin, or `wait_s` seconds if
//! wait_s >= 0. Throws InvalidInputError when stdin ends before the user confirmed.
std::function<void(std::size_t)> pose_prompter(const CalibrationSessionInfo& info, double wait_s);

}  // namespace scanmesh::cli
