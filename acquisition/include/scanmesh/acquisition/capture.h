// The capture loop of a turntable laser scan: for each of N steps, turn the table, wait for it to
// settle, take a frame with all lasers off and one frame per laser with only that laser on, and
// append the step to a session folder (session.h). Resumable: a session that already holds k
// complete steps continues with step k.
#pragma once

#include <chrono>
#include <functional>
#include <string>

#include "scanmesh/acquisition/session.h"
#include "scanmesh/drivers/board.h"
#include "scanmesh/drivers/camera.h"

namespace scanmesh {

struct CaptureOptions {
  double settle_s = 0.2;   //!< wait after each move (vibration of the object on the table)
  int discard_frames = 1;  //!< frames thrown away after a laser switched (exposure in flight)
  //! Wait function (tests and the simulator scale or skip real sleeping).
  std::function<void(double seconds)> sleep;
  //! Called before each step's move with the step index (a calibration session asks the user to
  //! place the board here when a new pose begins, or the simulation moves its board).
  std::function<void(std::size_t step)> before_step;
  //! Called after each complete step with (steps done, steps total).
  std::function<void(std::size_t, std::size_t)> progress;
  //! Asked before each step: true ends the capture there (a user's stop or pause; the lasers
  //! are off between steps and the session holds every complete step, so it can be resumed).
  std::function<bool()> stop_requested;
};

struct CaptureReport {
  std::size_t first_step = 0;  //!< where this run started (0, or the resume point)
  std::size_t steps_done = 0;  //!< complete steps in the session now
  std::uint64_t dropped_frames = 0;
  double seconds = 0;
  bool stopped = false;  //!< ended early by stop_requested
};

//! Captures the remaining steps of `session` with `board` (connected) and `camera`. On a device
//! failure, throws DeviceError naming the device and the step ("step 37: ..."), after switching
//! the lasers off; every step completed before stays in the session.
CaptureReport capture_steps(SessionWriter& session, drivers::Board& board, drivers::Camera& camera,
                            const CaptureOptions& options = {});

}  // namespace scanmesh
